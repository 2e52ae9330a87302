// SPDX-License-Identifier: Apache-2.0
// sim_dds_bridge: SIM streams as ROS 2 topics for other computers (--publish), and ROS 2 topics
// from DDS into local SIM streams (--subscribe), on Fast DDS over UDP. A thin program: the
// options become one Outbound or Inbound per topic, each with its own thread; this thread only
// reports. See docs/bridge.md.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bridge_options.hpp"
#include "clock_diagnostics.hpp"
#include "dds_session.hpp"
#include "inbound.hpp"
#include "outbound.hpp"
#include "static_transforms.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/ros2/message.hpp"

// Debian's libfastrtps 2.9.1 itself deletes an object of its RTPSReader with the wrong size when a
// participant is destroyed (ASan: new-delete-type-mismatch inside ~RTPSReader). It is not the
// bridge's code and is harmless with the system allocator, so sanitizer builds skip that one check.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SIM_BRIDGE_WITH_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(SIM_BRIDGE_WITH_ASAN)
extern "C" const char* __asan_default_options() { return "new_delete_type_mismatch=0"; }
#endif

namespace {

using namespace sim;
using namespace sim::bridge;

std::string counters_json(const Counters& c) {
  auto n = [](const std::atomic<std::uint64_t>& v) { return std::to_string(v.load()); };
  return "\"frames_seen\":" + n(c.frames_seen) + ",\"bridged\":" + n(c.bridged) +
         ",\"serialized\":" + n(c.serialized) + ",\"no_reader\":" + n(c.no_reader) +
         ",\"skipped_rate\":" + n(c.skipped_rate) + ",\"torn\":" + n(c.torn) +
         ",\"malformed\":" + n(c.malformed) + ",\"failed\":" + n(c.failed) +
         ",\"matched\":" + std::to_string(c.matched.load()) +
         ",\"connected\":" + (c.connected.load() ? "true" : "false");
}

struct Report {
  std::vector<std::unique_ptr<Outbound>>& outbound;
  std::vector<std::unique_ptr<Inbound>>& inbound;
  StaticTransforms& transforms;
  ClockDiagnostics& clocks;

  // One JSON object: every topic's counters (camera_info and /tf_static once they exist).
  std::string json() const {
    std::string out = "{\"topics\":[";
    bool first = true;
    auto add = [&](const char* direction, const std::string& stream, const std::string& topic,
                   const Counters& c) {
      out += std::string(first ? "" : ",") + "{\"direction\":\"" + direction +
             "\",\"stream\":\"" + stream + "\",\"topic\":\"" + topic + "\"," +
             counters_json(c) + "}";
      first = false;
    };
    for (const auto& o : outbound) {
      const auto& opt = o->options();
      add("publish", opt.stream, o->raw_topic(), o->raw());
      if (opt.jpeg_quality) add("publish", opt.stream, o->compressed_topic(), o->compressed());
      if (o->camera_info().connected.load()) {
        add("publish", opt.stream, o->camera_info_topic(), o->camera_info());
      }
    }
    if (transforms.counters().connected.load()) {
      add("publish", "", tf_static_topic, transforms.counters());
    }
    if (clocks.counters().connected.load()) add("publish", "", diagnostics_topic, clocks.counters());
    for (const auto& i : inbound) {
      add("subscribe", i->options().stream, i->options().topic, i->counters());
    }
    return out + "]}";
  }

  // "/lidar_top→ 120 sent 1 reader  /remote← 30 in 0 bad".
  std::string text() const {
    std::vector<std::pair<std::string_view, std::string>> items;
    std::string out;
    for (const auto& o : outbound) {
      const Counters& c = o->raw();
      out += (out.empty() ? "" : "  ") + o->raw_topic() + " → " + std::to_string(c.bridged.load()) +
             " sent, " + std::to_string(c.matched.load()) + " readers, " +
             std::to_string(c.skipped_rate.load()) + " rate-skipped";
      if (o->options().jpeg_quality) {
        out += ", " + std::to_string(o->compressed().bridged.load()) + " jpeg";
      }
    }
    for (const auto& i : inbound) {
      const Counters& c = i->counters();
      out += (out.empty() ? "" : "  ") + i->options().topic + " ← " + std::to_string(c.bridged.load()) +
             " frames, " + std::to_string(c.malformed.load()) + " malformed";
    }
    return out;
  }

