# Executables: src/apps/<name>.cpp -> <name>. They may use the ROS layer
# (e.g. to read bags) when it exists.
file(GLOB VITAMIN_E_APPS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/apps/*.cpp)
foreach(app_src ${VITAMIN_E_APPS})
  get_filename_component(app ${app_src} NAME_WE)
  add_executable(${app} ${app_src})
  target_link_libraries(${app} vitamin_e_core)
  if(TARGET vitamin_e_ros)
    target_link_libraries(${app} vitamin_e_ros)
    target_compile_definitions(${app} PRIVATE VITAMIN_E_WITH_ROS=1)
  endif()
  # rosrun vitamin_e <name> works from install/ as from devel/.
  install(TARGETS ${app} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endforeach()
