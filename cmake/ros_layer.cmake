# The ROS layer: everything under src/ros/ (nodelets, conversions, bag reader).
# Only these sources (and src/nodes/) include ROS headers.
file(GLOB VITAMIN_E_ROS_SRCS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/ros/*.cpp)
if(VITAMIN_E_ROS_SRCS)
  add_library(vitamin_e_ros ${VITAMIN_E_ROS_SRCS})
  target_include_directories(vitamin_e_ros PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include ${catkin_INCLUDE_DIRS}
    ${CATKIN_DEVEL_PREFIX}/${CATKIN_GLOBAL_INCLUDE_DESTINATION})
  target_link_libraries(vitamin_e_ros PUBLIC vitamin_e_core ${catkin_LIBRARIES})
  add_dependencies(vitamin_e_ros ${${PROJECT_NAME}_EXPORTED_TARGETS} ${catkin_EXPORTED_TARGETS})
endif()
