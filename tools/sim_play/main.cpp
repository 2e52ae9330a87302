// SPDX-License-Identifier: Apache-2.0
// sim_play: plays an MCAP recording (sim_record's, or any ROS 2 MCAP with PointCloud2, Image or
// CompressedImage topics) into SIM streams on the recording's own schedule, so consumers cannot
// tell it from the live sensors.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "channel_player.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/pacer.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/mcap/reader.hpp"
#include "sim/names.hpp"
#include "sim/reader.hpp"

namespace {

struct Remap {
  std::map<std::string, std::string> topics;  // "/a" -> "/b"
  std::string stream_for(const std::string& topic) const {
    const auto it = topics.find(topic);
    return it == topics.end() ? topic : it->second;
  }
};

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

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_play",
      "Play an MCAP recording into SIM streams on its own schedule: sim_record's files (the "
      "streams come back with their exact layout) or ROS 2 recordings whose topics are "
      "PointCloud2, Image or CompressedImage (JPEG). A damaged file plays as far as it is intact.");
  CLI::App& app = cli.app();
  std::string file;
  double rate = 1.0;
  bool max_rate = false;
  bool loop = false;
  double start_s = 0;
  std::vector<std::string> remaps;
  bool wait_readers = false;
  bool quiet = false;
  app.add_option("file", file, "the MCAP file")->required()->type_name("FILE");
  auto* rate_option = app.add_option("--rate", rate, "speed factor: 2 plays twice as fast")
                          ->check(CLI::PositiveNumber)
                          ->capture_default_str();
  app.add_flag("--max-rate", max_rate, "as fast as possible, no pacing")->excludes(rate_option);
  app.add_flag("--loop", loop, "start over at the end until stopped");
  app.add_option("--start", start_s, "skip the first S seconds of the recording")
      ->check(CLI::NonNegativeNumber)
      ->type_name("S");
  app.add_option("--remap", remaps, "play topic /a into stream /b (repeatable)")->type_name("/a=/b");
  app.add_flag("--wait-for-readers", wait_readers,
               "create the streams, then wait until a reader waits on each before playing");
  app.add_flag("--quiet", quiet, "no progress line and no summary");
  cli.add_config_file();
  if (auto code = cli.parse(argc, argv)) return *code;

  Remap remap;
  for (const auto& r : remaps) {
    const auto eq = r.find('=');
    if (eq == std::string::npos) return cli.usage_error("--remap takes /topic=/stream, not \"" + r + "\"");
    const std::string to = r.substr(eq + 1);
    if (const auto problem = sim::stream_name_problem(to); !problem.empty()) return cli.usage_error(problem);
    remap.topics[r.substr(0, eq)] = to;
  }

  auto& stop = sim::apps::StopSignal::install();
  auto status = sim::apps::StatusLine::for_stderr("sim_play", quiet);
  auto reader = sim::mcap::Reader::open(file);
  if (!reader) return cli.fail(reader.error().message);
  if (!reader->problem().empty()) status.note(reader->problem());

  // One player per playable channel; several channels of one topic (a stream whose layout
  // changed while recording) share its stream name.
  std::map<std::uint16_t, sim::play::ChannelPlayer> players;
  for (const auto& [id, channel] : reader->channels()) {
    std::string stream = remap.stream_for(channel.topic);
    if (!sim::stream_name_problem(stream).empty()) {
      status.note("topic " + channel.topic + " is not a SIM stream name; give it one with --remap " +
                  channel.topic + "=/name");
      continue;
    }
    auto player = sim::play::ChannelPlayer::for_channel(channel, reader->schema_of(channel), stream);
    if (!player) {
      status.note(player.error().message);
      continue;
    }
    players.emplace(id, std::move(*player));
  }
  if (players.empty()) return cli.fail(file + " has no topic SIM can play (PointCloud2, Image or CompressedImage in CDR)");

  // Streams are created before playing: from the metadata, or from each topic's first message.
  bool need_first_messages = false;
  for (auto& [id, player] : players) need_first_messages |= !player.shape_known();
  if (need_first_messages) {
    while (auto m = reader->next()) {
      auto it = players.find(m->header.channel_id);
      if (it != players.end() && !it->second.shape_known()) {
        if (auto error = it->second.learn_shape(m->data)) status.note(error->message);
      }
    }
    reader->rewind();
  }
  std::vector<std::string> streams;
  for (auto& [id, player] : players) {
    if (!player.shape_known()) continue;
    if (std::find(streams.begin(), streams.end(), player.stream()) != streams.end()) continue;
    if (auto error = player.create_stream()) return cli.fail(error->message);
    streams.push_back(player.stream());
  }
  std::printf("playing %s into %zu stream%s\n", file.c_str(), streams.size(), streams.size() == 1 ? "" : "s");
  std::fflush(stdout);
  if (wait_readers && !wait_for_readers(streams, stop)) return sim::apps::kExitOk;

  std::uint64_t first_time = 0;
  std::uint64_t last_time = 0;
  if (reader->statistics()) {
    first_time = reader->statistics()->message_start_time;
    last_time = reader->statistics()->message_end_time;
  }
  const auto window_start = [&](std::uint64_t first) {
    return first + static_cast<std::uint64_t>(start_s * 1e9);
  };
  sim::apps::Pacer pacer(max_rate ? 0.0 : rate);
  std::int64_t shift_ns = 0;  // added to times and stamps on each loop
  std::uint64_t played = 0;
  std::uint64_t undecodable = 0;
  unsigned pass = 0;
  while (!stop.requested()) {
    ++pass;
    std::uint64_t pass_first = 0, pass_last = 0, in_window = 0;
    bool have_first = first_time != 0;
    while (!stop.requested()) {
      auto m = reader->next();
      if (!m) break;
      if (!have_first) {
        first_time = m->header.log_time;
        have_first = true;
      }
      if (m->header.log_time < window_start(first_time)) continue;
      auto it = players.find(m->header.channel_id);
      if (it == players.end()) continue;
      if (in_window++ == 0) pass_first = m->header.log_time;
      pass_last = std::max(pass_last, m->header.log_time);
      if (!pacer.wait(static_cast<std::int64_t>(m->header.log_time) + shift_ns, stop)) break;
      if (auto error = it->second.play(m->data, shift_ns)) {
        if (undecodable++ == 0) status.note(error->message);
        continue;
      }
      ++played;
      if (status.due()) {
        const std::uint64_t end = std::max(last_time, pass_last);
        const double fraction = end > window_start(first_time)
            ? static_cast<double>(m->header.log_time - window_start(first_time)) /
                  static_cast<double>(end - window_start(first_time))
            : 1.0;
        status.update(sim::apps::fields({{"played", sim::apps::number(100 * fraction, 0) + " %"},
                                         {"frames", std::to_string(played)},
                                         {"pass", std::to_string(pass)}}));
      }
    }
    if (!loop || stop.requested() || in_window == 0) break;
    // The next pass continues one mean interval after this one's last message.
    const std::uint64_t span = pass_last - pass_first;
    const std::uint64_t gap = in_window > 1 ? span / (in_window - 1) : 0;
    pacer.shift(static_cast<std::int64_t>(span + gap));
    shift_ns += static_cast<std::int64_t>(span + gap);
    reader->rewind();
  }

  std::string summary = sim::apps::fields({{"frames", std::to_string(played)},
                                           {"passes", std::to_string(pass)}});
  for (const auto& [id, player] : players) summary += "  " + player.stream() + " " + std::to_string(player.frames());
  status.finish(summary);
  if (undecodable > 0) {
    status.note(std::to_string(undecodable) + " messages could not be decoded and were skipped");
  }
  if (!reader->problem().empty()) {
    status.note(reader->problem() + (reader->problem_count() > 1
                                         ? " (and " + std::to_string(reader->problem_count() - 1) + " more problems)"
                                         : ""));
    return sim::apps::kExitFailure;
  }
  return undecodable > 0 ? sim::apps::kExitFailure : sim::apps::kExitOk;
}
