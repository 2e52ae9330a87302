#!/usr/bin/env bash
# Inside a private network namespace (run by run.sh): SIM producers + sim_dds_bridge, then real
# ROS 2 Jazzy tools (rmw_cyclonedds_cpp) against it. Every command and its output go to stdout.
# NEEDS a ROS 2 Jazzy build in the workspace WS_TOOLS names (see run.sh); NOT part of CI.
# Env: WS (ROS 2 workspace), SIM (repository root), B (build dir), OUT (scratch), HERE (this folder).
set -u
ip link set lo up; ip link set lo multicast on
# A bridge that aborts leaves a core in $OUT; stop_bridge prints its backtrace (gdb).
ulimit -c unlimited; cd "$OUT"; rm -f core core.*
set +u; . "$WS/install/setup.bash"; set -u
export RMW_IMPLEMENTATION=rmw_cyclonedds_cpp
export CYCLONEDDS_URI="file://$WS_TOOLS/cyclonedds-lo.xml"
unset ROS_DOMAIN_ID ROS_LOCALHOST_ONLY ROS_AUTOMATIC_DISCOVERY_RANGE
L=/rosi_lidar; C=/rosi_camera
BRIDGE_BIN=${BRIDGE_BIN:-$B/bridge/dds/sim_dds_bridge}
run() { echo; echo "\$ $*"; "$@" 2>&1; echo "[exit $?]"; }
alive() { kill -0 $BRIDGE 2>/dev/null && echo "[bridge alive]" || echo "[BRIDGE GONE]"; }
trim() { head -n "${1:-60}"; }

start_producers() {
  "$B/replay/pcap/sim_replay_pcap" "$SIM/tests/drivers/hesai/data/pandar64_dual.pcap" \
    --calibration "$SIM/tests/drivers/hesai/data/pandar64.calibration.csv" --stream $L \
    --loop --restamp --quiet --frame-id lidar_top --x 1.2 --z 1.8 --yaw 1.5708 > "$OUT/pcap.out" 2>&1 &
  PCAP=$!
  "$B/replay/video/sim_replay_video" "$OUT/frames" --stream $C --fps 10 --loop --quiet \
    --camera-info "$SIM/tests/apps/data/camera_front.yaml" \
    --frame-id camera_front_optical --x 1.9 --z 1.4 --roll -1.5708 --yaw -1.5708 > "$OUT/video.out" 2>&1 &
  VIDEO=$!
}
start_bridge() { # start_bridge TAG [extra options]
  local tag=$1; shift
  "$BRIDGE_BIN" --publish $L --publish $C --json --status-period 1 "$@" \
    > "$OUT/bridge-$tag.json" 2> "$OUT/bridge-$tag.err" &
  BRIDGE=$!
}
stop_bridge() { # stop_bridge TAG
  kill -INT $BRIDGE; wait $BRIDGE; echo "[bridge exit $?]"
  for core in core core.*; do
    [ -f "$core" ] || continue
    echo "--- backtrace of the bridge's core ($1)"
    gdb -batch -ex bt "$BRIDGE_BIN" "$core" 2>&1 | grep -E '^#' | head -40
    mv "$core" "$OUT/bridge-$1.core"
  done
  echo "--- bridge stderr ($1)"; cat "$OUT/bridge-$1.err"
  echo "--- bridge last counters ($1)"; tail -1 "$OUT/bridge-$1.json"
}

echo "## $(date -u +%FT%TZ) producers"
start_producers
sleep 1
run "$B/tools/sim_ls" $L $C

echo; echo "## phase A: bridge with default QoS (best effort)"
start_bridge A
sleep 3
run ros2 node list --no-daemon --spin-time 3
run ros2 node info --no-daemon --spin-time 3 /sim_dds_bridge
run ros2 topic list -t --no-daemon --spin-time 3
for t in $L $C/image_raw $C/camera_info /tf_static; do
  run ros2 topic info -v --no-daemon --spin-time 3 $t
