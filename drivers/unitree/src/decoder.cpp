// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/decoder.hpp"

#include <algorithm>
#include <cctype>

#include "sim/clock.hpp"
#include "sim/unitree/bytes.hpp"
#include "sim/unitree/l2_protocol.hpp"

namespace sim::unitree {
namespace {

// The L1 sends no per-point time; its nominal 21,600 samples/s gives the spacing.
constexpr std::uint32_t kL1PointPeriodNs = 46'296;

bool iequals(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

std::uint32_t clamp_offset(std::int64_t ns) noexcept {
  return static_cast<std::uint32_t>(std::clamp<std::int64_t>(ns, 0, 0xFFFFFFFFLL));
}

}  // namespace

const char* to_string(Model model) noexcept { return model == Model::l1 ? "L1" : "L2"; }

std::optional<Model> parse_model(std::string_view text) noexcept {
  if (iequals(text, "L1") || iequals(text, "unitree-l1")) return Model::l1;
  if (iequals(text, "L2") || iequals(text, "unitree-l2")) return Model::l2;
  return std::nullopt;
}

std::string model_problem(std::string_view text) {
  if (parse_model(text)) return {};
  return "unknown model '" + std::string(text) + "'; use L1 or L2";
}

// ---------------------------------------------------------------------------------------------

ScanAssembler::ScanAssembler(ScanSink& sink, std::uint32_t packets_per_scan) noexcept
    : sink_(sink), packets_per_scan_(std::max<std::uint32_t>(packets_per_scan, 1)) {}

std::span<LidarPoint> ScanAssembler::begin_packet(std::int64_t stamp_ns, std::int64_t clock_ns,
                                                  std::int64_t receive_ns) noexcept {
  if (!open_) {
    storage_ = sink_.begin_scan();
    open_ = true;
    points_ = 0;
    packets_ = 0;
    stamp_ns_ = stamp_ns;
    receive_ns_ = receive_ns;
    scan_clock_ns_ = clock_ns;
  }
  return storage_.subspan(points_);
}

bool ScanAssembler::end_packet(std::size_t points_written) noexcept {
  points_ = std::min(points_ + points_written, storage_.size());
  if (++packets_ < packets_per_scan_) return false;
  sink_.end_scan(points_, stamp_ns_, receive_ns_);
  open_ = false;
  storage_ = {};
  return true;
}

void ScanAssembler::close() noexcept {
  if (!open_) return;
  sink_.end_scan(points_, stamp_ns_, receive_ns_);
  open_ = false;
  storage_ = {};
}

void ScanAssembler::abandon() noexcept {
  open_ = false;
  storage_ = {};
  points_ = 0;
  packets_ = 0;
}

// ---------------------------------------------------------------------------------------------

Decoder::Decoder(const DecoderOptions& options, ScanSink& sink)
    : options_(options), sink_(sink), assembler_(sink, options.packets_per_scan) {}

std::uint64_t Decoder::max_points_per_scan(const DecoderOptions& options) noexcept {
  const std::uint64_t packets = std::max<std::uint32_t>(options.packets_per_scan, 1);
  if (options.model == Model::l1) return l1::kPointsPerPacket * packets;
  return std::max<std::uint64_t>(l2::kPointsPerPacket * packets, l2::kPointsPer2dPacket);
}

void Decoder::push(std::span<const std::uint8_t> bytes, std::int64_t host_ns) noexcept {
  while (!bytes.empty()) {
    const std::size_t taken =
        options_.model == Model::l2 ? l2_framer_.feed(bytes) : l1_framer_.feed(bytes);
    bytes = bytes.subspan(taken);
    drain(host_ns);
  }
}

void Decoder::drain(std::int64_t host_ns) noexcept {
  if (options_.model == Model::l2) {
    while (const auto packet = l2_framer_.next()) on_l2_packet(*packet, host_ns);
  } else {
    while (const auto message = l1_framer_.next()) on_l1_message(*message, host_ns);
  }
}

void Decoder::finish() noexcept {
  if (options_.model == Model::l2) {
    l2_framer_.finish();
  } else {
    l1_framer_.finish();
  }
}

void Decoder::reset() noexcept {
  finish();
  assembler_.abandon();
  last_seq_.reset();
  l1_distance_.reset();
  l1_aux_.reset();
}

DecoderCounters Decoder::counters() const noexcept {
  DecoderCounters c = counters_;
  c.framing = options_.model == Model::l2 ? l2_framer_.counters() : l1_framer_.counters();
  return c;
}

std::int64_t Decoder::stamp_of(std::int64_t sensor_ns, std::int64_t host_ns) const noexcept {
  return options_.time_source == TimeSource::host ? host_ns : saturating_add_ns(sensor_ns, stamp_offset_ns_);
}

void Decoder::on_l2_packet(std::span<const std::uint8_t> packet, std::int64_t host_ns) noexcept {
  const std::uint32_t type = le::u32(packet, 4);
  if (type == l2::imu) {
    std::optional<ImuSample> sample = l2::parse_imu(packet);
    if (!sample) {
      ++counters_.malformed;
      return;
    }
    sample->stamp_ns = stamp_of(sample->stamp_ns, host_ns);
    sink_.packet_time(sample->stamp_ns, host_ns);
    ++counters_.imu_samples;
    sink_.imu(*sample);
    return;
  }
  if (type == l2::point_2d) {
    on_l2_2d_packet(packet, host_ns);
    return;
  }
  if (type != l2::point_3d) {
    ++counters_.ignored;
    return;
  }
  const std::optional<l2::PointPacketHeader> header = l2::parse_point_header(packet);
  if (!header) {
    ++counters_.malformed;
    return;
  }
  if (last_seq_ && header->seq != *last_seq_ + 1) {
    const std::uint32_t gap = header->seq - *last_seq_ - 1;  // wraps on a restart: ignore those
    if (gap < 1'000'000) counters_.lost_packets += gap;
  }
  last_seq_ = header->seq;

  const std::int64_t stamp = stamp_of(header->stamp_ns, host_ns);
  sink_.packet_time(stamp, host_ns);
  // Offsets within a scan always come from the sensor's clock: host receive times of packets in
  // one burst of datagrams say nothing about when they were measured.
  const std::span<LidarPoint> room = assembler_.begin_packet(stamp, header->stamp_ns, host_ns);
  const std::uint32_t base = clamp_offset(header->stamp_ns - assembler_.scan_clock_ns());
  const l2::DecodeLimits limits{options_.range_min_m, options_.range_max_m};
  const l2::DecodeResult result = l2::decode_points(packet, *header, limits, base, room);
  counters_.dropped_points += result.overflow;
  counters_.points += result.written;
  if (assembler_.end_packet(result.written)) ++counters_.scans;
}

void Decoder::on_l2_2d_packet(std::span<const std::uint8_t> packet, std::int64_t host_ns) noexcept {
  const std::optional<l2::PointPacketHeader> header = l2::parse_2d_header(packet);
  if (!header) {
    ++counters_.malformed;
    return;
  }
  // One 2D packet is one whole planar scan: it never joins a 3D scan (a work-mode change
  // drops a half-assembled 3D scan).
  assembler_.abandon();
  const std::int64_t stamp = stamp_of(header->stamp_ns, host_ns);
  sink_.packet_time(stamp, host_ns);
  const std::span<LidarPoint> room = assembler_.begin_packet(stamp, header->stamp_ns, host_ns);
  const l2::DecodeLimits limits{options_.range_min_m, options_.range_max_m};
  const l2::DecodeResult result = l2::decode_2d_points(packet, *header, limits, 0, room);
  counters_.dropped_points += result.overflow;
  counters_.points += result.written;
  assembler_.end_packet(result.written);
  assembler_.close();
  ++counters_.scans;
}

void Decoder::on_l1_message(const MavlinkMessage& message, std::int64_t host_ns) noexcept {
  switch (message.msgid) {
    case l1::kMsgDistance: {
      if (l1_distance_) ++counters_.unpaired;
      l1_distance_ = l1::parse_distance(message.payload);
      break;
    }
    case l1::kMsgAuxiliary: {
      if (l1_aux_) ++counters_.unpaired;
      l1_aux_ = l1::parse_auxiliary(message.payload);
      break;
    }
    case l1::kMsgImu: {
      std::optional<ImuSample> sample = l1::parse_imu(message.payload);
      if (sample) {
        sample->stamp_ns = host_ns;  // the L1 sends no time with its IMU
        sink_.packet_time(host_ns, host_ns);
        ++counters_.imu_samples;
        sink_.imu(*sample);
      }
      return;
    }
    default:
      ++counters_.ignored;
      return;
  }
  if (l1_distance_ && l1_aux_) {
    if (l1_distance_->packet_id == l1_aux_->packet_id) {
      decode_l1_pair(host_ns);
    } else {
      // Keep the newer of the two; the older one's partner was lost.
      ++counters_.unpaired;
      if (message.msgid == l1::kMsgDistance) {
        l1_aux_.reset();
      } else {
        l1_distance_.reset();
      }
    }
  }
}

void Decoder::decode_l1_pair(std::int64_t host_ns) noexcept {
  sink_.packet_time(host_ns, host_ns);  // the L1 sends no time: its stamps are host time
  const std::span<LidarPoint> room = assembler_.begin_packet(host_ns, 0, host_ns);
  const std::uint32_t base = clamp_offset(std::int64_t{assembler_.packets_in_scan()} *
                                          l1::kPointsPerPacket * kL1PointPeriodNs);
  const l1::DecodeLimits limits{options_.range_min_m, options_.range_max_m, 0.0F};
  const l1::DecodeResult result =
      l1::decode_points(*l1_distance_, *l1_aux_, limits, base, kL1PointPeriodNs, room);
  counters_.dropped_points += result.overflow;
  counters_.points += result.written;
  if (assembler_.end_packet(result.written)) ++counters_.scans;
  l1_distance_.reset();
  l1_aux_.reset();
}

}  // namespace sim::unitree
