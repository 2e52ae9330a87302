# SPDX-License-Identifier: Apache-2.0
"""The soak's checks find what they look for: a torn frame and a reader that slept through
frames (so a soak that reports 0 of them has looked). Real processes, a few seconds; and the
soak's judgements on recorded observations (writer stall or missed, memory slope).

    SIM_SOAK_AGENT=build/release/tests/soak/sim_soak_agent python3 tests/soak/test_soak_checks.py
"""
import json
import os
import signal
import subprocess
import sys
import time

AGENT = os.environ["SIM_SOAK_AGENT"]


def run_pair(stream, writer_args, reader_env, seconds=3.0):
    """A soak writer and a blocking reader of it; the reader's violation lines."""
    writer = subprocess.Popen([AGENT, "writer", "--stream", stream, "--hz", "30", "--points", "2000",
                               *writer_args], stdout=subprocess.DEVNULL)
    env = dict(os.environ, **reader_env)
    reader = subprocess.Popen([AGENT, "read", "--mode", "block", f"{stream}:33.333"], env=env,
                              stdout=subprocess.PIPE, text=True)
    first = reader.stdout.readline()  # its first line: it runs (a loaded machine starts slowly)
    time.sleep(seconds)
    reader.send_signal(signal.SIGTERM)
    out, _ = reader.communicate(timeout=30)
    out = first + out
    writer.send_signal(signal.SIGTERM)
    writer.wait(timeout=30)
    subprocess.run([os.path.join(os.path.dirname(AGENT), "..", "..", "tools", "sim_rm"), "--force", stream],
                   capture_output=True)
    assert reader.returncode == 0, f"the reader ended with {reader.returncode}"
    assert writer.returncode == 0, f"the writer ended with {writer.returncode}"
    lines = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    return [l for l in lines if l["kind"] == "violation"], [l for l in lines if l["kind"] == "stats"][-1]


def test_a_torn_frame_is_reported():
    violations, stats = run_pair(f"/test_soak_torn_{os.getpid()}", ["--tear-every", "5"], {})
    torn = [v for v in violations if v["what"] == "torn"]
    assert torn, f"no torn frame reported: {stats}"
    assert all(v["seq"] % 5 == 0 for v in torn), f"a whole frame reported torn: {torn}"


def test_a_reader_that_sleeps_through_frames_is_reported():
    # 150 ms asleep before each wait while the writer publishes every 33 ms: more than two periods.
    violations, stats = run_pair(f"/test_soak_late_{os.getpid()}", [], {"SIM_SOAK_OVERSLEEP_MS": "150"})
    assert any(v["what"] == "missed" for v in violations), f"no missed frame reported: {stats}"
    assert not any(v["what"] in ("torn", "out_of_order") for v in violations), violations


def test_a_stall_of_every_reader_while_the_writer_paused_is_a_writer_stall():
    # Recorded observations like those of the 40-minute run on 44ca5db: cam4, both readers at once.
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from soak import classify_stalls
    ms = 1_000_000
    miss = lambda process, start, end: {"process": process, "what": "missed", "stream": "/s_cam4",
                                        "readable_ns": start * ms, "end_ns": end * ms,
                                        "stall_ms": float(end - start), "period_ms": 33.333}
    gap = {"stream": "/s_cam4", "from_ns": 1000 * ms, "to_ns": 1090 * ms, "gap_ms": 90.0}
    together = [miss("read_block", 1000, 1100), miss("read_borrow", 1002, 1101)]
    assert classify_stalls(together, [gap]) == 2
    assert {v["what"] for v in together} == {"writer_stall"}
    # The writer published on time: both readers slept through frames, lost wake-ups.
    on_time = [miss("read_block", 1000, 1100), miss("read_borrow", 1002, 1101)]
    assert classify_stalls(on_time, []) == 0 and {v["what"] for v in on_time} == {"missed"}
    # One reader alone while the writer paused: still missed (the others were woken).
    alone = [miss("read_block", 1000, 1100)]
    assert classify_stalls(alone, [gap]) == 0 and alone[0]["what"] == "missed"
    # One reader alone, but the writer's commit of the frame took 120 ms (recorded in a 120 s soak
    # here: read_block, cam6 seq 269, stall 101.8 ms; the wake-up came as the commit returned).
    in_commit = [miss("read_block", 1000, 1102)]
    assert classify_stalls(in_commit, [dict(gap, in_commit=True, from_ns=999 * ms, to_ns=1120 * ms)]) == 1
    # The writer paused for a moment only: the rest of the stall is still over the allowance.
    short = [miss("read_block", 1000, 1140), miss("read_borrow", 1000, 1140)]
    assert classify_stalls(short, [dict(gap, to_ns=1050 * ms, gap_ms=50.0)]) == 0
    # Another stream's writer paused, or the pause was at another moment: missed.
    elsewhere = [miss("read_block", 1000, 1100), miss("read_borrow", 1000, 1100)]
    other = [dict(gap, stream="/s_cam2"), dict(gap, from_ns=2000 * ms, to_ns=2100 * ms)]
    assert classify_stalls(elsewhere, other) == 0


def test_a_live_lidar_that_heard_the_other_sensor_or_said_nothing_is_found():
    # What the two live drivers on one port printed when they ended (multicast_findings).
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from soak import multicast_findings
    clean = {"frames": "120", "other_senders": "0", "malformed": "0", "wrong_model": "0"}
    assert multicast_findings([("writer/s_lidar2", 0, clean), ("writer/s_lidar3", 0, clean)]) == []
    # Killed by SIGKILL (or SIGTERM before its handler): no summary, nothing to judge.
    assert multicast_findings([("writer/s_lidar2", -9, None), ("writer/s_lidar3", -15, None)]) == []
    heard = multicast_findings([("writer/s_lidar2", 0, dict(clean, other_senders="14963", malformed="4501"))])
    assert len(heard) == 1 and "other_senders=14963" in heard[0] and "malformed=4501" in heard[0], heard
    silent = multicast_findings([("writer/s_lidar3", 0, None), ("writer/s_lidar3", 1, None)])
    assert len(silent) == 2 and all("no summary" in p for p in silent), silent


def test_memory_is_judged_by_its_slope_not_by_a_step():
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from soak import theil_sen
    step = [(t, 40_000 + (8_000 if t > 5 else 0)) for t in range(0, 100, 2)]   # a pool filled once
    leak = [(t, 40_000 + 64 * t) for t in range(0, 100, 2)]                      # 64 KiB a second
    assert theil_sen(step) == 0.0
    assert abs(theil_sen(leak) - 64) < 1e-9


def test_an_undisturbed_reader_reports_nothing():
    violations, stats = run_pair(f"/test_soak_clean_{os.getpid()}", [], {})
    assert violations == [], violations
    assert stats["streams"], stats
    assert next(iter(stats["streams"].values()))["frames"] > 0, stats


if __name__ == "__main__":
    failed = 0
    for name, test in list(globals().items()):
        if name.startswith("test_"):
            try:
                test()
                print(f"ok   {name}")
            except AssertionError as e:
                failed += 1
                print(f"FAIL {name}: {e}")
    sys.exit(1 if failed else 0)
