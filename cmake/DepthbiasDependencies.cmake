# Every external dependency, all from Debian's packages (scripts/setup.sh installs them).
# DEPTHBIAS_DEPENDENCIES is the one list: the build finds each package here, and the installed
# depthbiasConfig.cmake finds the same ones (find_dependency) before it recreates the targets of
# DepthbiasSystemTargets.cmake and imports the library's.
set(DEPTHBIAS_DEPENDENCIES
  "Threads"
  "Eigen3 3.3 NO_MODULE"
  "yaml-cpp"
  "Ceres"
  # OpenCV: the panel's image-space work on the accumulated depth image (lib/panel/hole_fill.cpp)
  "OpenCV COMPONENTS core imgproc"
  "PCL COMPONENTS common sample_consensus segmentation search kdtree filters")
foreach(dependency IN LISTS DEPTHBIAS_DEPENDENCIES)
  separate_arguments(arguments UNIX_COMMAND "${dependency}")
  find_package(${arguments} REQUIRED)
endforeach()
if(DEPTHBIAS_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()

# The interface targets assembled from those packages (depthbias_pcl, depthbias_rosbag, the
# yaml-cpp::yaml-cpp name): one file for the build and the installed package alike.
include(${CMAKE_CURRENT_LIST_DIR}/DepthbiasSystemTargets.cmake)
if(DEPTHBIAS_MISSING)
  message(FATAL_ERROR "depthbias: not found: ${DEPTHBIAS_MISSING} (run scripts/setup.sh)")
endif()
