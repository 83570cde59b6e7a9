# The core for other catkin packages: one shared library,
# libvitamin_e.so, holding every core module (the in-tree targets keep linking
# the static modules), exported by catkin_package(LIBRARIES vitamin_e) and
# installed with the headers (include/vitamin_e/...). A downstream package:
#   find_package(catkin REQUIRED COMPONENTS vitamin_e)
#   target_link_libraries(my_node ${catkin_LIBRARIES})
add_library(vitamin_e SHARED ${CMAKE_CURRENT_SOURCE_DIR}/cmake/vitamin_e_core_library.cpp)
set(_ve_whole "")
foreach(m ${VITAMIN_E_MODULES})
  get_target_property(_type vitamin_e_${m} TYPE)
  if(_type STREQUAL "STATIC_LIBRARY")
    list(APPEND _ve_whole vitamin_e_${m})
  endif()
endforeach()
# Every object of every module, not only those a first user pulls in.
target_link_libraries(vitamin_e PRIVATE -Wl,--whole-archive ${_ve_whole} -Wl,--no-whole-archive)
target_include_directories(vitamin_e PUBLIC ${VITAMIN_E_CORE_INCLUDES})
install(TARGETS vitamin_e
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
install(DIRECTORY include/vitamin_e/ DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})
