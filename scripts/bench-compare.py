#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Two builds' Google Benchmark programs side by side, as ratios with confidence intervals.

  scripts/bench-compare.py --before BUILD_A --after BUILD_B [--rounds 7] [--json out.json]
                           [--filter REGEX] [PROGRAM ...]

PROGRAM is a benchmark's path inside each build folder (default: the LiDAR decode benchmarks,
bench/{hesai,velodyne,ouster}/bench_*_decode). Each round runs every program of both builds
once, alternating which goes first, so a machine that speeds up or slows down during the run
weighs on both alike. A benchmark's figure is its `x_real_time` counter (seconds of sensor data
decoded per second) or, without one, the inverse of its real time. The ratio is after/before per
round; the table shows its geometric mean with a 95 % confidence interval (Student's t on the
logarithms over the rounds) and says "slower" or "faster" only when the interval excludes 1.

Take the figures on a quiet machine (the load average is printed with them): at load 20 the
Ouster decoder read 37x real time, quiet 131x. Exit codes: 0 compared, 1 a program failed,
2 usage error.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys

DEFAULT_PROGRAMS = ["bench/hesai/bench_hesai_decode", "bench/velodyne/bench_velodyne_decode",
                    "bench/ouster/bench_ouster_decode"]

# Student's t, two-sided 95 %, by degrees of freedom (rounds - 1).
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262,
       10: 2.228, 12: 2.179, 15: 2.131, 20: 2.086, 30: 2.042}


def t95(dof):
    keys = sorted(k for k in T95 if k <= dof)
    return T95[keys[-1]] if keys else T95[1]


def run(program, filter_regex):
    """One run of a benchmark program: {benchmark name: figure}."""
    argv = [program, "--benchmark_format=json"]
    if filter_regex:
        argv.append(f"--benchmark_filter={filter_regex}")
    done = subprocess.run(argv, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{program} exited with {done.returncode}: {done.stderr.strip()[-400:]}")
    figures = {}
    for b in json.loads(done.stdout)["benchmarks"]:
        if b.get("run_type") == "aggregate":
            continue
        if "x_real_time" in b:
            figures[b["name"]] = float(b["x_real_time"])
        elif b.get("real_time"):
            figures[b["name"]] = 1.0 / float(b["real_time"])
    return figures


def summarise(pairs):
    """pairs: [(before, after)] per round -> (median before, median after, ratio, low, high)."""
    logs = [math.log(a / b) for b, a in pairs if a > 0 and b > 0]
    mean = statistics.fmean(logs)
    half = t95(len(logs) - 1) * statistics.stdev(logs) / math.sqrt(len(logs)) if len(logs) > 1 else float("inf")
    return (statistics.median(b for b, _ in pairs), statistics.median(a for _, a in pairs),
            math.exp(mean), math.exp(mean - half), math.exp(mean + half))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=__doc__.split("\n\n", 1)[1])
    parser.add_argument("--before", required=True, help="the build folder taken as 1.0")
    parser.add_argument("--after", required=True, help="the build folder compared with it")
    parser.add_argument("--rounds", type=int, default=7, help="runs of each program per build (default 7)")
    parser.add_argument("--filter", help="--benchmark_filter for every program")
    parser.add_argument("--json", help="also write every round's figures and the table as JSON here")
    parser.add_argument("programs", nargs="*", default=DEFAULT_PROGRAMS)
    args = parser.parse_args()
    if args.rounds < 2:
        parser.error("--rounds must be 2 or more: a confidence interval needs two rounds.")
    for build in (args.before, args.after):
        for program in args.programs:
            if not os.access(os.path.join(build, program), os.X_OK):
                parser.error(f"{os.path.join(build, program)} is not a program: build it first "
                             "(cmake -DSIM_BUILD_BENCH=ON, target of the same name).")

    load_before = os.getloadavg()[0]
    rounds = {}  # name -> [(before, after)]
    try:
        for r in range(args.rounds):
            for program in args.programs:
                order = ("before", "after") if r % 2 == 0 else ("after", "before")
                figures = {side: run(os.path.join(getattr(args, side), program), args.filter) for side in order}
                for name, before in figures["before"].items():
                    if name in figures["after"]:
                        rounds.setdefault(name, []).append((before, figures["after"][name]))
            print(f"bench-compare: round {r + 1} of {args.rounds} done (load {os.getloadavg()[0]:.1f})",
                  file=sys.stderr, flush=True)
    except RuntimeError as error:
        print(f"bench-compare: {error}", file=sys.stderr)
        return 1
    load_after = os.getloadavg()[0]

    rows = []
    print(f"{'benchmark':<32} {'before':>9} {'after':>9} {'after/before':>12}  95 % interval")
    for name, pairs in rounds.items():
        before, after, ratio, low, high = summarise(pairs)
        verdict = "slower" if high < 1 else "faster" if low > 1 else "same"
        rows.append({"benchmark": name, "before": before, "after": after, "ratio": ratio, "low": low,
                     "high": high, "verdict": verdict, "rounds": len(pairs)})
        print(f"{name:<32} {before:>8.1f}x {after:>8.1f}x {ratio:>12.3f}  [{low:.3f}, {high:.3f}] {verdict}")
    print(f"(x = seconds of sensor data per second on one core, median of {args.rounds} rounds; "
          f"load average {load_before:.1f} before, {load_after:.1f} after)")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump({"before": args.before, "after": args.after, "load": [load_before, load_after],
                       "rows": rows, "rounds": rounds}, out, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
