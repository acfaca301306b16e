# The installable package: the umbrella target depthbias::depthbias, the exported targets of
# every module (depthbias_library() installs each), depthbiasConfig.cmake with its version file,
# and the Debian packages cpack -G DEB makes. Included from the top CMakeLists.txt after lib/ and
# apps/, so every module and tool there (whatever lib/CMakeLists.txt found) is in the package.
include(CMakePackageConfigHelpers)

set(DEPTHBIAS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/depthbias)

# depthbias::depthbias links every module.
get_property(DEPTHBIAS_MODULES GLOBAL PROPERTY DEPTHBIAS_MODULES)
add_library(depthbias_all INTERFACE)
add_library(depthbias::depthbias ALIAS depthbias_all)
set_target_properties(depthbias_all PROPERTIES EXPORT_NAME depthbias)
foreach(module IN LISTS DEPTHBIAS_MODULES)
  target_link_libraries(depthbias_all INTERFACE depthbias::${module})
endforeach()
install(TARGETS depthbias_all EXPORT depthbiasTargets)
install(EXPORT depthbiasTargets NAMESPACE depthbias:: DESTINATION ${DEPTHBIAS_CMAKE_DIR}
        COMPONENT dev)

# The Debian packages a consumer's build needs: DEPTHBIAS_DEPENDENCIES' and the libraries of
# DepthbiasSystemTargets.cmake (named in depthbias-dev's Depends and in the Config's message).
set(DEPTHBIAS_DEV_DEPENDS
  libeigen3-dev libceres-dev libyaml-cpp-dev libopencv-dev libpcl-dev
  librosbag-storage-dev libroscpp-core-dev libconsole-bridge-dev libroslz4-dev
  libboost-filesystem-dev liblz4-dev libbz2-dev)
list(JOIN DEPTHBIAS_DEV_DEPENDS " " DEPTHBIAS_DEV_DEPENDS_TEXT)

# depthbiasConfig.cmake finds the packages the build found (DEPTHBIAS_DEPENDENCIES).
set(DEPTHBIAS_FIND_DEPENDENCIES "")
foreach(dependency IN LISTS DEPTHBIAS_DEPENDENCIES)
  string(APPEND DEPTHBIAS_FIND_DEPENDENCIES "find_dependency(${dependency})\n")
endforeach()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/depthbiasConfig.cmake.in
  ${PROJECT_BINARY_DIR}/depthbiasConfig.cmake
  INSTALL_DESTINATION ${DEPTHBIAS_CMAKE_DIR}
  PATH_VARS CMAKE_INSTALL_INCLUDEDIR)
# 0.x: a new minor version may break the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/depthbiasConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/depthbiasConfig.cmake
              ${PROJECT_BINARY_DIR}/depthbiasConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/DepthbiasSystemTargets.cmake
        DESTINATION ${DEPTHBIAS_CMAKE_DIR} COMPONENT dev)

# Beside the tools: the parameter files, the simulated protocols, the article's data and the
# Snakemake workflow (share/depthbias/).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/depthbias/config COMPONENT tools)
# The build tree mirrors that layout (build/share/depthbias/config → the source's config/), so a
# tool finds its default files beside itself in any build folder as in an installed tree.
file(MAKE_DIRECTORY ${PROJECT_BINARY_DIR}/share/depthbias)
file(CREATE_LINK ${PROJECT_SOURCE_DIR}/config ${PROJECT_BINARY_DIR}/share/depthbias/config
     SYMBOLIC)
if(EXISTS ${PROJECT_SOURCE_DIR}/workflow)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/workflow/
          DESTINATION ${CMAKE_INSTALL_DATADIR}/depthbias/workflow COMPONENT tools
          PATTERN ".snakemake" EXCLUDE PATTERN "__pycache__" EXCLUDE)
endif()

# cpack -G DEB: two Debian packages, as Debian splits a library.
#   depthbias      the tools (+ share/depthbias/); Depends computed from the binaries
#                  (dpkg-shlibdeps): the runtime libraries only, what a field machine needs.
#   depthbias-dev  headers, static libraries and the CMake package; Depends on depthbias and on
#                  the -dev packages a consumer's link needs (DEPTHBIAS_DEPENDENCIES and the
#                  libraries of DepthbiasSystemTargets.cmake).
set(DEPTHBIAS_PACKAGE_CONTACT "depthbias maintainers <depthbias@example.invalid>" CACHE STRING
    "Maintainer field of the Debian packages")
set(CPACK_PACKAGE_NAME depthbias)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${DEPTHBIAS_PACKAGE_CONTACT}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "RealSense D455 depth-bias measurement, bias models and correction")
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL tools dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "")
set(CPACK_DEBIAN_TOOLS_PACKAGE_NAME depthbias)
set(CPACK_DEBIAN_TOOLS_PACKAGE_SECTION science)
set(CPACK_DEBIAN_TOOLS_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME depthbias-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
list(JOIN DEPTHBIAS_DEV_DEPENDS ", " dev_depends)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "depthbias (= ${PROJECT_VERSION}), ${dev_depends}")
set(CPACK_COMPONENT_TOOLS_DESCRIPTION
    "Command-line tools: bag_info, panel_extract, fit_bias, correct_depth, simulate")
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "C++ library (static), headers and CMake package: find_package(depthbias)")
include(CPack)
