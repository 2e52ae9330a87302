#!/usr/bin/env bash
# The main job with no sensor attached: installs what is missing, builds, replays the bundled
# Pandar64 recording into /lidar_top and a real video into /camera_front, in a loop, and shows
# the live streams with sim_ls and sim_echo --stats. Ctrl-C stops everything and removes the streams.
#
#   scripts/demo.sh                 run until Ctrl-C
#   scripts/demo.sh --duration 20   run for 20 seconds
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
duration=0
if [[ ${1:-} == --duration ]]; then duration=${2:?--duration takes seconds}; fi
if [[ ${1:-} == --help || ${1:-} == -h ]]; then sed -n '2,8p' "$0"; exit 0; fi

"$root/scripts/install-deps.sh" "$root/scripts/demo-deps.txt"
mkdir -p build
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSIM_BUILD_BENCH=OFF >build/release.configure.log
cmake --build build/release -j"${SIM_JOBS:-2}" --target sim_replay_pcap sim_replay_video sim_echo sim_ls sim_rm
cmake --build build/release -j"${SIM_JOBS:-2}" --target sim_foxglove  # the live view
bin=build/release
data=tests/hesai/data

video=/usr/share/doc/opencv-doc/examples/data/vtest.avi
[[ -f $video ]] || video=$(find /usr/share/doc/opencv-doc -name 'vtest.avi*' 2>/dev/null | head -n 1)
if [[ $video == *.gz ]]; then gunzip -c "$video" >build/vtest.avi && video=build/vtest.avi; fi

pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  "$bin/tools/sim_rm" --force /lidar_top /camera_front >/dev/null 2>&1 || true
}
trap cleanup EXIT
trap 'exit 0' INT TERM

"$bin/replay/pcap/sim_replay_pcap" "$data/pandar64_dual.pcap" --stream /lidar_top \
  --calibration "$data/pandar64.calibration.csv" --loop --quiet &
pids+=($!)
if [[ -f $video ]]; then
  "$bin/replay/video/sim_replay_video" "$video" --stream /camera_front --loop --quiet &
  pids+=($!)
else
  echo "demo: no video found (opencv-doc not installed); showing the LiDAR stream only"
fi

port=${SIM_FOXGLOVE_PORT:-8765}
"$bin/viewer/foxglove/sim_foxglove" --port "$port" >/dev/null &
pids+=($!)

sleep 2
echo "demo: open http://127.0.0.1:$port/ in a browser to see the streams live"
echo "      (or connect Foxglove / Lichtblick to ws://127.0.0.1:$port)"
"$bin/tools/sim_ls"
echo
echo "Live statistics, one line per stream per second (Ctrl-C to stop):"
echo_args=(--stats --interval 1)
((duration > 0)) && echo_args+=(--duration "$duration")
"$bin/tools/sim_echo" /lidar_top "${echo_args[@]}" &
pids+=($!)
if [[ -f $video ]]; then
  "$bin/tools/sim_echo" /camera_front "${echo_args[@]}" &
  pids+=($!)
fi
wait "${pids[-1]}"
