"""SIM (Sensor-in-Memory): camera and LiDAR frames between processes through shared memory.

    import sim
    with sim.Reader("/camera_front") as reader:
        frame = reader.read_next(timeout=1.0)        # a copy: Frame(array, info) or None
        if frame is not None:
            image, info = frame                       # image.shape == (height, width, channels)
        borrowed = reader.borrow()                    # zero-copy: a read-only view into shared memory
        if borrowed is not None:
            mean = borrowed.array.mean()
            if not borrowed.still_valid():            # the writer overwrote it meanwhile
                mean = None

LiDAR frames are structured arrays of LIDAR_POINT_DTYPE (x, y, z, intensity, time_offset_ns,
ring, return_index: the fields of the C++ sim::LidarPoint). Errors raise SimError whose message
is the library's one-sentence explanation.

A stream may describe its sensor: `reader.sensor_info` is None or a SensorInfo (frame_id,
parent_frame, mounting, calibration with numpy K/R/P, identity, time base); a frame's
`info.sensor_generation` changes whenever the writer sets a new one (Writer(..., sensor=…),
writer.set_sensor_info(…)).

A stream may also carry its clock: `reader.clock` is None or a ClockStatus (source, state,
grandmaster, offset to the host, verdict and its problem sentence; `summary()` in one line); a
frame's `info.clock_generation` changes whenever the writer sets a new one (writer.set_clock(…)),
and `info.stamp_clock` says which clock its stamp is in.
"""

from ._sim import (
    LIDAR_POINT_DTYPE,
    Borrow,
    CameraCalibration,
    ClockSource,
    ClockState,
    ClockStatus,
    ClockVerdict,
    Frame,
    FrameInfo,
    Layout,
    LayoutKind,
    Loan,
    Mounting,
    PixelFormat,
    PointTime,
    PointType,
    Reader,
    ReaderStats,
    ReadStatus,
    RegionOfInterest,
    SensorIdentity,
    SensorInfo,
    SimError,
    StampClock,
    TimeBase,
    Writer,
    destroy,
    frame_id_problem,
    list_streams,
)

__all__ = [
    "LIDAR_POINT_DTYPE",
    "Borrow",
    "CameraCalibration",
    "ClockSource",
    "ClockState",
    "ClockStatus",
    "ClockVerdict",
    "Frame",
    "FrameInfo",
    "Layout",
    "LayoutKind",
    "Loan",
    "Mounting",
    "PixelFormat",
    "PointTime",
    "PointType",
    "Reader",
    "ReaderStats",
    "ReadStatus",
    "RegionOfInterest",
    "SensorIdentity",
    "SensorInfo",
    "SimError",
    "StampClock",
    "TimeBase",
    "Writer",
    "destroy",
    "frame_id_problem",
    "list_streams",
]
