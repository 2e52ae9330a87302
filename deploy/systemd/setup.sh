#!/usr/bin/env bash
# Installs the SIM system user/group and the example units (run as root, after installing the
# sim-tools package or `cmake --install` into /usr).
#   deploy/systemd/setup.sh             then: systemctl enable --now sim-lidar-hesai sim-lidar-monitor
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
[[ $(id -u) -eq 0 ]] || { echo "setup.sh: run as root" >&2; exit 2; }
install -D -m 0644 "$here/sim.sysusers.conf" /etc/sysusers.d/sim.conf
systemd-sysusers /etc/sysusers.d/sim.conf
install -d -m 0750 -o root -g sim /etc/sim /etc/sim/hesai
install -m 0644 "$here/sim-lidar-hesai.service" "$here/sim-lidar-monitor.service" /etc/systemd/system/
systemctl daemon-reload
echo "setup.sh: user and group 'sim' exist; units installed. Add people who read the streams to the group: usermod -aG sim NAME"
