// SPDX-License-Identifier: Apache-2.0
// The V4L2 driver: device frames → decoder → writer's slot, driven by poll(). It survives the
// camera going away: the stream's region stays (readers see it go stale), the device is retried
// until it returns, and capture resumes on the same stream.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/camera/camera_clock.hpp"
#include "sim/camera/clock_mapping.hpp"
#include "sim/imaging/decoder.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim/camera/v4l2_device.hpp"
#include "sim/camera/v4l2_io.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/writer.hpp"

namespace sim::camera {

enum class TimestampSource : std::uint8_t {
  device,   // the buffer's V4L2 timestamp (start of exposure or end of transfer), to realtime
  receive,  // CLOCK_REALTIME when the buffer was dequeued
};

struct ControlSetting {
  std::string key;
  std::string value;
};

struct V4l2CaptureConfig {
  std::string device = "/dev/video0";
  std::string stream = "/camera_front";
  FormatRequest format;
  std::vector<ControlSetting> controls;
  std::uint32_t buffers = 4;
  TimestampSource timestamps = TimestampSource::device;
  std::int64_t time_offset_ns = 0;  // added to every stamp (fixed latency compensation)
  // No frame for this long while streaming: the stream is restarted, as after an unplug.
  std::chrono::milliseconds frame_timeout{3000};
  std::chrono::milliseconds retry_period{500};  // between attempts to reopen a lost device
  bool checksum = false;
  // The stream's description (frame, mounting, calibration); the capture adds the device (card
  // as the model, bus as where it is plugged) and the clock of the stamps. A calibration of
  // another size than the frames: start() fails (invalid_argument); after a reconnect in another
  // size the calibration is dropped with a log line. nullopt: no description.
  std::optional<SensorInfo> sensor;
  // Status messages (device lost, reconnected, …); none when empty.
  std::function<void(std::string_view)> log;
  // The clock check: each frame's stamp against its arrival, judged with the reported clock
  // (reported_clock()) and the host's (`host_clock`; empty: unknown) and written to the stream's
  // clock record about once a second, within a camera's tolerance.
  timing::ClockTolerance clock_tolerance = camera_clock_tolerance();
  std::function<ClockStatus()> host_clock;
};

struct CaptureStats {
  std::uint64_t published = 0;
  std::uint64_t dropped = 0;        // gaps in the V4L2 sequence: frames the device lost
  std::uint64_t corrupt = 0;        // compressed frames that did not decode
  std::uint64_t bad_size = 0;       // short buffers or frames of another size
  std::uint64_t device_errors = 0;  // buffers flagged V4L2_BUF_FLAG_ERROR
  std::uint64_t timeouts = 0;       // stalls longer than frame_timeout
  std::uint64_t device_losses = 0;
  std::uint64_t reconnects = 0;
};

enum class StepResult : std::uint8_t {
  published,     // a frame went into the stream
  skipped,       // a frame arrived but was bad (counted in the stats) and not published
  no_frame,      // nothing arrived within the step's timeout
  device_lost,   // the device went away just now; the next steps try to reopen it
  reconnected,   // the device is back and streaming again
  disconnected,  // still waiting for the device
};

const char* to_string(StepResult result) noexcept;

// The clock of a V4L2 stream's stamps after a buffer stamped with `clock` (sim::ClockStatus):
// source host (V4L2 stamps with the host's monotonic clock, mapped to realtime per frame), state
// unknown (the host's own synchronisation is judged apart), stamps sensor for the buffer's stamp,
// host_arrival for receive time. A buffer whose clock is UNKNOWN or COPY cannot be mapped: the
// frames carry the receive time, and the record says so with a warning.
ClockStatus v4l2_clock_status(TimestampSource timestamps, BufferClock clock, std::int64_t reported_ns);

class V4l2Capture {
 public:
  // Opens the device, applies the controls, negotiates, creates the stream and starts
  // streaming. One sentence on failure.
  static Expected<V4l2Capture> start(V4l2Io& io, V4l2CaptureConfig config);

  V4l2Capture(V4l2Capture&&) noexcept = default;
  V4l2Capture& operator=(V4l2Capture&&) noexcept = default;
  V4l2Capture(const V4l2Capture&) = delete;
  V4l2Capture& operator=(const V4l2Capture&) = delete;
  ~V4l2Capture() = default;

  // Waits up to `timeout` for one frame (or one reconnect attempt) and handles it.
  StepResult step(std::chrono::milliseconds timeout);
  // Steps until `stop` is set; `on_step` (optional) sees each result, e.g. for a status line.
  void run(const std::atomic<bool>& stop,
           const std::function<void(StepResult, const V4l2Capture&)>& on_step = {});

  const CaptureStats& stats() const noexcept { return stats_; }
  const StreamFormat& format() const noexcept { return format_; }
  const ImageLayout& output_layout() const noexcept { return decoder_->output_layout(); }
  const Writer& writer() const noexcept { return *writer_; }
  bool connected() const noexcept { return device_.has_value(); }
  // The clock of the stream's stamps as the buffers' flags say (v4l2_clock_status), readable from
  // any thread: hand it to the clock reporter. Refreshed when the buffers' clock changes and
  // once a second; source host, stamps unknown before the first frame.
  ReportedClock reported_clock() const { return reported_; }

 private:
  V4l2Capture(V4l2Io& io, V4l2CaptureConfig config) noexcept;
  // Open + controls + negotiate + decoder + (re)create writer + start streaming.
  std::optional<Error> connect(bool first);
  // config_.sensor completed for `device` with frames of `output`; the calibration size checked
  // (an error on the first connect, dropped with a log line after).
  Expected<std::optional<SensorInfo>> describe(const V4l2Device& device, const ImageLayout& output,
                                               bool first) const;
  void disconnect() noexcept;
  void log(const std::string& message) const;
  StepResult handle(const DeviceFrame& frame);
  // The reported clock after a frame stamped with `clock` arrived at `received`.
  void report_clock(BufferClock clock, std::int64_t received);

  V4l2Io* io_ = nullptr;
  V4l2CaptureConfig config_;
  std::optional<V4l2Device> device_;
  std::optional<imaging::FrameDecoder> decoder_;
  std::optional<Writer> writer_;
  std::optional<SensorInfo> sensor_;  // the description the stream carries
  StreamFormat format_{};
  CaptureStats stats_{};
  MonotonicToRealtime clock_;
  ReportedClock reported_;
  timing::ClockReporter clock_check_;
  std::optional<BufferClock> reported_for_;  // the buffers' clock of the last report
  std::int64_t reported_at_ = 0;             // CLOCK_REALTIME of the last report
  std::optional<std::uint32_t> last_sequence_;
  std::chrono::steady_clock::time_point last_frame_{};
  std::chrono::steady_clock::time_point next_retry_{};
};

}  // namespace sim::camera
