"""The stream's sensor description from Python: set by a Writer, read by a Reader, damage raised."""

import math
import os

import numpy as np
import pytest

import sim

# Where the description's frame_id lies in a region file: the header page (4096), the sensor block
# in it (448, held there by a static_assert in sim/region.hpp), its record (+64), the field (+16).
FRAME_ID_OFFSET = 4096 + 448 + 64 + 16


def camera_info():
    return sim.SensorInfo(
        frame_id="camera_front_optical",
        parent_frame="base_link",
        mounting=sim.Mounting.from_xyz_rpy(1.5, 0.0, 1.2, -math.pi / 2, 0.0, -math.pi / 2),
        calibration=sim.CameraCalibration(
            width=640,
            height=480,
            camera_name="front",
            distortion_model="plumb_bob",
            d=[-0.1, 0.01, 0.0, 0.0, 0.0],
            k=[[500.0, 0.0, 320.0], [0.0, 501.0, 240.0], [0.0, 0.0, 1.0]],
            p=[[500.0, 0.0, 320.0, 0.0], [0.0, 501.0, 240.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
            binning_x=1,
            roi=sim.RegionOfInterest(x_offset=10, y_offset=20, height=100, width=200, do_rectify=True),
        ),
        identity=sim.SensorIdentity(vendor="Basler", model="acA640", serial="123", firmware="1.0"),
        calibration_source="file:///etc/sim/front.yaml",
        time_base=sim.TimeBase.sensor_synchronized,
        time_sync="PTP locked",
    )


def test_a_description_set_by_a_writer_reads_back_with_numpy_matrices(stream_name):
    writer = sim.Writer(stream_name, sim.Layout.image(640, 480, "bgr8"), sensor=camera_info())
    reader = sim.Reader(stream_name)
    info = reader.sensor_info
    assert info == camera_info()
    assert info.frame_id == "camera_front_optical" and info.parent_frame == "base_link"
    np.testing.assert_allclose(info.mounting.rotation, [-0.5, 0.5, -0.5, 0.5], atol=1e-12)
    np.testing.assert_array_equal(info.mounting.translation, [1.5, 0.0, 1.2])
    calibration = info.calibration
    assert calibration.k.shape == (3, 3) and calibration.k[1, 1] == 501.0
    assert calibration.r.shape == (3, 3) and np.array_equal(calibration.r, np.eye(3))
    assert calibration.p.shape == (3, 4) and calibration.p[0, 2] == 320.0
    np.testing.assert_array_equal(calibration.d, [-0.1, 0.01, 0.0, 0.0, 0.0])
    assert (calibration.width, calibration.height, calibration.binning_x) == (640, 480, 1)
    assert calibration.roi.width == 200 and calibration.roi.do_rectify
    assert calibration.summary() == "640x480 plumb_bob fx=500.0 fy=501.0 cx=320.0 cy=240.0"
    assert info.identity.serial == "123"
    assert info.time_base == sim.TimeBase.sensor_synchronized and info.time_sync == "PTP locked"
    assert info.point_time == sim.PointTime.none
    writer.close()


def test_a_stream_without_a_description_gives_none_and_generation_zero(stream_name):
    writer = sim.Writer(stream_name, capacity=16)
    reader = sim.Reader(stream_name)
    assert reader.sensor_info is None
    writer.write(b"x")
    assert reader.read().info.sensor_generation == 0


def test_set_sensor_info_changes_the_generation_of_the_next_frame(stream_name):
    writer = sim.Writer(stream_name, capacity=16, sensor=sim.SensorInfo(frame_id="lidar_top"))
    reader = sim.Reader(stream_name)
    writer.write(b"a")
    first = reader.read().info
    assert first.sensor_generation != 0 and first.as_dict()["sensor_generation"] == first.sensor_generation
    writer.set_sensor_info(sim.SensorInfo(frame_id="lidar_roof", point_time=sim.PointTime.after_frame_stamp))
    writer.write(b"b")
    assert reader.read().info.sensor_generation != first.sensor_generation
    assert reader.sensor_info.frame_id == "lidar_roof"
    assert reader.sensor_info.point_time == sim.PointTime.after_frame_stamp


def test_a_bad_description_is_refused_with_the_librarys_sentence(stream_name):
    bad = sim.SensorInfo(frame_id="lidar top")
    assert "holds a space" in bad.problem()
    with pytest.raises(sim.SimError, match="holds a space"):
        sim.Writer(stream_name, capacity=16, sensor=bad)
    writer = sim.Writer(stream_name, capacity=16)
    with pytest.raises(sim.SimError, match="unit quaternion"):
        writer.set_sensor_info(sim.SensorInfo(frame_id="lidar", mounting=sim.Mounting(rotation=[0, 0, 0, 2])))
    with pytest.raises(ValueError, match="k takes 9 numbers"):
        sim.CameraCalibration(width=1, height=1, k=[1, 2, 3])
    assert sim.frame_id_problem("base_link") == ""
    assert "starts with '/'" in sim.frame_id_problem("/base_link")


def test_a_damaged_description_raises_from_sensor_info_only_and_frames_keep_flowing(stream_name):
    writer = sim.Writer(stream_name, capacity=16, sensor=sim.SensorInfo(frame_id="lidar_top"))
    reader = sim.Reader(stream_name)
    # Another process damages the description in the region.
    with open("/dev/shm/sim." + stream_name[1:], "r+b") as region:
        region.seek(FRAME_ID_OFFSET)
        assert region.read(9) == b"lidar_top"
        region.seek(FRAME_ID_OFFSET)
        region.write(b"/")
    with pytest.raises(sim.SimError, match="sensor description is damaged: .*starts with '/'") as error:
        reader.sensor_info
    assert error.value.code == "region_invalid"
    writer.write(b"still")
    frame = reader.read()
    assert frame is not None and frame.array.tobytes() == b"still"
    assert reader.stats.frames == 1


def test_mounting_from_xyz_rpy_matches_tf2(stream_name):
    half = math.sqrt(0.5)
    np.testing.assert_allclose(sim.Mounting.from_xyz_rpy(0, 0, 0, 0, 0, math.pi / 2).rotation, [0, 0, half, half])
    np.testing.assert_allclose(
        sim.Mounting.from_xyz_rpy(0, 0, 0, math.pi / 2, 0, math.pi / 2).rotation, [0.5, 0.5, 0.5, 0.5]
    )


def test_reads_the_description_a_cpp_writer_in_another_process_set(stream_name, peer):
    writer = peer("describe", stream_name)
    writer.expect_line("ready")
    reader = sim.Reader(stream_name)
    frame = reader.read()
    assert frame is not None and frame.info.sensor_generation != 0
    info = reader.sensor_info
    assert (info.frame_id, info.parent_frame) == ("camera_left_optical", "base_link")
    np.testing.assert_array_equal(info.mounting.translation, [0.5, 0.25, 1.5])
    np.testing.assert_array_equal(info.mounting.rotation, [0.0, 0.0, 0.0, 1.0])
    calibration = info.calibration
    assert (calibration.width, calibration.height) == (1280, 720)
    assert calibration.distortion_model == "rational_polynomial"
    np.testing.assert_array_equal(calibration.d, [0.1, -0.2, 0.001, 0.002, 0.3, 0.01, 0.02, 0.03])
    np.testing.assert_array_equal(calibration.k, [[900, 0, 640], [0, 905, 360], [0, 0, 1]])
    np.testing.assert_array_equal(calibration.p, [[900, 0, 640, 0], [0, 905, 360, 0], [0, 0, 1, 0]])
    assert info.identity == sim.SensorIdentity(vendor="Lucid", model="TRI054S", serial="221000123", firmware="1.64")
    assert info.time_base == sim.TimeBase.sensor_synchronized and info.time_sync == "PTP slave, locked"
    code, _, err = writer.finish()
    assert code == 0, err
