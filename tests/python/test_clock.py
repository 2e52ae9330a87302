"""The stream's clock record from Python: set by a Writer, read by a Reader, seen per frame."""

import math

import pytest

import sim


def tai_clock():
    clock = sim.ClockStatus()
    clock.source = sim.ClockSource.ptp
    clock.state = sim.ClockState.locked
    clock.ptp_domain = 0
    clock.grandmaster = "00a069.fffe.0b552d"
    clock.utc_offset_s = 37
    clock.offset_to_host_ns = 37_000_120_000
    clock.spread_ns = 4_000
    clock.verdict = sim.ClockVerdict.error
    clock.problem = "the sensor's clock is 37.0 s ahead of the host: TAI against UTC"
    clock.stamps = sim.StampClock.sensor
    return clock


def test_a_clock_set_by_a_writer_reads_back_typed(stream_name):
    writer = sim.Writer(stream_name, capacity=64)
    reader = sim.Reader(stream_name)
    assert reader.clock is None
    writer.set_clock(tai_clock())
    clock = reader.clock
    assert clock == tai_clock()
    assert clock.source == sim.ClockSource.ptp
    assert clock.offset_to_host_ns == 37_000_120_000
    assert clock.offset_from_master_ns is None
    assert clock.utc_offset_s == 37
    assert "37.0 s" in clock.summary() and clock.summary().endswith("TAI against UTC")


def test_each_frame_says_which_clock_its_stamp_is_in(stream_name):
    writer = sim.Writer(stream_name, capacity=64)
    reader = sim.Reader(stream_name)
    writer.write(b"a")
    first = reader.read().info
    assert first.clock_generation == 0 and first.stamp_clock == sim.StampClock.unknown
    fixed = tai_clock()
    fixed.stamps = sim.StampClock.host_arrival
    writer.set_clock(fixed)
    writer.write(b"b")
    second = reader.read().info
    assert second.clock_generation != 0
    assert second.stamp_clock == sim.StampClock.host_arrival
    assert second.as_dict()["stamp_clock"] == "host_arrival"


def test_a_bad_clock_is_refused_with_a_sentence(stream_name):
    writer = sim.Writer(stream_name, capacity=64)
    clock = tai_clock()
    clock.drift_ppm = math.nan
    with pytest.raises(sim.SimError, match="drift is not a finite number"):
        writer.set_clock(clock)
