// SPDX-License-Identifier: Apache-2.0
// The shared-memory format of one stream (internal). docs/protocol.md explains the protocol.
//
//   page 0   WaitPage      the only bytes readers may write: how many of them sleep on the futex
//   page 1   RegionHeader  written by the writer only; readers map it read-only
//   slot 0   payload       page aligned, `capacity` bytes
//   slot 1   payload
//
// Everything in shared memory is an offset or a fixed-width value, never a pointer.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::detail {

inline constexpr std::size_t kCacheLine = 64;
inline constexpr std::size_t kPage = 4096;
inline constexpr std::uint64_t kMagic = 0x314e474552'4d4953ull;  // "SIMREGN1", little-endian
inline constexpr std::uint32_t kVersion = 1;
// A slot's sequence word holds the frame number it contains, with this bit set while the writer
// is filling it. Frame numbers start at 1 and never reach 2^63.
inline constexpr std::uint64_t kWritingBit = 1ull << 63;
inline constexpr std::uint32_t kFlagChecksum = 1u << 0;
inline constexpr std::uint32_t kKnownFlags = kFlagChecksum;
inline constexpr std::uint64_t kMaxCapacity = 1ull << 40;  // 1 TiB per slot is beyond any sensor

static_assert(std::atomic<std::uint64_t>::is_always_lock_free);
static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
static_assert(sizeof(std::atomic<std::uint64_t>) == 8, "atomics must be plain words in shm");

// The layout as stored in the header: fixed-width fields only.
struct LayoutRecord {
  std::uint32_t kind;
  std::uint32_t pixel_format;
  std::uint32_t width;
  std::uint32_t height;
  std::uint32_t channels;
  std::uint32_t stride;
  std::uint32_t bit_depth;
  std::uint32_t point_type;
  std::uint32_t point_size;
  std::uint32_t reserved;
  std::uint64_t max_points;
};
static_assert(sizeof(LayoutRecord) == 48);

LayoutRecord to_record(const Layout& layout) noexcept;
Layout from_record(const LayoutRecord& record) noexcept;

// Page 0, written by readers that may write the region file (the owner's own readers); a
// group-readable region's other readers never write it (see Writer: it then wakes on every publish).
//
// `sleepers` is what the writer's fast path reads. A reader killed while asleep would leave it
// raised forever, so each reader that can also claims one of `asleep` by holding an OFD lock on
// the byte kReaderLockBase + index of the region file, and marks its slot while it sleeps. The
// kernel drops a dead reader's lock, so the writer (when a wake-up finds nobody) and the next
// reader to claim that slot can prove its owner is gone and take its mark back out of the count.
inline constexpr std::size_t kReaderSlots = (kPage - kCacheLine) / sizeof(std::uint64_t);
inline constexpr std::size_t kSpinLeases = 4;
struct alignas(kPage) WaitPage {
  alignas(kCacheLine) std::atomic<std::uint32_t> sleepers;  // readers in futex_wait or about to be
  std::uint32_t reserved0;
  // Added in place of padding (zero in regions of older writers, which is "free"): leases of the
  // adaptive readers spinning on this stream now. Each holds the CLOCK_MONOTONIC time its spin
  // ends, so a spinner killed mid-spin frees its lease by itself (wake_plan.hpp, SpinLeases).
  std::atomic<std::int64_t> spin_lease[kSpinLeases];
  // Per slot: 0, or the token of the slot's owner while it is counted in `sleepers`. Tokens are
  // unique per reader, so a stale mark is never mistaken for a new owner's (compare-exchange).
  alignas(kCacheLine) std::atomic<std::uint64_t> asleep[kReaderSlots];
};
static_assert(sizeof(WaitPage) == kPage);
static_assert(offsetof(WaitPage, asleep) == kCacheLine, "spin leases must stay in the padding");

// Byte-range locks on the region file (F_OFD_SETLK; ranges need not lie inside the file). Only
// exclusive locks count, and taking one needs write access: a reader that may only read the file
// can take shared locks, which nobody here looks at.
inline constexpr off_t kWriterLockByte = 0;   // held by the live writer for its whole life
inline constexpr off_t kRemoverLockByte = 1;  // held by destroy() while it checks and unlinks
inline constexpr off_t kReaderLockBase = 64;  // + slot index: held by the reader owning the slot

