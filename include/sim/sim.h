/* SPDX-License-Identifier: Apache-2.0 */
/* The C API of SIM: the five calls of the SIM paper, with handles. Usable from C and C++.
 *
 *   sim_writer *w = SIM_writerInit("/camera_front", 640 * 480 * 3);
 *   SIM_writeData(w, frame, size);
 *   sim_reader *r = SIM_readerInit("/camera_front", sizeof buf);
 *   long long n = SIM_readData(r, buf, sizeof buf, &info);
 *
 * Errors are negative SIM_E* codes; SIM_lastError() says what happened in one sentence.
 * An empty frame (a LiDAR revolution with no returns) is a frame: SIM_readData returns 0 for it
 * and sets info->seq, which is 0 exactly when nothing new was delivered. */
#ifndef SIM_SIM_H
#define SIM_SIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sim_writer sim_writer;
typedef struct sim_reader sim_reader;

typedef struct sim_frame_info {
  uint64_t seq;        /* 1 for the first frame ever published on the stream; 0: no frame delivered */
  int64_t stamp_ns;    /* sensor time, CLOCK_REALTIME */
  int64_t publish_ns;  /* publish time, CLOCK_MONOTONIC */
  uint64_t size;       /* bytes */
  int64_t receive_ns;  /* when the host received the frame's first data, CLOCK_REALTIME; 0 if unknown */
} sim_frame_info;

enum {
  SIM_EINVAL = -1,          /* a NULL handle or buffer, or an impossible argument */
  SIM_ETOOLARGE = -2,       /* the frame is larger than the stream's capacity */
  SIM_EBUFFER = -3,         /* the caller's buffer is smaller than the newest frame */
  SIM_ECHECKSUM = -4,       /* the newest frame failed its checksum and was dropped */
  SIM_EWRITERGONE = -5,     /* nothing new and no writer is alive; it may come back */
  SIM_ESTALE = -6,          /* nothing new and the newest frame is older than the deadline */
  SIM_EREGION = -7,         /* the region failed validation */
  SIM_EOVERRUN = -8,        /* the writer kept overwriting the frame during the copy; retry */
  SIM_ETIMEDOUT = -9,       /* SIM_waitsetWait: no stream had a new frame before the timeout */
  SIM_EWOKEN = -10          /* SIM_waitsetWait: ended early by SIM_waitsetWake */
};

/* Creates or takes over the stream; NULL on error (see SIM_lastError). */
sim_writer *SIM_writerInit(const char *name, size_t capacity);
/* Copies one frame in and publishes it: 0, or a negative SIM_E* code. */
int SIM_writeData(sim_writer *w, const void *data, size_t size);
void SIM_writerClose(sim_writer *w);

/* Opens an existing stream of this user whose frames fit in `capacity` bytes (0: any); NULL on
 * error. */
sim_reader *SIM_readerInit(const char *name, size_t capacity);
/* The same for a stream another user writes: its region must belong to `trust_owner` (a user name
 * or uid) and/or to `trust_group` (a group name or gid, whose every member is then trusted); NULL
 * or "" leaves that part unchecked, both NULL is SIM_readerInit. A region of anyone else is
 * refused, and SIM_lastError names its actual owner. */
sim_reader *SIM_readerInitTrusting(const char *name, size_t capacity, const char *trust_owner,
                                   const char *trust_group);
/* >0: bytes of a frame newer than the last one returned; 0: nothing new, or an empty frame
 * (info->seq tells: 0 for nothing new); <0: SIM_E* code. `info` may be NULL. */
long long SIM_readData(sim_reader *r, void *buf, size_t size, sim_frame_info *info);
/* Sleeps until a newer frame is published: 1 new frame, 0 timeout, <0 SIM_E* code.
 * timeout_ms < 0 waits for ever. */
int SIM_waitData(sim_reader *r, int timeout_ms);
void SIM_readerClose(sim_reader *r);

/* How SIM_waitData waits (see sim::WaitMode): SIM_WAIT_BLOCK sleeps until a publish (default),
 * SIM_WAIT_POLL spins (one core), SIM_WAIT_ADAPTIVE sleeps until shortly before the writer's next
 * expected publish and spins briefly. 0, or SIM_EINVAL. */
enum { SIM_WAIT_BLOCK = 0, SIM_WAIT_POLL = 1, SIM_WAIT_ADAPTIVE = 2 };
int SIM_readerSetWaitMode(sim_reader *r, int mode);

