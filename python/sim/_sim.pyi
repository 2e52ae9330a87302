"""Type stubs of the extension module sim._sim (see python/src/module.cpp)."""

from __future__ import annotations

import enum
from typing import Any, Iterator, Optional, Union

import numpy as np
import numpy.typing as npt

LIDAR_POINT_DTYPE: np.dtype[np.void]
"""x, y, z, intensity (float32), time_offset_ns (uint32), ring (uint16), return_index (uint8); 24 bytes."""

class SimError(RuntimeError):
    """An error from SIM; str(e) is the library's one-sentence explanation."""

    code: str
    """Its kind: 'invalid_name', 'not_found', 'writer_exists', 'permission_denied', 'closed',
    'too_large', 'loan_open', 'committed', 'region_invalid', …"""

class ReadStatus(enum.Enum):
    new_frame = 0
    no_new_frame = 1
    writer_gone = 2
    stale = 3
    checksum_mismatch = 4
    buffer_too_small = 5
    overrun = 6
    region_invalid = 7

class PixelFormat(enum.Enum):
    unknown = 0
    mono8 = 1
    mono16 = 2
    bgr8 = 3
    rgb8 = 4
    bgra8 = 5
    rgba8 = 6
    yuyv = 7
    uyvy = 8
    bayer_rggb8 = 9
    bayer_bggr8 = 10
    bayer_gbrg8 = 11
    bayer_grbg8 = 12
    mjpeg = 13

class PointType(enum.Enum):
    unknown = 0
    xyz32 = 1
    xyzi32 = 2
    lidar_point = 3

class LayoutKind(enum.Enum):
    bytes = 0
    image = 1
    points = 2

class Layout:
    """What a stream's payload looks like (stored in the stream)."""

    @staticmethod
    def raw() -> Layout: ...
    @staticmethod
    def image(width: int, height: int, format: Union[PixelFormat, str]) -> Layout: ...
    @staticmethod
    def points(max_points: int, type: Union[PointType, str] = "lidar_point") -> Layout: ...
    @property
    def kind(self) -> LayoutKind: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def channels(self) -> int: ...
    @property
    def stride(self) -> int: ...
    @property
    def format(self) -> PixelFormat: ...
    @property
    def bit_depth(self) -> int: ...
    @property
    def point_type(self) -> PointType: ...
    @property
    def point_size(self) -> int: ...
    @property
    def max_points(self) -> int: ...
    @property
    def min_capacity(self) -> int: ...
    @property
    def dtype(self) -> np.dtype[Any]: ...
    def describe(self) -> str: ...
    def __eq__(self, other: object) -> bool: ...

class FrameInfo:
    """What the writer said about a frame."""

    @property
    def seq(self) -> int: ...
    @property
    def stamp_ns(self) -> int: ...
    @property
    def publish_ns(self) -> int: ...
    @property
    def receive_ns(self) -> int: ...
    @property
    def size(self) -> int: ...
    @property
    def layout(self) -> Layout: ...
    @property
    def sensor_generation(self) -> int:
        """0 when the stream has no sensor description; changes whenever the writer sets one."""
    @property
    def clock_generation(self) -> int:
        """0 when the stream has no clock record; changes whenever the writer sets one."""
    @property
    def stamp_clock(self) -> StampClock: ...
    def as_dict(self) -> dict[str, Any]: ...

class ReaderStats:
    @property
    def frames(self) -> int: ...
    @property
    def skipped(self) -> int: ...
    @property
    def overruns(self) -> int: ...
    @property
    def checksum_failures(self) -> int: ...
    @property
    def reopens(self) -> int: ...

class Frame:
    """A copied frame; unpacks as (array, info)."""

    @property
    def array(self) -> npt.NDArray[Any]: ...
    @property
    def info(self) -> FrameInfo: ...
    def __iter__(self) -> Iterator[Any]: ...

class Borrow:
    """A frame read in place; its array is a read-only view that keeps the mapping alive."""

    @property
    def array(self) -> npt.NDArray[Any]: ...
    @property
    def info(self) -> FrameInfo: ...
    def still_valid(self) -> bool: ...

class Reader:
    def __init__(
        self,
        name: str,
        *,
        stale_after: float = 0.0,
        verify_checksum: bool = True,
        trust_owner: str = "",
        trust_group: str = "",
    ) -> None: ...
    def read(self) -> Optional[Frame]: ...
    def read_next(self, timeout: Optional[float]) -> Optional[Frame]: ...
    def wait(self, timeout: Optional[float]) -> bool: ...
    def borrow(self) -> Optional[Borrow]: ...
    def writer_alive(self) -> bool: ...
    def close(self) -> None: ...
    @property
    def closed(self) -> bool: ...
    @property
    def last_status(self) -> ReadStatus: ...
    @property
    def name(self) -> str: ...
    @property
    def capacity(self) -> int: ...
    @property
    def layout(self) -> Layout: ...
    @property
    def stats(self) -> ReaderStats: ...
    @property
    def sensor_info(self) -> Optional[SensorInfo]:
        """The stream's description (a copy) or None; raises SimError (code 'region_invalid') when
        the description in the stream is damaged, while frames keep flowing."""
    @property
    def clock(self) -> Optional[ClockStatus]:
        """The stream's clock record (a copy) or None; raises SimError when it is damaged."""
    def __enter__(self) -> Reader: ...
    def __exit__(self, *args: object) -> None: ...

class Loan:
    """The writer's back slot to fill in place; commit() publishes it."""

    @property
    def array(self) -> npt.NDArray[Any]: ...
    @property
    def capacity(self) -> int: ...
    def commit(
        self, nbytes: Optional[int] = None, *, stamp_ns: Optional[int] = None, receive_ns: int = 0
    ) -> None: ...

