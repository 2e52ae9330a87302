# What makes the build cheaper on these 2-core machines without building or testing less
# (docs/build-times.md). Nothing here changes what a target compiles to.

# lld links the ~100 programs and suites in a fraction of GNU ld's time. Off by default so a
# user's build keeps its toolchain's linker; the presets, scripts/test.sh and scripts/demo.sh
# turn it on (it falls back to the default linker when the compiler cannot use lld).
option(SIM_USE_LLD "Link with LLVM's lld when the compiler accepts -fuse-ld=lld (Debian: lld)" OFF)
if(SIM_USE_LLD)
  include(CheckLinkerFlag)
  check_linker_flag(CXX -fuse-ld=lld SIM_HAVE_LLD)
  if(SIM_HAVE_LLD)
    add_link_options(-fuse-ld=lld)
  else()
    message(STATUS "SIM_USE_LLD: ${CMAKE_CXX_COMPILER} cannot link with lld; using its default linker")
  endif()
endif()

# sim_use_test_pch(target options): with clang (the sanitizer stages, which compile every suite
# again), the suite compiles with a precompiled header the suites share: GoogleTest and the
# standard headers it pulls in, parsed and their templates instantiated once per tree (target
# sim_test_pch, REUSE_FROM); 0.80 of the CPU time on the Velodyne suites (docs/build-times.md).
# Reuse needs the same flags, so the host is set up as a suite is (sim_target_defaults, an
# executable: -fPIE, GTest's usage requirements, the suite's extra `options`) with no definitions
# of its own (a suite may add -D's): suites compiled with SIM_SUITE_COMPILE_OPTIONS share
# sim_test_pch, those that keep the build type's flags alone share sim_test_pch_optimized. Users
# and PCH compile with -pthread: some pkg-config flags carry it (Aravis) and a PCH made without
# it is refused; elsewhere it only defines _REENTRANT.
# Not with GCC: GCC 12 then reports warnings in system headers' code inlined at -O3 (a
# -Warray-bounds false positive in std::string's operator+ broke test_velodyne_synthetic).
# Off: -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON (ccache: CCACHE_SLOPPINESS=pch_defines,time_macros,
# as scripts/test.sh sets).
function(sim_use_test_pch target options)
  if(CMAKE_DISABLE_PRECOMPILE_HEADERS OR NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    return()
  endif()
  set(host sim_test_pch)
  if(NOT "${options}" STREQUAL "${SIM_SUITE_COMPILE_OPTIONS}")
    set(host sim_test_pch_optimized)
  endif()
  if(NOT TARGET ${host})
    set(source ${PROJECT_BINARY_DIR}/${host}.cpp)
    file(CONFIGURE OUTPUT ${source} CONTENT "// The host of the suites' precompiled header.\nint main() { return 0; }\n")
    add_executable(${host} ${source})
    sim_target_defaults(${host})
    target_link_libraries(${host} PRIVATE GTest::gtest GTest::gtest_main)
    target_compile_options(${host} PRIVATE -pthread ${options})
    # The standard headers nearly every suite includes, then GoogleTest (which pulls in most of
    # the rest). Only outside headers: a change to SIM's own never rebuilds every suite.
    target_precompile_headers(${host} PRIVATE
      $<$<COMPILE_LANGUAGE:CXX>:<algorithm$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<atomic$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<chrono$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<filesystem$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<thread$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<gtest/gtest.h$<ANGLE-R>>)
  endif()
  # clang refuses a PCH made with other flags (say, an -m or -f option from a library a suite
  # links): such a suite calls sim_add_test with NO_PCH.
  target_precompile_headers(${target} REUSE_FROM ${host})
  target_compile_options(${target} PRIVATE -pthread)
endfunction()
