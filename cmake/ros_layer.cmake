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
    # The real folder: its files are copied (the package folder's entry is a link, scripts/build.sh).
    get_filename_component(_ve_dir_real ${CMAKE_CURRENT_SOURCE_DIR}/${dir} REALPATH)
    install(DIRECTORY ${_ve_dir_real}/ DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION}/${dir})
  endif()
endforeach()
# Scripts the launch files run (rosrun / <node type>): installed, so that a launch file
# works from install/ as from devel/.
catkin_install_python(PROGRAMS scripts/play_bag.py scripts/make_bag.sh
  DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(PROGRAMS scripts/screenshot_rviz.sh DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

# The workspace's package folder links each entry of the checkout (scripts/build.sh), and
# install(FILES) copies a link as a link (package.xml, nodelet_plugins.xml): the install space
# would point back into the checkout.
# Declared after every install rule of the package (catkin_package's package.xml included),
# so it runs last: each link in the package's installed share folder becomes a copy.
install(CODE "
  file(GLOB_RECURSE _ve_links LIST_DIRECTORIES true \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CATKIN_PACKAGE_SHARE_DESTINATION}/*\")
  foreach(_ve_link \${_ve_links})
    if(IS_SYMLINK \"\${_ve_link}\")
      get_filename_component(_ve_target \"\${_ve_link}\" REALPATH)
      file(REMOVE \"\${_ve_link}\")
      get_filename_component(_ve_parent \"\${_ve_link}\" DIRECTORY)
      get_filename_component(_ve_name \"\${_ve_link}\" NAME)
      file(COPY \"\${_ve_target}\" DESTINATION \"\${_ve_parent}\")
      get_filename_component(_ve_target_name \"\${_ve_target}\" NAME)
      if(NOT _ve_target_name STREQUAL _ve_name)
        file(RENAME \"\${_ve_parent}/\${_ve_target_name}\" \"\${_ve_link}\")
      endif()
    endif()
  endforeach()
")