done
echo; echo '$ timeout -s INT 12 ros2 topic hz '$L; timeout -s INT 12 ros2 topic hz $L 2>&1 | tail -6
echo; echo '$ timeout -s INT 12 ros2 topic hz '$C/image_raw; timeout -s INT 12 ros2 topic hz $C/image_raw 2>&1 | tail -6
echo; echo '$ CYCLONEDDS_URI=<lo + 4 MB receive buffer> timeout -s INT 12 ros2 topic hz '$C/image_raw
CYCLONEDDS_URI="file://$HERE/cyclonedds-lo-4mb.xml" timeout -s INT 12 ros2 topic hz $C/image_raw 2>&1 | tail -6
echo; echo '$ CYCLONEDDS_URI=<lo + 4 MB receive buffer> timeout -s INT 12 ros2 topic hz '$L
CYCLONEDDS_URI="file://$HERE/cyclonedds-lo-4mb.xml" timeout -s INT 12 ros2 topic hz $L 2>&1 | tail -6
echo; echo '$ timeout 20 ros2 topic echo --once --no-daemon --qos-durability transient_local --qos-reliability reliable /tf_static tf2_msgs/msg/TFMessage'; timeout 20 ros2 topic echo --once --no-daemon --qos-durability transient_local --qos-reliability reliable /tf_static tf2_msgs/msg/TFMessage 2>&1 | trim 80; echo "[exit ${PIPESTATUS[0]}]"; alive
# CameraInfo goes out only beside images that are sent: keep an image reader running meanwhile.
timeout -s INT 40 ros2 topic hz $C/image_raw > "$OUT/hz-bg.out" 2>&1 & HZ=$!
sleep 2
echo; echo "\$ timeout 20 ros2 topic echo --once --no-daemon $C/camera_info sensor_msgs/msg/CameraInfo   (with ros2 topic hz $C/image_raw running)"
timeout 20 ros2 topic echo --once --no-daemon $C/camera_info sensor_msgs/msg/CameraInfo 2>&1 | trim 80; echo "[exit ${PIPESTATUS[0]}]"; alive
echo; echo "\$ timeout 20 ros2 topic echo --once --no-daemon --no-arr $C/image_raw sensor_msgs/msg/Image"
timeout 20 ros2 topic echo --once --no-daemon --no-arr $C/image_raw sensor_msgs/msg/Image 2>&1 | trim 40; echo "[exit ${PIPESTATUS[0]}]"; alive
kill -INT $HZ 2>/dev/null; wait $HZ 2>/dev/null
echo; echo "\$ timeout 20 ros2 topic echo --once --no-daemon --no-arr $L sensor_msgs/msg/PointCloud2"
timeout 20 ros2 topic echo --once --no-daemon --no-arr $L sensor_msgs/msg/PointCloud2 2>&1 | trim 40; echo "[exit ${PIPESTATUS[0]}]"; alive
echo; echo "\$ timeout 20 ros2 topic echo --once --no-daemon --field fields $L sensor_msgs/msg/PointCloud2"
timeout 20 ros2 topic echo --once --no-daemon --field fields $L sensor_msgs/msg/PointCloud2 2>&1 | trim 60; echo "[exit ${PIPESTATUS[0]}]"; alive
# Two ROS 2 nodes join at once while a third reads: each takes a participant index whose user-data
# port (7411 + 2i) the bridge may never have sent to. Fast DDS 2.9.1 aborted the bridge on such a
# join (docs/ros2-interop.md, "Defect: the bridge aborts in Fast DDS").
timeout -s INT 30 ros2 topic hz $C/image_raw > "$OUT/hz-bg2.out" 2>&1 & HZ=$!
sleep 4
echo; echo "\$ 2 x timeout 20 ros2 topic echo --once --no-daemon --qos-durability transient_local --qos-reliability reliable /tf_static tf2_msgs/msg/TFMessage, at once   (with ros2 topic hz $C/image_raw running)"
E1=; E2=
timeout 20 ros2 topic echo --once --no-daemon --qos-durability transient_local --qos-reliability reliable /tf_static tf2_msgs/msg/TFMessage > "$OUT/echo-1.out" 2>&1 & E1=$!
timeout 20 ros2 topic echo --once --no-daemon --qos-durability transient_local --qos-reliability reliable /tf_static tf2_msgs/msg/TFMessage > "$OUT/echo-2.out" 2>&1 & E2=$!
wait $E1; echo "[echo 1 exit $?, $(grep -c child_frame_id "$OUT/echo-1.out") transforms]"
wait $E2; echo "[echo 2 exit $?, $(grep -c child_frame_id "$OUT/echo-2.out") transforms]"; alive
kill -INT $HZ 2>/dev/null; wait $HZ 2>/dev/null
echo; echo "\$ timeout 20 image_listener $C/image_raw 5   (peer_nodes; asks RELIABLE, bridge is best effort: expected not to match)"
timeout 20 image_listener $C/image_raw 5 2>&1 | trim 10; echo "[exit ${PIPESTATUS[0]}]"; alive
stop_bridge A

echo; echo "## phase B: bridge with --reliable"
start_bridge B --reliable
sleep 3
run ros2 topic info -v --no-daemon --spin-time 3 $C/image_raw
echo; echo "\$ timeout 30 image_listener $C/image_raw 5"
timeout 30 image_listener $C/image_raw 5 2>&1 | trim 10; echo "[exit ${PIPESTATUS[0]}]"; alive
echo; echo "\$ CYCLONEDDS_URI=<lo + 4 MB receive buffer> timeout 30 image_listener $C/image_raw 5"
CYCLONEDDS_URI="file://$HERE/cyclonedds-lo-4mb.xml" timeout 30 image_listener $C/image_raw 5 2>&1 | trim 10; echo "[exit ${PIPESTATUS[0]}]"; alive
stop_bridge B

kill -INT $PCAP $VIDEO; wait $PCAP $VIDEO
echo "--- producers"; cat "$OUT/pcap.out" "$OUT/video.out"
"$B/tools/sim_rm" $L $C
ros2 daemon stop 2>&1 | tail -1
echo "## $(date -u +%FT%TZ) done"
