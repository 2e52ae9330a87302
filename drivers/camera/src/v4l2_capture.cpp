// SPDX-License-Identifier: Apache-2.0
#include "sim/camera/v4l2_capture.hpp"

#include "sim/apps/camera_info_file.hpp"

#include <algorithm>
#include <thread>
#include <utility>

#include "sim/clock.hpp"

namespace sim::camera {

const char* to_string(StepResult result) noexcept {
  switch (result) {
    case StepResult::published: return "published";
    case StepResult::skipped: return "skipped";
    case StepResult::no_frame: return "no_frame";
    case StepResult::device_lost: return "device_lost";
    case StepResult::reconnected: return "reconnected";
    case StepResult::disconnected: return "disconnected";
  }
  return "?";
}

ClockStatus v4l2_clock_status(TimestampSource timestamps, BufferClock clock, std::int64_t reported_ns) {
  ClockStatus status;
  status.source = ClockSource::host;  // the host's own synchronisation is judged apart
  status.reported_ns = reported_ns;
  status.stamps = StampClock::host_arrival;
  if (timestamps == TimestampSource::receive) return status;
  switch (clock) {
    case BufferClock::monotonic:
      status.stamps = StampClock::sensor;  // the buffer's own stamp, mapped to realtime per frame
      return status;
    case BufferClock::unknown:
      status.problem =
          "the V4L2 driver gives its buffers no stamp of a known clock (TIMESTAMP_UNKNOWN, or none), so the "
          "frames carry the host receive time instead, late by the exposure and the transfer; say --timestamps "
          "receive";
      break;
    case BufferClock::copy:
      status.problem =
          "the V4L2 buffers' stamps are copied from an output queue (TIMESTAMP_COPY, a memory-to-memory "
          "device) and say nothing of this capture, so the frames carry the host receive time instead; say "
          "--timestamps receive";
      break;
  }
  status.verdict = ClockVerdict::warn;
  return status;
}

V4l2Capture::V4l2Capture(V4l2Io& io, V4l2CaptureConfig config) noexcept
    : io_(&io), config_(std::move(config)), clock_check_(config_.clock_tolerance) {
  ClockStatus before;
  before.source = ClockSource::host;
  if (config_.timestamps == TimestampSource::receive) before.stamps = StampClock::host_arrival;
  reported_.set(before);
  clock_check_.set_sources({reported_, config_.host_clock});
}

void V4l2Capture::report_clock(BufferClock clock, std::int64_t received) {
  // Not per frame: when the buffers' clock changes, and once a second for reported_ns.
  if (reported_for_ == clock && received - reported_at_ < 1'000'000'000) return;
  const ClockStatus status = v4l2_clock_status(config_.timestamps, clock, received);
  if (reported_for_ != clock && !status.problem.empty()) log("warning: " + status.problem);
  reported_.set(status);
  reported_for_ = clock;
  reported_at_ = received;
}

Expected<V4l2Capture> V4l2Capture::start(V4l2Io& io, V4l2CaptureConfig config) {
  if (config.buffers < 2 || config.buffers > 32) {
    return Error{ErrorCode::invalid_argument, "--buffers must be 2 to 32"};
  }
  V4l2Capture capture(io, std::move(config));
  if (auto error = capture.connect(true)) return *error;
  return capture;
}

void V4l2Capture::log(const std::string& message) const {
  if (config_.log) config_.log(message);
}

std::optional<Error> V4l2Capture::connect(bool first) {
  auto device = V4l2Device::open(*io_, config_.device);
  if (!device) return device.error();
  for (const auto& control : config_.controls) {
    if (auto error = device->set_control(control.key, control.value)) {
      if (first) return error;
      log("warning: " + error->message);  // a control should not keep a camera offline
    }
  }
  auto format = device->negotiate(config_.format);
  if (!format) return format.error();
  auto decoder = imaging::FrameDecoder::create(format->layout, config_.format.output);
  if (!decoder) return decoder.error();
  auto described = describe(*device, decoder->output_layout(), first);
  if (!described) return described.error();

  const Layout layout = Layout::of(decoder->output_layout());
  // A device that announces no sizeimage for MJPEG still needs room: two bytes a pixel is more
  // than any camera JPEG at usable quality.
  const std::uint64_t max_jpeg = format->size_image != 0
                                     ? format->size_image
                                     : std::uint64_t{format->layout.width} * format->layout.height * 2;
  const std::uint64_t capacity = decoder->output_capacity(max_jpeg);
  if (!writer_ || writer_->layout() != layout || writer_->capacity() != capacity) {
    if (writer_) log("the camera came back with another format; the stream is recreated");
    writer_.reset();  // the stream's writer lock must be free before the region is replaced
    StreamSpec spec;
    spec.name = config_.stream;
    spec.capacity = capacity;
    spec.layout = layout;
    spec.checksum = config_.checksum;
    spec.sensor = *described;
    auto writer = Writer::create(spec);
    if (!writer) return writer.error();
    writer_.emplace(std::move(writer.value()));
    clock_check_.new_stream();  // its first frame carries the clock record too
  } else if (*described && *described != sensor_) {
    // The same stream, another camera or mode behind it: readers see the new description.
    if (auto set = writer_->set_sensor_info(**described); !set) log("warning: " + set.error().message);
  }
  sensor_ = *described;
  if (auto error = device->start(config_.buffers)) return error;

  device_.emplace(std::move(device.value()));
  decoder_.emplace(std::move(decoder.value()));
  format_ = *format;
  last_sequence_.reset();  // sequence numbers restart with the stream
  clock_check_.restart();   // and the clock check's measurement: a reconnect is not a step
  last_frame_ = std::chrono::steady_clock::now();
  return std::nullopt;
}

Expected<std::optional<SensorInfo>> V4l2Capture::describe(const V4l2Device& device,
                                                          const ImageLayout& output,
                                                          bool first) const {
  if (!config_.sensor) return std::optional<SensorInfo>();
  SensorInfo info = *config_.sensor;
  const std::uint32_t width = output.width;
  const std::uint32_t height = output.height;
  if (info.calibration) {
    if (auto fits = apps::check_calibration_size(*info.calibration, width, height); !fits) {
      if (first) return fits.error();
      log("warning: " + fits.error().message + "; the stream carries no calibration now");
      info.calibration.reset();
    }
  }
  // V4L2 names the card and the bus it is on; it knows no vendor, serial or firmware.
  info.identity.model = sensor_text(device.card(), SensorInfo::kMaxName);
  info.identity.serial = sensor_text(device.bus(), SensorInfo::kMaxName);
  info.time_base = TimeBase::host;
  info.time_sync = config_.timestamps == TimestampSource::device
                       ? "V4L2 buffer time (host monotonic clock) mapped to realtime"
                       : "host receive time";
  info.point_time = PointTime::none;
  return std::optional<SensorInfo>(std::move(info));
}

void V4l2Capture::disconnect() noexcept {
  device_.reset();  // stops streaming, unmaps, closes; the writer (and the region) stays
}

StepResult V4l2Capture::step(std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  if (!device_) {
    const auto now = Clock::now();
    if (now < next_retry_) {
      const auto wait = std::min<Clock::duration>(next_retry_ - now, timeout);
      std::this_thread::sleep_for(wait);
      if (Clock::now() < next_retry_) return StepResult::disconnected;
    }
    if (auto error = connect(false)) {
      next_retry_ = Clock::now() + config_.retry_period;
      return StepResult::disconnected;
    }
    ++stats_.reconnects;
    log("reconnected to " + config_.device + "; streaming again");
    return StepResult::reconnected;
  }

  DeviceFrame frame;
  const auto wait_ms = static_cast<int>(std::min<std::int64_t>(timeout.count(), 60'000));
  switch (device_->wait(wait_ms, frame)) {
    case WaitResult::frame: {
      const StepResult result = handle(frame);
      if (device_->requeue(frame) == WaitResult::device_lost) {
        ++stats_.device_losses;
        log(config_.device + " was lost; retrying until it comes back");
        disconnect();
        next_retry_ = Clock::now() + config_.retry_period;
      }
      return result;
    }
    case WaitResult::timeout:
    case WaitResult::again:
      if (Clock::now() - last_frame_ > config_.frame_timeout) {
        ++stats_.timeouts;
        log("no frame from " + config_.device + " for " +
            std::to_string(config_.frame_timeout.count()) + " ms; restarting the device");
        disconnect();
        next_retry_ = Clock::now();
        return StepResult::device_lost;
      }
      return StepResult::no_frame;
    case WaitResult::device_lost:
      break;
  }
  ++stats_.device_losses;
  log(config_.device + " was lost (unplugged?); the stream stays and the device is retried");
  disconnect();
  next_retry_ = Clock::now() + config_.retry_period;
  return StepResult::device_lost;
}

StepResult V4l2Capture::handle(const DeviceFrame& frame) {
  const std::int64_t received = realtime_ns();
  last_frame_ = std::chrono::steady_clock::now();
  if (last_sequence_ && frame.sequence > *last_sequence_ + 1) {
    stats_.dropped += frame.sequence - *last_sequence_ - 1;
  }
  last_sequence_ = frame.sequence;
  if (frame.error) {
    ++stats_.device_errors;
    return StepResult::skipped;
  }

  std::int64_t stamp = received;
  // A monotonic stamp of 0 is no stamp: the receive time then, as for an unknown clock.
  const BufferClock clock = frame.timestamp_ns > 0 ? frame.clock : BufferClock::unknown;
  if (config_.timestamps == TimestampSource::device && clock == BufferClock::monotonic) {
    clock_.resample();  // per frame: a realtime step or slew shows in the next stamp
    stamp = clock_.to_realtime(frame.timestamp_ns);
  }
  stamp += config_.time_offset_ns;
  report_clock(clock, received);
  clock_check_.start(*writer_);  // the stream's first record, before its first frame: once

  Loan loan = writer_->loan();
  const imaging::DecodeResult decoded = decoder_->decode(frame.bytes, loan.bytes());
  switch (decoded.status) {
    case imaging::DecodeStatus::ok:
      // An uncommitted loan publishes nothing, so every failure below simply returns.
      if (std::move(loan).commit(decoded.size, stamp, received) != WriteStatus::ok) return StepResult::skipped;
      ++stats_.published;
      clock_check_.add(stamp, received);  // what readers get against the frame's arrival
      clock_check_.tick(*writer_, received);
      return StepResult::published;
    case imaging::DecodeStatus::corrupt_input:
    case imaging::DecodeStatus::failed:
      ++stats_.corrupt;
      return StepResult::skipped;
    case imaging::DecodeStatus::short_input:
    case imaging::DecodeStatus::wrong_size:
    case imaging::DecodeStatus::output_too_small:
      ++stats_.bad_size;
      return StepResult::skipped;
  }
  return StepResult::skipped;
}

void V4l2Capture::run(const std::atomic<bool>& stop,
                      const std::function<void(StepResult, const V4l2Capture&)>& on_step) {
  while (!stop.load(std::memory_order_relaxed)) {
    const StepResult result = step(std::chrono::milliseconds(200));
    if (on_step) on_step(result, *this);
  }
}

}  // namespace sim::camera
