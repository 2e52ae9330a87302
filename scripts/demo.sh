#!/usr/bin/env bash
# The main job with no sensor attached: installs what is missing, builds, replays the bundled
# Pandar64, VLP-16 and Ouster OS-1 recordings into /lidar_top, /lidar_front and /lidar_rear and a
# real video into /camera_front, each with its frame and mounting, in a loop, and shows
# every stream live with sim_ls --watch. Ctrl-C stops everything and removes the streams the
# demo created (never a stream another program owns: the demo refuses to start instead).
#
#   scripts/demo.sh                 run until Ctrl-C
#   scripts/demo.sh --duration 20   run for 20 seconds
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
duration=0
if [[ ${1:-} == --duration ]]; then duration=${2:?--duration takes seconds}; fi
if [[ ${1:-} == --help || ${1:-} == -h ]]; then sed -n '2,9p' "$0"; exit 0; fi

# Only what the demo runs: its packages (scripts/demo-deps.txt), its folders, its five programs,
# in its own tree (build/demo), so it never reconfigures or rebuilds scripts/test.sh's
# build/release nor the other way round. -O1 without debug info: quickest to the live view (a
# CLI11-heavy file: 8 CPU-s at -O1, 11 at -O2, 14 at -O3) and plenty fast for four replays.
"$root/scripts/install-deps.sh" --only "$root/scripts/demo-deps.txt"
echo "demo: packages ready after ${SECONDS} s; building the demo's programs in build/demo"
bin=build/demo
folders="imaging;drivers/common;drivers/hesai;drivers/ouster;drivers/velodyne"
folders+=";drivers/unitree;replay/pcap;replay/video;viewer/foxglove"
mkdir -p build
generator=()
command -v ninja >/dev/null && [[ ! -f $bin/Makefile ]] && generator=(-G Ninja)
cmake -S . -B "$bin" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG" \
  -DCMAKE_C_FLAGS_RELEASE="-O1 -DNDEBUG" -DSIM_USE_LLD=ON -DSIM_DRIVER_FOLDERS="$folders" \
  -DSIM_BUILD_TESTS=OFF -DSIM_BUILD_BENCH=OFF -DSIM_BUILD_EXAMPLES=OFF -DSIM_BUILD_PYTHON=OFF \
  -DSIM_INSTALL=OFF >"$bin.configure.log" 2>&1 || { cat "$bin.configure.log"; exit 1; }
cmake --build "$bin" -j"${SIM_JOBS:-2}" --target sim_replay_pcap sim_replay_video sim_ls sim_rm sim_foxglove
echo "demo: built after ${SECONDS} s"
data=tests/drivers/hesai/data
streams=(/lidar_top /lidar_front /lidar_rear /camera_front)

# A live writer owns one of our names (a real driver, another demo): leave it alone.
for name in "${streams[@]}"; do
  if "$bin/tools/sim_ls" --json --window 0 | grep -q "\"name\":\"$name\".*\"writer_alive\":true"; then
    echo "demo: $name is already published by a running program; stop it (or use another machine) and run the demo again." >&2
    exit 1
  fi
done

video=/usr/share/doc/opencv-doc/examples/data/vtest.avi
[[ -f $video ]] || video=$(find /usr/share/doc/opencv-doc -name 'vtest.avi*' 2>/dev/null | head -n 1)
if [[ $video == *.gz ]]; then gunzip -c "$video" >build/vtest.avi && video=build/vtest.avi; fi

pids=()
created=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  # Only the streams this demo's replays created; without --force, so a stream another writer
  # took over meanwhile is kept.
  ((${#created[@]} > 0)) && "$bin/tools/sim_rm" "${created[@]}" >/dev/null 2>&1 || true
}
trap cleanup EXIT
trap 'exit 0' INT TERM

# Each stream carries its frame and its mounting on the vehicle (base_link), as sim_ls shows.
"$bin/replay/pcap/sim_replay_pcap" "$data/pandar64_dual.pcap" --stream /lidar_top \
  --calibration "$data/pandar64.calibration.csv" --loop --quiet --frame-id lidar_top --z 1.9 &
pids+=($!)
created+=(/lidar_top)
"$bin/replay/pcap/sim_replay_pcap" tests/drivers/velodyne/data/vlp16_dual.pcap --stream /lidar_front \
  --calibration tests/drivers/velodyne/data/VLP16.yaml --loop --quiet --frame-id lidar_front --x 2.1 --z 0.6 &
pids+=($!)
created+=(/lidar_front)
"$bin/replay/pcap/sim_replay_pcap" tests/drivers/ouster/data/OS-1-32-G_v2.1.1_1024x10.pcap --stream /lidar_rear \
  --calibration tests/drivers/ouster/data/OS-1-32-G_v2.1.1_1024x10.json --loop --quiet \
  --frame-id lidar_rear --x -0.9 --z 1.7 --yaw 3.14159265 &
pids+=($!)
created+=(/lidar_rear /lidar_rear.imu)  # the Ouster replay also publishes its IMU
if [[ -f $video ]]; then
  "$bin/replay/video/sim_replay_video" "$video" --stream /camera_front --loop --quiet \
    --frame-id camera_front_optical --x 1.8 --z 1.4 --roll -1.5707963 --yaw -1.5707963 &
  pids+=($!)
  created+=(/camera_front)
else
  echo "demo: no video found (opencv-doc not installed); showing the LiDAR stream only"
fi

port=${SIM_FOXGLOVE_PORT:-8765}
"$bin/viewer/foxglove/sim_foxglove" --port "$port" >/dev/null &
pids+=($!)

sleep 1
echo "demo: open http://127.0.0.1:$port/ in a browser to see the streams live"
echo "      (or connect Foxglove / Lichtblick to ws://127.0.0.1:$port)"
if ((duration > 0)); then
  "$bin/tools/sim_ls" --watch &
  pids+=($!)
  sleep "$duration"
else
  "$bin/tools/sim_ls" --watch
fi
