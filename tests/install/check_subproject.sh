#!/usr/bin/env bash
# SIM added with add_subdirectory (as FetchContent does) gives the user's project just the
# library: no tests, tools, drivers, benchmarks, Python or install rules; and a program built
# against it runs.  Usage: check_subproject.sh SOURCE_DIR
set -euo pipefail
source=$1
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
fail() { echo "check_subproject: $*" >&2; exit 1; }
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$source/tests/install/subproject" -B "$scratch/build" -DSIM_SOURCE_DIR="$source" \
  "${launcher[@]}" >"$scratch/configure.log" 2>&1 || { cat "$scratch/configure.log"; fail "configure failed"; }
targets=$(cmake --build "$scratch/build" --target help)
grep -qw sim_shared <<<"$targets" || fail "the library target is missing"
for unwanted in sim_ls sim_python core_stream sim_lidar_hesai sim_bench sim_example_c; do
  ! grep -qw "$unwanted" <<<"$targets" || fail "$unwanted was added to the user's build"
done
! grep -q "^ *add_test\|ADD_TEST" "$scratch/build/sim/CTestTestfile.cmake" 2>/dev/null ||
  fail "SIM registered its tests in the user's build"
cmake --build "$scratch/build" --target app -j2 >"$scratch/build.log" 2>&1 || { cat "$scratch/build.log"; fail "build failed"; }
"$scratch/build/app" "/subproject_check_$$" >/dev/null || fail "the program built against SIM failed"
echo "check_subproject: add_subdirectory gives just the library, and it works"
