# SPDX-License-Identifier: Apache-2.0
"""The soak can fail: every guarantee it checks is broken on purpose and the soak must go red,
each fault on the check that guards it. One short lean soak (no Foxglove, no DDS, 640x480
cameras) with every fault at once, each on its own streams or process (soak.py fault_spec):

    torn              the soak writer of cam3 tears every 97th frame       -> torn frames
    lost_wakeups      readers of lidar0 and cam1 are never woken            -> missed (lidar0),
                      (they find frames at their 100 ms region checks)         frames below the floor (cam1)
    half_frames       readers of cam4 sleep through 3 frames after every    -> frames below the floor (cam4)
                      third wake-up: half the frames
    leak              read_block leaks 256 KiB a second                     -> its memory slope
    stale_region      cam5's writer leaves a region of another name         -> the region set, left behind
    broken_recording  every sim_record segment is cut in half before play   -> recordings that do not play

    SIM_SOAK_BUILD=build/dev python3 tests/soak/test_soak_faults.py [--seconds 45]

A longer run for people: --seconds 120 (the checks' margins then grow; the verdicts must not change).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def run_soak(build, seconds, faults):
    with tempfile.TemporaryDirectory(prefix="soak_faults_") as tmp:
        out = os.path.join(tmp, "soak.json")
        argv = [sys.executable, os.path.join(HERE, "soak.py"), "--build", build, "--seconds", str(seconds),
                "--warmup", "8", "--lean", "--image", "640x480", "--seed", "7", "--fault", faults, "--json", out]
        run = subprocess.run(argv, capture_output=True, text=True, timeout=seconds + 240)
        print(run.stdout[-6000:])
        print(run.stderr[-2000:], file=sys.stderr)
        assert os.path.exists(out), f"the soak wrote no result (exit {run.returncode})"
        with open(out) as f:
            return run.returncode, json.load(f)


def check_value(result, starts):
    return next(c["value"] for c in result["checks"] if c["check"].startswith(starts))


def verdicts(code, result, streams):
    """Each fault's check and whether it went red, as (fault, red, evidence)."""
    v = result["violations"]
    cam, lidar = streams
    short = {(d["reader"], d["stream"].rsplit("_", 1)[1]) for d in result["deliveries"] if not d["ok"]}
    memory = [r for r in result["resources"] if r["process"] == "read_block" and r["what"] == "rss_anon_kib"]
    regions = [r for r in result["resources"] if r["process"] == "/dev/shm"]
    return [
        ("the soak fails", code == 1 and not result["pass"], f"exit {code}"),
        ("torn", any(x["what"] == "torn" and x["stream"].endswith("_cam3") for x in v),
         check_value(result, "torn frames")),
        ("lost_wakeups (LiDAR: late)", any(x["what"] == "missed" and x["stream"].endswith("_lidar0") for x in v),
         check_value(result, "blocked reader missed")),
        ("lost_wakeups (replayed camera: frames lost)", ("read_block", "cam1") in short, sorted(short)),
        ("half_frames", ("read_block", "cam4") in short and ("read_borrow", "cam4") in short, sorted(short)),
        ("leak", bool(memory) and not memory[0]["ok"], memory),
        ("stale_region (region set)", bool(regions) and not regions[0]["ok"], regions),
        ("stale_region (left behind)", check_value(result, "our /dev/shm regions left behind") > 0,
         check_value(result, "our /dev/shm regions left behind")),
        ("broken_recording", check_value(result, "recordings that do not play back") > 0,
         result["recordings"]),
        # what was not broken stays green: the faults are seen where they are, nowhere else
        ("no torn frame elsewhere", all(x["stream"].endswith("_cam3") for x in v if x["what"] == "torn"),
         [x for x in v if x["what"] == "torn"][:3]),
        ("no short delivery elsewhere", all(s in ("cam1", "cam4") for _, s in short), sorted(short)),
        ("no crash or hang", check_value(result, "crashes or hangs") == 0, result["failures"]),
    ]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=int, default=int(os.environ.get("SIM_SOAK_FAULT_SECONDS", 45)))
    args = parser.parse_args()
    build = os.environ.get("SIM_SOAK_BUILD", "build/release")
    code, result = run_soak(build, args.seconds, "all")
    failed = 0
    for what, red, evidence in verdicts(code, result, ("cam", "lidar")):
        print(f"{'ok  ' if red else 'FAIL'} {what}: {json.dumps(evidence, default=str)[:300]}")
        failed += not red
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
