# Unit tests: test/unit/test_<module>_<what>.cpp -> gtest executable linked with
# vitamin_e_<module> (and test/support/*.cpp helpers). Registered with catkin,
# so they run under ctest and catkin_make run_tests.
if(CATKIN_ENABLE_TESTING)
  file(GLOB VITAMIN_E_TEST_SUPPORT CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/support/*.cpp)
  file(GLOB VITAMIN_E_UNIT_TESTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/unit/test_*.cpp)
  foreach(test_src ${VITAMIN_E_UNIT_TESTS})
    get_filename_component(test_name ${test_src} NAME_WE)
    string(REGEX REPLACE "^test_([a-z]+)_.*$" "\\1" test_module ${test_name})
    # test_system_*: end-to-end tests over the whole core (pipeline + synth + eval).
    if(test_module STREQUAL "system")
      set(test_module core)
    endif()
    if(NOT TARGET vitamin_e_${test_module})
      message(FATAL_ERROR "${test_src}: name must be test_<module>_<what>.cpp with a core module")
    endif()
    catkin_add_gtest(${test_name} ${test_src} ${VITAMIN_E_TEST_SUPPORT}
      WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/test)
    target_link_libraries(${test_name} vitamin_e_${test_module})
    target_compile_definitions(${test_name} PRIVATE VITAMIN_E_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
  endforeach()
  # ./scripts/results.sh on a made-up suite output (no data, seconds).
  add_test(NAME script_results COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_results.sh)
  # ./scripts/step_ratio.py on made-up trajectories (seconds).
  add_test(NAME script_step_ratio COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_step_ratio.sh)
  # ./scripts/bench_pipeline_report.py on made-up run folders (seconds).
  add_test(NAME script_bench_pipeline_report
           COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_bench_pipeline_report.sh)
  # ./scripts/config_sweep.py with stand-in binaries (seconds).
  add_test(NAME script_config_sweep COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_config_sweep.sh)
  # Every script's -h / --help: its usage, exit 0, nothing built (seconds).
  add_test(NAME script_help COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_script_help.sh)
  # No merge conflict markers left in the source tree (seconds).
  add_test(NAME script_no_conflict_markers COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_no_conflict_markers.sh)
  # ./scripts/ros.sh, rosrun and the ROS tools of docs/ROS.md on this workspace (seconds).
  get_filename_component(_ve_workspace ${CATKIN_DEVEL_PREFIX} DIRECTORY)
  add_test(NAME script_ros_tools COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test/scripts/test_ros_tools.sh ${_ve_workspace})
  # Tests of the offline tools and the ROS layer (test/ros/*.test, test/tools/*.cpp).
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/cmake/ros_tests.cmake)
    include(cmake/ros_tests.cmake)
  endif()
endif()
