# Small wrappers so every module is built the same way and every test is named <folder>/<name>
# (`ctest -R core/` runs one module).

# hdr4d_add_library(<name> [SOURCES ...] DEPS ... [PCH header]): the library hdr4d_<name>; without
# SOURCES a header-only (INTERFACE) library. PCH: its own precompiled header instead of the
# shared one.
function(hdr4d_add_library name)
  cmake_parse_arguments(ARG "" "PCH" "SOURCES;DEPS" ${ARGN})
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
  if(HDR4D_UNITY)
    # Batches of 8 sources compile as one file, so the headers and templates they share are
    # compiled once per batch. Highway's per-target files re-include themselves
    # (HWY_TARGET_INCLUDE) and stay alone.
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
    foreach(src IN LISTS ARG_SOURCES)
      # Only the folder's own .cpp files can be Highway's; a generated header (the viewer's
      # assets) does not exist yet when CMake configures.
      if(NOT src MATCHES "\\.cpp$" OR IS_ABSOLUTE "${src}")
        continue()
      endif()
      file(STRINGS ${CMAKE_CURRENT_SOURCE_DIR}/${src} hwy REGEX "HWY_TARGET_INCLUDE")
      if(hwy)
        set_source_files_properties(${src} TARGET_DIRECTORY ${target}
                                    PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
      endif()
    endforeach()
  endif()
  if(HDR4D_PCH AND ARG_PCH)
    target_precompile_headers(${target} PRIVATE ${ARG_PCH})
  elseif(HDR4D_PCH)
    target_precompile_headers(${target} REUSE_FROM hdr4d_lib_pch)
  endif()
endfunction()

# hdr4d_add_executable(<name> SOURCES ... DEPS ...)
function(hdr4d_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_compile_options(${name} PRIVATE ${HDR4D_WARNINGS})
endfunction()

# Builds from scratch (CI's) spend most of their time parsing the same third-party headers and
# generating code for test files. With HDR4D_PCH every library reuses one precompiled header
# (cmake/pch/library.h, built once by hdr4d_lib_pch) unless it names its own (PCH), and every
# test reuses cmake/pch/tests.h (hdr4d_test_pch). Test files are compiled at -O1
# (HDR4D_TEST_OPT): the code under test is the libraries', built with the build type's flags.
function(hdr4d_add_pch_targets)
  if(NOT HDR4D_PCH)
    return()
  endif()
  _hdr4d_add_pch_target(hdr4d_lib_pch library.h "" "")
  if(HDR4D_BUILD_TESTS)
    _hdr4d_add_pch_target(hdr4d_test_pch tests.h "GTest::gtest;GTest::gmock" "${HDR4D_TEST_OPT}")
  endif()
endfunction()

# A target that only builds cmake/pch/<header> for others to reuse: built with hdr4d_core's usage
# requirements (HDR4D_CORE_DEPS, which every library and test links) and the same options as its
# users, so that the precompiled header is valid where it is reused.
function(_hdr4d_add_pch_target target header extra_deps extra_options)
  add_library(${target} OBJECT ${PROJECT_SOURCE_DIR}/cmake/pch/anchor.cpp)
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${target} PRIVATE ${HDR4D_CORE_DEPS} ${extra_deps})
  target_compile_options(${target} PRIVATE ${HDR4D_WARNINGS} ${extra_options})
  target_precompile_headers(${target} PRIVATE ${PROJECT_SOURCE_DIR}/cmake/pch/${header})
endfunction()

# hdr4d_add_test(<folder> <name> [NEEDS_CLI] SOURCES ... DEPS ... [PROPERTIES ...]): a GoogleTest
# binary whose cases are registered as <folder>/<Suite>.<Case> and run from the repository root
# (tests/testing.h has the helpers: temp folders, shared data, running the hdr4d binary; their
# main, tests/testing_main.cpp, applies HDR4D_SIMD_TARGETS).
# PROPERTIES are CTest properties of every case (e.g. FIXTURES_SETUP / FIXTURES_REQUIRED, or COST:
# the seconds a case takes, so that a fresh clone, which has no timing history, starts the longest
# cases first instead of finishing on one of them alone).
function(hdr4d_add_test folder name)
  if(NOT HDR4D_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "NEEDS_CLI" "" "SOURCES;DEPS;PROPERTIES" ${ARGN})
  set(target ${folder}_${name})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} hdr4d_testing GTest::gtest GTest::gmock)
  target_compile_options(${target} PRIVATE ${HDR4D_WARNINGS} ${HDR4D_TEST_OPT})
  if(HDR4D_PCH)
    target_precompile_headers(${target} REUSE_FROM hdr4d_test_pch)
  endif()
  if(ARG_NEEDS_CLI)
    add_dependencies(${target} hdr4d)  # its cases run the hdr4d binary
  endif()
  gtest_discover_tests(${target}
    TEST_PREFIX "${folder}/"
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    DISCOVERY_TIMEOUT 60
    PROPERTIES ${ARG_PROPERTIES})
endfunction()

# hdr4d_add_benchmark(<name> SOURCES ... DEPS ...): a Google Benchmark binary (its main:
# benchmark/runtime/bench_main.cpp, which applies HDR4D_SIMD_TARGETS).
function(hdr4d_add_benchmark name)
  if(NOT HDR4D_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(bench_${name} ${ARG_SOURCES})
  target_link_libraries(bench_${name} PRIVATE ${ARG_DEPS} hdr4d_bench_main)
  target_compile_options(bench_${name} PRIVATE ${HDR4D_WARNINGS})
endfunction()
