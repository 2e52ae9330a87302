"""Shared fixtures: unique stream names removed after each test, and the C++ peer process."""

import itertools
import os
import subprocess

import pytest

import sim

_counter = itertools.count()


@pytest.fixture
def stream_name():
    """A stream name no other test (or parallel run) uses; the stream is removed afterwards."""
    name = f"/pytest_{os.getpid()}_{next(_counter)}"
    yield name
    try:
        sim.destroy(name, force=True)
    except sim.SimError:
        pass  # never created, or already removed by the test


class Peer:
    """sim_python_peer in another process; stdin closing tells a writer to stop."""

    def __init__(self, *args):
        self.process = subprocess.Popen(
            [os.environ["SIM_PYTHON_PEER"], *map(str, args)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )

    def expect_line(self, expected):
        line = self.process.stdout.readline().strip()
        assert line == expected, f"peer said {line!r}; stderr: {self.process.stderr.read()}"

    def finish(self, timeout=30):
        """Closes the peer's stdin and returns its exit code and output."""
        out, err = self.process.communicate(timeout=timeout)
        return self.process.returncode, out, err

    def kill(self):
        if self.process.poll() is None:
            self.process.kill()
        self.process.communicate()


@pytest.fixture
def peer():
    started = []

    def start(*args):
        p = Peer(*args)
        started.append(p)
        return p

    yield start
    for p in started:
        p.kill()
