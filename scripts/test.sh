#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test: every suite under AddressSanitizer +
# UndefinedBehaviorSanitizer with every fuzz target run for a bounded time, the suites that need a
# plain optimised build (and the soak) in the release tree, and the concurrency suites under
# ThreadSanitizer.
#
#   scripts/test.sh                  everything (what CI runs)
#   SIM_STRESS_FRAMES=10000000 SIM_FUZZ_SECONDS=600 scripts/test.sh   longer stress and fuzzing
#   SIM_TEST_STAGES="release" scripts/test.sh                        one stage only
#   SIM_SOAK_SECONDS=3600 scripts/test.sh                            a longer soak (0: none)
# Stages: release (GCC -O3: every library and program, the suites only a build without sanitizers
# can run (the installed tree, the Python module, the benchmarks' smoke runs, the soak's fault
# test; SIM_TEST_SET=release), then the soak of the whole vehicle: scripts/soak.sh), deb (the Debian
# packages from the release tree, installed with apt-get, checked and removed: scripts/test-debs.sh),
# asan (every other suite, under ASan+UBSan, and the fuzzers), tsan. Without the asan stage (the
# quick loop) the release stage builds and runs every suite. Warnings are errors here
# (SIM_WERROR=ON), as in the CMake presets.
#
# The quick loop (the release build and suite alone, no soak; docs/build-times.md):
#   SIM_TEST_STAGES=release SIM_SOAK_SECONDS=0 scripts/test.sh       (scripts/quick.sh)
# SIM_CCACHE_DIR=/some/dir: compile through ccache with that cache (off unless set).
# At the end (also after a failure) it prints the wall time of each stage's configure, build and
# test; build/<stage>/.ninja_log has each target's (scripts/build-times.sh build/<stage>).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
jobs=${SIM_JOBS:-2}
stages=${SIM_TEST_STAGES:-"release deb asan tsan"}
stress=${SIM_STRESS_FRAMES:-1000000}
sanitizer_stress=${SIM_SANITIZER_STRESS_FRAMES:-200000}
# 5 s per fuzz target in CI (28 targets, ~2 s of start-up each): a smoke run of every parser from
# its seeds on; long fuzzing: SIM_FUZZ_SECONDS=600, or one target run by hand for hours.
fuzz_seconds=${SIM_FUZZ_SECONDS:-5}
soak_seconds=${SIM_SOAK_SECONDS:-120}
read -r -a ctest_args <<<"${SIM_CTEST_ARGS:-}"  # scripts/quick.sh -R name: some suites only

# Wall time of each step, printed at the end whether the run passed or not.
times=()
started=$SECONDS
timed() {  # timed LABEL command…: runs the command and records its wall time
  local label=$1 t0=$SECONDS rc=0
  shift
  "$@" || rc=$?
  times+=("$(printf '%-28s %5d s' "$label" $((SECONDS - t0)))")
  return $rc
}
report_times() {
  printf '\n=== wall time per step ===\n'
  printf '%s\n' "${times[@]}"
  printf '%-28s %5d s\n' "total" $((SECONDS - started))
}
trap report_times EXIT

timed "install-deps" "$root/scripts/install-deps.sh"

