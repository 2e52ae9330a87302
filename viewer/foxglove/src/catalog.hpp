// SPDX-License-Identifier: Apache-2.0
// Which SIM streams exist, what they look like and how they are doing: polls sim::list_streams()
// and sim::inspect() on its own thread, gives each showable stream a channel id (a new id when a
// stream's layout changes, as Foxglove ids must keep their schema) and reports what appeared and
// what went away. The page's stream table is a snapshot of it.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "encoder.hpp"
#include "sim/foxglove/protocol.hpp"
#include "sim/reader.hpp"

namespace sim::foxglove {

struct StreamEntry {
  std::string name;
  std::optional<StreamStatus> status;  // nullopt when the stream cannot be inspected
  std::string problem;                 // why not, one sentence
  double rate_hz = 0;                  // frames per second over the last poll window
  std::int64_t age_ns = -1;            // since the newest frame was published; -1 before any
  std::optional<Channel> channel;      // nullopt for streams Foxglove cannot show
};

// A channel and the layout its messages are encoded from.
struct AdvertisedStream {
  Channel channel;
  Layout layout{};
};

class Catalog {
 public:
  // Called on the catalog's thread with the channels that appeared and the ids that went away.
  using ChangeHandler = std::function<void(const std::vector<AdvertisedStream>& added,
                                           const std::vector<std::uint32_t>& removed)>;

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

 private:
  struct Tracked {
    StreamEntry entry;
    Layout layout{};
    std::uint64_t capacity = 0;
    std::uint64_t window_frames = 0;
    std::int64_t window_start_ns = 0;
  };
  void run();

  const std::vector<std::string> only_;
  const EncodeOptions encode_;
  const std::chrono::milliseconds period_;
  const ChangeHandler on_change_;
  const std::function<void()> after_poll_;

  mutable std::mutex mutex_;
  std::map<std::string, Tracked> streams_;
  std::uint32_t next_channel_id_ = 1;

  std::mutex poll_mutex_;  // one poll at a time
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace sim::foxglove
