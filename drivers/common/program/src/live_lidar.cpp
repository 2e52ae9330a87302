// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/live_lidar.hpp"

#include <algorithm>
#include <cstdio>
#include <string_view>
#include <utility>

#include "sim/apps/host_clock_options.hpp"
#include "sim/clock.hpp"

namespace sim::apps {

void add_receive_options(CommandLine& cli, LiveReceiveOptions& o, lidar::IpVersions versions,
                         const std::function<void(CommandLine&)>& add_ports) {
  const Option::Problem address = [versions](const std::string& text) {
    return lidar::address_problem(text, versions);
  };
  cli.add_option("--bind", o.bind,
                 versions == lidar::IpVersions::v4 ? "local IPv4 address to receive on"
                                                   : "local address to receive on")
      .type_name("ADDR")
      .check(address);
  add_ports(cli);
  cli.add_option("--multicast,--multicast-group", o.multicast_group, "join this multicast group")
      .type_name("GROUP")
      .check([versions](const std::string& text) { return lidar::multicast_group_problem(text, versions); });
  cli.add_option("--source", o.source, "accept packets only from this sender address")
      .type_name("ADDR")
      .check(address);
  cli.add_option("--receive-buffer", o.receive_buffer, "SO_RCVBUF to ask for per socket, bytes")
      .in_range(65536, 1 << 30);
  cli.add_option("--status-interval", o.status_interval,
                 "seconds between status lines; 0 for none [1 on a terminal, 10 otherwise]")
      .type_name("S")
      .non_negative();
  cli.add_option("--silence-timeout", o.silence_timeout,
                 "a gap this long (s) means the sensor stopped: the next packet starts a new frame")
      .positive();
  add_host_clock_options(cli, o.host_clock);
  cli.add_option("--stamp-fallback", o.stamp_fallback,
                 "host: while the sensor's clock is judged in error (or not judged yet), stamp frames "
                 "with their arrival on this host instead, and say so in the clock record and each "
                 "frame; back to the sensor's stamps when it is not")
      .one_of({"off", "host"});
}

void add_output_options(CommandLine& cli, LiveReceiveOptions& o, const std::string& summary_help) {
  cli.add_flag("--summary", o.summary, summary_help);
  cli.add_flag("-q,--quiet", o.quiet, "no status line and no final line");
}

void set_listen(lidar::UdpListen& listen, const LiveReceiveOptions& o) {
  listen.bind = o.bind;
  listen.multicast_group = o.multicast_group;
  listen.source = o.source;
  listen.receive_buffer = o.receive_buffer;
  listen.silence_timeout = std::chrono::nanoseconds(static_cast<std::int64_t>(o.silence_timeout * 1e9));
}

namespace {

timing::HostClockWatchOptions watch_options(const LiveReceiveOptions& o) {
  timing::HostClockWatchOptions options;
  options.clock = o.host_clock;
  if (o.quiet) options.log = [](const std::string&) {};
  return options;
}

}  // namespace

HostClockSource::HostClockSource(const LiveReceiveOptions& options)
    : watch_(watch_options(options)),
      stamp_fallback_(options.stamp_fallback == "host" ? timing::StampFallback::host : timing::StampFallback::off) {}

timing::ClockSources HostClockSource::sources() const {
  timing::ClockSources sources;
  sources.host = [this] { return watch_.latest(); };
  sources.stamp_fallback = stamp_fallback_;  // each switch on stderr, --quiet or not: it changes the stamps
  return sources;
}

std::string sentence(std::string text) {
  while (!text.empty() && (text.back() == '.' || text.back() == ' ')) text.pop_back();
  return text + ".";
}

std::string receive_status(const lidar::ReceiveCounters& counters, std::int64_t last_packet_ns,
                           std::int64_t silence_ns, bool expecting, bool final_line) {
  std::string text = lidar::describe_problems(counters);
  if (final_line) return text;
  const std::int64_t now = monotonic_ns();
  if (last_packet_ns != 0 && now - last_packet_ns > silence_ns) {
    text += "  (no packets for " + std::to_string((now - last_packet_ns) / 1'000'000'000) + " s)";
  } else if (last_packet_ns == 0 && expecting) {
    text += "  (no packets yet)";
  }
  return text;
}

LiveStatus::LiveStatus(std::string tool, const LiveReceiveOptions& options)
    : options_(options), live_(stderr_is_terminal() && !options.quiet),
      line_(StatusLine::for_stderr(std::move(tool), options.quiet)) {}

void LiveStatus::check_receive_buffer(int granted, int asked) {
  if (granted >= asked) return;
  line_.note("the receive buffer is " + std::to_string(granted) + " bytes, less than the " +
             std::to_string(asked) + " asked; raise it with sysctl -w net.core.rmem_max=" +
             std::to_string(asked) + " to ride out stalls without losing packets.");
}

lidar::ReceiverCallbacks LiveStatus::callbacks(Text text) {
  text_ = std::move(text);
  lidar::ReceiverCallbacks callbacks;
  callbacks.note = [this](std::string_view message) { line_.note(sentence(std::string(message))); };
  const double interval = options_.status_interval.value_or(live_ ? 1.0 : 10.0);
  if (interval > 0 && !options_.quiet) {
    callbacks.tick_period = std::chrono::nanoseconds(static_cast<std::int64_t>(interval * 1e9));
    callbacks.tick = [this] {
      // On a terminal the line is redrawn in place; in a log each tick is a line of its own.
      if (live_) {
        line_.update(text_(false));
      } else {
        line_.note(text_(false));
      }
    };
  }
  return callbacks;
}

void add_clock_poll_option(CommandLine& cli, double& seconds) {
  cli.add_option("--clock-poll-seconds", seconds,
                 "how often to ask the sensor about its clock (source, lock, offset from master, "
                 "grandmaster) off the frame path, when its address is known (--sensor-ip or "
                 "--source); 0: never")
      .in_range(0.0, 3600.0);
}

lidar::ReceiverCallbacks with_clock_tick(lidar::ReceiverCallbacks callbacks, std::function<void()> clock_tick,
                                         std::chrono::nanoseconds period) {
  if (!clock_tick) return callbacks;
  if (!callbacks.tick || callbacks.tick_period.count() <= 0) {
    callbacks.tick_period = period;
    callbacks.tick = std::move(clock_tick);
    return callbacks;
  }
  const std::int64_t status_ns = callbacks.tick_period.count();
  callbacks.tick_period = std::min(callbacks.tick_period, period);
  callbacks.tick = [status = std::move(callbacks.tick), clock = std::move(clock_tick), status_ns,
                    next_ns = monotonic_ns() + status_ns]() mutable {
    clock();
    // The receiver calls at the shorter period; the status line keeps its own (a tick may come
    // a little early, so "due" allows a millisecond).
    const std::int64_t now = monotonic_ns();
    if (now + 1'000'000 >= next_ns) {
      next_ns = now + status_ns;
      status();
    }
  };
  return callbacks;
}

void LiveStatus::finish(const std::string& stream_summary, const lidar::ReceiveCounters& c) {
  line_.finish(text_ ? text_(true) : std::string());
  if (!options_.summary) return;
  const auto ull = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  std::printf("summary %s datagrams=%llu other_source=%llu unrecognised=%llu oversized=%llu resumes=%llu "
              "other_senders=%llu\n",
              stream_summary.c_str(), ull(c.datagrams), ull(c.other_source), ull(c.unrecognised),
              ull(c.oversized), ull(c.resumes), ull(c.other_senders));
  std::fflush(stdout);
}

}  // namespace sim::apps