stage() { printf '\n=== %s ===\n' "$*"; }
# Ninja when there (scripts/deps/core.txt: ninja-build): per-target times in .ninja_log and no
# make recursion; lld links; ccache only when SIM_CCACHE_DIR names a cache that survives runs.
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
launcher=(-DCMAKE_C_COMPILER_LAUNCHER= -DCMAKE_CXX_COMPILER_LAUNCHER=)  # none, even if a tree had one
if [[ -n ${SIM_CCACHE_DIR:-} ]] && command -v ccache >/dev/null; then
  export CCACHE_DIR=$SIM_CCACHE_DIR CCACHE_BASEDIR=$root CCACHE_NOHASHDIR=1
  export CCACHE_SLOPPINESS=${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
configure() {  # configure BUILD_DIR [cmake options…]
  local dir=$1
  shift
  # A tree configured earlier with another generator (Unix Makefiles): start it afresh.
  if [[ ${#generator[@]} -gt 0 && -f $dir/CMakeCache.txt ]] &&
     ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$dir/CMakeCache.txt"; then
    rm -rf "$dir/CMakeCache.txt" "$dir/CMakeFiles"
  fi
  cmake -S "$root" -B "$dir" "${generator[@]}" "${launcher[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSIM_WERROR=ON \
    -DSIM_USE_LLD=ON "$@" >"$dir.configure.log" 2>&1 ||
    { cat "$dir.configure.log"; return 1; }
}

# ctest starts the longest suites first when it knows their times (Testing/Temporary/
# CTestCostData.txt, written by every run); a fresh clone takes them from scripts/ctest-cost/,
# refreshed by copying a CI run's file there (docs/build-times.md).
seed_costs() {  # seed_costs BUILD_DIR STAGE
  local known=$root/scripts/ctest-cost/$2.txt dest=$1/Testing/Temporary/CTestCostData.txt
  if [[ -f $known && ! -f $dest ]]; then mkdir -p "${dest%/*}" && cp "$known" "$dest"; fi
}

# As root (CI) every network test must get its private network namespace: one that cannot fails
# instead of skipping (tests/support/sim_test/network.hpp).
[[ $(id -u) == 0 ]] && export SIM_REQUIRE_PRIVATE_NETWORK=1
# Sanitizer reports end the test that triggered them, with a stack.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1}
mkdir -p "$root/build"
# Each suite is compiled once: when the asan stage runs, it builds and runs every suite it can, and
# the release tree only those it cannot (about half the release stage's compile time).
release_tests=all
[[ " $stages " == *" asan "* ]] && release_tests=release
sanitizer_flags="-O1 -gline-tables-only -DNDEBUG"

for s in $stages; do
  case $s in
    release)
      stage "release build (GCC, -O3) and its suites (SIM_TEST_SET=$release_tests)"
      # -O3 as a user's plain Release build (GCC 12 warns there, not at -O2); /usr: the prefix
      # of the Debian packages the deb stage makes from this tree.
      timed "release: configure" configure build/release -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr \
        -DSIM_TEST_SET="$release_tests"
      timed "release: build" cmake --build build/release -j"$jobs"
      seed_costs build/release release
      SIM_STRESS_FRAMES=$stress timed "release: test" ctest --test-dir build/release -j"$jobs" --output-on-failure \
        "${ctest_args[@]}"
      # The whole vehicle under chaos for SIM_SOAK_SECONDS (tests/soak/README.md); 0 skips it.
      if ((soak_seconds > 0)); then
        stage "soak of the whole vehicle (${soak_seconds} s)"
        SIM_SOAK_BUILD=build/release SIM_SOAK_SECONDS=$soak_seconds timed "release: soak" "$root/scripts/soak.sh"
      fi
      ;;
    deb)
      stage "Debian packages: build, apt-get install, check, remove"
      [[ -f build/release/CPackConfig.cmake ]] || { echo "test.sh: the deb stage needs the release stage first" >&2; exit 2; }
      timed "deb: build, install, check" "$root/scripts/test-debs.sh" build/release
      ;;
    asan)
      stage "AddressSanitizer + UndefinedBehaviorSanitizer, with libFuzzer targets (${fuzz_seconds} s each)"
      # -O1 and line tables only: what sanitizer reports need (stacks with file:line), at a
      # fraction of the compile and link time of -O2 -g on these 2 cores. The suites' own code
      # at -O0: half its compile time was the optimizer, and the code under test stays at -O1.
      timed "asan: configure" configure build/asan -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
        -DCMAKE_C_FLAGS_RELWITHDEBINFO="$sanitizer_flags" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$sanitizer_flags" \
        -DSIM_SUITE_COMPILE_OPTIONS=-O0 \
        -DSIM_SANITIZE=address,undefined -DSIM_FUZZ=ON -DSIM_FUZZ_SECONDS="$fuzz_seconds" \
        -DSIM_BUILD_BENCH=OFF
      timed "asan: build" cmake --build build/asan -j"$jobs"
      seed_costs build/asan asan
      SIM_STRESS_FRAMES=$sanitizer_stress timed "asan: test" ctest --test-dir build/asan -j"$jobs" --output-on-failure
      ;;
    tsan)
      stage "ThreadSanitizer, concurrency suites"
      timed "tsan: configure" configure build/tsan -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
        -DCMAKE_C_FLAGS_RELWITHDEBINFO="$sanitizer_flags" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$sanitizer_flags" \
        -DSIM_SANITIZE=thread -DSIM_BUILD_DRIVERS=OFF -DSIM_BUILD_BENCH=OFF
      # Only the suites it runs and the programs they start (cmake/SimHelpers.cmake).
      timed "tsan: build" cmake --build build/tsan -j"$jobs" --target sim_concurrency_suites
      seed_costs build/tsan tsan
      SIM_STRESS_FRAMES=$sanitizer_stress timed "tsan: test" ctest --test-dir build/tsan -j"$jobs" -L concurrency \
        --output-on-failure
      ;;
    *) echo "test.sh: unknown stage '$s' (release, deb, asan, tsan)" >&2; exit 2 ;;
  esac
done
stage "all stages passed: $stages"
