# SPDX-License-Identifier: Apache-2.0
"""The soak's reader through the Python module: sim.Reader.read_next (copies, numpy).

    PYTHONPATH=build/release/python python3 tests/soak/soak_py_reader.py NAME

Checks every frame it gets like the C++ readers (tests/soak/soak_frames.hpp): the pattern
of the soak writer and the generated video, or a whole number of finite LiDAR points; sequence
numbers always rising; a frame whose checksum fails (read_next then returns None, and the
reader's stats count it) is torn. One JSON line per second; SIGTERM ends it with exit 0.
"""
import json
import signal
import sys
import time

import numpy as np

import sim

MAGIC = 0x314B414F534D4953
VIDEO_TAG = 0x5649444500000000
HEADER_WORDS = 11
STRIDE = 64
U64 = np.uint64


def mix(z):
    """splitmix64's finaliser on a numpy uint64 array (wrapping arithmetic)."""
    z = (z ^ (z >> U64(30))) * U64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> U64(27))) * U64(0x94D049BB133111EB)
    return z ^ (z >> U64(31))


def whole(frame):
    """True when the bytes are a whole frame (see soak_frames.hpp)."""
    raw = frame.reshape(-1).view(np.uint8)
    if raw.size >= 8 and int(raw[:8].view("<u8")[0]) == MAGIC:
        if raw.size % 8 or raw.size < HEADER_WORDS * 8:
            return False
        words = raw.view("<u8")
        tag = words[1:2].astype(U64)
        index = np.arange(HEADER_WORDS, words.size, STRIDE, dtype=U64)
        index = np.append(index, U64(words.size - 1))
        if int(tag[0]) & ~0xFF == VIDEO_TAG:  # a picture of the generated video: flat
            expected = U64(0x0101010101010101 * (0x10 + 0x1F * (int(tag[0]) & 7)))
        else:
            with np.errstate(over="ignore"):
                expected = mix(index + U64(0x9E3779B97F4A7C15)) ^ mix(tag ^ U64(0xD1B54A32D192ED03))
        return bool(np.all(words[index.astype(np.int64)] == expected))
    if raw.size % 24:
        return False
    xyz = raw.view("<f4").reshape(-1, 6)[::7, :3]
    return bool(np.all(np.isfinite(xyz)) and np.all(np.abs(xyz) <= 1000.0))


class Counters:
    def __init__(self, name):
        self.name = name
        self.frames = self.torn = self.out_of_order = self.opens = 0

    def violation(self, what, seq):
        print(json.dumps({"kind": "violation", "what": what, "stream": self.name, "seq": seq}), flush=True)

    def print(self, final):
        streams = {self.name: {"frames": self.frames, "torn": self.torn,
                               "out_of_order": self.out_of_order, "opens": self.opens}}
        print(json.dumps({"kind": "stats", "role": "python", "final": final, "streams": streams}), flush=True)


def read_until_gone(reader, c, stop, next_print):
    """Reads until the writer stays gone for 2 s (the caller then reopens by name)."""
    last_seq = last_publish = 0
    gone_since = None
    while not stop():
        if time.monotonic() >= next_print[0]:
            c.print(False)
            next_print[0] += 1.0
        try:
            failures = reader.stats.checksum_failures
            frame = reader.read_next(timeout=1.0)
            failed = reader.stats.checksum_failures - failures
        except Exception:  # region removed or invalid: reopen by name
            return
        if failed > 0:  # read_next gives None for a frame whose checksum fails: it was torn
            c.torn += failed
            c.violation("torn", 0)
        if frame is None:
            if not reader.writer_alive():
                gone_since = gone_since or time.monotonic()
                if time.monotonic() - gone_since > 2.0:
                    return
                time.sleep(0.05)
            continue
        gone_since = None
        array, info = frame
        c.frames += 1
        if info.size and not whole(array):
            c.torn += 1
            c.violation("torn", info.seq)
        # Not above the previous number is out of order, unless published later: a stream
        # removed and created anew numbers from 1 again.
        if last_seq and info.seq <= last_seq and info.publish_ns <= last_publish:
            c.out_of_order += 1
            c.violation("out_of_order", info.seq)
        last_seq, last_publish = info.seq, info.publish_ns


def main():
    if len(sys.argv) != 2:
        print("usage: soak_py_reader.py NAME", file=sys.stderr)
        return 2
    name = sys.argv[1]
    stopped = []
    signal.signal(signal.SIGTERM, lambda *_: stopped.append(True))
    signal.signal(signal.SIGINT, lambda *_: stopped.append(True))
    c = Counters(name)
    next_print = [time.monotonic() + 1.0]
    while not stopped:
        try:
            reader = sim.Reader(name)
        except Exception:
            time.sleep(0.02)
            continue
        c.opens += 1
        with reader:
            read_until_gone(reader, c, lambda: bool(stopped), next_print)
    c.print(True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
