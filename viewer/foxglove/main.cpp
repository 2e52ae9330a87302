// SPDX-License-Identifier: Apache-2.0
// sim_foxglove: SIM streams live in Foxglove / Lichtblick (Foxglove WebSocket protocol) and in a
// browser (the built-in page), from one port. The work is in the sim_foxglove library; options,
// stop signals and exit codes are the programs' shared ones (apps/common).
#include <poll.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/foxglove/server.hpp"
#include "sim/names.hpp"

namespace {

// "none", "jpeg" or "jpeg:Q"; false when it is none of these.
bool parse_compress(const std::string& text, sim::foxglove::ServerOptions& options) {
  if (text == "none") return true;
  if (text.rfind("jpeg", 0) != 0) return false;
  options.compress_jpeg = true;
  if (text.size() == 4) return true;
  if (text[4] != ':' || text.size() == 5 || text.size() > 8) return false;
  int quality = 0;
  for (const char c : text.substr(5)) {
    if (c < '0' || c > '9') return false;
    quality = quality * 10 + (c - '0');
  }
  options.jpeg_quality = quality;
  return quality >= 1 && quality <= 100;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_foxglove",
      "Serve SIM streams to Foxglove or Lichtblick over the Foxglove WebSocket protocol "
      "(ws://HOST:PORT) and as a live page in a browser (http://HOST:PORT/). Images go out as "
      "sensor_msgs/msg/Image (or CompressedImage), LiDAR frames as PointCloud2, in CDR.");
  sim::foxglove::ServerOptions options;
  std::string compress = "none";
  bool json = false;
  cli.add_option("streams", options.streams,
                 "only these streams (default: every stream, and new ones as they appear)")
      .check([](const std::string& name) { return sim::stream_name_problem(name); });
  cli.add_option("--port", options.port, "TCP port of the WebSocket and the page; 0 picks a free one");
  cli.add_option("--bind", options.bind,
                 "address to listen on; 0.0.0.0 opens it to the network (no authentication)");
  cli.add_option("--max-rate", options.max_rate_hz,
                 "at most this many messages per second per channel and client (0: every frame; "
                 "else at least 0.000001)")
      .check(
          [](const std::string& text) -> std::string {
            const double rate = std::strtod(text.c_str(), nullptr);
            return rate == 0 || rate >= sim::foxglove::kMinRateHz
                       ? std::string()
                       : "--max-rate takes 0 (every frame) or a rate of at least 0.000001 Hz";
          },
          "RATE");
  cli.add_option("--max-connections", options.max_connections,
                 "page and Foxglove connections served at once; more get HTTP 503")
      .in_range(1u, 100000u);
  cli.add_option("--allow-origin", options.allowed_origins,
                 "a web origin (https://host[:port]) whose pages may open the WebSocket, beside this "
                 "server's page and Foxglove's web app; its host is also accepted by the page. "
                 "* allows any (not safe)");
  cli.add_option("--compress", compress,
                 "images as JPEG sensor_msgs/msg/CompressedImage: none, jpeg or jpeg:QUALITY (1-100)");
  cli.add_flag("--json", json, "print the listening line as JSON");
  cli.add_trust(options.trust);
  cli.add_config_file();
  if (auto code = cli.parse(argc, argv)) return *code;
  if (!parse_compress(compress, options)) {
    return cli.usage_error("--compress takes none, jpeg or jpeg:QUALITY with QUALITY from 1 to 100.");
  }

  auto& stop = sim::apps::StopSignal::install();
  auto server = sim::foxglove::Server::start(options);
  if (!server) return cli.fail(server.error());

  const std::string host = options.bind == "0.0.0.0" ? "localhost" : options.bind;
  const unsigned port = server->port();
  if (json) {
    std::printf("{\"event\":\"listening\",\"bind\":\"%s\",\"port\":%u}\n", options.bind.c_str(),
                port);
  } else {
    std::printf("sim_foxglove: listening on %s port %u\n"
                "  page:     http://%s:%u/\n"
                "  Foxglove: open a Foxglove WebSocket connection to ws://%s:%u\n",
                options.bind.c_str(), port, host.c_str(), port, host.c_str(), port);
  }
  std::fflush(stdout);

  pollfd stop_fd{stop.fd(), POLLIN, 0};
  while (!stop.requested()) ::poll(&stop_fd, 1, 1000);
  server->stop();
  return sim::apps::kExitOk;
}
