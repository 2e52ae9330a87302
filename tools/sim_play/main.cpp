// SPDX-License-Identifier: Apache-2.0
// sim_play: plays an MCAP recording (sim_record's, or any ROS 2 MCAP with PointCloud2, Image or
// CompressedImage topics) into SIM streams on the recording's own schedule, so consumers cannot
// tell it from the live sensors.
//
// The steps, each a function below: read the command line; open the file; make one player per
// playable channel; bound the streams; create them; play the messages (paced, looped); report;
// remove the streams it made.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "channel_player.hpp"
#include "sensor_metadata.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/pacer.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/mcap/reader.hpp"
#include "sim/names.hpp"
#include "sim/reader.hpp"

namespace {

using sim::play::Players;
using sim::play::SensorMetadata;
using sim::play::ShmBudget;

struct PlayOptions {
  std::string file;
  double rate = 1.0;
  bool max_rate = false;
  bool loop = false;
  double start_s = 0;
  std::map<std::string, std::string> remap;  // "/topic" -> "/stream"
  bool wait_readers = false;
  bool quiet = false;
  std::uint64_t max_capacity_mib = 256;
  std::uint64_t max_streams = 64;
  std::uint64_t max_shm_mib = 2048;
  bool keep_streams = false;

  // The stream a channel plays into: --remap of its topic, else of the stream sim_record
  // recorded it from (sim.stream: images are on <stream>/image_raw), else that stream, else
  // the topic itself.
  std::string stream_for(const sim::mcap::Channel& channel) const {
    if (const auto it = remap.find(channel.topic); it != remap.end()) return it->second;
    const auto recorded = channel.metadata.find("sim.stream");
    if (recorded == channel.metadata.end()) return channel.topic;
    const auto it = remap.find(recorded->second);
    return it == remap.end() ? recorded->second : it->second;
  }
};

// Every sentence goes through here: they quote topics and names from the file, which must not
// reach the terminal as control sequences.
void say(sim::apps::StatusLine& status, const std::string& sentence) {
  status.note(sim::mcap::printable(sentence));
}

// The command line; returns an exit code when the program must end now (--help, usage error).
std::optional<int> parse_command_line(sim::apps::CommandLine& cli, int argc, char** argv, PlayOptions& o) {
  std::vector<std::string> remaps;
  cli.add_option("file", o.file, "the MCAP file").required().type_name("FILE");
  const auto rate_option = cli.add_option("--rate", o.rate, "speed factor: 2 plays twice as fast").positive();
  cli.add_flag("--max-rate", o.max_rate, "as fast as possible, no pacing").excludes(rate_option);
  cli.add_flag("--loop", o.loop, "start over at the end until stopped");
  cli.add_option("--start", o.start_s, "skip the first S seconds of the recording")
      .in_range(0.0, 1e9)
      .type_name("S");
  cli.add_option("--remap", remaps, "play topic /a into stream /b (repeatable)").type_name("/a=/b");
  cli.add_flag("--wait-for-readers", o.wait_readers,
               "create the streams, then wait until a reader waits on each before playing");
  cli.add_option("--max-capacity", o.max_capacity_mib,
                 "MiB per frame a stream may take at most (a recording cannot reserve more shared memory)")
      .in_range(std::uint64_t{1}, std::uint64_t{1} << 20)
      .type_name("MIB");
  cli.add_option("--max-streams", o.max_streams,
                 "streams a recording may make at most (a file naming more is refused)")
      .in_range(std::uint64_t{1}, std::uint64_t{100000})
      .type_name("N");
  cli.add_option("--max-shm", o.max_shm_mib,
                 "MiB of shared memory all streams may take together (never more than /dev/shm has free)")
      .in_range(std::uint64_t{1}, std::uint64_t{1} << 30)
      .type_name("MIB");
  cli.add_flag("--keep-streams", o.keep_streams,
               "leave the streams in /dev/shm when playback ends (by default they are removed)");
  cli.add_flag("--quiet", o.quiet, "no progress line and no summary");
  cli.add_config_file();
  if (auto code = cli.parse(argc, argv)) return code;
  for (const auto& r : remaps) {
    const auto eq = r.find('=');
    if (eq == std::string::npos) return cli.usage_error("--remap takes /topic=/stream, not \"" + r + "\"");
    const std::string to = r.substr(eq + 1);
    if (const auto problem = sim::stream_name_problem(to); !problem.empty()) return cli.usage_error(problem);
    o.remap[r.substr(0, eq)] = to;
  }
  return std::nullopt;
}

// One player per playable channel; several channels of one topic (a stream whose layout
// changed while recording) share its stream name.
Players make_players(const sim::mcap::Reader& reader, const SensorMetadata& metadata, const PlayOptions& o,
                     ShmBudget& budget, sim::apps::StatusLine& status) {
  Players players;
  for (const auto& [id, channel] : reader.channels()) {
    if (metadata.handles(id)) continue;
    std::string stream = o.stream_for(channel);
    if (!sim::stream_name_problem(stream).empty()) {
      say(status, "topic " + channel.topic + " is not a SIM stream name; give it one with --remap " +
                      channel.topic + "=/name");
      continue;
    }
    auto player = sim::play::ChannelPlayer::for_channel(channel, reader.schema_of(channel), stream,
                                                        o.max_capacity_mib << 20, budget);
    if (!player) {
      say(status, player.error().message);
      continue;
    }
    players.emplace(id, std::move(*player));
  }
  return players;
}

// Why the players would make more streams than --max-streams (a 45 KB file named 500), or empty.
std::string too_many_streams(const Players& players, const PlayOptions& o) {
  std::set<std::string> streams;
  for (const auto& [id, player] : players) streams.insert(player.stream());
  if (streams.size() <= o.max_streams) return {};
  return sim::mcap::printable(o.file) + " would make " + std::to_string(streams.size()) +
         " streams, more than --max-streams " + std::to_string(o.max_streams) +
         "; raise it if you trust the recording";
}

// What each channel holds bounds what its stream may reserve (review L4): reads the file until
// every player has met its channel's first message (or to the end; a channel the summary's
// Statistics count no message for is not waited for), hands each player that message or
// nothing, then rewinds. Usually the first chunk holds them all.
void bound_by_first_messages(sim::mcap::Reader& reader, Players& players, sim::apps::StatusLine& status) {
  const auto& stats = reader.statistics();
  const auto holds_messages = [&stats](std::uint16_t id) {
    if (!stats || stats->channel_message_counts.empty()) return true;  // not counted: look
    const auto count = stats->channel_message_counts.find(id);
    return count != stats->channel_message_counts.end() && count->second > 0;
  };
  std::set<std::uint16_t> waiting;
  for (const auto& [id, player] : players) {
    if (holds_messages(id)) waiting.insert(id);
  }
  std::set<std::uint16_t> met;
  std::vector<std::string> asked_more;  // one sentence each; a crafted file may have 64
  while (!waiting.empty()) {
    auto m = reader.next();
    if (!m) break;
    if (waiting.erase(m->header.channel_id) == 0) continue;
    met.insert(m->header.channel_id);
    auto& player = players.at(m->header.channel_id);
    if (!player.shape_known()) {
      if (auto error = player.learn_shape(m->data)) say(status, error->message);
    } else if (auto asked = player.bound_by(m->data)) {
      asked_more.push_back(std::move(*asked));
    }
  }
  for (auto& [id, player] : players) {
    if (met.count(id) > 0) continue;
    if (auto asked = player.bound_by(std::nullopt)) asked_more.push_back(std::move(*asked));
  }
  reader.rewind();
  if (asked_more.empty()) return;
  const auto more = asked_more.size() - 1;
  say(status, asked_more.front() + (more > 0 ? " (and so do " + std::to_string(more) + " more topics)" : ""));
}

// Creates every stream before playing, each sized from its metadata or its channel's first
// message. A stream that cannot be created is said and its channels dropped; returns the streams
// made.
std::vector<std::string> create_streams(sim::mcap::Reader& reader, Players& players,
                                        sim::apps::StatusLine& status, bool& failed) {
  bound_by_first_messages(reader, players, status);
  std::vector<std::string> streams;
  for (auto it = players.begin(); it != players.end();) {
    auto& player = it->second;
    const bool made = std::find(streams.begin(), streams.end(), player.stream()) != streams.end();
    if (!player.shape_known() || made) {
      ++it;
      continue;
    }
    if (auto error = player.create_stream()) {
      say(status, error->message);
      failed = true;
      it = players.erase(it);
      continue;
    }
    streams.push_back(player.stream());
    ++it;
  }
  return streams;
}

// Waits until a reader sleeps on every stream (--wait-for-readers); false when stopped.
bool wait_for_readers(const std::vector<std::string>& streams, const sim::apps::StopSignal& stop) {
  for (const auto& name : streams) {
    for (;;) {
      auto status = sim::inspect(name);
      if (status && status->sleeping_readers > 0) break;
      if (!stop.sleep_for(std::chrono::milliseconds(5))) return false;
    }
  }
  return true;
}

// Plays the file once or, with --loop, until stopped: each pass continues one mean message
// interval after the last, with times and stamps shifted so they keep going forward.
class Playback {
 public:
  Playback(sim::mcap::Reader& reader, Players& players, SensorMetadata& metadata, const PlayOptions& o,
           const sim::apps::StopSignal& stop, sim::apps::StatusLine& status)
      : reader_(reader), players_(players), metadata_(metadata), options_(o), stop_(stop), status_(status),
        pacer_(o.max_rate ? 0.0 : o.rate) {}

