# The ROS layer. Only src/ros/ and src/nodes/ include ROS headers.
#   src/ros/*.cpp          -> vitamin_e_ros       (static, PIC): conversions, bag reader
#   src/ros/nodelets/*.cpp -> vitamin_e_nodelets  (shared): the pluginlib nodelets of nodelet_plugins.xml
#   src/nodes/<name>.cpp   -> <name>              (plain nodes that load a nodelet with nodelet::Loader)
set(VITAMIN_E_ROS_INCLUDES ${CMAKE_CURRENT_SOURCE_DIR}/include ${catkin_INCLUDE_DIRS}
  ${CATKIN_DEVEL_PREFIX}/${CATKIN_GLOBAL_INCLUDE_DESTINATION})

file(GLOB VITAMIN_E_ROS_SRCS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/ros/*.cpp)
if(VITAMIN_E_ROS_SRCS)
  add_library(vitamin_e_ros STATIC ${VITAMIN_E_ROS_SRCS})
  set_target_properties(vitamin_e_ros PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_include_directories(vitamin_e_ros PUBLIC ${VITAMIN_E_ROS_INCLUDES})
  target_link_libraries(vitamin_e_ros PUBLIC vitamin_e_core ${catkin_LIBRARIES})
  add_dependencies(vitamin_e_ros ${${PROJECT_NAME}_EXPORTED_TARGETS} ${catkin_EXPORTED_TARGETS})
endif()

file(GLOB VITAMIN_E_NODELET_SRCS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/ros/nodelets/*.cpp)
if(VITAMIN_E_NODELET_SRCS AND TARGET vitamin_e_ros)
  add_library(vitamin_e_nodelets SHARED ${VITAMIN_E_NODELET_SRCS})
  target_include_directories(vitamin_e_nodelets PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/ros/nodelets)
  target_link_libraries(vitamin_e_nodelets PRIVATE vitamin_e_ros)
  add_dependencies(vitamin_e_nodelets ${${PROJECT_NAME}_EXPORTED_TARGETS} ${catkin_EXPORTED_TARGETS})
  install(TARGETS vitamin_e_nodelets
    ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
    LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
endif()

file(GLOB VITAMIN_E_NODE_SRCS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/nodes/*.cpp)
foreach(node_src ${VITAMIN_E_NODE_SRCS})
  get_filename_component(node ${node_src} NAME_WE)
  add_executable(${node} ${node_src})
  target_include_directories(${node} PRIVATE ${VITAMIN_E_ROS_INCLUDES})
  target_link_libraries(${node} ${catkin_LIBRARIES})
  install(TARGETS ${node} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endforeach()

install(FILES nodelet_plugins.xml DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
foreach(dir launch config rviz)
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${dir})
    install(DIRECTORY ${dir}/ DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION}/${dir})
  endif()
endforeach()
# Scripts the launch files run (rosrun / <node type>): installed, so that a launch file
# works from install/ as from devel/.
catkin_install_python(PROGRAMS scripts/play_bag.py scripts/make_bag.sh
  DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(PROGRAMS scripts/screenshot_rviz.sh DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
