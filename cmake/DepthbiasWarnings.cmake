# One place for the warning flags every target gets.
function(depthbias_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
endfunction()

# depthbias_library(NAME SOURCES... DEPS ...): lib/<NAME> as target depthbias_<NAME>, alias depthbias::<NAME>.
function(depthbias_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(depthbias_${name} STATIC ${ARG_SOURCES})
  add_library(depthbias::${name} ALIAS depthbias_${name})
  target_include_directories(depthbias_${name} PUBLIC ${PROJECT_SOURCE_DIR}/lib)
  target_link_libraries(depthbias_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  set_target_properties(depthbias_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  depthbias_warnings(depthbias_${name})
endfunction()

# depthbias_app(NAME SOURCE DEPS...): a thin command-line program.
function(depthbias_app name source)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${ARGN})
  depthbias_warnings(${name})
endfunction()

# depthbias_test(NAME SOURCES... DEPS ...): one GoogleTest binary, registered with ctest.
function(depthbias_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    DEPTHBIAS_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    DEPTHBIAS_BINARY_DIR="${PROJECT_BINARY_DIR}"
    DEPTHBIAS_TEST_DATA="${PROJECT_SOURCE_DIR}/tests/data")
  depthbias_warnings(${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${ARG_LABELS}" ENVIRONMENT "DEPTHBIAS_BIN=${PROJECT_BINARY_DIR}/apps")
endfunction()