// Fixed when the region is created, before it becomes visible under its name.
struct alignas(kCacheLine) Identity {
  std::uint64_t magic;
  std::uint32_t version;
  std::uint32_t header_size;  // sizeof(RegionHeader)
  std::uint64_t file_size;
  std::uint64_t capacity;     // bytes per slot
  std::uint64_t slot_offset[2];
  std::uint32_t flags;
  std::uint32_t reserved;
  std::int64_t created_realtime_ns;
  LayoutRecord layout;
};

// Who writes now (or wrote last). Diagnostics only: liveness comes from the writer's file lock,
// which the kernel releases when the process dies, so a reused pid cannot fake a live writer.
struct alignas(kCacheLine) WriterIdentity {
  std::atomic<std::int32_t> pid;
  std::atomic<std::uint32_t> attach_count;   // writers that have owned this region so far
  std::atomic<std::int64_t> start_realtime_ns;
  std::atomic<std::uint64_t> command[2];      // process name, 16 bytes, NUL padded
};

struct alignas(kCacheLine) Publication {
  std::atomic<std::uint64_t> latest_seq;  // newest published frame; 0 before the first
  std::atomic<std::uint32_t> futex_word;  // +1 on every publish, by every writer; readers sleep on it
  std::atomic<std::uint32_t> retired;     // 1: a newer region replaced this one; reopen by name
  // 1: the writer wakes the futex on every publish (group-readable streams), so readers that may
  // not write the wait page can sleep too. Zero from writers that predate it: such readers poll.
  std::atomic<std::uint32_t> wakes_every_publish;
};

struct alignas(kCacheLine) Liveness {
  std::atomic<std::int64_t> heartbeat_ns;       // CLOCK_MONOTONIC
  std::atomic<std::int64_t> latest_publish_ns;  // CLOCK_MONOTONIC
  std::atomic<std::uint64_t> frames_published;
  std::atomic<std::int64_t> max_publish_interval_ns;
  // Added in place of padding (zero from writers that do not keep them): this writer's publish
  // period and its typical deviation, smoothed over recent frames (PeriodEstimate in writer.cpp).
  std::atomic<std::int64_t> period_ns;
  std::atomic<std::int64_t> jitter_ns;
  std::atomic<std::uint64_t> frames_this_writer;  // published since this writer attached
};
static_assert(sizeof(Liveness) == kCacheLine);

// Per-slot metadata, guarded by `seq` as a seqlock: valid only if `seq` reads the same (and
// without kWritingBit) before and after the metadata and payload are read.
struct alignas(kCacheLine) SlotMeta {
  std::atomic<std::uint64_t> seq;
  std::atomic<std::uint64_t> size;
  std::atomic<std::int64_t> stamp_ns;
  std::atomic<std::int64_t> publish_ns;
  std::atomic<std::uint64_t> checksum;
  // Added in place of padding (zero in regions whose writer did not set it): readers of either
  // age agree on every other field, so the format version stays 1.
  std::atomic<std::int64_t> receive_ns;
  // Added in place of padding (0, "unknown", from writers that predate it): the StampClock the
  // frame's stamp_ns is in, as the writer's clock record said when it published the frame.
  std::atomic<std::uint32_t> stamp_clock;
};
static_assert(sizeof(SlotMeta) == kCacheLine);