/* Several streams at once (sim::WaitSet). The readers must outlive the set. */
typedef struct sim_waitset sim_waitset;
sim_waitset *SIM_waitsetCreate(void);
/* Adds a reader: its index in the set (0, 1, ...), or a negative SIM_E* code. */
int SIM_waitsetAdd(sim_waitset *ws, sim_reader *r);
/* Sleeps until a reader of the set has a new frame: its index (>= 0), SIM_ETIMEDOUT, SIM_EWOKEN,
 * or SIM_EINVAL. timeout_ms < 0 waits for ever. */
int SIM_waitsetWait(sim_waitset *ws, int timeout_ms);
/* From any thread (not racing SIM_waitsetClose): the current or next SIM_waitsetWait returns
 * SIM_EWOKEN at once (sim::Wakeup). 0, or SIM_EINVAL. */
int SIM_waitsetWake(sim_waitset *ws);
/* 1 if reader `index` has a new frame now, else 0. */
int SIM_waitsetReady(const sim_waitset *ws, int index);
void SIM_waitsetClose(sim_waitset *ws);

/* A file descriptor that becomes readable when any of the named streams has a new frame, for
 * epoll/poll loops (sim::StreamNotifier). NULL on error (see SIM_lastError). */
typedef struct sim_notifier sim_notifier;
sim_notifier *SIM_notifierOpen(const char *const *names, size_t count);
int SIM_notifierFd(const sim_notifier *n);
/* Resets the fd; sets arrived[i] (count entries, may be NULL) to 1 for each stream with new
 * frames. Returns how many streams had new frames. */
int SIM_notifierDrain(sim_notifier *n, int *arrived, size_t count);
void SIM_notifierClose(sim_notifier *n);

/* The sensor that makes a stream's frames (sim::SensorInfo): its frame and mounting, a camera's
 * calibration, the unit's identity and the time base of its stamps. Strings are NUL-terminated
 * within their arrays; matrices are row-major. */
enum { SIM_NAME_MAX = 64, SIM_SOURCE_MAX = 128, SIM_DISTORTION_MAX = 16 };
enum {
  SIM_TIME_BASE_UNKNOWN = 0,
  SIM_TIME_BASE_HOST = 1,                /* the host's CLOCK_REALTIME when the data arrived */
  SIM_TIME_BASE_SENSOR_SYNCHRONIZED = 2, /* the sensor's clock, synchronised (PTP, PPS) to UTC */
  SIM_TIME_BASE_SENSOR_FREE_RUNNING = 3  /* the sensor's own clock, not synchronised */
};
enum { SIM_POINT_TIME_NONE = 0, SIM_POINT_TIME_AFTER_FRAME_STAMP = 1 };
typedef struct sim_camera_calibration {
  uint32_t width, height;
  char camera_name[SIM_NAME_MAX];
  char distortion_model[SIM_NAME_MAX]; /* "plumb_bob", "rational_polynomial", "equidistant", ... */
  uint32_t distortion_count;           /* entries of d in use, at most SIM_DISTORTION_MAX */
  double d[SIM_DISTORTION_MAX];
  double k[9];
  double r[9];
  double p[12];
  uint32_t binning_x, binning_y;
  uint32_t roi_x_offset, roi_y_offset, roi_height, roi_width;
  int roi_do_rectify;
} sim_camera_calibration;
typedef struct sim_sensor_info {
  char frame_id[SIM_NAME_MAX];     /* the sensor's frame, e.g. "lidar_top" */
  char parent_frame[SIM_NAME_MAX]; /* e.g. "base_link" */
  int has_mounting;                /* 1: translation (m) and rotation (x, y, z, w) are known */
  double translation[3];
  double rotation[4];
  int has_calibration; /* 1: a camera with a calibration */
  sim_camera_calibration calibration;
  char vendor[SIM_NAME_MAX], model[SIM_NAME_MAX], serial[SIM_NAME_MAX], firmware[SIM_NAME_MAX];
  char calibration_source[SIM_SOURCE_MAX];
  int time_base; /* SIM_TIME_BASE_* */
  char time_sync[SIM_SOURCE_MAX];
  int point_time; /* SIM_POINT_TIME_* */
} sim_sensor_info;
/* Sets (or replaces) the stream's sensor description: 0, or SIM_EINVAL with SIM_lastError saying
 * what is wrong with it (a bad frame name, a non-unit quaternion, ...). Frames published from now
 * on carry a new sensor generation. */
int SIM_writerSetSensorInfo(sim_writer *w, const sim_sensor_info *info);
/* Copies the stream's sensor description into *out: 1 copied, 0 the stream has none, SIM_EREGION
 * when the description in the stream is damaged (frames still flow; SIM_lastError says what). */
