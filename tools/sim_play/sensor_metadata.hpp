// SPDX-License-Identifier: Apache-2.0
// What a recording says about its sensors, put back into the streams sim_play writes: the
// CameraInfo messages beside each image topic (on the sibling topic <ns>/camera_info, as
// sim_record, sim_dds_bridge and rosbag2 recordings of camera drivers lay them out) give the
// image stream its calibration; /tf_static (tf2_msgs/TFMessage) gives each stream the mounting
// of the frame its messages name; /diagnostics (diagnostic_msgs/DiagnosticArray, as sim_record
// writes each stream's clock, "sim: <stream> clock") gives each stream its clock record.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "channel_player.hpp"
#include "sim/mcap/reader.hpp"

namespace sim::play {

class SensorMetadata {
 public:
  // Finds the CameraInfo, /tf_static and DiagnosticArray channels of the file.
  explicit SensorMetadata(const mcap::Reader& reader);

  // Whether messages of `channel` are metadata (not frames): they are given to take().
  bool handles(std::uint16_t channel) const { return topics_.count(channel) > 0; }
  // Pairs each CameraInfo channel with the image players of its namespace, and gives every
  // player the mountings.
  void attach(Players& players);
  // One CameraInfo, TFMessage or DiagnosticArray: the players it concerns get it before their
  // next frame (statuses of anything but a recorded stream's clock are left alone). A
  // message that cannot be decoded is an error (one sentence).
  std::optional<Error> take(std::uint16_t channel, std::span<const std::byte> message, Players& players);

 private:
  enum class Kind { camera_info, tf_static, diagnostics };
  std::optional<Error> take_diagnostics(std::uint16_t channel, std::span<const std::byte> message,
                                        Players& players);
  std::map<std::uint16_t, Kind> kinds_;
  std::map<std::uint16_t, std::string> topics_;
  std::map<std::uint16_t, std::vector<std::uint16_t>> images_of_;  // CameraInfo channel -> image channels
  Mountings mountings_;
};

}  // namespace sim::play
