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
  SIM_EOVERRUN = -8         /* the writer kept overwriting the frame during the copy; retry */
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

/* Removes the stream's region; refused (<0) while its writer is alive. */
int SIM_destroy(const char *name);
/* The last error of this thread, in one sentence; "" after a call that succeeded. The pointer
 * stays valid for the thread's whole life; its text changes with the thread's next SIM_ call. */
const char *SIM_lastError(void);

#ifdef __cplusplus
}
#endif

#endif /* SIM_SIM_H */
