"""Waiting from Python: Ctrl-C interrupts a wait, other threads' calls do not wait for it, and a
closed writer's loan publishes nothing (review findings M3, M4, L8)."""

import os
import signal
import subprocess
import sys
import threading
import time

import pytest

import sim

WAITER = """
import sys, sim
name, call = sys.argv[1], sys.argv[2]
writer = sim.Writer(name, capacity=16)
reader = sim.Reader(name)
try:
    print("waiting", flush=True)  # inside the try: a signal that comes early is caught all the same
    reader.read_next(None) if call == "read_next" else reader.wait(None)
    print("returned", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


@pytest.mark.parametrize("call", ["read_next", "wait"])
def test_ctrl_c_interrupts_a_wait_without_timeout(stream_name, call):
    process = subprocess.Popen(
        [sys.executable, "-c", WAITER, stream_name, call], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert process.stdout.readline().strip() == "waiting"
        time.sleep(0.3)  # into the wait
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)  # a hang guard: without the fix it never ends
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert out.strip() == "interrupted", err
    assert process.returncode == 0, err


def test_stats_and_layout_do_not_wait_for_another_threads_wait(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    reader = sim.Reader(stream_name)
    got = []
    waiter = threading.Thread(target=lambda: got.append(reader.read_next(timeout=60)))
    waiter.start()
    time.sleep(0.3)  # into read_next
    stats, layout, capacity = reader.stats, reader.layout, reader.capacity
    # Had the properties waited for the reader's mutex, they would have returned only when the
    # other thread's 60 s wait ended: it would no longer be waiting.
    assert waiter.is_alive() and not got
    assert stats.frames == 0 and layout == sim.Layout.raw() and capacity == 16
    while not got:
        writer.write(b"wake")
        waiter.join(0.05)
    assert got[0] is not None, "the other thread's wait had run out: the properties waited for it"
    assert got[0].array.tobytes() == b"wake"
    assert reader.stats.frames == 1


def test_a_loan_committed_after_its_writer_closed_publishes_nothing(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    reader = sim.Reader(stream_name)
    loan = writer.loan()
    loan.array[:3] = [1, 2, 3]
    writer.close()
    with pytest.raises(sim.SimError, match="the writer is closed"):
        loan.commit(3)
    assert reader.read() is None


def test_a_leftover_view_of_a_committed_loan_does_not_keep_the_writer_alive(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    loan = writer.loan()
    view = loan.array
    view[:4] = [1, 2, 3, 4]
    loan.commit(4)
    del loan
    writer.close()
    del writer
    # The stream is free for a new writer in this very process, and the old view stays readable.
    again = sim.Writer(stream_name, capacity=16)
    assert view[:4].tolist() == [1, 2, 3, 4]
    again.write(b"next")
    assert sim.Reader(stream_name).read().array.tobytes() == b"next"
