// SPDX-License-Identifier: Apache-2.0
// Plays the messages of one MCAP channel into one SIM stream: decodes each ROS 2 message
// (sim::ros2) straight into a loaned slot and commits it with the message's sensor stamp.
// The stream's layout comes from the channel's "sim.*" metadata when SIM recorded it (so it is
// recreated exactly), else from the first message (PointCloud2, Image or CompressedImage
// recorded elsewhere); a later message that does not fit makes the stream grow.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>

#include "sim/clock_status.hpp"
#include "sim/layout.hpp"
#include "sim/mcap/format.hpp"
#include "sim/mcap/layout_metadata.hpp"
#include "sim/result.hpp"
#include "sim/ros2/message.hpp"
#include "sim/writer.hpp"

namespace sim::play {

// The mountings a recording's /tf_static holds: child frame -> (parent frame, mounting).
// `generation` changes with every /tf_static message, so players notice without comparing.
struct Mountings {
  std::map<std::string, std::pair<std::string, Mounting>, std::less<>> by_child;
  // Each child's chain composed up to base_link (or the root of its tree when base_link is not
  // in it): RealSense's camera_link -> camera_color_frame -> camera_color_optical_frame becomes
  // one mounting of the optical frame under base_link, as a stream's description holds one.
  std::map<std::string, std::pair<std::string, Mounting>, std::less<>> to_root;
  std::uint64_t generation = 0;
};

// The shared memory all streams of one playback take together: at most `limit` bytes
// (--max-shm), and never more than /dev/shm has free, checked before a region is created or grown.
// A file of a few kilobytes must not be able to fill /dev/shm, however many channels it names.
class ShmBudget {
 public:
  explicit ShmBudget(std::uint64_t limit) noexcept : limit_(limit) {}
  // Takes `needed` bytes for a region of `stream` that replaces one of `current` bytes (0 for a
  // new stream); the sentence of what to do when they do not fit.
  std::optional<Error> take(const std::string& stream, std::uint64_t current, std::uint64_t needed);
  // Gives back the bytes of a region that is gone.
  void give_back(std::uint64_t bytes) noexcept { used_ -= std::min(used_, bytes); }

 private:
  std::uint64_t limit_;
  std::uint64_t used_ = 0;
};

// The most one slot may take for a channel whose first message holds `message_bytes`: eight times
// that (a LiDAR stream keeps room for a few times one revolution's points), and at least 1 MiB.
// A file needs no more to play: a later, larger message makes its stream grow.
inline constexpr std::uint64_t kRoomFloor = std::uint64_t{1} << 20;
constexpr std::uint64_t room_for(std::uint64_t message_bytes) noexcept {
  return std::max(kRoomFloor, message_bytes * 8);
}

class ChannelPlayer {
 public:
  // Checks the channel can be played (ROS 2 CDR of a type SIM has) without creating anything.
  // `max_capacity`: bytes per slot the stream may take at most, whatever the file says (a file
  // of a few bytes must not reserve gigabytes of shared memory); `budget`: what all streams may
  // take together (it must outlive the player).
  static Expected<ChannelPlayer> for_channel(const mcap::Channel& channel, const mcap::Schema* schema,
                                             std::string stream, std::uint64_t max_capacity,
                                             ShmBudget& budget);

  const std::string& stream() const noexcept { return stream_; }
  const std::string& topic() const noexcept { return topic_; }
  // The SIM stream the channel was recorded from (its "sim.stream" metadata), else its topic:
  // the name a recorded clock status gives (before --remap).
  const std::string& recorded_stream() const noexcept { return recorded_stream_; }
  // Whether the stream's shape is known before the first message (SIM recordings).
  bool shape_known() const noexcept { return shape_.has_value(); }
  // Creates the stream now (only when shape_known()).
  std::optional<Error> create_stream();
  // Learns the shape from a message when the metadata did not give it.
  std::optional<Error> learn_shape(std::span<const std::byte> message);
  // A recording may reserve no more shared memory than it holds (review L4): given the channel's
  // first message (nullopt: it holds none) before the stream is created, a recorded shape whose
  // slot is larger than room_for() that message is dropped and the stream sized from its
  // messages instead, as a recording made elsewhere is. The sentence saying so, if it was.
  std::optional<std::string> bound_by(std::optional<std::span<const std::byte>> first_message);

  // Decodes one message into the stream, stamped with its header stamp + stamp_shift_ns.
  // An error for a message that cannot be decoded (nothing is published then).
  std::optional<Error> play(std::span<const std::byte> message, std::int64_t stamp_shift_ns);

  std::uint64_t frames() const noexcept { return frames_; }
  // Whether this player made (or took over) a region of its stream at some point.
  bool made_stream() const noexcept { return made_stream_; }

  // What the stream says about its sensor comes from the recording: the calibration of the
  // CameraInfo beside the images, the mounting of the frame its messages name from /tf_static.
  // Both are applied before the next frame is published (the frame carries them).
  void set_calibration(const CameraCalibration& calibration);
  void use_mountings(const Mountings* mountings) noexcept { mountings_ = mountings; }
  // The stream's clock as recorded (sim_record's /diagnostics): set on the stream now, or as soon
  // as it exists, and again on a region that replaces it.
  void set_clock(const ClockStatus& clock);
  // Why the recording's description could not be given to the stream (empty: it could, or
  // there was none).
  const std::string& sensor_problem() const noexcept { return sensor_problem_; }

 private:
  ChannelPlayer(ros2::MessageType type, std::string topic, std::string stream,
                std::string recorded_stream, std::optional<mcap::StreamShape> shape,
                std::uint64_t max_capacity, ShmBudget& budget)
      : type_(type), topic_(std::move(topic)), stream_(std::move(stream)),
        recorded_stream_(std::move(recorded_stream)), shape_(shape), max_capacity_(max_capacity),
        budget_(&budget) {}
  void apply_clock();
  std::optional<Error> ensure_writer(const mcap::StreamShape& wanted);
  std::optional<Error> commit(Loan&& loan, std::uint64_t size, std::int64_t stamp_ns);
  // Sets the stream's description when the frame id, calibration or mountings changed.
  void update_sensor(std::string_view frame_id);

  ros2::MessageType type_;
  std::string topic_;
  std::string stream_;
  std::string recorded_stream_;
  std::optional<mcap::StreamShape> shape_;
  std::uint64_t max_capacity_;
  ShmBudget* budget_;
  std::optional<Writer> writer_;
  bool made_stream_ = false;
  std::uint64_t frames_ = 0;

  const Mountings* mountings_ = nullptr;
  std::uint64_t mountings_seen_ = 0;
  std::optional<CameraCalibration> calibration_;
  std::string frame_id_;               // of the last message played
  bool sensor_dirty_ = false;
  std::optional<SensorInfo> sensor_;   // the description the stream carries
  std::string sensor_problem_;         // the first reason a description could not be set
  std::optional<ClockStatus> clock_;   // as recorded; set on every region this player makes
};

using Players = std::map<std::uint16_t, ChannelPlayer>;  // by MCAP channel id

}  // namespace sim::play