  void run() {
    while (!stop_.requested()) {
      ++passes_;
      const Pass pass = play_pass();
      if (!options_.loop || stop_.requested() || pass.messages == 0) break;
      const std::uint64_t span = pass.last - pass.first;
      const std::uint64_t gap = pass.messages > 1 ? span / (pass.messages - 1) : 0;
      pacer_.shift(static_cast<std::int64_t>(span + gap));
      shift_ns_ += static_cast<std::int64_t>(span + gap);
      reader_.rewind();
    }
  }

  std::uint64_t played() const noexcept { return played_; }
  std::uint64_t undecodable() const noexcept { return undecodable_; }
  unsigned passes() const noexcept { return passes_; }

 private:
  struct Pass {
    std::uint64_t first = UINT64_MAX, last = 0, messages = 0;  // log times of what was played
  };

  // Messages logged before this are skipped (--start). Without --start nothing is: a file whose
  // messages are out of order plays the early ones late, at once, rather than dropping them.
  std::uint64_t skip_before(std::uint64_t first_in_file_order) const {
    if (options_.start_s <= 0) return 0;
    const std::uint64_t start = reader_.start_time().value_or(first_in_file_order);
    return start + static_cast<std::uint64_t>(options_.start_s * 1e9);
  }

  Pass play_pass() {
    Pass pass;
    std::optional<std::uint64_t> window;
    while (!stop_.requested()) {
      auto m = reader_.next();
      if (!m) break;
      if (!window) window = skip_before(m->header.log_time);
      if (metadata_.handles(m->header.channel_id)) {  // even before --start: /tf_static comes first
        if (auto error = metadata_.take(m->header.channel_id, m->data, players_)) {
          if (undecodable_++ == 0) say(status_, error->message);
        }
        continue;
      }
      if (m->header.log_time < *window) continue;
      auto it = players_.find(m->header.channel_id);
      if (it == players_.end()) continue;
      ++pass.messages;
      pass.first = std::min(pass.first, m->header.log_time);
      pass.last = std::max(pass.last, m->header.log_time);
      if (!pacer_.wait(static_cast<std::int64_t>(m->header.log_time) + shift_ns_, stop_)) break;
      if (auto error = it->second.play(m->data, shift_ns_)) {
        if (undecodable_++ == 0) say(status_, error->message);
        continue;
      }
      ++played_;
      if (status_.due()) show_progress(m->header.log_time, *window);
    }
    return pass;
  }

