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

# ccache only caches GCC's compiles of a precompiled header's users with -fpch-preprocess
# (and CCACHE_SLOPPINESS=pch_defines,time_macros, which scripts/test.sh sets).
if(CMAKE_CXX_COMPILER_LAUNCHER MATCHES "ccache" AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  add_compile_options($<$<COMPILE_LANGUAGE:CXX>:-fpch-preprocess>)
endif()

# sim_use_test_pch(target): the suite compiles with the precompiled GoogleTest header that every
# suite shares. Parsing gtest.h and the standard headers it pulls in is most of the work of a
# small suite's compile; the header is built once per build tree (target sim_test_pch) and
# reused. Reuse needs the same compiler flags, so the PCH target is set up as a suite is
# (sim_target_defaults, an executable: -fPIE, GTest's usage requirements) and carries no
# definitions of its own (a suite may add its own -D's; GCC and clang accept extra ones).
# Every user and the PCH compile with -pthread: some libraries' pkg-config flags carry it (Aravis)
# and both compilers refuse a PCH made without it; for the rest it only defines _REENTRANT.
# -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON turns it off.
# Clang only: GCC 12 reports warnings from system headers' code inlined at -O3 when the headers
# come from a PCH (a -Warray-bounds false positive in std::string's operator+ became an error
# in tests/drivers/velodyne), and measured on a test there, GCC's PCH saved 30% of a compile
# while clang's, which also instantiates the templates once (-fpch-instantiate-templates), saves
# more: the sanitizer stages, which compile the suites twice, are where it pays.
function(sim_use_test_pch target)
  if(CMAKE_DISABLE_PRECOMPILE_HEADERS OR NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    return()
  endif()
  if(NOT TARGET sim_test_pch)
    set(source ${PROJECT_BINARY_DIR}/sim_test_pch.cpp)
    file(CONFIGURE OUTPUT ${source} CONTENT "// The host of the suites' precompiled header.\nint main() { return 0; }\n")
    add_executable(sim_test_pch ${source})
    sim_target_defaults(sim_test_pch)
    target_link_libraries(sim_test_pch PRIVATE GTest::gtest GTest::gtest_main)
    target_compile_options(sim_test_pch PRIVATE -pthread)
    # The standard headers nearly every suite includes, then GoogleTest (which pulls in most of
    # the rest). Only outside headers: a change to SIM's own never rebuilds every suite.
    target_precompile_headers(sim_test_pch PRIVATE
      $<$<COMPILE_LANGUAGE:CXX>:<algorithm$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<atomic$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<chrono$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<filesystem$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<thread$<ANGLE-R>>
      $<$<COMPILE_LANGUAGE:CXX>:<gtest/gtest.h$<ANGLE-R>>)
  endif()
  # A suite whose flags differ (say, an -m or -f option from a library it links) cannot use the
  # PCH: GCC says so with -Winvalid-pch, an error under SIM_WERROR, rather than silently
  # compiling slower; clang refuses it. Such a suite calls sim_add_test with NO_PCH.
  target_precompile_headers(${target} REUSE_FROM sim_test_pch)
  target_compile_options(${target} PRIVATE -pthread)
endfunction()
