#!/usr/bin/env bash
# SIM's sim_dds_bridge against a real ROS 2 (Jazzy, rmw_cyclonedds_cpp) in a private network
# namespace: a Pandar64 replay and a camera replay (with calibration and mountings) are bridged,
# then ros2 node/topic list, topic info -v, topic hz, topic echo and peer_nodes' image_listener
# look at them. Results are written up in docs/ros2-interop.md.
#
# NEEDS a ROS 2 Jazzy build in the workspace WS_TOOLS names (build.sh: core nodes py, i.e. rclcpp,
# rmw_cyclonedds_cpp, ros2cli and peer_nodes installed in $WS) and a release build of SIM
# (sim_dds_bridge, sim_replay_pcap, sim_replay_video, sim_ls, sim_rm). Root (unshare --net).
# NOT part of CI: CI has no ROS 2.
#
# Usage: WS=/tmp/ros2ws [SIM=<repo>] [B=<build dir>] [BRIDGE_BIN=<sim_dds_bridge>] [OUT=/tmp/ros2-interop] bash run.sh > log
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export HERE
export SIM=${SIM:-$(cd "$HERE/../.." && pwd)}
export B=${B:-$SIM/build/release}
export WS=${WS:-/tmp/ros2ws}
: "${WS_TOOLS:?set WS_TOOLS to the folder of a ROS 2 Jazzy test workspace (its build.sh and cyclonedds-lo.xml)}"
export WS_TOOLS
export OUT=${OUT:-/tmp/ros2-interop}
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin   # Debian python, not pyenv
[ -f "$WS/install/setup.bash" ] || { echo "no ROS 2 install in $WS (run $WS_TOOLS/build.sh)" >&2; exit 1; }
mkdir -p "$OUT"
# 10 RGB PNG frames 768x576 (the size of tests/apps/data/camera_front.yaml), stdlib python only
[ -d "$OUT/frames" ] || /usr/bin/python3 - "$OUT/frames" 10 768 576 <<'PY'
import os, struct, sys, zlib
d = sys.argv[1]; n = int(sys.argv[2]) if len(sys.argv) > 2 else 10
w = int(sys.argv[3]) if len(sys.argv) > 3 else 768; h = int(sys.argv[4]) if len(sys.argv) > 4 else 576
os.makedirs(d, exist_ok=True)
def chunk(t, b): return struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b) & 0xffffffff)
for i in range(n):
    bar0 = (i * w // n); rows = []
    for y in range(h):
        row = bytearray(b'\0')
        g = y * 255 // (h - 1)
        for x in range(w):
            on = bar0 <= x < bar0 + w // n
            row += bytes((255 if on else x * 255 // (w - 1), g, 40 * i % 256))
        rows.append(bytes(row))
    raw = zlib.compress(b''.join(rows), 1)
    png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) + chunk(b'IDAT', raw) + chunk(b'IEND', b'')
    open(os.path.join(d, 'frame_%03d.png' % i), 'wb').write(png)
print('wrote', n, 'frames', w, 'x', h, 'to', d)
PY
exec timeout 600 unshare --net bash "$HERE/session.sh"