// The sensor description (sim/sensor_info.hpp) as stored: fixed-width fields only. Strings are
// NUL-terminated and NUL-padded; numbers are native-endian like every other field of the region.
inline constexpr std::size_t kNameField = 64;    // SensorInfo::kMaxName + its NUL
inline constexpr std::size_t kSourceField = 128;  // SensorInfo::kMaxSource + its NUL
inline constexpr std::uint32_t kSensorHasMounting = 1u << 0;
inline constexpr std::uint32_t kSensorHasCalibration = 1u << 1;
inline constexpr std::uint32_t kSensorKnownFlags = kSensorHasMounting | kSensorHasCalibration;
struct SensorRecord {
  std::uint32_t flags;       // kSensorHas*
  std::uint32_t time_base;   // TimeBase
  std::uint32_t point_time;  // PointTime
  std::uint32_t reserved;
  char frame_id[kNameField];
  char parent_frame[kNameField];
  char vendor[kNameField];
  char model[kNameField];
  char serial[kNameField];
  char firmware[kNameField];
  char calibration_source[kSourceField];
  char time_sync[kSourceField];
  double translation[3];
  double rotation[4];  // x, y, z, w
  // The camera calibration, meaningful with kSensorHasCalibration only.
  std::uint32_t width;
  std::uint32_t height;
  char camera_name[kNameField];
  char distortion_model[kNameField];
  std::uint32_t distortion_count;  // entries of `d` in use, at most 16
  std::uint32_t binning_x;
  std::uint32_t binning_y;
  std::uint32_t roi_x_offset;
  std::uint32_t roi_y_offset;
  std::uint32_t roi_height;
  std::uint32_t roi_width;
  std::uint32_t roi_do_rectify;  // 0 or 1
  double d[16];
  double k[9];
  double r[9];
  double p[12];
};
static_assert(sizeof(SensorRecord) == 1248, "the record has no padding: readers compare it bytewise");

// The description and its seqlock word. The word is 0 in a region whose writers never set a
// description (and in regions of writers that predate it), so the format stays version 1:
//   bit 0      set while the writer rewrites `record` (readers copy again)
//   bit 1      a description is present (clear: the writer has none)
//   bits 2..63 the generation: +1 on every change, carried over when a region is replaced
// FrameInfo::sensor_generation is the generation while bit 1 is set, else 0.
inline constexpr std::uint64_t kSensorWriting = 1;
inline constexpr std::uint64_t kSensorPresent = 2;
inline constexpr std::uint64_t kSensorGenerationStep = 4;
struct alignas(kCacheLine) SensorBlock {
  std::atomic<std::uint64_t> word;
  std::uint64_t reserved[7];
  SensorRecord record;
};

// The clock record (sim/clock_status.hpp) as stored: fixed-width fields only, no padding.
// Optional numbers are a flag bit and a value (zero when the bit is clear); strings are
// NUL-terminated and NUL-padded. It has its own seqlock word, with the same bits as the sensor
// description's (kSensorWriting, kSensorPresent, generation in steps of kSensorGenerationStep),
// so a clock that changes every second never makes readers re-read the calibration.
inline constexpr std::size_t kGrandmasterField = 24;  // ClockStatus::kMaxGrandmaster + its NUL
inline constexpr std::size_t kProblemField = 256;     // ClockStatus::kMaxProblem + its NUL
inline constexpr std::uint32_t kClockHasOffsetFromMaster = 1u << 0;
inline constexpr std::uint32_t kClockHasPathDelay = 1u << 1;
inline constexpr std::uint32_t kClockHasUtcOffset = 1u << 2;
inline constexpr std::uint32_t kClockHasOffsetToHost = 1u << 3;
inline constexpr std::uint32_t kClockPtpTimescale = 1u << 4;
inline constexpr std::uint32_t kClockKnownFlags = (1u << 5) - 1;
struct ClockRecord {
  std::uint32_t flags;  // kClock*
  std::uint32_t source;
  std::uint32_t state;
  std::int32_t ptp_domain;
  std::int64_t offset_from_master_ns;
  std::int64_t path_delay_ns;
  std::int32_t utc_offset_s;
  std::uint32_t verdict;
  std::int64_t tai_correction_ns;
  std::int64_t reported_ns;
  std::int64_t offset_to_host_ns;
  std::int64_t spread_ns;
  double drift_ppm;
  std::uint32_t steps;
  std::uint32_t stamps;
  std::int64_t last_step_ns;
  std::uint64_t packets_measured;
  std::int64_t measured_ns;
  char grandmaster[kGrandmasterField];
  char problem[kProblemField];
};
static_assert(sizeof(ClockRecord) == 392, "the record has no padding: readers compare it bytewise");

struct alignas(kCacheLine) ClockBlock {
  std::atomic<std::uint64_t> word;  // as SensorBlock::word
  std::uint64_t reserved[7];
  ClockRecord record;
};

