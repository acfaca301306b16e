# Interface targets depthbias assembles from Debian's packages. Included by the build (after
# cmake/DepthbiasDependencies.cmake found the packages) and, installed beside it, by
# depthbiasConfig.cmake (after find_dependency found the same ones): the exported module targets
# name these targets, so a consumer gets them under the same names, found on its own machine.
# They are IMPORTED targets, so an export names them without exporting them.
# Each library missing on the machine is added to DEPTHBIAS_MISSING (the caller reports it).

# yaml-cpp 0.7 on Debian exports the plain target name.
if(TARGET yaml-cpp AND NOT TARGET yaml-cpp::yaml-cpp)
  add_library(yaml-cpp::yaml-cpp ALIAS yaml-cpp)
endif()

# PCL as an interface target, so only the modules that use it see its flags. Without VTK's
# targets: PCL_LIBRARIES names them for PCL's viewers, which depthbias does not use, and VTK::mpi
# needs the C language enabled in every project that links it (a C++-only consumer would fail).
if(NOT TARGET depthbias_pcl)
  add_library(depthbias_pcl INTERFACE IMPORTED)
  set(pcl_libraries ${PCL_LIBRARIES})
  list(FILTER pcl_libraries EXCLUDE REGEX "^VTK::")
  target_include_directories(depthbias_pcl SYSTEM INTERFACE ${PCL_INCLUDE_DIRS})
  target_link_libraries(depthbias_pcl INTERFACE ${pcl_libraries})
  target_compile_definitions(depthbias_pcl INTERFACE ${PCL_DEFINITIONS})
endif()

# rosbag_storage (ROS1 bag format) from Debian: its CMake config wants catkin and its .pc file
# names a pluginlib.pc that Debian does not ship, so the target is assembled here.
if(NOT TARGET depthbias_rosbag)
  add_library(depthbias_rosbag INTERFACE IMPORTED)
  foreach(lib rosbag_storage roscpp_serialization rostime cpp_common console_bridge roslz4
              boost_filesystem)
    find_library(DEPTHBIAS_LIB_${lib} NAMES ${lib})
    if(DEPTHBIAS_LIB_${lib})
      target_link_libraries(depthbias_rosbag INTERFACE ${DEPTHBIAS_LIB_${lib}})
    else()
      list(APPEND DEPTHBIAS_MISSING "lib${lib}.so")
    endif()
  endforeach()
  foreach(sub pluginlib class_loader rcpputils rcutils ament_index_cpp tinyxml2)
    if(EXISTS /usr/include/${sub})
      target_include_directories(depthbias_rosbag SYSTEM INTERFACE /usr/include/${sub})
    endif()
  endforeach()
endif()

# rosbag2 storage (MCAP chunks in zstd or lz4, SQLite3 .db3 files, CRC-32 of MCAP chunks) from
# Debian's libzstd, liblz4, libsqlite3 and zlib: plain C libraries found by name.
if(NOT TARGET depthbias_ros2_storage)
  add_library(depthbias_ros2_storage INTERFACE IMPORTED)
  foreach(lib zstd lz4 sqlite3 z)
    find_library(DEPTHBIAS_LIB_${lib} NAMES ${lib})
    if(DEPTHBIAS_LIB_${lib})
      target_link_libraries(depthbias_ros2_storage INTERFACE ${DEPTHBIAS_LIB_${lib}})
    else()
      list(APPEND DEPTHBIAS_MISSING "lib${lib}.so")
    endif()
  endforeach()
endif()
