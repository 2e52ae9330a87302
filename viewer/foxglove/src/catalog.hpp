// SPDX-License-Identifier: Apache-2.0
// Which SIM streams exist, what they look like and how they are doing: polls sim::list_streams()
// and sim::inspect() on its own thread, gives each showable stream a channel id (a new id when a
// stream's layout changes, as Foxglove ids must keep their schema) and reports what appeared and
// what went away. The page's stream table is a snapshot of it. Beside the streams' channels it
// keeps two latched ones: /tf_static (every mounting) and /diagnostics (every stream's clock as a
// diagnostic_msgs/msg/DiagnosticArray, one status per stream, for Foxglove's Diagnostics panels).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "encoder.hpp"
#include "foxglove_messages.hpp"
#include "pump.hpp"
#include "sim/foxglove/protocol.hpp"
#include "sim/clock_status.hpp"
#include "sim/reader.hpp"

namespace sim::foxglove {

struct StreamEntry {
  std::string name;
  std::optional<StreamStatus> status;  // nullopt when the stream cannot be inspected
  std::string problem;                 // why not, one sentence
  double rate_hz = 0;                  // frames per second over the last poll window
  std::int64_t age_ns = -1;            // since the newest frame was published; -1 before any
  std::optional<Channel> channel;      // nullopt for streams Foxglove cannot show
  std::optional<Channel> calibration_channel;  // calibrated cameras only
  // Another stream mounts the same frame differently (review L10), one sentence naming both.
  std::string mounting_problem;
};

// A channel and what its messages are made from: the frames of a stream of `layout` (a pump
// encodes them), or, for a latched channel (calibration, transforms), its one current message.
struct AdvertisedStream {
  Channel channel;
  std::string stream;  // the SIM stream's name (the channel's topic may add a namespace)
  Layout layout{};
  std::shared_ptr<const Message> latched;
};

// What one poll found changed.
struct CatalogChanges {
  std::vector<AdvertisedStream> added;
  std::vector<std::uint32_t> removed;
  std::vector<std::shared_ptr<const Message>> updated;  // new messages of latched channels
  bool empty() const { return added.empty() && removed.empty() && updated.empty(); }
};

class Catalog {
 public:
  // Called on the catalog's thread with what changed.
  using ChangeHandler = std::function<void(const CatalogChanges& changes)>;

  Catalog(std::vector<std::string> only, EncodeOptions encode, std::chrono::milliseconds period,
          ChangeHandler on_change, std::function<void()> after_poll = {});
  Catalog(const Catalog&) = delete;
  Catalog& operator=(const Catalog&) = delete;
  ~Catalog();

  void start();
  void stop();
  // Polls once now (the thread does this every period).
  void poll();

  std::vector<StreamEntry> snapshot() const;
  std::optional<StreamEntry> find(const std::string& name) const;
  // Every mounting the streams describe (each sensor's frame in its parent), as last polled.
  std::vector<FrameTransform> mountings() const;

 private:
  struct Tracked {
    StreamEntry entry;
    std::optional<SensorInfo> sensor;  // as the last poll read it
    Layout layout{};
    std::uint64_t capacity = 0;
    std::uint64_t window_frames = 0;
    std::int64_t window_start_ns = 0;
  };
  void run();
  void track(Tracked& t, const StreamStatus& s, CatalogChanges& changes);
  void track_calibration(Tracked& t, const std::optional<SensorInfo>& sensor,
                         CatalogChanges& changes);
  std::vector<FrameTransform> collect_mountings();
  void track_transforms(CatalogChanges& changes);
  void track_clocks(CatalogChanges& changes);
  Channel new_channel(std::string topic, const MessageSchema& schema);

  const std::vector<std::string> only_;
  const EncodeOptions encode_;
  const std::chrono::milliseconds period_;
  const ChangeHandler on_change_;
  const std::function<void()> after_poll_;

  mutable std::mutex mutex_;
  std::map<std::string, Tracked> streams_;
  std::uint32_t next_channel_id_ = 1;
  std::optional<Channel> transforms_channel_;
  std::vector<FrameTransform> transforms_;
  std::set<std::string> told_conflicts_;  // said once on stderr each
  // What the /diagnostics message says now: by stream, its hardware id, clock and writer's life.
  struct ClockEntry {
    std::string hardware_id;
    std::optional<ClockStatus> clock;
    bool writer_alive = false;
    friend bool operator==(const ClockEntry& a, const ClockEntry& b) {
      return a.hardware_id == b.hardware_id && a.clock == b.clock && a.writer_alive == b.writer_alive;
    }
  };
  std::optional<Channel> diagnostics_channel_;
  std::map<std::string, ClockEntry> clocks_;

  std::mutex poll_mutex_;  // one poll at a time
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace sim::foxglove