  void show_progress(std::uint64_t now, std::uint64_t window) {
    const auto& stats = reader_.statistics();
    const std::uint64_t from = std::max(window, reader_.start_time().value_or(now));
    const std::uint64_t to = stats ? stats->message_end_time : now;
    const double fraction = to > from && now >= from
                                ? std::min(1.0, static_cast<double>(now - from) / static_cast<double>(to - from))
                                : 1.0;
    status_.update(sim::apps::fields({{"played", sim::apps::number(100 * fraction, 0) + " %"},
                                      {"frames", std::to_string(played_)},
                                      {"pass", std::to_string(passes_)}}));
  }

  sim::mcap::Reader& reader_;
  Players& players_;
  SensorMetadata& metadata_;
  const PlayOptions& options_;
  const sim::apps::StopSignal& stop_;
  sim::apps::StatusLine& status_;
  sim::apps::Pacer pacer_;
  std::int64_t shift_ns_ = 0;  // added to times and stamps on each loop
  std::uint64_t played_ = 0;
  std::uint64_t undecodable_ = 0;
  unsigned passes_ = 0;
};

// Removes the streams the players made, once they closed them, unless --keep-streams: like a
// player whose topics vanish when it stops, a playback leaves no region behind in /dev/shm (a
// reader keeps the frames it holds; a stream another writer took meanwhile is left alone).
void remove_streams(Players& players, bool keep) {
  std::set<std::string> made;
  for (const auto& [id, player] : players) {
    if (player.made_stream()) made.insert(player.stream());
  }
  players.clear();  // closes the writers
  if (keep) return;
  for (const auto& name : made) (void)sim::destroy(name);
}

// The summary line and the sentences of what went wrong; the exit code.
int report(const Playback& playback, const Players& players, const sim::mcap::Reader& reader,
           bool streams_failed, sim::apps::StatusLine& status) {
  std::string summary = sim::apps::fields({{"frames", std::to_string(playback.played())},
                                           {"passes", std::to_string(playback.passes())}});
  for (const auto& [id, player] : players) summary += "  " + player.stream() + " " + std::to_string(player.frames());
  status.finish(summary);
  for (const auto& [id, player] : players) {
    if (!player.sensor_problem().empty()) say(status, player.sensor_problem());
  }
  if (playback.undecodable() > 0) {
    say(status, std::to_string(playback.undecodable()) + " messages could not be decoded and were skipped");
  }
  if (!reader.problem().empty()) {
    const auto more = reader.problem_count() - 1;
    say(status, reader.problem() + (more > 0 ? " (and " + std::to_string(more) + " more problems)" : ""));
  }
  const bool failed = !reader.problem().empty() || playback.undecodable() > 0 || streams_failed;
  return failed ? sim::apps::kExitFailure : sim::apps::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_play",
      "Play an MCAP recording into SIM streams on its own schedule: sim_record's files (the "
      "streams come back with their exact layout) or ROS 2 recordings whose topics are "
      "PointCloud2, Image or CompressedImage (JPEG). A damaged file plays as far as it is intact.");
  PlayOptions options;
  if (auto code = parse_command_line(cli, argc, argv, options)) return *code;

