// SPDX-License-Identifier: Apache-2.0
// Point formula (reference §1.1): x = d·cos(el)·sin(az), y = d·cos(el)·cos(az), z = d·sin(el),
// az = block azimuth + channel azimuth offset. The multi-return filters follow nebula's
// decoder so its reference clouds are reproduced exactly (../shared/data/lidar/SOURCES.md).
#include "sim/hesai/frame_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace sim::hesai {
namespace {

constexpr unsigned full_turn = 36000;  // 0.01°
// A firing group up to this far behind the previous one is a reordered or repeated packet,
// not a new revolution.
constexpr unsigned reorder_window = 1000;
// Sequence jumps larger than this are a sensor restart, not loss.
constexpr std::uint32_t max_counted_loss = 100000;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

}  // namespace

Expected<FrameAssembler> FrameAssembler::create(Calibration calibration,
                                                AssemblerOptions options) {
  const ModelInfo& m = info(options.model);
  const std::string model_name(to_string(options.model));
  if (calibration.channels() != m.channels) {
    return invalid("the calibration has " + std::to_string(calibration.channels()) +
                   " channels but a " + model_name + " has " + std::to_string(m.channels) +
                   "; use the calibration file of this sensor or set the right model");
  }
  if (options.firetimes && options.firetimes->channels() != m.channels) {
    return invalid("the firing-time file has " + std::to_string(options.firetimes->channels()) +
                   " channels but a " + model_name + " has " + std::to_string(m.channels) +
                   "; use Hesai's firing-time file for this model");
  }
  const float min_range = options.min_range_m.value_or(m.min_range_m);
  const float max_range = options.max_range_m.value_or(m.max_range_m);
  if (!std::isfinite(min_range) || !std::isfinite(max_range) || min_range < 0 ||
      max_range <= min_range) {
    return invalid("the range limits must satisfy 0 <= minimum < maximum, got " +
                   std::to_string(min_range) + " to " + std::to_string(max_range) + " m");
  }
  if (!std::isfinite(options.multi_return_distance_threshold_m) ||
      options.multi_return_distance_threshold_m < 0) {
    return invalid("the multi-return distance threshold must be 0 (off) or a positive distance");
  }
  if (!std::isfinite(options.cut_azimuth_deg)) {
    return invalid("the cut azimuth must be an angle in degrees, e.g. 0 or 180");
  }
  return FrameAssembler(std::move(calibration), std::move(options));
}

FrameAssembler::FrameAssembler(Calibration calibration, AssemblerOptions options)
    : calibration_(std::move(calibration)), options_(std::move(options)) {
  const ModelInfo& m = info(options_.model);
  channels_ = m.channels;
  min_range_m_ = options_.min_range_m.value_or(m.min_range_m);
  max_range_m_ = options_.max_range_m.value_or(m.max_range_m);
  double cut = std::fmod(options_.cut_azimuth_deg, 360.0);
  if (cut < 0) cut += 360.0;
  cut_centi_deg_ = static_cast<std::uint16_t>(std::lround(cut * 100.0) % full_turn);

  constexpr double deg = std::numbers::pi / 180.0;
  earliest_channel_offset_ns_ = std::numeric_limits<std::int32_t>::max();
  for (unsigned ch = 0; ch < channels_; ++ch) {
    const double elevation = calibration_[ch].elevation_deg * deg;
    cos_elevation_[ch] = static_cast<float>(std::cos(elevation));
    sin_elevation_[ch] = static_cast<float>(std::sin(elevation));
    std::int32_t offset = Packet::channel_offset_ns(options_.model, ch);
    if (options_.firetimes) {
      // Hesai's file has the same meaning as the built-in tables, except QT64 whose table
      // adds 10 µs to the file's values (reference §5).
      const double extra = options_.model == Model::pandar_qt64 ? 10000.0 : 0.0;
      offset = static_cast<std::int32_t>(std::lround((*options_.firetimes)[ch] * 1000.0 + extra));
    }
    channel_offset_ns_[ch] = offset;
    earliest_channel_offset_ns_ = std::min(earliest_channel_offset_ns_, offset);
  }
  update_azimuth_offsets(0);
}

void FrameAssembler::update_azimuth_offsets(std::uint16_t rpm) noexcept {
  constexpr double deg = std::numbers::pi / 180.0;
  const bool compensate = options_.firetimes && options_.firetime_azimuth_compensation;
  for (unsigned ch = 0; ch < channels_; ++ch) {
    double offset = calibration_[ch].azimuth_offset_deg;
    // The laser fires firetime µs after the block time, while the head turns rpm·6e-6 °/µs.
    if (compensate) offset += (*options_.firetimes)[ch] * rpm * 6e-6;
    cos_azimuth_offset_[ch] = static_cast<float>(std::cos(offset * deg));
    sin_azimuth_offset_[ch] = static_cast<float>(std::sin(offset * deg));
  }
  compensated_rpm_ = rpm;
}

std::span<LidarPoint> FrameAssembler::destination() noexcept {
  return output_attached_ ? output_ : std::span<LidarPoint>(carry_);
}

