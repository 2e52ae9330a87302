# SPDX-License-Identifier: Apache-2.0
"""The soak's checks find what they look for: a torn frame and a reader that slept through
frames (so a soak that reports 0 of them has looked). Real processes, a few seconds.

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
                               *writer_args])
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