  // Problems the topic threads met since the last look, one sentence each.
  void problems(apps::StatusLine& status) const {
    auto tell = [&](Counters& c) {
      for (const std::string& p : c.take_problems()) status.note(p);
    };
    for (const auto& o : outbound) {
      tell(o->raw());
      tell(o->compressed());
      tell(o->camera_info());
    }
    tell(transforms.counters());
    tell(clocks.counters());
    for (const auto& i : inbound) tell(i->counters());
  }
};

struct Options {
  RawOptions raw;
  int domain = 0;
  bool json = false;
  bool quiet = false;
  double status_period = 1.0;
  Trust trust;
  std::optional<apps::Option> subscribe;  // for pairing each plain --as with its --subscribe
  std::optional<apps::Option> as;
};

void add_options(apps::CommandLine& cli, Options& o) {
  RawOptions& raw = o.raw;
  cli.add_option("--publish", raw.publish, "SIM stream to publish as the ROS 2 topic of the same name (repeatable)")
      .type_name("STREAM");
  o.subscribe = cli.add_option("--subscribe", raw.subscribe,
                               "ROS 2 topic to write into a SIM stream (repeatable)")
                    .type_name("TOPIC");
  o.as = cli.add_option("--as", raw.as,
                        "SIM stream for the --subscribe before it [the topic's name], or "
                        "TOPIC=STREAM")
             .type_name("STREAM");
  cli.add_option("--domain", o.domain, "DDS domain id (ROS_DOMAIN_ID)").in_range(0, 232);
  cli.add_option("--frame-id", raw.frame_id, "header.frame_id of a published stream [its name without '/']")
      .type_name("STREAM=ID");
  cli.add_option("--max-rate", raw.max_rate, "send at most this many frames a second of a stream")
      .type_name("STREAM=HZ");
  cli.add_option("--compress", raw.compress,
                 "also publish a stream as sensor_msgs/msg/CompressedImage on <topic>/compressed "
                 "(JPEG quality 1-100) [90]")
      .type_name("STREAM=jpeg[:Q]");
  cli.add_flag("--reliable", raw.reliable,
               "publish with reliable QoS instead of ROS 2's sensor-data profile (best effort); "
               "for subscribers with the default QoS");
  cli.add_flag("--reliable-subscribe", raw.reliable_subscribe,
               "subscribe with reliable QoS (then best-effort publishers, most drivers, do not "
               "match) [best effort: matches both]");
  cli.add_flag("--json", o.json, "print every topic's counters as one JSON line per status period on stdout");
  cli.add_option("--status-period", o.status_period, "seconds between status reports")
      .in_range(0.05, 3600.0);
  cli.add_flag("-q,--quiet", o.quiet, "no status line and no summary");
  cli.add_trust(o.trust);
  cli.add_config_file();
}

// Pairs each plain --as with the --subscribe given before it (RawOptions::as_after).
void pair_as_with_subscribes(const apps::CommandLine& cli, Options& o) {
  std::vector<std::size_t> after;
  std::size_t subscribes_seen = 0;
  for (const apps::Option& option : cli.parse_order()) {
    if (o.subscribe && option == *o.subscribe) ++subscribes_seen;
    if (o.as && option == *o.as) after.push_back(subscribes_seen);
  }
  // The parse order lists one entry per value; keep only those of plain --as values.
  std::size_t k = 0;
  for (const std::string& item : o.raw.as) {
    if (k < after.size() && item.find('=') == std::string::npos) o.raw.as_after.push_back(after[k]);
    ++k;
  }
}

// Every topic's thread: one Outbound per --publish, one Inbound per --subscribe, and the
// mountings each direction shares (/tf_static).
struct Topics {
  Topics(DdsSession& session, BridgePlan& plan, const Trust& trust)
      : transforms(session), clocks(session) {
    if (!plan.inbound.empty()) remote_transforms.emplace(session);
    for (auto& o : plan.outbound) {
      o.trust = trust;
      outbound.push_back(std::make_unique<Outbound>(session, transforms, clocks, o));
    }
    for (auto& i : plan.inbound) {
      inbound.push_back(std::make_unique<Inbound>(session, *remote_transforms, i));
    }
  }
  // Review L4: the threads stop before the last report, so it counts every message they handled.
  void stop() {
    for (auto& o : outbound) o->stop();
    for (auto& i : inbound) i->stop();
  }
  ~Topics() {
    outbound.clear();  // before the transforms and clocks they publish into
    inbound.clear();
  }

  StaticTransforms transforms;
  ClockDiagnostics clocks;
  std::optional<RemoteTransforms> remote_transforms;
  std::vector<std::unique_ptr<Outbound>> outbound;
  std::vector<std::unique_ptr<Inbound>> inbound;
};

// One line per topic when the bridge starts: which way it goes.
void announce(apps::StatusLine& status, const Topics& topics, int domain) {
  for (const auto& o : topics.outbound) {
    status.note(o->options().stream + " → DDS rt" + announced_topic(o->options()) + " (domain " +
                std::to_string(domain) + ")");
  }
  for (const auto& i : topics.inbound) {
    status.note("DDS rt" + i->options().topic + " → " + i->options().stream);
  }
}

// Reports every --status-period until a stop: problems, the JSON line, the status line.
void report_until_stopped(const Options& o, const Report& report, apps::StatusLine& status,
                          const apps::StopSignal& stop) {
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(o.status_period * 1e9));
  while (stop.sleep_for(period)) {
    report.problems(status);
    if (o.json) {
      std::printf("%s\n", report.json().c_str());
      std::fflush(stdout);
    }
    status.update(report.text());
  }
}

}  // namespace

int main(int argc, char** argv) {
  apps::CommandLine cli(
      "sim_dds_bridge",
      "Bridges SIM streams and ROS 2 topics over DDS (Fast DDS, UDP): --publish makes a local SIM "
      "stream the ROS 2 topic of the same name (points as sensor_msgs/msg/PointCloud2, images as "
      "sensor_msgs/msg/Image, mjpeg as CompressedImage), serialized only while a remote reader "
      "listens; --subscribe writes a ROS 2 Image, CompressedImage or PointCloud2 topic into a "
      "local SIM stream.");
  Options options;
  add_options(cli, options);
  if (auto code = cli.parse(argc, argv)) return *code;
  pair_as_with_subscribes(cli, options);
  auto plan = plan_bridge(options.raw);
  if (!plan) return cli.fail(plan.error());

  auto& stop = apps::StopSignal::install();
  auto session = DdsSession::create(options.domain);
  if (!session) return cli.fail(session.error());
  Topics topics(**session, *plan, options.trust);
  const Report report{topics.outbound, topics.inbound, topics.transforms, topics.clocks};

  auto status = apps::StatusLine::for_stderr("sim_dds_bridge", options.quiet);
  if (!options.quiet) announce(status, topics, options.domain);
  report_until_stopped(options, report, status, stop);
  topics.stop();
  report.problems(status);
  if (options.json) std::printf("%s\n", report.json().c_str());
  status.finish(report.text());
  return apps::kExitOk;
}
