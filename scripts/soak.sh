#!/usr/bin/env bash
# The soak test of the whole vehicle (issue 23): seven 1920x1200 cameras at 30 Hz and two replayed LiDARs
# into SIM, readers of every kind (C++ blocking, borrowing, adaptive, a WaitSet, C, Python,
# sim_foxglove with a Foxglove client and the page, sim_record, sim_dds_bridge with a Cyclone DDS
# subscriber in a private network namespace), two live LiDAR drivers on one UDP port fed by
# multicast (two groups) in another, and a chaos loop that kills and restarts them.
# Prints a table (and JSON with --json) and exits 0 only if every check passed.
#
#   scripts/soak.sh                       two minutes (SIM_SOAK_SECONDS, default 120)
#   scripts/soak.sh --seconds 3600        one hour
#   scripts/soak.sh --seconds 600 --json soak.json --seed 7
#   SIM_SOAK_BUILD=build/release scripts/soak.sh   use (and build) another build folder
#   scripts/soak.sh --seconds 60 --fault all      break every guarantee on purpose: must FAIL
#
# Needs root (or CAP_SYS_ADMIN) for the private network namespace, like the bridge's tests.
# What is checked and why it is fair on a loaded machine: tests/soak/README.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
if [[ ${1:-} == --help || ${1:-} == -h ]]; then sed -n '2,16p' "$0"; exit 0; fi
build=${SIM_SOAK_BUILD:-build/release}
seconds=${SIM_SOAK_SECONDS:-120}

"$root/scripts/install-deps.sh"
if [[ ! -f $build/CMakeCache.txt ]]; then
  mkdir -p "$(dirname "$build")"
  # As scripts/test.sh configures build/release (Ninja, lld), so neither reconfigures the other's.
  generator=()
  command -v ninja >/dev/null && generator=(-G Ninja)
  cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr -DSIM_USE_LLD=ON \
    -DSIM_WERROR=ON >"$build.configure.log" 2>&1 ||
    { cat "$build.configure.log"; exit 1; }
fi
cmake --build "$build" -j"${SIM_JOBS:-2}" --target sim_soak_agent sim_soak_c_reader sim_soak_dds \
  sim_replay_video sim_replay_pcap sim_record sim_play sim_dds_bridge sim_rm sim_foxglove sim_python \
  sim_lidar_hesai sim_lidar_velodyne
# The Foxglove client's npm packages (pinned; installed once, as for the viewer's tests).
"$root/tests/viewer/foxglove/node/install.sh"
# The Python the module was built for (with numpy), not whichever python3 is first on the PATH.
python=$(sed -n 's/^_\?Python3_EXECUTABLE:[A-Z]*=//p' "$build/CMakeCache.txt" | head -n 1)
exec "${python:-python3}" "$root/tests/soak/soak.py" --build "$build" --seconds "$seconds" "$@"