int SIM_readerSensorInfo(sim_reader *r, sim_sensor_info *out);
/* The sensor generation of the frame SIM_readData delivered last (0: none, or the stream has no
 * description). It changes whenever the writer sets a new description: call SIM_readerSensorInfo
 * again then. (Not in sim_frame_info, whose size programs built against older headers rely on.) */
uint64_t SIM_readerSensorGeneration(const sim_reader *r);

/* A stream's clock as data (sim::ClockStatus, sim/clock_status.hpp): where its stamps come from,
 * what the sensor reports of its synchronisation, what the driver measured against the host, and
 * the verdict. Optional numbers come with a has_ flag. */
enum {
  SIM_CLOCK_SOURCE_UNKNOWN = 0, SIM_CLOCK_SOURCE_HOST = 1, SIM_CLOCK_SOURCE_PTP = 2,
  SIM_CLOCK_SOURCE_GPTP = 3, SIM_CLOCK_SOURCE_PPS_NMEA = 4, SIM_CLOCK_SOURCE_SYNC_PULSE = 5,
  SIM_CLOCK_SOURCE_FREE_RUNNING = 6, SIM_CLOCK_SOURCE_REPLAYED = 7
};
enum {
  SIM_CLOCK_STATE_UNKNOWN = 0, SIM_CLOCK_STATE_LOCKED = 1, SIM_CLOCK_STATE_ACQUIRING = 2,
  SIM_CLOCK_STATE_HOLDOVER = 3, SIM_CLOCK_STATE_FREE_RUNNING = 4
};
enum { SIM_CLOCK_UNKNOWN = 0, SIM_CLOCK_OK = 1, SIM_CLOCK_WARN = 2, SIM_CLOCK_ERROR = 3 };
enum {
  SIM_STAMP_UNKNOWN = 0, SIM_STAMP_SENSOR = 1, SIM_STAMP_SENSOR_TAI_CORRECTED = 2,
  SIM_STAMP_HOST_ARRIVAL = 3
};
enum { SIM_GRANDMASTER_MAX = 24, SIM_PROBLEM_MAX = 256 };
typedef struct sim_clock_status {
  int source, state, ptp_domain; /* SIM_CLOCK_SOURCE_*, SIM_CLOCK_STATE_*, -1 unknown */
  int has_offset_from_master, has_path_delay, has_utc_offset, has_offset_to_host;
  int64_t offset_from_master_ns, path_delay_ns;
  char grandmaster[SIM_GRANDMASTER_MAX]; /* "xxxxxx.xxxx.xxxxxx", "" unknown */
  int32_t utc_offset_s;                  /* TAI - UTC announced by the master */
  int ptp_timescale;
  int64_t tai_correction_ns, reported_ns;
  int64_t offset_to_host_ns, spread_ns; /* sensor - host, measured */
  double drift_ppm;
  uint32_t steps;
  int64_t last_step_ns;
  uint64_t packets_measured;
  int64_t measured_ns;
  int verdict;                   /* SIM_CLOCK_OK, ... */
  char problem[SIM_PROBLEM_MAX]; /* one sentence, "" when ok */
  int stamps;                    /* SIM_STAMP_*: the clock frames are stamped in now */
} sim_clock_status;
/* Sets (or replaces) the stream's clock record: 0, or SIM_EINVAL with SIM_lastError saying what
 * is wrong. Frames published from now on carry clock->stamps (SIM_readerStampClock). */
int SIM_writerSetClock(sim_writer *w, const sim_clock_status *clock);
/* Copies the stream's clock record into *out: 1 copied, 0 the stream has none, SIM_EREGION when
 * the record is damaged (frames still flow; SIM_lastError says what). */
int SIM_readerClock(sim_reader *r, sim_clock_status *out);
/* Of the frame SIM_readData delivered last: the clock record's generation (call SIM_readerClock
 * when it changed) and the SIM_STAMP_* clock its stamp is in. */
uint64_t SIM_readerClockGeneration(const sim_reader *r);
int SIM_readerStampClock(const sim_reader *r);

/* Removes the stream's region; refused (<0) while its writer is alive. */
int SIM_destroy(const char *name);
/* The last error of this thread, in one sentence; "" after a call that succeeded. The pointer
 * stays valid for the thread's whole life; its text changes with the thread's next SIM_ call. */
const char *SIM_lastError(void);

#ifdef __cplusplus
}
#endif

#endif /* SIM_SIM_H */
