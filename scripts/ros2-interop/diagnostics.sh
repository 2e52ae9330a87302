#!/bin/bash
# The streams' clocks on /diagnostics as a real ROS 2 sees them (docs/ros2-interop.md, "Clock
# diagnostics"). Run as root from the repository: `unshare --net scripts/ros2-interop/diagnostics.sh`.
# B=<build dir> (build/dev), WS=<ROS 2 Jazzy workspace> (/tmp/ros2ws, from
# a ROS 2 Jazzy install tarball), WS_TOOLS=<that folder> (for cyclonedds-lo.xml). A test camera reports a clock 37 s ahead (TAI):
# sim_dds_bridge publishes it, ros2 lists, describes and echoes /diagnostics.
B=${B:-build/dev}
WS=${WS:-/tmp/ros2ws}
: "${WS_TOOLS:?set WS_TOOLS to the folder of a ROS 2 Jazzy test workspace (its cyclonedds-lo.xml and jazzy-install.tar.gz)}"
S=/interop_clock_$$
ip link set lo up && ip link set lo multicast on
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
. "$WS/install/setup.bash"
export RMW_IMPLEMENTATION=rmw_cyclonedds_cpp CYCLONEDDS_URI=file://$WS_TOOLS/cyclonedds-lo.xml
"$B/tests/mcap/mcap_test_camera" --stream "$S" --width 64 --height 48 --frames 0 --fps 5 --clock >/dev/null &
CAM=$!
sleep 1
"$B/bridge/dds/sim_dds_bridge" --publish "$S" --quiet &
BRIDGE=$!
sleep 3
echo "== ros2 topic list -t"; ros2 topic list -t --no-daemon --spin-time 3
echo "== ros2 topic info -v /diagnostics"; ros2 topic info -v --no-daemon --spin-time 3 /diagnostics
echo "== ros2 topic echo --once /diagnostics"
timeout 20 ros2 topic echo --once --no-daemon /diagnostics diagnostic_msgs/msg/DiagnosticArray
echo "echo exit $?"
kill "$BRIDGE"; wait "$BRIDGE"; echo "bridge exit $?"
kill "$CAM"; wait "$CAM"
"$B/tools/sim_rm" "$S" >/dev/null