// The writer's whole program name ("sim_replay_video"), of which WriterIdentity::command keeps
// the kernel's 15 characters ("sim_replay_vide"). NUL-terminated and NUL-padded. Readers show it
// only when it continues a 15-character `command`: all zero (writers that predate it) or a name
// that does not (left by an earlier writer, which a writer that predates it does not clear)
// shows `command` instead, so the format stays version 1.
inline constexpr std::size_t kProgramField = 256;
struct alignas(kCacheLine) ProgramName {
  std::atomic<std::uint64_t> words[kProgramField / 8];
};

struct alignas(kPage) RegionHeader {
  Identity identity;
  WriterIdentity writer;
  Publication publication;
  Liveness liveness;
  SlotMeta slots[2];
  // Added in place of padding (zero from older writers: no description).
  SensorBlock sensor;
  // Added in place of padding (zero from older writers: the 15 characters of `writer.command`).
  ProgramName program;
  // Added in place of padding (zero from older writers: no clock record).
  ClockBlock clock;
};
static_assert(sizeof(RegionHeader) == kPage);
static_assert(offsetof(RegionHeader, clock) == 2048, "the clock record stays in the old padding");
static_assert(offsetof(RegionHeader, sensor) == 448, "the sensor block stays in the old padding");
static_assert(offsetof(RegionHeader, program) == 1792, "the program name stays in the old padding");

inline constexpr std::uint64_t kHeaderOffset = kPage;
inline constexpr std::uint64_t kFirstSlotOffset = 2 * kPage;

constexpr std::uint64_t round_up_to_page(std::uint64_t n) { return (n + kPage - 1) / kPage * kPage; }

// Where the slots go and how large the file is for a given capacity.
struct Geometry {
  std::uint64_t slot_offset[2];
  std::uint64_t file_size;
};
constexpr Geometry geometry_for(std::uint64_t capacity) {
  const std::uint64_t slot_bytes = round_up_to_page(capacity);
  return {{kFirstSlotOffset, kFirstSlotOffset + slot_bytes}, kFirstSlotOffset + 2 * slot_bytes};
}

// Empty if `name` is a valid stream name ("/" then 1–200 of [A-Za-z0-9_.-], not "." or "..").
std::string name_problem(std::string_view name);
// /dev/shm/sim.<name without its slash>
std::string region_path(std::string_view name);
inline constexpr std::string_view kRegionDir = "/dev/shm";
inline constexpr std::string_view kRegionPrefix = "sim.";

// Checks a header the caller must not trust against the file it came from. Empty if valid.
std::string header_problem(const Identity& identity, std::uint64_t file_size);

// Open-file-description locks on one byte of the region file. The kernel drops them when the
// last descriptor of the open file goes, however its process ends.
bool try_lock_byte(int fd, off_t byte, bool exclusive) noexcept;
void unlock_byte(int fd, off_t byte) noexcept;
// Whether another open file holds an exclusive lock on `byte`.
bool byte_locked(int fd, off_t byte) noexcept;
// Waits until no other open file holds an exclusive lock on `byte` (a remover holds it for
// microseconds and never waits while holding it).
void wait_until_unlocked(int fd, off_t byte) noexcept;

inline bool try_lock_writer(int fd) noexcept { return try_lock_byte(fd, kWriterLockByte, true); }
inline bool writer_lock_held(int fd) noexcept { return byte_locked(fd, kWriterLockByte); }
inline void unlock_writer(int fd) noexcept { unlock_byte(fd, kWriterLockByte); }

// `text` with every byte outside printable ASCII shown as \xNN, for error messages.
std::string printable(std::string_view text);

// Stores the caller's names for readers: the kernel's process name in `writer.command` and, when
// the kernel cut it to 15 characters, the whole program name in `program` (else zeros).
void store_writer_names(WriterIdentity& writer, ProgramName& program);
// The writer's whole program name, or its process name where no longer one continues it;
// bytes outside printable ASCII are shown as '?'.
std::string writer_name(const WriterIdentity& writer, const ProgramName& program);

Error errno_error(ErrorCode code, std::string what, int err);

// "alice (uid 1000)", or "uid 1000" for a user with no name here (trust.cpp); likewise groups.
std::string user_name(uid_t uid);
std::string group_name(gid_t gid);

}  // namespace sim::detail
