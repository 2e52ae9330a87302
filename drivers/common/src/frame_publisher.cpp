// SPDX-License-Identifier: Apache-2.0
#include "sim/lidar/frame_publisher.hpp"

#include <ostream>
#include <system_error>
#include <utility>

#include "sim/clock.hpp"
#include "sim/sensor_info.hpp"

namespace sim::lidar {

std::string file_source(const std::filesystem::path& file) {
  std::error_code ignored;
  const auto absolute = std::filesystem::absolute(file, ignored).lexically_normal();
  return sensor_text("file://" + absolute.string(), SensorInfo::kMaxSource);
}

void describe_frames(std::ostream& out, bool machine, std::uint64_t frames, std::uint64_t packets,
                     std::uint64_t lost, std::uint64_t malformed) {
  const char* sep = machine ? "=" : " ";
  out << "frames" << sep << frames << " packets" << sep << packets << " lost" << sep << lost
      << " malformed" << sep << malformed;
}

FramePublisher::FramePublisher(Writer writer, PublishCounters& counters) noexcept
    : writer_(std::move(writer)), counters_(counters) {
  lend();
}

std::span<LidarPoint> FramePublisher::slot() const noexcept { return loan_.as<LidarPoint>(); }

std::span<LidarPoint> FramePublisher::publish_stamped(std::size_t point_count, std::int64_t stamp_ns,
                                                      std::int64_t host_receive_ns, bool whole) noexcept {
  const WriteStatus status =
      std::move(loan_).commit(point_count * sizeof(LidarPoint), stamp_ns, host_receive_ns);
  if (status == WriteStatus::ok) {
    ++counters_.frames;
    counters_.points += point_count;
    if (!whole) ++counters_.partial_frames;
    last_points_ = point_count;
  } else {
    ++counters_.failed;
  }
  lend();  // the next frame goes to the new back slot
  return slot();
}

void FramePublisher::lend() noexcept {
  loan_ = Loan{};  // a writer lends one slot at a time: give back the one still open first
  loan_ = writer_.loan();
}

}  // namespace sim::lidar