std::size_t& FrameAssembler::destination_count() noexcept {
  return output_attached_ ? output_count_ : carry_count_;
}

std::size_t FrameAssembler::pending_points() const noexcept {
  return output_attached_ ? output_count_ : carry_count_;
}

void FrameAssembler::set_output(std::span<LidarPoint> output) noexcept {
  if (output_attached_ && output_count_ > 0) {
    // Replaced in the middle of a frame: its points so far stay in the old span.
    current_.whole = false;
    current_.dropped += static_cast<std::uint32_t>(output_count_);
    counters_.dropped_points += output_count_;
  }
  output_ = output;
  output_attached_ = true;
  const std::size_t copied = std::min(carry_count_, output.size());
  std::copy_n(carry_.begin(), copied, output.begin());
  if (copied < carry_count_) {
    current_.dropped += static_cast<std::uint32_t>(carry_count_ - copied);
    counters_.dropped_points += carry_count_ - copied;
  }
  output_count_ = copied;
  carry_count_ = 0;
}

void FrameAssembler::reset() noexcept {
  current_ = FrameState{};
  output_count_ = 0;
  carry_count_ = 0;
  packet_counted_ = false;
  have_last_ = false;
  azimuth_step_ = 0;
  have_sequence_ = false;
}

CompletedFrame FrameAssembler::finish(std::size_t count, bool ended_at_cut) noexcept {
  CompletedFrame frame;
  frame.point_count = count;
  frame.stamp_ns = current_.stamp_ns;
  frame.host_receive_ns = current_.host_ns;
  frame.index = frame_index_++;
  frame.packets = current_.packets;
  frame.lost_packets = current_.lost;
  frame.dropped_points = current_.dropped;
  frame.whole_revolution = current_.whole && ended_at_cut;
  ++counters_.frames;
  // The span now belongs to the caller; points go to the carry-over buffer until set_output.
  output_attached_ = false;
  output_ = {};
  output_count_ = 0;
  carry_count_ = 0;
  return frame;
}

std::optional<CompletedFrame> FrameAssembler::flush() noexcept {
  std::optional<CompletedFrame> frame;
  if (current_.started) {
    if (output_attached_) {
      frame = finish(output_count_, false);
    } else {
      counters_.dropped_points += carry_count_;
      ++counters_.frames_without_output;
      carry_count_ = 0;
    }
  }
  current_ = FrameState{};
  packet_counted_ = false;
  have_last_ = false;
  return frame;
}

void FrameAssembler::start_frame(const Packet& packet, unsigned block, std::int64_t host_ns,
                                 bool whole) noexcept {
  current_ = FrameState{};
  current_.started = true;
  current_.whole = whole;
  // The frame's stamp is its earliest firing, so every point's offset is ≥ 0.
  current_.stamp_ns =
      packet.time_ns() + packet.block_offset_ns(block) + earliest_channel_offset_ns_;
  current_.host_ns = host_ns;
  packet_counted_ = false;
}

void FrameAssembler::on_cut(PushResult& result) noexcept {
  if (!current_.started) return;
  if (current_.whole || options_.emit_partial_frames) {
    if (output_attached_) {
      result.frame = finish(output_count_, true);
      return;
    }
    // Completed while the caller still holds the previous frame: nowhere to put it.
    counters_.dropped_points += carry_count_;
    ++counters_.frames_without_output;
  } else {
    ++counters_.partial_frames_dropped;
  }
  destination_count() = 0;
}

void FrameAssembler::count_loss(const Packet& packet) noexcept {
  if (const auto sequence = packet.sequence()) {
    if (have_sequence_) {
      const std::uint32_t ahead = *sequence - last_sequence_;  // modulo 2^32
      if (ahead == 0 || ahead > 0x8000'0000u) {
        ++counters_.out_of_order;
        if (ahead != 0 && ~ahead + 1 < reorder_window) return;  // a late packet: keep position
      } else if (ahead - 1 <= max_counted_loss) {
        counters_.lost_packets += ahead - 1;
        current_.lost += ahead - 1;
      }
    }
    have_sequence_ = true;
    last_sequence_ = *sequence;
    return;
  }
  // No sequence (Pandar40P/64 without it): a gap between the last firing of the previous packet
  // and the first of this one, in units of the packet's azimuth span.
  const unsigned groups = packet.blocks() / packet.returns();
  if (have_last_ && azimuth_step_ > 0) {
    const unsigned gap = (packet.azimuth(0) + full_turn - last_azimuth_) % full_turn;
    if (gap < full_turn / 2 && gap * 2 > azimuth_step_ * 3u) {
      const double per_packet = static_cast<double>(azimuth_step_) * groups;
      const auto missing = static_cast<std::uint32_t>(std::lround((gap - azimuth_step_) / per_packet));
      counters_.lost_packets += missing;
      current_.lost += missing;
    }
  }
  if (groups > 1) {
    const unsigned span =
        (packet.azimuth((groups - 1) * packet.returns()) + full_turn - packet.azimuth(0)) % full_turn;
    azimuth_step_ = static_cast<std::uint16_t>(span / (groups - 1));
  }
}

