#!/usr/bin/env bash
# Does sim_record keep up? Records the Pandar64 capture (sim_replay_pcap --loop, 10 Hz) and a
# 1920x1200 BGR test camera at rising frame rates, with each compression, and prints the frames
# missed. The highest camera rate with none missed is the recorder's sustained rate on this
# machine. Not run by ctest (it takes minutes and measures speed); see docs/mcap.md.
#
#   tests/mcap/keep_up.sh BUILD_DIR [SECONDS] [OUT_DIR]
#   SIM_KEEP_UP_FPS="30 60 90" SIM_KEEP_UP_PATTERNS="ramp noise" tests/mcap/keep_up.sh build/release
set -euo pipefail
build=${1:?usage: keep_up.sh BUILD_DIR [SECONDS] [OUT_DIR]}
seconds=${2:-10}
out=${3:-$(mktemp -d)}
mkdir -p "$out"
root=$(cd "$(dirname "$0")/../.." && pwd)
fps_list=${SIM_KEEP_UP_FPS:-"30 60 90 120"}
patterns=${SIM_KEEP_UP_PATTERNS:-"ramp noise"}
cam=/keep_up_cam_$$
lidar=/keep_up_lidar_$$
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -f "/dev/shm/sim.${cam#/}" "/dev/shm/sim.${lidar#/}" "$out"/keep_up.mcap
}
trap cleanup EXIT

"$build/replay/pcap/sim_replay_pcap" "$root/tests/drivers/hesai/data/pandar64_dual.pcap" --stream "$lidar" \
  --calibration "$root/tests/drivers/hesai/data/pandar64.calibration.csv" --loop --quiet &
pids+=($!)
echo "pattern compression camera_fps input_MB_per_s camera_frames camera_missed lidar_frames lidar_missed file_MB"
for pattern in $patterns; do
  for compression in none lz4 zstd; do
    for fps in $fps_list; do
      flag=(); [[ $pattern == noise ]] && flag=(--noise)
      "$build/tests/mcap/mcap_test_camera" --stream "$cam" --width 1920 --height 1200 --fps "$fps" \
        --frames 0 "${flag[@]}" >/dev/null &
      camera_pid=$!
      sleep 1
      json=$("$build/tools/sim_record/sim_record" -o "$out/keep_up.mcap" "$cam" "$lidar" \
        --compression "$compression" --duration "$seconds" --json --quiet 2>/dev/null | tail -n 1)
      kill "$camera_pid"; wait "$camera_pid" 2>/dev/null || true
      rm -f "/dev/shm/sim.${cam#/}"
      python3 - "$json" "$pattern" "$compression" "$fps" "$cam" "$lidar" <<'PY'
import json, sys
r = json.loads(sys.argv[1]); pattern, compression, fps, cam, lidar = sys.argv[2:]
s = {x["name"]: x for x in r["streams"]}
rate = sum(x["bytes"] for x in r["streams"]) / r["seconds"] / 1e6
print(pattern, compression, fps, f"{rate:.0f}", s[cam]["frames"], s[cam]["missed"],
      s[lidar]["frames"], s[lidar]["missed"], f"{r['bytes'] / 1e6:.0f}")
PY
      rm -f "$out/keep_up.mcap"
    done
  done
done
