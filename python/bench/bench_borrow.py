#!/usr/bin/env python3
"""Python borrow vs copy of one 6,912,000-byte frame (a 1920x1200 BGR image), side by side with
numpy's own copy of the same bytes as the reference, in one run.

    PYTHONPATH=build/release/python python3 python/bench/bench_borrow.py [--frames 500]

For each frame the writer publishes (not timed), the reader gets it either as a copy
(Reader.read(): a new numpy array) or as a borrowed read-only view (Reader.borrow().array, then
still_valid()), and touches one byte per 4 KiB page of the result so both paths pay for reaching
the data. Prints median and p99 in microseconds; --json for scripts.
"""

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

import sim

WIDTH, HEIGHT = 1920, 1200  # 6,912,000 bytes of bgr8


def touch(array):
    return int(array.reshape(-1)[::4096].sum())


def measure(frames, get):
    name = f"/bench_borrow_{os.getpid()}"
    times = []
    with sim.Writer(name, sim.Layout.image(WIDTH, HEIGHT, "bgr8")) as writer, sim.Reader(name) as reader:
        frame = np.random.default_rng(1).integers(0, 256, (HEIGHT, WIDTH, 3), dtype=np.uint8)
        for _ in range(frames):
            writer.write(frame)
            start = time.perf_counter_ns()
            get(reader)
            times.append(time.perf_counter_ns() - start)
    sim.destroy(name, force=True)
    return times


def copy(reader):
    touch(reader.read().array)


def borrow(reader):
    b = reader.borrow()
    touch(b.array)
    assert b.still_valid()


def numpy_copy_reference(frames):
    source = np.random.default_rng(1).integers(0, 256, (HEIGHT, WIDTH, 3), dtype=np.uint8)
    times = []
    for _ in range(frames):
        start = time.perf_counter_ns()
        touch(source.copy())
        times.append(time.perf_counter_ns() - start)
    return times


def summary(times):
    ordered = sorted(times)
    return {
        "median_us": statistics.median(ordered) / 1000,
        "p99_us": ordered[min(len(ordered) - 1, int(len(ordered) * 0.99))] / 1000,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=500, help="frames per method (default 500)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    if args.frames < 1:
        parser.error("--frames must be 1 or more")
    results = {
        "numpy copy (reference)": summary(numpy_copy_reference(args.frames)),
        "sim copy (read)": summary(measure(args.frames, copy)),
        "sim borrow (zero-copy view)": summary(measure(args.frames, borrow)),
    }
    if args.json:
        json.dump({"frame_bytes": WIDTH * HEIGHT * 3, "frames": args.frames, "results": results}, sys.stdout)
        print()
        return 0
    print(f"{WIDTH * HEIGHT * 3:,} B frames, {args.frames} per method")
    print(f"{'method':<30}{'median µs':>12}{'p99 µs':>12}")
    for method, r in results.items():
        print(f"{method:<30}{r['median_us']:>12.1f}{r['p99_us']:>12.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
