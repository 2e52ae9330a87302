// SPDX-License-Identifier: Apache-2.0
// Per-unit angle correction ("calibration") and optional firing-time correction, parsed from
// Hesai's CSV files. Every unit has its own angle file; decoding with another unit's file gives
// points that are off by up to a few tenths of a degree, so drivers require one.
//
// Angle file: a header line ("Laser id,Elevation,Azimuth" or "Channel,Elevation,Azimuth", any
// case), then one line per channel "channel (1-based),elevation °,azimuth offset °". Firing-time
// file: a header line ("Channel,fire time(us)"), then "channel,µs" lines in any order.
// Both: optional UTF-8 BOM, LF or CRLF, trailing blank lines, a missing final newline.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "sim/hesai/model.hpp"
#include "sim/result.hpp"

namespace sim::hesai {

struct ChannelAngles {
  float elevation_deg;
  float azimuth_offset_deg;
};

class Calibration {
 public:
  // Parses an angle-correction CSV. With `model`, the file must have exactly that model's
  // channel count. `source` names the file in error messages ("pandar64.csv:7: ...").
  static Expected<Calibration> parse(std::string_view text, std::optional<Model> model,
                                     std::string_view source = "calibration");
  static Expected<Calibration> load(const std::filesystem::path& path,
                                    std::optional<Model> model);

  // From values already in memory (tests, a calibration served over PTC). Needs ≥ 1 channel.
  static Expected<Calibration> from_angles(std::vector<ChannelAngles> angles);

  std::size_t channels() const noexcept { return angles_.size(); }
  const ChannelAngles& operator[](std::size_t channel) const noexcept { return angles_[channel]; }
  const std::vector<ChannelAngles>& angles() const noexcept { return angles_; }

 private:
  explicit Calibration(std::vector<ChannelAngles> angles) : angles_(std::move(angles)) {}
  std::vector<ChannelAngles> angles_;
};

// Firing time of each channel relative to its block, in microseconds, as Hesai publishes it
// (negative for Pandar64/40P: the laser fires before the block time).
class FiretimeCorrection {
 public:
  static Expected<FiretimeCorrection> parse(std::string_view text, std::optional<Model> model,
                                            std::string_view source = "firetime correction");
  static Expected<FiretimeCorrection> load(const std::filesystem::path& path,
                                           std::optional<Model> model);

  std::size_t channels() const noexcept { return firetime_us_.size(); }
  double operator[](std::size_t channel) const noexcept { return firetime_us_[channel]; }

 private:
  explicit FiretimeCorrection(std::vector<double> us) : firetime_us_(std::move(us)) {}
  std::vector<double> firetime_us_;
};

}  // namespace sim::hesai
