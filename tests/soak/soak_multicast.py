#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""soak_multicast.py: two LiDARs on one UDP port by multicast, for the soak.

    unshare --net -- python3 soak_multicast.py --port 2368 GROUP,SOURCE,CAPTURE [GROUP,SOURCE,CAPTURE…]

Runs in a network namespace of its own (`unshare --net` execs it): brings loopback up with
multicast and a route for 224.0.0.0/4, says {"kind":"ready",…} on stdout, then sends each
capture's UDP payloads to its GROUP:port from its own SOURCE address (127.0.0.x, all local on
loopback), at the capture's own pace, looping. Two sensors, two groups, one port: a driver that
joined one group must hear only that sensor. The drivers under test join the namespace with
`nsenter --net=/proc/PID/ns/net` (soak.py starts them so, as writers of their streams).

One JSON line a second: datagrams sent per group, and how often the pacing fell more than half a
second behind (a paused machine; it then goes on from where it is instead of sending a burst).
SIGTERM or SIGINT: a last line, exit 0.
"""
import argparse
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import threading
import time

BEHIND_S = 0.5  # further behind than this, the schedule restarts from now (no burst)


def udp_payloads(path):
    """(seconds, payload) of every IPv4 UDP datagram of a classic pcap (Ethernet, µs or ns)."""
    with open(path, "rb") as f:
        data = f.read()
    magic = struct.unpack_from("<I", data, 0)[0]
    if magic not in (0xA1B2C3D4, 0xA1B23C4D):
        raise ValueError(f"{path} is not a little-endian classic pcap file")
    fraction = 1e-9 if magic == 0xA1B23C4D else 1e-6
    if struct.unpack_from("<I", data, 20)[0] != 1:
        raise ValueError(f"{path} is not an Ethernet capture")
    out, offset = [], 24
    while offset + 16 <= len(data):
        sec, sub, length, _ = struct.unpack_from("<IIII", data, offset)
        frame = data[offset + 16:offset + 16 + length]
        offset += 16 + length
        ether = 14
        if len(frame) >= 18 and frame[12:14] == b"\x81\x00":  # one VLAN tag
            ether = 18
        if len(frame) < ether + 28 or frame[ether - 2:ether] != b"\x08\x00" or frame[ether + 9] != 17:
            continue
        ihl = (frame[ether] & 0x0F) * 4
        udp = ether + ihl
        udp_length = struct.unpack_from("!H", frame, udp + 4)[0]
        out.append((sec + sub * fraction, frame[udp + 8:udp + udp_length]))
    if len(out) < 2:
        raise ValueError(f"{path} holds fewer than two UDP datagrams")
    return out


def private_loopback():
    """Loopback up, multicast on it, and 224.0.0.0/4 routed through it (this namespace only)."""
    env = dict(os.environ, PATH="/usr/sbin:/sbin:" + os.environ.get("PATH", "/usr/bin:/bin"))
    for argv in (["ip", "link", "set", "lo", "up", "multicast", "on"],
                 ["ip", "route", "add", "224.0.0.0/4", "dev", "lo"]):
        run = subprocess.run(argv, capture_output=True, text=True, env=env)
        if run.returncode != 0:
            raise OSError(f"'{' '.join(argv)}' failed: {run.stderr.strip()}")


class Feed:
    """One sensor: a capture's payloads to a group from a source address, at the recorded pace."""

    def __init__(self, group, source, capture, port):
        self.group, self.port = group, port
        self.packets = udp_payloads(capture)
        first, last = self.packets[0][0], self.packets[-1][0]
        # One loop lasts the capture plus one mean gap, so the loops join at the sensor's rate.
        self.loop_s = (last - first) * len(self.packets) / (len(self.packets) - 1)
        self.first = first
        self.sent = 0
        self.resyncs = 0
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1"))
        self.sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        self.sock.bind((source, 0))

    def run(self, stop):
        start = time.monotonic()
        loop = 0
        while not stop.is_set():
            for stamp, payload in self.packets:
                due = start + loop * self.loop_s + (stamp - self.first)
                delay = due - time.monotonic()
                if delay > 0.002:  # send in small batches: one sleep per ~2 ms of packets
                    if stop.wait(delay):
                        return
                elif delay < -BEHIND_S:
                    self.resyncs += 1
                    start += -delay
                self.sock.sendto(payload, (self.group, self.port))
                self.sent += 1
            loop += 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, required=True, help="the one UDP port every sensor sends to")
    parser.add_argument("feeds", nargs="+", metavar="GROUP,SOURCE,CAPTURE")
    args = parser.parse_args()
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    try:
        private_loopback()
        feeds = [Feed(*spec.split(",", 2), args.port) for spec in args.feeds]
    except (OSError, ValueError) as e:
        print(f"soak_multicast: {e}", file=sys.stderr)
        return 1
    threads = [threading.Thread(target=f.run, args=(stop,), daemon=True) for f in feeds]
    for t in threads:
        t.start()
    print(json.dumps({"kind": "ready", "pid": os.getpid(), "port": args.port}), flush=True)

    def stats(final=False):
        line = {"kind": "stats", "role": "multicast", "groups": {
            f.group: {"sent": f.sent, "resyncs": f.resyncs} for f in feeds}}
        if final:
            line["final"] = True
        print(json.dumps(line), flush=True)

    while not stop.wait(1.0):
        stats()
    for t in threads:
        t.join(5)
    stats(final=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
