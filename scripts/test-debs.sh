#!/usr/bin/env bash
# Builds the Debian packages from a build tree configured with CMAKE_INSTALL_PREFIX=/usr (the
# release stage of scripts/test.sh, or `cmake --preset release`), installs them on this machine
# with apt-get as a user would, checks the installed tools, the C/C++ development files and the
# Python module, then removes them again.
#
#   scripts/test-debs.sh [BUILD_DIR]        (default build/release; needs root or sudo)
#
# Exit codes: 0 done, 1 a check failed, 2 wrong command line.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build/release}
[[ $# -le 1 && -f $build/CPackConfig.cmake ]] ||
  { echo "usage: scripts/test-debs.sh [BUILD_DIR]  (a configured and built tree; no CPackConfig.cmake in $build)" >&2; exit 2; }
prefix=$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$build/CMakeCache.txt")
[[ $prefix == /usr ]] ||
  { echo "test-debs: $build installs into '$prefix'; configure it with -DCMAKE_INSTALL_PREFIX=/usr" >&2; exit 2; }

as_root=()
[[ $(id -u) -eq 0 ]] || as_root=(sudo)
packages=(libsim0 libsim-dev sim-tools python3-sim)
scratch=$(mktemp -d)
remove() { "${as_root[@]}" apt-get purge -y -qq "${packages[@]}" >/dev/null 2>&1 || true; rm -rf "$scratch"; }
trap remove EXIT
fail() { echo "test-debs: $*" >&2; exit 1; }

echo "test-debs: building the packages"
rm -rf "$build/packages"
(cd "$build" && cpack -G DEB >"$scratch/cpack.log" 2>&1) || { cat "$scratch/cpack.log"; fail "cpack failed"; }
debs=("$build"/packages/*.deb)
((${#debs[@]} == ${#packages[@]})) || fail "expected ${#packages[@]} packages, cpack made: ${debs[*]##*/}"
for deb in "${debs[@]}"; do
  dpkg-deb -f "$deb" Package Version Depends | sed "s|^|  ${deb##*/}: |"
done

echo "test-debs: apt-get install ./*.deb"
export DEBIAN_FRONTEND=noninteractive
(cd "$build/packages" && "${as_root[@]}" apt-get install -y -qq ./*.deb >"$scratch/apt.log" 2>&1) ||
  { cat "$scratch/apt.log"; fail "apt-get install failed"; }

cd "$scratch"  # nothing below may find the source or build tree by accident
unset LD_LIBRARY_PATH PKG_CONFIG_PATH CMAKE_PREFIX_PATH PYTHONPATH
[[ $(command -v sim_ls) == /usr/bin/sim_ls ]] || fail "sim_ls is not /usr/bin/sim_ls"
sim_ls --help >/dev/null || fail "sim_ls --help failed"
ls /usr/share/sim/config/*/*.yaml >/dev/null || fail "no configs in /usr/share/sim/config"
# The example systemd units name the installed programs correctly and parse.
if command -v systemd-analyze >/dev/null; then
  systemd-analyze verify "$root"/deploy/systemd/*.service || fail "deploy/systemd units do not verify"
fi

# examples/consumer against the installed package: find_package and pkg-config, shared and static.
cmake -S "$root/examples/consumer" -B consumer >/dev/null || fail "find_package(sim) failed"
cmake --build consumer >/dev/null || fail "examples/consumer did not build"
for program in consumer_cpp consumer_static consumer_cxx17 consumer_c consumer_c_static; do
  "consumer/$program" "/test_debs_${program}_$$" >/dev/null || fail "$program failed"
done
# shellcheck disable=SC2046
cc "$root/examples/hello.c" -o hello $(pkg-config --cflags --libs sim) || fail "pkg-config sim failed"
./hello "/test_debs_hello_$$" >/dev/null || fail "hello (pkg-config) failed"

# The Python module of Debian's python3.
/usr/bin/python3 - <<'PY' || fail "the Python module failed"
import os, numpy as np, sim
assert sim.__file__.startswith("/usr/lib/python3/dist-packages/"), sim.__file__
name = f"/test_debs_python_{os.getpid()}"
with sim.Writer(name, sim.Layout.image(4, 2, "rgb8")) as w, sim.Reader(name) as r:
    w.write(np.full((2, 4, 3), 7, np.uint8))
    image, info = r.read()
    assert image.shape == (2, 4, 3) and int(image.sum()) == 7 * 24 and info.seq == 1
sim.destroy(name, force=True)
PY

echo "test-debs: apt-get purge"
"${as_root[@]}" apt-get purge -y -qq "${packages[@]}" >/dev/null || fail "apt-get purge failed"
[[ ! -e /usr/bin/sim_ls && ! -e /usr/include/sim/sim.h ]] || fail "files remain after purge"
echo "test-debs: the packages install, work (tools, C/C++ via CMake and pkg-config, Python) and remove cleanly"