class Writer:
    def __init__(
        self,
        name: str,
        layout: Layout = ...,
        *,
        capacity: int = 0,
        checksum: bool = False,
        mode: int = 0o600,
        heartbeat_period: float = 0.0,
        sensor: Optional[SensorInfo] = None,
    ) -> None: ...
    def set_sensor_info(self, info: SensorInfo) -> None: ...
    def set_clock(self, clock: ClockStatus) -> None: ...
    def write(self, frame: Any, *, stamp_ns: Optional[int] = None, receive_ns: int = 0) -> None: ...
    def loan(self) -> Loan: ...
    def close(self) -> None: ...
    @property
    def closed(self) -> bool: ...
    @property
    def name(self) -> str: ...
    @property
    def capacity(self) -> int: ...
    @property
    def layout(self) -> Layout: ...
    @property
    def last_seq(self) -> int: ...
    def __enter__(self) -> Writer: ...
    def __exit__(self, *args: object) -> None: ...

class TimeBase(enum.Enum):
    unknown = 0
    host = 1
    sensor_synchronized = 2
    sensor_free_running = 3

class ClockSource(enum.Enum):
    unknown = 0
    host = 1
    ptp = 2
    gptp = 3
    pps_nmea = 4
    sync_pulse = 5
    free_running = 6
    replayed = 7

class ClockState(enum.Enum):
    unknown = 0
    locked = 1
    acquiring = 2
    holdover = 3
    free_running = 4

class ClockVerdict(enum.Enum):
    unknown = 0
    ok = 1
    warn = 2
    error = 3

class StampClock(enum.Enum):
    unknown = 0
    sensor = 1
    sensor_tai_corrected = 2
    host_arrival = 3

class ClockStatus:
    """A stream's clock: reported, measured against the host, judged (C++ sim::ClockStatus)."""
    source: ClockSource
    state: ClockState
    ptp_domain: int
    offset_from_master_ns: Optional[int]
    path_delay_ns: Optional[int]
    grandmaster: str
    utc_offset_s: Optional[int]
    ptp_timescale: bool
    tai_correction_ns: int
    reported_ns: int
    offset_to_host_ns: Optional[int]
    spread_ns: int
    drift_ppm: float
    steps: int
    last_step_ns: int
    packets_measured: int
    measured_ns: int
    verdict: ClockVerdict
    problem: str
    stamps: StampClock
    def __init__(self) -> None: ...
    def summary(self) -> str: ...
    def problem_text(self) -> str: ...

class PointTime(enum.Enum):
    none = 0
    after_frame_stamp = 1

class Mounting:
    """The sensor's frame in its parent: translation (m), rotation (x, y, z, w). Numpy copies."""

    def __init__(self, translation: Any = (0.0, 0.0, 0.0), rotation: Any = (0.0, 0.0, 0.0, 1.0)) -> None: ...
    @staticmethod
    def from_xyz_rpy(x: float, y: float, z: float, roll: float, pitch: float, yaw: float) -> Mounting: ...
    translation: npt.NDArray[np.float64]
    rotation: npt.NDArray[np.float64]
    def __eq__(self, other: object) -> bool: ...

class RegionOfInterest:
    def __init__(
        self, *, x_offset: int = 0, y_offset: int = 0, height: int = 0, width: int = 0, do_rectify: bool = False
    ) -> None: ...
    x_offset: int
    y_offset: int
    height: int
    width: int
    do_rectify: bool
    def __eq__(self, other: object) -> bool: ...

class CameraCalibration:
    """sensor_msgs/CameraInfo's calibration; d, k (3x3), r (3x3), p (3x4) are numpy copies."""

    def __init__(
        self,
        *,
        width: int = 0,
        height: int = 0,
        camera_name: str = "",
        distortion_model: str = "plumb_bob",
        d: Any = (),
        k: Any = None,
        r: Any = None,
        p: Any = None,
        binning_x: int = 0,
        binning_y: int = 0,
        roi: Optional[RegionOfInterest] = None,
    ) -> None: ...
    width: int
    height: int
    camera_name: str
    distortion_model: str
    d: npt.NDArray[np.float64]
    k: npt.NDArray[np.float64]
    r: npt.NDArray[np.float64]
    p: npt.NDArray[np.float64]
    binning_x: int
    binning_y: int
    roi: RegionOfInterest
    def summary(self) -> str: ...
    def __eq__(self, other: object) -> bool: ...

class SensorIdentity:
    def __init__(self, *, vendor: str = "", model: str = "", serial: str = "", firmware: str = "") -> None: ...
    vendor: str
    model: str
    serial: str
    firmware: str
    def __eq__(self, other: object) -> bool: ...

class SensorInfo:
    """What a stream says about its sensor (C++ sim::SensorInfo)."""

    def __init__(
        self,
        *,
        frame_id: str,
        parent_frame: str = "base_link",
        mounting: Optional[Mounting] = None,
        calibration: Optional[CameraCalibration] = None,
        identity: Optional[SensorIdentity] = None,
        calibration_source: str = "",
        time_base: TimeBase = TimeBase.unknown,
        time_sync: str = "",
        point_time: PointTime = PointTime.none,
    ) -> None: ...
    frame_id: str
    parent_frame: str
    mounting: Optional[Mounting]
    calibration: Optional[CameraCalibration]
    identity: SensorIdentity
    calibration_source: str
    time_base: TimeBase
    time_sync: str
    point_time: PointTime
    def problem(self) -> str:
        """Why a writer would refuse this description, in one sentence, or ""."""
    def __eq__(self, other: object) -> bool: ...

def frame_id_problem(frame: str) -> str: ...
def list_streams() -> list[str]: ...
def destroy(name: str, *, force: bool = False) -> None: ...
