# rostests of the ROS layer (included by cmake/tests.cmake when testing is on).
# test/ros/<name>.test.in is configured into the build tree (it names the test
# data made at build time) and registered with add_rostest, so ctest (and
# ./scripts/test.sh) runs it. One gtest executable (test/ros/test_ros_*.cpp,
# main() in test_ros_nodelets.cpp) serves every .test file (--gtest_filter).
find_package(rostest REQUIRED)
find_package(roslaunch REQUIRED)
# Every launch file parses and finds its packages and nodes (bag:= of euroc.launch has no
# default: IGNORE_UNSET_ARGS).
roslaunch_add_file_check(launch IGNORE_UNSET_ARGS)

set(VE_TEST_DATA ${CMAKE_CURRENT_BINARY_DIR}/rostest_data)
set(VE_TEST_OUT ${CMAKE_CURRENT_BINARY_DIR}/rostest_out)
set(VE_TEST_FRAMES 60)
set(VE_TEST_LONG_FRAMES 200)  # long.bag: the mesh stream's test
set(VE_SOURCE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
file(MAKE_DIRECTORY ${VE_TEST_OUT})

# The input sequence: the project's generator when it is built, else a room
# ray-cast by the script itself.
set(_ve_bag_args ${VE_TEST_DATA} --frames ${VE_TEST_FRAMES} --long-frames ${VE_TEST_LONG_FRAMES})
set(_ve_bag_deps ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/make_test_bag.py ${CMAKE_CURRENT_SOURCE_DIR}/scripts/make_bag.sh)
if(TARGET vitamin_e_make_sequence)
  list(APPEND _ve_bag_args --generator $<TARGET_FILE:vitamin_e_make_sequence>
    --make-bag ${CMAKE_CURRENT_SOURCE_DIR}/scripts/make_bag.sh)
  list(APPEND _ve_bag_deps vitamin_e_make_sequence)
endif()
add_custom_command(OUTPUT ${VE_TEST_DATA}/sequence.bag ${VE_TEST_DATA}/sensors.bag ${VE_TEST_DATA}/long.bag
    ${VE_TEST_DATA}/long_groundtruth.tum
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/make_test_bag.py ${_ve_bag_args}
  DEPENDS ${_ve_bag_deps}
  COMMENT "rostest input sequence -> ${VE_TEST_DATA}")
add_custom_target(vitamin_e_rostest_data DEPENDS ${VE_TEST_DATA}/sequence.bag)

file(GLOB _ve_rostest_srcs CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/test_ros_*.cpp)
add_executable(test_ros_nodelets EXCLUDE_FROM_ALL ${_ve_rostest_srcs})
target_include_directories(test_ros_nodelets PRIVATE ${VITAMIN_E_ROS_INCLUDES} ${GTEST_INCLUDE_DIRS})
target_link_libraries(test_ros_nodelets ${GTEST_LIBRARIES} vitamin_e_ros vitamin_e_eval ${catkin_LIBRARIES})
add_dependencies(test_ros_nodelets ${${PROJECT_NAME}_EXPORTED_TARGETS} ${catkin_EXPORTED_TARGETS})
add_dependencies(tests test_ros_nodelets vitamin_e_rostest_data)

file(GLOB _ve_rostests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/*.test.in)
foreach(in ${_ve_rostests})
  get_filename_component(name ${in} NAME_WE)
  configure_file(${in} ${CMAKE_CURRENT_BINARY_DIR}/rostest/${name}.test @ONLY)
  add_rostest(${CMAKE_CURRENT_BINARY_DIR}/rostest/${name}.test DEPENDENCIES test_ros_nodelets vitamin_e_rostest_data)
endforeach()

# euroc.launch run to its end by roslaunch (its own master), not under rostest: the
# launch ends itself when the bag ends, which would end a rostest too.
#  - rostest_euroc_launch_imu: sensors.bag (with /imu0): the map's z within 5 deg of the true
#    up, the ATE within 10 % of vitamin_e_run's on the same bag
#  - rostest_install_space: make install; a package outside the tree links libvitamin_e from
#    install/ and runs; euroc.launch runs from install/ only; the tools are installed
if(TARGET vitamin_e_run AND TARGET vitamin_e_evaluate)
  add_test(NAME rostest_euroc_launch_imu
    COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/run_euroc_launch.py
      --data ${VE_TEST_DATA} --bag sensors.bag --out ${VE_TEST_OUT}/euroc_launch_imu
      --evaluate $<TARGET_FILE:vitamin_e_evaluate> --max-tilt-deg 5 --compare-offline $<TARGET_FILE:vitamin_e_run>)
  add_test(NAME rostest_install_space
    COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/run_euroc_launch.py
      --data ${VE_TEST_DATA} --bag sequence.bag --out ${VE_TEST_OUT}/install_space
      --evaluate $<TARGET_FILE:vitamin_e_evaluate> --install ${CMAKE_BINARY_DIR}
      --downstream ${CMAKE_CURRENT_SOURCE_DIR}/test/downstream)
  # The pipelined tracker in bag mode gives the same run as vitamin_e_run --pipelined (no IMU).
  add_test(NAME rostest_euroc_launch_pipelined
    COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/run_euroc_launch.py
      --data ${VE_TEST_DATA} --bag sequence.bag --out ${VE_TEST_OUT}/euroc_launch_pipelined
      --evaluate $<TARGET_FILE:vitamin_e_evaluate> --launch-arg pipelined:=true --launch-arg imu:=false
      --compare-offline $<TARGET_FILE:vitamin_e_run> --offline-arg=--pipelined --offline-same)
  # imu_topic:="" as a shell leaves it (the two quotes): no IMU, the launch tracks (it crashed).
  add_test(NAME rostest_euroc_launch_no_imu
    COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/run_euroc_launch.py
      --data ${VE_TEST_DATA} --bag sensors.bag --out ${VE_TEST_OUT}/euroc_launch_no_imu
      --evaluate $<TARGET_FILE:vitamin_e_evaluate> --launch-arg "imu_topic:=\"\""
      --expect-log "the first camera in ROS axes" --min-poses 50)
  # save_map / load_map / localization_only / ns through the launch files; a damaged map ends the launch.
  add_test(NAME rostest_launch_maps
    COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/run_launch_maps.py
      --data ${VE_TEST_DATA} --out ${VE_TEST_OUT}/launch_maps --evaluate $<TARGET_FILE:vitamin_e_evaluate>)
  set_tests_properties(rostest_euroc_launch_imu rostest_euroc_launch_pipelined rostest_install_space
    rostest_euroc_launch_no_imu rostest_launch_maps
    PROPERTIES TIMEOUT 600)
endif()
