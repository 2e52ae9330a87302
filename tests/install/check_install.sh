#!/usr/bin/env bash
# Installs SIM from a build tree into a scratch prefix and uses it the ways users do:
#   - the installed tools start without LD_LIBRARY_PATH (RPATH relative to the binary), also
#     after the whole prefix is moved;
#   - the configs are in share/sim/config;
#   - C and C++ (C++17 and C++20) programs build and run against it through find_package (shared
#     and static, and a C-only project) and through pkg-config (sim.pc shared, sim_static.pc static).
# Usage: check_install.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1
source=$2
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
unset LD_LIBRARY_PATH
stream="/install_check_$$"
fail() { echo "check_install: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$scratch/prefix" >/dev/null
"$scratch/prefix/bin/sim_ls" --help >/dev/null || fail "installed sim_ls --help failed"
mv "$scratch/prefix" "$scratch/moved"
"$scratch/moved/bin/sim_ls" --help >/dev/null || fail "sim_ls --help failed after moving the prefix"
prefix="$scratch/moved"
ls "$prefix"/share/sim/config/*/*.yaml >/dev/null 2>&1 || fail "no configs in share/sim/config"
libdir=$(dirname "$(find "$prefix" -name 'libsim.so' | head -1)")
[[ -n $libdir ]] || fail "libsim.so was not installed"

not_linked_to_libsim() {  # a static program must not need libsim.so at run time
  ! readelf -d "$1" | grep -q 'NEEDED.*libsim' || fail "$1 needs libsim.so though linked statically"
}

# find_package: C and C++, shared and static.
cmake -S "$source/examples/consumer" -B "$scratch/consumer" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$scratch/consumer" >/dev/null
for program in consumer_cpp consumer_static consumer_cxx17 consumer_c consumer_c_static; do
  "$scratch/consumer/$program" "${stream}_$program" >/dev/null || fail "find_package: $program failed"
done
not_linked_to_libsim "$scratch/consumer/consumer_static"
not_linked_to_libsim "$scratch/consumer/consumer_c_static"
cmake -S "$source/examples/consumer/c_only" -B "$scratch/c_only" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$scratch/c_only" >/dev/null
"$scratch/c_only/consumer_c_only_static" "${stream}_c_only_static" >/dev/null || fail "C-only static failed"
"$scratch/c_only/consumer_c_only" "${stream}_c_only" >/dev/null || fail "C-only shared failed"
not_linked_to_libsim "$scratch/c_only/consumer_c_only_static"

# pkg-config: C and C++, shared (with an rpath, as a user would add) and static.
export PKG_CONFIG_PATH="$libdir/pkgconfig"
# shellcheck disable=SC2046
cc "$source/examples/hello.c" -o "$scratch/pc_c" $(pkg-config --cflags --libs sim) -Wl,-rpath,"$libdir"
# shellcheck disable=SC2046
cc "$source/examples/hello.c" -o "$scratch/pc_c_static" $(pkg-config --cflags --libs sim_static)
# shellcheck disable=SC2046
c++ -std=c++20 "$source/examples/points.cpp" -o "$scratch/pc_cpp" $(pkg-config --cflags --libs sim) \
  -Wl,-rpath,"$libdir"
# shellcheck disable=SC2046
c++ -std=c++20 "$source/examples/points.cpp" -o "$scratch/pc_cpp_static" $(pkg-config --cflags --libs sim_static)
# shellcheck disable=SC2046
c++ -std=c++17 -DSIM_EXPECT_CPLUSPLUS=201703L "$source/examples/consumer/consumer_cxx.cpp" -o "$scratch/pc_cpp17" \
  $(pkg-config --cflags --libs sim) -Wl,-rpath,"$libdir"
for program in pc_c pc_c_static pc_cpp pc_cpp_static pc_cpp17; do
  "$scratch/$program" "${stream}_$program" >/dev/null || fail "pkg-config: $program failed"
done
not_linked_to_libsim "$scratch/pc_c_static"
not_linked_to_libsim "$scratch/pc_cpp_static"
echo "check_install: tools start from a moved prefix; find_package and pkg-config work for C and C++, shared and static"
