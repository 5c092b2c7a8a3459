# Small wrappers so every module is built the same way and every test is named <folder>/<name>
# (`ctest -R core/` runs one module).

# hdr4d_add_library(<name> [SOURCES ...] DEPS ...): the library hdr4d_<name>; without SOURCES a
# header-only (INTERFACE) library.
function(hdr4d_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target hdr4d_${name})
  if(NOT ARG_SOURCES)
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
    return()
  endif()
  add_library(${target} STATIC ${ARG_SOURCES})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${target} PUBLIC ${ARG_DEPS})
  target_compile_options(${target} PRIVATE ${HDR4D_WARNINGS})
endfunction()

# hdr4d_add_executable(<name> SOURCES ... DEPS ...)
function(hdr4d_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_compile_options(${name} PRIVATE ${HDR4D_WARNINGS})
endfunction()

# hdr4d_add_test(<folder> <name> [NEEDS_CLI] SOURCES ... DEPS ... [PROPERTIES ...]): a GoogleTest
# binary whose cases are registered as <folder>/<Suite>.<Case> and run from the repository root
# (tests/testing.h has the helpers: temp folders, shared data, running the hdr4d binary).
# PROPERTIES are CTest properties of every case (e.g. FIXTURES_SETUP / FIXTURES_REQUIRED).
function(hdr4d_add_test folder name)
  if(NOT HDR4D_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "NEEDS_CLI" "" "SOURCES;DEPS;PROPERTIES" ${ARGN})
  set(target ${folder}_${name})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} hdr4d_testing GTest::gtest GTest::gmock)
  target_compile_options(${target} PRIVATE ${HDR4D_WARNINGS})
  if(ARG_NEEDS_CLI)
    add_dependencies(${target} hdr4d)  # its cases run the hdr4d binary
  endif()
  gtest_discover_tests(${target}
    TEST_PREFIX "${folder}/"
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    DISCOVERY_TIMEOUT 60
    PROPERTIES ${ARG_PROPERTIES})
endfunction()

# hdr4d_add_benchmark(<name> SOURCES ... DEPS ...): a Google Benchmark binary.
function(hdr4d_add_benchmark name)
  if(NOT HDR4D_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(bench_${name} ${ARG_SOURCES})
  target_link_libraries(bench_${name} PRIVATE ${ARG_DEPS} benchmark::benchmark_main)
  target_compile_options(bench_${name} PRIVATE ${HDR4D_WARNINGS})
endfunction()
