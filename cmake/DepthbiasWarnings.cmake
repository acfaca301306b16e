include(GNUInstallDirs)

# One place for the warning flags every target gets.
function(depthbias_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
endfunction()

# depthbias_library(NAME [SOURCES...] [DEPS ...] [PRIVATE_DEPS ...]): lib/<NAME> as target
# depthbias_<NAME>, alias depthbias::<NAME> (an interface library when there are no sources).
# Every module made here is installed and exported the same way (depthbias_install_module), and
# the umbrella target depthbias::depthbias links them all (cmake/DepthbiasPackage.cmake).
function(depthbias_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  # The library's headers include each other as "<module>/<file>.h": lib/ in the build, and in
  # the installed tree include/depthbias/ (where they are) plus include/ (for a consumer's
  # <depthbias/<module>/<file>.h>).
  set(includes $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/lib>
               $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/depthbias>
               $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(ARG_SOURCES)
    add_library(depthbias_${name} STATIC ${ARG_SOURCES})
    target_include_directories(depthbias_${name} PUBLIC ${includes})
    target_link_libraries(depthbias_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
    target_compile_features(depthbias_${name} PUBLIC cxx_std_17)
    set_target_properties(depthbias_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    depthbias_warnings(depthbias_${name})
    if(DEPTHBIAS_SANITIZE)
      # An instrumented archive needs the sanitizers wherever it is used, consumers of the
      # installed package included: their runtime at link time, and the same instrumentation at
      # compile time, since headers compile differently under it (Eigen, for one, allocates
      # through its own aligned malloc under AddressSanitizer, and an inline destructor built
      # without it would free such a block with std::free).
      target_compile_options(depthbias_${name} INTERFACE -fsanitize=address,undefined)
      target_link_options(depthbias_${name} INTERFACE -fsanitize=address,undefined)
    endif()
  else()
    add_library(depthbias_${name} INTERFACE)
    target_include_directories(depthbias_${name} INTERFACE ${includes})
    target_link_libraries(depthbias_${name} INTERFACE ${ARG_DEPS})
    target_compile_features(depthbias_${name} INTERFACE cxx_std_17)
  endif()
  add_library(depthbias::${name} ALIAS depthbias_${name})
  depthbias_install_module(${name})
endfunction()

# depthbias_install_module(NAME): installs target depthbias_<NAME> (exported as
# depthbias::<NAME>) and the module's public headers to include/depthbias/<NAME>/. A header is
# private, and not installed, when its opening comment says "Private to <NAME>." (as in
# lib/io/bag_records.h); every installed header must compile on its own in a consumer
# (scripts/test_consumer.sh checks it).
function(depthbias_install_module name)
  set_target_properties(depthbias_${name} PROPERTIES EXPORT_NAME ${name})
  install(TARGETS depthbias_${name} EXPORT depthbiasTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
  file(GLOB headers CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.h)
  set(public "")
  foreach(header IN LISTS headers)
    file(STRINGS ${header} private LIMIT_INPUT 400 REGEX "^// Private to ${name}\\.")
    if(NOT private)
      list(APPEND public ${header})
    endif()
  endforeach()
  install(FILES ${public} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/depthbias/${name}
          COMPONENT dev)
  set_property(GLOBAL APPEND PROPERTY DEPTHBIAS_MODULES ${name})
endfunction()

# depthbias_app(NAME SOURCE DEPS...): a thin command-line program, installed to bin/.
function(depthbias_app name source)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${ARGN})
  depthbias_warnings(${name})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT tools)
endfunction()

# depthbias_test(NAME SOURCES... DEPS ...): one GoogleTest binary, registered with ctest.
function(depthbias_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest_main)
  # tests/support/: helpers every test may use ("support/tools.h").
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    DEPTHBIAS_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    DEPTHBIAS_BINARY_DIR="${PROJECT_BINARY_DIR}"
    DEPTHBIAS_TEST_DATA="${PROJECT_SOURCE_DIR}/tests/data")
  depthbias_warnings(${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${ARG_LABELS}" ENVIRONMENT "DEPTHBIAS_BIN=${PROJECT_BINARY_DIR}/apps")
endfunction()
