"""The Python module against the C++ library: real shared memory, real processes."""

import threading

import numpy as np
import pytest

import sim


def pixel_values(seq, width, height):
    """What sim_python_peer writes (and checks) for frame `seq`: (seq*7 + x*3 + y*5 + c) & 0xFF."""
    y, x, c = np.meshgrid(np.arange(height), np.arange(width), np.arange(3), indexing="ij")
    return ((seq * 7 + x * 3 + y * 5 + c) & 0xFF).astype(np.uint8)


def expected_points(seq, count):
    """What sim_python_peer write-points publishes as point i of frame `seq`."""
    i = np.arange(count)
    points = np.zeros(count, dtype=sim.LIDAR_POINT_DTYPE)
    points["x"] = i * 0.5
    points["y"] = -i
    points["z"] = seq
    points["intensity"] = i % 256
    points["time_offset_ns"] = i * 10
    points["ring"] = i % 64
    points["return_index"] = i % 2
    return points


def test_reads_the_images_a_cpp_writer_publishes_from_another_process(stream_name, peer):
    writer = peer("write-image", stream_name, 64, 48)
    writer.expect_line("ready")
    with sim.Reader(stream_name) as reader:
        assert reader.layout.kind == sim.LayoutKind.image
        assert reader.layout.format == sim.PixelFormat.bgr8
        for _ in range(3):
            frame = reader.read_next(timeout=10)
            assert frame is not None, reader.last_status
            image, info = frame
            assert image.shape == (48, 64, 3) and image.dtype == np.uint8
            assert info.size == 48 * 64 * 3 and info.stamp_ns == info.seq * 1000
            np.testing.assert_array_equal(image, pixel_values(info.seq, 64, 48))
    assert writer.finish()[0] == 0


def test_reads_lidar_frames_as_structured_arrays_with_the_lidar_point_fields(stream_name, peer):
    writer = peer("write-points", stream_name, 1000)
    writer.expect_line("ready")
    reader = sim.Reader(stream_name)
    frame = reader.read_next(timeout=10)
    assert frame is not None, reader.last_status
    points, info = frame
    assert points.dtype == sim.LIDAR_POINT_DTYPE and points.dtype.itemsize == 24
    assert points.dtype.names == ("x", "y", "z", "intensity", "time_offset_ns", "ring", "return_index")
    assert points.shape == (1000,)
    want = expected_points(info.seq, 1000)
    for field in want.dtype.names:
        np.testing.assert_array_equal(points[field], want[field], err_msg=field)
    writer.finish()


def test_a_cpp_reader_in_another_process_gets_every_byte_python_writes(stream_name, peer):
    width, height = 40, 30
    writer = sim.Writer(stream_name, sim.Layout.image(width, height, "bgr8"))
    reader = peer("read-image", stream_name, 3)
    # The reader opens the stream at its own pace: keep publishing until it has checked three frames.
    done = threading.Event()

    def publish():
        while not done.is_set():
            seq = writer.last_seq + 1
            writer.write(pixel_values(seq, width, height))
            done.wait(0.01)

    thread = threading.Thread(target=publish)
    thread.start()
    try:
        code, out, err = reader.finish(timeout=60)
    finally:
        done.set()
        thread.join()
    assert code == 0, err
    assert out.count(" ok") == 3


def test_writes_through_a_loan_in_place(stream_name):
    with sim.Writer(stream_name, sim.Layout.points(500)) as writer, sim.Reader(stream_name) as reader:
        loan = writer.loan()
        slot = loan.array
        assert slot.dtype == sim.LIDAR_POINT_DTYPE and slot.shape == (500,) and slot.flags.writeable
        want = expected_points(1, 200)
        slot[:200] = want
        loan.commit(200 * sim.LIDAR_POINT_DTYPE.itemsize, stamp_ns=123)
        points, info = reader.read()
        assert info.seq == 1 and info.stamp_ns == 123 and points.shape == (200,)
        np.testing.assert_array_equal(points, want)
        with pytest.raises(sim.SimError, match="already committed") as error:
            loan.commit()
        assert error.value.code == "committed"


def test_a_borrowed_view_is_read_only_and_keeps_the_memory_after_the_reader_is_gone(stream_name):
    writer = sim.Writer(stream_name, sim.Layout.image(16, 8, "mono8"))
    frame = np.arange(16 * 8, dtype=np.uint8).reshape(8, 16, 1)
    writer.write(frame)
    reader = sim.Reader(stream_name)
    borrowed = reader.borrow()
    view = borrowed.array
    assert view.shape == (8, 16, 1) and not view.flags.writeable and not view.flags.owndata
    with pytest.raises(ValueError):
        view[0, 0, 0] = 1
    reader.close()
    del reader, borrowed  # only the view is left; its base keeps the mapping
    writer.close()
    del writer
    sim.destroy(stream_name, force=True)
    np.testing.assert_array_equal(view, frame)


