// SPDX-License-Identifier: Apache-2.0
// sim_foxglove: SIM streams live in Foxglove / Lichtblick (Foxglove WebSocket protocol) and in a
// browser (the built-in page), from one port. The work is in the sim_foxglove library.
#include <signal.h>

#include <cstdio>
#include <string>

#include "sim/foxglove/server.hpp"
#include "sim_tools/cli.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "Serve SIM streams to Foxglove or Lichtblick over the Foxglove WebSocket protocol "
      "(ws://HOST:PORT) and as a live page in a browser (http://HOST:PORT/)."};
  sim::foxglove::ServerOptions options;
  std::string compress = "none";
  bool json = false;
  app.add_option("streams", options.streams, "only these streams (default: every stream, and "
                                             "new ones as they appear)");
  app.add_option("--port", options.port, "TCP port for WebSocket and page; 0 picks a free one")
      ->capture_default_str();
  app.add_option("--bind", options.bind,
                 "address to listen on; 0.0.0.0 opens it to the network (no authentication)")
      ->capture_default_str();
  app.add_option("--max-rate", options.max_rate_hz,
                 "at most this many messages per second per channel and client (0: every frame)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--compress", compress,
                 "images as JPEG sensor_msgs/msg/CompressedImage: jpeg or jpeg:QUALITY (1-100)")
      ->capture_default_str();
  app.add_flag("--json", json, "print the listening line as JSON");
  if (auto code = sim::tools::parse(app, argc, argv)) return *code;

  if (compress.rfind("jpeg", 0) == 0) {
    options.compress_jpeg = true;
    if (compress.size() > 4) {
      if (compress[4] != ':') {
        std::fprintf(stderr, "sim_foxglove: --compress takes none, jpeg or jpeg:QUALITY.\n");
        return sim::tools::kExitUsage;
      }
      try {
        std::size_t used = 0;
        options.jpeg_quality = std::stoi(compress.substr(5), &used);
        if (used != compress.size() - 5) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        options.jpeg_quality = 0;
      }
      if (options.jpeg_quality < 1 || options.jpeg_quality > 100) {
        std::fprintf(stderr, "sim_foxglove: the JPEG quality in --compress jpeg:Q is 1 to 100.\n");
        return sim::tools::kExitUsage;
      }
    }
  } else if (compress != "none") {
    std::fprintf(stderr, "sim_foxglove: --compress takes none, jpeg or jpeg:QUALITY.\n");
    return sim::tools::kExitUsage;
  }
  for (const auto& name : options.streams) {
    if (name.empty() || name.front() != '/') {
      std::fprintf(stderr, "sim_foxglove: stream names start with '/', e.g. /lidar_top.\n");
      return sim::tools::kExitUsage;
    }
  }

  // Signals are taken synchronously by this thread; the server's threads never see them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  auto server = sim::foxglove::Server::start(options);
  if (!server) {
    std::fprintf(stderr, "sim_foxglove: %s\n", server.error().message.c_str());
    return server.error().code == sim::ErrorCode::invalid_argument ? sim::tools::kExitUsage
                                                                   : sim::tools::kExitFailure;
  }
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

  int received = 0;
  sigwait(&stop_signals, &received);
  server->stop();
  return sim::tools::kExitOk;
}