PushResult FrameAssembler::push(std::span<const std::uint8_t> payload,
                                std::int64_t host_receive_ns) noexcept {
  PushResult result;
  Packet packet;
  result.error = Packet::parse(payload, options_.model, packet);
  if (result.error != PacketError::none) {
    ++counters_.rejected[static_cast<std::size_t>(result.error)];
    if (result.error == PacketError::wrong_model) {
      ++counters_.wrong_model;
    } else {
      ++counters_.malformed;
    }
    return result;
  }
  ++counters_.packets;
  count_loss(packet);
  if (options_.firetimes && options_.firetime_azimuth_compensation &&
      packet.motor_rpm() != compensated_rpm_) {
    update_azimuth_offsets(packet.motor_rpm());
  }

  const unsigned returns = packet.returns();
  for (unsigned block = 0; block < packet.blocks(); block += returns) {
    const std::uint16_t azimuth = packet.azimuth(block);
    const auto phase = static_cast<std::uint16_t>((azimuth + full_turn - cut_centi_deg_) % full_turn);
    bool advance = true;
    if (!have_last_) {
      // Joining mid-revolution (start, reset, flush): this frame is partial.
      start_frame(packet, block, host_receive_ns, false);
    } else {
      const unsigned forward = (phase + full_turn - last_phase_) % full_turn;
      if (forward > full_turn - reorder_window) {
        advance = false;  // a late packet: its points belong to this frame, no cut
      } else if (phase < last_phase_) {
        on_cut(result);
        start_frame(packet, block, host_receive_ns, true);
      }
    }
    if (!current_.started) start_frame(packet, block, host_receive_ns, false);
    if (!packet_counted_) {
      ++current_.packets;
      packet_counted_ = true;
    }
    decode_group(packet, block);
    if (advance) {
      last_phase_ = phase;
      last_azimuth_ = azimuth;
      have_last_ = true;
    }
  }
  packet_counted_ = false;
  return result;
}

void FrameAssembler::decode_group(const Packet& packet, unsigned first_block) noexcept {
  const unsigned returns = packet.returns();
  const float unit = packet.distance_unit_m();
  const double azimuth_rad = packet.azimuth(first_block) * (std::numbers::pi / 18000.0);
  const auto sin_block = static_cast<float>(std::sin(azimuth_rad));
  const auto cos_block = static_cast<float>(std::cos(azimuth_rad));
  // Blocks of a group fire together, so one time for the group; offsets are ≥ 0 by the stamp's
  // choice, clamped only against a sensor clock that jumps.
  const std::int64_t group_time =
      packet.time_ns() + packet.block_offset_ns(first_block) - current_.stamp_ns;
  const float threshold = options_.multi_return_distance_threshold_m;
  const bool multi = returns > 1;

  std::span<LidarPoint> out = destination();
  std::size_t& count = destination_count();

  for (unsigned ch = 0; ch < channels_; ++ch) {
    std::array<std::uint16_t, 3> raw{};
    std::array<std::uint8_t, 3> reflectivity{};
    for (unsigned r = 0; r < returns; ++r) {
      raw[r] = packet.raw_distance(first_block + r, ch);
      reflectivity[r] = packet.reflectivity(first_block + r, ch);
    }
    for (unsigned r = 0; r < returns; ++r) {
      if (raw[r] == 0 && options_.drop_zero_distance) continue;
      const float distance = static_cast<float>(raw[r]) * unit;
      if (distance < min_range_m_ || distance > max_range_m_) continue;
      if (multi && r + 1 != returns) {
        // Only a non-last return can be dropped as a duplicate of another return.
        bool duplicate = false;
        for (unsigned other = 0; other < returns && !duplicate; ++other) {
          if (other == r) continue;
          if (options_.drop_identical_returns && raw[other] == raw[r] &&
              reflectivity[other] == reflectivity[r]) {
            duplicate = true;
          }
          if (threshold > 0 &&
              std::fabs(static_cast<float>(raw[other]) * unit - distance) < threshold) {
            duplicate = true;
          }
        }
        if (duplicate) continue;
      }
      if (count >= out.size()) {
        ++current_.dropped;
        ++counters_.dropped_points;
        continue;
      }
      const float sin_az = sin_block * cos_azimuth_offset_[ch] + cos_block * sin_azimuth_offset_[ch];
      const float cos_az = cos_block * cos_azimuth_offset_[ch] - sin_block * sin_azimuth_offset_[ch];
      const float horizontal = distance * cos_elevation_[ch];
      const std::int64_t offset = std::clamp<std::int64_t>(
          group_time + channel_offset_ns_[ch], 0, std::numeric_limits<std::uint32_t>::max());
      LidarPoint& p = out[count++];
      p.x = horizontal * sin_az;
      p.y = horizontal * cos_az;
      p.z = distance * sin_elevation_[ch];
      p.intensity = reflectivity[r];
      p.time_offset_ns = static_cast<std::uint32_t>(offset);
      p.ring = static_cast<std::uint16_t>(ch);
      p.return_index = static_cast<std::uint8_t>(r);
      p.reserved = 0;
    }
  }
}

}  // namespace sim::hesai