def test_still_valid_turns_false_once_the_writer_reuses_the_borrowed_slot(stream_name):
    writer = sim.Writer(stream_name, capacity=64)
    reader = sim.Reader(stream_name)
    writer.write(b"first")
    borrowed = reader.borrow()
    assert bytes(borrowed.array) == b"first" and borrowed.still_valid()
    writer.write(b"second")  # the other slot
    assert borrowed.still_valid()
    writer.write(b"third")  # the borrowed slot again
    assert not borrowed.still_valid()
    assert reader.borrow().array.tobytes() == b"third"


def test_a_copied_frame_is_the_callers_to_keep(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    reader = sim.Reader(stream_name)
    writer.write(b"one")
    first = reader.read().array
    writer.write(b"two")
    second = reader.read().array
    writer.write(b"six")  # overwrites the slot `first` came from
    assert first.tobytes() == b"one" and second.tobytes() == b"two" and first.flags.writeable


def test_read_next_lets_other_python_threads_run_while_it_waits(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    reader = sim.Reader(stream_name)
    got = []
    waiting = threading.Thread(target=lambda: got.append(reader.read_next(timeout=30)))
    waiting.start()
    # If read_next held the GIL, this thread could not write until the 30 s timeout ran out,
    # and the waiting thread would have returned None.
    while not got:
        writer.write(b"wake")
        waiting.join(0.05)
    assert got[0] is not None and got[0].array.tobytes() == b"wake"


def test_bad_names_raise_the_librarys_sentence(stream_name):
    with pytest.raises(sim.SimError) as error:
        sim.Reader("no_slash")
    assert error.value.code == "invalid_name" and "/" in str(error.value)
    with pytest.raises(sim.SimError) as error:
        sim.Writer("/bad name!", capacity=16)
    assert error.value.code == "invalid_name"
    with pytest.raises(sim.SimError) as error:
        sim.Reader(stream_name)  # nobody created it
    assert error.value.code == "not_found" and stream_name in str(error.value)


def test_a_second_writer_is_refused_while_the_first_lives(stream_name):
    first = sim.Writer(stream_name, capacity=16)
    with pytest.raises(sim.SimError) as error:
        sim.Writer(stream_name, capacity=16)
    assert error.value.code == "writer_exists"
    first.close()
    sim.Writer(stream_name, capacity=16).close()  # the stream is free again


def test_closed_readers_and_writers_raise_and_a_closed_stream_reads_as_writer_gone(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    reader = sim.Reader(stream_name)
    writer.write(b"last")
    writer.close()
    assert writer.closed
    with pytest.raises(sim.SimError, match="closed"):
        writer.write(b"more")
    assert reader.read().array.tobytes() == b"last"  # what was published stays readable
    assert reader.read_next(timeout=0.01) is None
    assert reader.last_status == sim.ReadStatus.writer_gone
    assert not reader.writer_alive()
    reader.close()
    with pytest.raises(sim.SimError, match="closed") as error:
        reader.read()
    assert error.value.code == "closed"


def test_frames_larger_than_the_stream_are_refused_with_a_sentence(stream_name):
    writer = sim.Writer(stream_name, capacity=8)
    with pytest.raises(sim.SimError, match="does not fit") as error:
        writer.write(np.zeros(9, dtype=np.uint8))
    assert error.value.code == "too_large"
    with pytest.raises(TypeError, match="C-contiguous"):
        writer.write(np.zeros((4, 4), dtype=np.uint8)[:, ::2])


def test_sixteen_bit_images_read_as_uint16(stream_name):
    writer = sim.Writer(stream_name, sim.Layout.image(5, 4, sim.PixelFormat.mono16))
    frame = (np.arange(20, dtype=np.uint16) * 1000).reshape(4, 5, 1)
    writer.write(frame)
    image, _ = sim.Reader(stream_name).read()
    assert image.dtype == np.uint16 and image.shape == (4, 5, 1)
    np.testing.assert_array_equal(image, frame)


def test_a_borrowed_view_stays_readable_while_new_writers_replace_the_region_twice(stream_name):
    first = sim.Writer(stream_name, capacity=16)
    first.write(b"old region")
    reader = sim.Reader(stream_name)
    view = reader.borrow().array  # the Borrow lives on only as the view's base
    first.close()
    for capacity, text in ((4096, b"second region"), (8192, b"third region")):
        # another capacity: a new region replaces the old one under the same name
        with sim.Writer(stream_name, capacity=capacity) as writer:
            writer.write(text)
            frame = reader.read_next(timeout=10)
            assert frame is not None and frame.array.tobytes() == text
    assert view.tobytes() == b"old region"


def test_one_loan_at_a_time_and_a_write_waits_for_the_open_loan(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    loan = writer.loan()
    with pytest.raises(sim.SimError) as error:
        writer.loan()
    assert error.value.code == "loan_open"
    with pytest.raises(sim.SimError) as error:
        writer.write(b"now")
    assert error.value.code == "loan_open"
    del loan  # given up uncommitted: publishes nothing, frees the writer
    writer.write(b"now")
    assert sim.Reader(stream_name).read().array.tobytes() == b"now"
