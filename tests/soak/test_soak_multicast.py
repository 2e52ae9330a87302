# SPDX-License-Identifier: Apache-2.0
"""The soak's two LiDARs on one port (soak_multicast.py and the live drivers, started as soak.py
starts them): with a group each, each driver publishes frames and hears only its sensor; with
both sensors sent to one group, the soak's judgement (multicast_findings) goes red. Real
processes in a private network namespace, a few seconds each; needs root (or CAP_SYS_ADMIN) for
the namespace, like the soak: without it the test says so and passes.

    SIM_SOAK_BUILD=build/dev python3 tests/soak/test_soak_multicast.py
"""
import json
import os
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import soak  # noqa: E402  (the soak's own argv builders and judgement)

BUILD = os.environ.get("SIM_SOAK_BUILD", "build/release")
SECONDS = 4.0
RUNS = [0]  # unique stream names per run


def wait_for(condition, limit=60.0):
    """Polls until condition() is true or the (generous) limit passes; its last value."""
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.05)
    return condition()


def run_pair(feeds):
    """The sender and one live driver per feed for SECONDS; each driver's (name, exit, summary)."""
    RUNS[0] += 1
    tag = f"/test_soak_mc{os.getpid()}_{RUNS[0]}"
    streams = [f"{tag}_{i}" for i in range(len(feeds))]
    sender = subprocess.Popen(soak.multicast_sender_argv(feeds), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True)
    drivers = []
    try:
        ready = sender.stdout.readline()
        if not ready.startswith("{"):
            err = sender.stderr.read() if sender.wait(30) is not None else ""
            if "unshare failed" in err or "Operation not permitted" in err:
                return None  # no namespace here
            raise AssertionError(f"the sender did not start: {err}")
        assert json.loads(ready)["kind"] == "ready", ready
        for feed, stream in zip(feeds, streams):
            program = soak.find_program(BUILD, feed[3])
            drivers.append(subprocess.Popen(soak.live_driver_argv(program, sender.pid, feed, stream),
                                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
        # Each driver has made its stream (it saw its sensor's first packet), then runs a while.
        assert wait_for(lambda: all(os.path.exists("/dev/shm/sim." + s[1:]) for s in streams)), \
            [d.stderr.read() for d in drivers if d.poll() is not None]
        time.sleep(SECONDS)
        runs = []
        for stream, driver in zip(streams, drivers):
            driver.send_signal(signal.SIGTERM)
            out, err = driver.communicate(timeout=30)
            line = next((l for l in out.splitlines() if l.startswith("summary ")), None)
            summary = dict(kv.split("=", 1) for kv in line.split()[1:] if "=" in kv) if line else None
            runs.append((stream, driver.returncode, summary))
        return runs
    finally:
        for d in drivers:
            if d.poll() is None:
                d.kill()
        sender.send_signal(signal.SIGTERM)
        sender.wait(30)
        subprocess.run([os.path.join(BUILD, "tools", "sim_rm"), "--force", *streams], capture_output=True)
        for s in streams:  # (when sim_rm is not built)
            if os.path.exists("/dev/shm/sim." + s[1:]):
                os.remove("/dev/shm/sim." + s[1:])


def test_each_driver_hears_only_its_own_group_on_the_shared_port():
    runs = run_pair(soak.MULTICAST_FEEDS)
    if runs is None:
        print("skipped: no network namespace here (needs root or CAP_SYS_ADMIN)")
        return
    assert soak.multicast_findings(runs) == [], runs
    for stream, code, summary in runs:
        assert code == 0, (stream, code)
        assert int(summary["frames"]) > 0, (stream, summary)  # (no rate asserted: a loaded machine is slow)
        assert summary["other_senders"] == "0", (stream, summary)


def test_two_sensors_sent_to_one_group_are_found():
    one_group = [soak.MULTICAST_FEEDS[0], (soak.MULTICAST_FEEDS[0][0], *soak.MULTICAST_FEEDS[1][1:])]
    runs = run_pair(one_group)
    if runs is None:
        print("skipped: no network namespace here (needs root or CAP_SYS_ADMIN)")
        return
    findings = soak.multicast_findings(runs)
    assert len(findings) == 2 and all("heard another sensor" in f for f in findings), (findings, runs)
    assert all(int(summary["other_senders"]) > 0 for _, _, summary in runs), runs


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