  auto& stop = sim::apps::StopSignal::install();
  auto status = sim::apps::StatusLine::for_stderr("sim_play", options.quiet);
  auto reader = sim::mcap::Reader::open(options.file);
  if (!reader) return cli.fail(sim::mcap::printable(reader.error().message));
  if (!reader->problem().empty()) say(status, reader->problem());

  SensorMetadata metadata(*reader);
  ShmBudget budget(options.max_shm_mib << 20);
  Players players = make_players(*reader, metadata, options, budget, status);
  if (players.empty()) {
    return cli.fail(sim::mcap::printable(options.file) +
                    " has no topic SIM can play (PointCloud2, Image or CompressedImage in CDR)");
  }
  if (const std::string refused = too_many_streams(players, options); !refused.empty()) {
    return cli.fail(refused);
  }
  bool streams_failed = false;
  const auto streams = create_streams(*reader, players, status, streams_failed);
  if (players.empty()) return cli.fail("no stream of " + sim::mcap::printable(options.file) + " could be created");
  std::printf("playing %s into %zu stream%s\n", sim::mcap::printable(options.file).c_str(), streams.size(),
              streams.size() == 1 ? "" : "s");
  std::fflush(stdout);
  if (options.wait_readers && !wait_for_readers(streams, stop)) {
    remove_streams(players, options.keep_streams);
    return sim::apps::kExitOk;
  }

  metadata.attach(players);
  Playback playback(*reader, players, metadata, options, stop, status);
  playback.run();
  const int code = report(playback, players, *reader, streams_failed, status);
  remove_streams(players, options.keep_streams);
  return code;
}
