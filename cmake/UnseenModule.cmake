# unseen_module(NAME <module> [DEPS <targets...>])
#
# Declares the library target unseen_<module> from src/unseen/<module>/*.cc. Every
# foo_test.cc beside it becomes a GoogleTest executable registered with CTest as
# <module>/foo_test; every foo_benchmark.cc a Google Benchmark executable (when
# UNSEEN_BUILD_BENCHMARKS is on).
function(unseen_compile_options target)
  # Warnings only: instruction set and sanitizers are build-wide (top-level CMakeLists.txt).
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter)
endfunction()

# Precompiled headers (UNSEEN_PRECOMPILE_HEADERS): the third-party and standard headers
# nearly every unit parses (cmake/precompiled.h; with GoogleTest for the tests,
# cmake/precompiled_test.h) are parsed once per build rather than once per unit: a test
# unit compiles in ~5 s instead of ~7.5. unseen_declare_precompiled_headers() builds them
# (targets unseen_pch, unseen_test_pch) with the build-wide flags every unit has;
# unseen_use_precompiled_headers(<target> lib|test) lets a target reuse them.
function(unseen_declare_precompiled_headers)
  if(NOT UNSEEN_PRECOMPILE_HEADERS)
    return()
  endif()
  set(deps Eigen3::Eigen opencv_core opencv_imgproc fmt::fmt spdlog::spdlog OpenMP::OpenMP_CXX)
  add_library(unseen_pch OBJECT ${PROJECT_SOURCE_DIR}/cmake/precompiled.cc)
  target_link_libraries(unseen_pch PRIVATE ${deps})
  unseen_compile_options(unseen_pch)
  target_precompile_headers(unseen_pch PRIVATE ${PROJECT_SOURCE_DIR}/cmake/precompiled.h)
  if(UNSEEN_BUILD_TESTS)
    add_library(unseen_test_pch OBJECT ${PROJECT_SOURCE_DIR}/cmake/precompiled.cc)
    target_link_libraries(unseen_test_pch PRIVATE ${deps} GTest::gtest)
    unseen_compile_options(unseen_test_pch)
    target_precompile_headers(unseen_test_pch PRIVATE
                              ${PROJECT_SOURCE_DIR}/cmake/precompiled_test.h)
  endif()
endfunction()

function(unseen_use_precompiled_headers target kind)
  if(UNSEEN_PRECOMPILE_HEADERS)
    if(kind STREQUAL "test")
      target_precompile_headers(${target} REUSE_FROM unseen_test_pch)
    else()
      target_precompile_headers(${target} REUSE_FROM unseen_pch)
    endif()
  endif()
endfunction()

function(unseen_module)
  cmake_parse_arguments(ARG "" "NAME" "DEPS" ${ARGN})
  set(dir ${CMAKE_CURRENT_SOURCE_DIR})
  file(GLOB all_sources CONFIGURE_DEPENDS ${dir}/*.cc)
  set(lib_sources "")
  set(test_sources "")
  set(bench_sources "")
  foreach(src ${all_sources})
    if(src MATCHES "_test\\.cc$")
      list(APPEND test_sources ${src})
    elseif(src MATCHES "_benchmark\\.cc$")
      list(APPEND bench_sources ${src})
    else()
      list(APPEND lib_sources ${src})
    endif()
  endforeach()

  set(target unseen_${ARG_NAME})
  if(lib_sources)
    add_library(${target} STATIC ${lib_sources})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} PUBLIC ${ARG_DEPS})
    target_compile_definitions(${target} PUBLIC UNSEEN_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
    unseen_compile_options(${target})
    unseen_use_precompiled_headers(${target} lib)
  else()  # header-only module
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
    target_compile_definitions(${target} INTERFACE UNSEEN_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  endif()

  if(UNSEEN_BUILD_TESTS)
    foreach(src ${test_sources})
      get_filename_component(name ${src} NAME_WE)
      set(exe ${ARG_NAME}_${name})
      add_executable(${exe} ${src})
      target_link_libraries(${exe} PRIVATE ${target} GTest::gtest GTest::gtest_main)
      unseen_compile_options(${exe})
      unseen_use_precompiled_headers(${exe} test)
      add_test(NAME ${ARG_NAME}/${name} COMMAND ${exe}
               WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
    endforeach()
  endif()
  if(UNSEEN_BUILD_BENCHMARKS)
    foreach(src ${bench_sources})
      get_filename_component(name ${src} NAME_WE)
      set(exe ${ARG_NAME}_${name})
      add_executable(${exe} ${src})
      target_link_libraries(${exe} PRIVATE ${target} benchmark::benchmark)
      unseen_compile_options(${exe})
      unseen_use_precompiled_headers(${exe} lib)
    endforeach()
  endif()
endfunction()
