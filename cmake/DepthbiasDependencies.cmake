# Every external dependency, all from Debian's packages (scripts/setup.sh installs them).
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(Ceres REQUIRED)
find_package(OpenCV REQUIRED COMPONENTS core imgproc)
find_package(PCL REQUIRED COMPONENTS common sample_consensus segmentation search kdtree filters)
if(DEPTHBIAS_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()

# yaml-cpp 0.7 on Debian exports the plain target name.
if(TARGET yaml-cpp AND NOT TARGET yaml-cpp::yaml-cpp)
  add_library(yaml-cpp::yaml-cpp ALIAS yaml-cpp)
endif()

# PCL as an interface target, so only the modules that use it see its flags.
add_library(depthbias_pcl INTERFACE)
target_include_directories(depthbias_pcl SYSTEM INTERFACE ${PCL_INCLUDE_DIRS})
target_link_libraries(depthbias_pcl INTERFACE ${PCL_LIBRARIES})
target_compile_definitions(depthbias_pcl INTERFACE ${PCL_DEFINITIONS})

# rosbag_storage (ROS1 bag format) from Debian: its CMake config wants catkin and its .pc file
# names a pluginlib.pc that Debian does not ship, so the target is assembled here.
set(DEPTHBIAS_ROSBAG_LIBS rosbag_storage roscpp_serialization rostime cpp_common console_bridge
    roslz4 boost_filesystem)
add_library(depthbias_rosbag INTERFACE)
foreach(lib ${DEPTHBIAS_ROSBAG_LIBS})
  find_library(DEPTHBIAS_LIB_${lib} NAMES ${lib} REQUIRED)
  target_link_libraries(depthbias_rosbag INTERFACE ${DEPTHBIAS_LIB_${lib}})
endforeach()
foreach(sub pluginlib class_loader rcpputils rcutils ament_index_cpp tinyxml2)
  if(EXISTS /usr/include/${sub})
    target_include_directories(depthbias_rosbag SYSTEM INTERFACE /usr/include/${sub})
  endif()
endforeach()
