# Helpers every folder uses, so warnings, tests and fuzzers are set up one way.

# The project's own targets (not third-party code) always build with the full warning set;
# -Werror is added only when SIM_WERROR is on (the presets and scripts/test.sh turn it on for
# developers and CI), so a new compiler's new warning never breaks a user's build.
function(sim_target_defaults target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion)
  if(SIM_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# The ThreadSanitizer stage of scripts/test.sh builds only this target: the suites labelled
# "concurrency" and the programs they start (folders add those with add_dependencies).
if(NOT TARGET sim_concurrency_suites)
  add_custom_target(sim_concurrency_suites)
endif()

# The suites' own code (not the libraries and programs they test) compiles with these options
# after the build type's: scripts/test.sh gives -O0 in the ASan+UBSan tree, where the optimizer
# was half of a suite's compile time (test_ouster_packet.cpp: 23 CPU-s at -O1, 11 at -O0) while
# what the suites exercise, the project's libraries and programs, stays at -O1; the sanitizers
# check unoptimized code at least as well. Empty (the default): the build type's flags alone.
# Not for the "concurrency" suites: their own loops are the stress (core_torn_frames under ASan:
# 11 s at -O1, 131 s at -O0, with fewer interleavings a second), so they keep the build's flags.
set(SIM_SUITE_COMPILE_OPTIONS "" CACHE STRING "Compile options added to the test suites' own code (e.g. -O0)")

# sim_suite_setup(target labels no_pch): a suite's compile options and precompiled header.
function(sim_suite_setup target labels no_pch)
  set(options ${SIM_SUITE_COMPILE_OPTIONS})
  if("concurrency" IN_LIST labels)
    set(options "")
  endif()
  target_compile_options(${target} PRIVATE ${options})
  if(NOT no_pch)
    sim_use_test_pch(${target} "${options}")
  endif()
endfunction()

# sim_add_test(NAME name SOURCES a.cpp… [LIBS lib…] [LABELS concurrency…] [TIMEOUT s] [NO_PCH])
# One GoogleTest executable registered as one ctest test, so ctest -j2 schedules whole suites.
# Label "concurrency" marks the suites the ThreadSanitizer build also runs. The suite compiles
# with the shared precompiled GoogleTest header (cmake/SimBuildSpeed.cmake) unless NO_PCH.
function(sim_add_test)
  cmake_parse_arguments(T "NO_PCH" "NAME;TIMEOUT" "SOURCES;LIBS;LABELS;ARGS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  sim_target_defaults(${T_NAME})
  target_link_libraries(${T_NAME} PRIVATE GTest::gtest GTest::gtest_main ${T_LIBS})
  sim_suite_setup(${T_NAME} "${T_LABELS}" "${T_NO_PCH}")
  add_test(NAME ${T_NAME} COMMAND ${T_NAME} ${T_ARGS})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  set_tests_properties(${T_NAME} PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}")
  if("concurrency" IN_LIST T_LABELS)
    add_dependencies(sim_concurrency_suites ${T_NAME})
  endif()
endfunction()

# sim_add_test_suites(NAME exe SOURCES a.cpp… [LIBS lib…] [LABELS …] [TIMEOUT s] [NO_PCH]
#                     TESTS ctest_name gtest_filter [ctest_name gtest_filter…])
# One GoogleTest executable for a folder's suites (one link instead of one per file), registered
# as one ctest test per TESTS pair, each running the suites its --gtest_filter names: ctest -j2
# still schedules suite by suite, and the names scripts and docs use stay. A suite no filter names
# still runs, under <exe>_other_suites (which runs nothing while every suite is named). Every
# source keeps its helpers in an anonymous namespace: the files now share one program.
function(sim_add_test_suites)
  cmake_parse_arguments(T "NO_PCH" "NAME;TIMEOUT" "SOURCES;LIBS;LABELS;TESTS" ${ARGN})
  list(LENGTH T_TESTS n)
  math(EXPR odd "${n} % 2")
  if(n EQUAL 0 OR odd)
    message(FATAL_ERROR "sim_add_test_suites(${T_NAME}): TESTS takes pairs of a ctest name and a gtest filter")
  endif()
  add_executable(${T_NAME} ${T_SOURCES})
  sim_target_defaults(${T_NAME})
  target_link_libraries(${T_NAME} PRIVATE GTest::gtest GTest::gtest_main ${T_LIBS})
  sim_suite_setup(${T_NAME} "${T_LABELS}" "${T_NO_PCH}")
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  set(named)
  math(EXPR last "${n} - 1")
  foreach(i RANGE 0 ${last} 2)
    math(EXPR j "${i} + 1")
    list(GET T_TESTS ${i} test)
    list(GET T_TESTS ${j} filter)
    add_test(NAME ${test} COMMAND ${T_NAME} --gtest_filter=${filter})
    set_tests_properties(${test} PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}")
    string(APPEND named ":${filter}")
  endforeach()
  string(SUBSTRING "${named}" 1 -1 named)
  add_test(NAME ${T_NAME}_other_suites COMMAND ${T_NAME} --gtest_filter=-${named})
  set_tests_properties(${T_NAME}_other_suites PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}")
  if("concurrency" IN_LIST T_LABELS)
    add_dependencies(sim_concurrency_suites ${T_NAME})
  endif()
endfunction()

# sim_add_fuzzer(NAME name SOURCES a.cpp… [LIBS lib…] [CORPUS dir])
# With SIM_FUZZ (clang): a libFuzzer binary run for SIM_FUZZ_SECONDS as the test fuzz_<name>.
# Without: the same entry point linked to a small main that replays the seed corpus, so the
# target always compiles and its seeds always run.
set(SIM_FUZZ_SECONDS 30 CACHE STRING "Seconds each fuzz target runs under ctest")
function(sim_add_fuzzer)
  cmake_parse_arguments(F "" "NAME;CORPUS" "SOURCES;LIBS" ${ARGN})
  add_executable(${F_NAME} ${F_SOURCES})
  sim_target_defaults(${F_NAME})
  target_link_libraries(${F_NAME} PRIVATE ${F_LIBS})
  if(SIM_FUZZ)
    target_compile_options(${F_NAME} PRIVATE -fsanitize=fuzzer)
    target_link_options(${F_NAME} PRIVATE -fsanitize=fuzzer)
    set(corpus_args)
    if(F_CORPUS)
      set(work_corpus ${CMAKE_CURRENT_BINARY_DIR}/${F_NAME}_corpus)
      file(MAKE_DIRECTORY ${work_corpus})
      set(corpus_args ${work_corpus} ${F_CORPUS})
    endif()
    add_test(NAME fuzz_${F_NAME}
             COMMAND ${F_NAME} -max_total_time=${SIM_FUZZ_SECONDS} -timeout=10 -rss_limit_mb=4096
                     -print_final_stats=1 ${corpus_args})
    set_tests_properties(fuzz_${F_NAME} PROPERTIES LABELS fuzz
                         TIMEOUT 600)
  else()
    target_sources(${F_NAME} PRIVATE ${PROJECT_SOURCE_DIR}/tests/fuzz_seed_main.cpp)
    if(F_CORPUS)
      add_test(NAME fuzz_seeds_${F_NAME} COMMAND ${F_NAME} ${F_CORPUS})
      set_tests_properties(fuzz_seeds_${F_NAME} PROPERTIES LABELS fuzz_seeds)
    endif()
  endif()
endfunction()
