// SPDX-License-Identifier: Apache-2.0
// sim_lidar_hesai: receives a Hesai Pandar's UDP packets (Boost.Asio) and publishes one SIM
// frame per revolution through LidarStream, the path sim_replay_pcap uses too.
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <boost/asio.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <optional>
#include <string>

#include "config_file.hpp"
#include "sim/clock.hpp"
#include "sim/hesai/lidar_stream.hpp"
#include "sim/hesai/stream_options.hpp"

namespace asio = boost::asio;
using asio::ip::udp;

namespace {

constexpr char tool[] = "sim_lidar_hesai";

// The largest Hesai payload is 1392 bytes; a larger buffer lets an oversized datagram arrive
// whole and be rejected by its size instead of silently cut to a plausible one.
constexpr std::size_t receive_buffer_size = 9000;

class Driver {
 public:
  Driver(sim::hesai::StreamOptions stream_options, sim::hesai::NetworkOptions network, bool summary)
      : options_(std::move(stream_options)),
        network_(std::move(network)),
        summary_(summary),
        socket_(io_),
        status_timer_(io_),
        signals_(io_, SIGINT, SIGTERM),
        terminal_(isatty(STDERR_FILENO) != 0) {}

  // Binds the socket and, when the model is known, creates the stream. Returns the exit code
  // to use on failure, or nullopt when ready.
  std::optional<int> open() {
    boost::system::error_code ec;
    const auto bind_address = asio::ip::make_address(network_.bind, ec);
    if (ec) return usage("--bind '" + network_.bind + "' is not an IP address.");
    if (!network_.source.empty()) {
      source_ = asio::ip::make_address(network_.source, ec);
      if (ec) return usage("--source '" + network_.source + "' is not an IP address.");
    }
    std::optional<asio::ip::address> group;
    if (!network_.multicast_group.empty()) {
      group = asio::ip::make_address(network_.multicast_group, ec);
      if (ec || !group->is_multicast()) {
        return usage("--multicast '" + network_.multicast_group + "' is not a multicast group address.");
      }
    }
    const udp::endpoint local(bind_address, static_cast<unsigned short>(network_.port));
    socket_.open(local.protocol(), ec);
    if (ec) return failure("cannot open a UDP socket: " + ec.message() + ".");
    // Several receivers of one multicast group must share the port; a unicast port must not be
    // shared, so two drivers on one port fail loudly instead of splitting the packets.
    if (group) socket_.set_option(udp::socket::reuse_address(true), ec);
    set_receive_buffer();
    socket_.bind(local, ec);
    if (ec == asio::error::address_in_use) {
      return failure("UDP port " + std::to_string(network_.port) + " on " + network_.bind +
                     " is already in use by another process (another driver?); stop it or "
                     "choose another --port.");
    }
    if (ec) {
      return failure("cannot bind to " + network_.bind + ":" + std::to_string(network_.port) +
                     ": " + ec.message() + "; check --bind and --port.");
    }
    if (group) {
      socket_.set_option(asio::ip::multicast::join_group(*group), ec);
      if (ec) return failure("cannot join multicast group " + group->to_string() + ": " + ec.message() + ".");
    }
    const udp::endpoint bound = socket_.local_endpoint();
    std::printf("%s: listening on %s:%u\n", tool, bound.address().to_string().c_str(), bound.port());
    std::fflush(stdout);
    if (options_.model) {
      options_.config.assembler.model = *options_.model;
      if (auto code = create_stream()) return code;
    }
    if (auto error = sim::hesai::apply_thread_placement(options_)) return failure(error->message);
    return std::nullopt;
  }

  int run() {
    signals_.async_wait([this](const boost::system::error_code& ec, int) {
      if (!ec) io_.stop();
    });
    receive();
    schedule_status();
    io_.run();
    if (exit_code_ != 0) return exit_code_;
    print_status(true);
    if (terminal_) std::fprintf(stderr, "\n");
    if (summary_) {
      std::printf("summary %s datagrams=%llu other_source=%llu unrecognised=%llu resumes=%llu\n",
                  stream_ ? stream_->describe_counters(true).c_str()
                          : "frames=0 packets=0 lost=0 malformed=0 wrong_model=0",
                  to_ull(datagrams_), to_ull(other_source_), to_ull(unrecognised_), to_ull(resumes_));
      std::fflush(stdout);
    }
    return 0;
  }

 private:
  static unsigned long long to_ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }

  std::optional<int> usage(const std::string& message) {
    std::fprintf(stderr, "%s: %s\n", tool, message.c_str());
    return 2;
  }
  std::optional<int> failure(const std::string& message) {
    std::fprintf(stderr, "%s: %s\n", tool, message.c_str());
    return 1;
  }

  void set_receive_buffer() {
    // A revolution arrives in bursts; at 3600 packets/s a default 200 KiB buffer holds ~50 ms
    // of data, so a short stall of this process would drop packets.
    boost::system::error_code ec;
    socket_.set_option(udp::socket::receive_buffer_size(network_.receive_buffer), ec);
    udp::socket::receive_buffer_size granted;
    socket_.get_option(granted, ec);
    if (granted.value() < network_.receive_buffer) {
      // Root may exceed net.core.rmem_max.
      const int wanted = network_.receive_buffer;
      ::setsockopt(socket_.native_handle(), SOL_SOCKET, SO_RCVBUFFORCE, &wanted, sizeof wanted);
      socket_.get_option(granted, ec);
    }
    if (granted.value() < network_.receive_buffer) {
      std::fprintf(stderr,
                   "%s: the receive buffer is %d bytes, less than the %d asked; raise it with "
                   "sysctl -w net.core.rmem_max=%d to ride out stalls without losing packets.\n",
                   tool, granted.value(), network_.receive_buffer, network_.receive_buffer);
    }
  }

  std::optional<int> create_stream() {
    auto stream = sim::hesai::LidarStream::create(options_.config);
    if (!stream) return failure(stream.error().message);
    stream_.emplace(std::move(stream.value()));
    return std::nullopt;
  }

  void receive() {
    socket_.async_receive_from(asio::buffer(buffer_), sender_,
                               [this](const boost::system::error_code& ec, std::size_t size) {
                                 if (ec == asio::error::operation_aborted) return;
                                 if (!ec) on_packet(size);
                                 if (exit_code_ == 0) receive();
                               });
  }

  void on_packet(std::size_t size) {
    ++datagrams_;
    if (source_ && sender_.address() != *source_) {
      ++other_source_;
      return;
    }
    const std::span<const std::uint8_t> payload(buffer_.data(), size);
    const std::int64_t host_ns = sim::realtime_ns();
    const std::int64_t now = sim::monotonic_ns();
    if (!stream_) {
      // No --model: the first packet that is a Hesai point-cloud packet tells it.
      const auto model = sim::hesai::detect_model(payload);
      if (!model) {
        ++unrecognised_;
        return;
      }
      options_.config.assembler.model = *model;
      if (const auto returns = sim::hesai::returns_in(payload, *model)) {
        options_.config.returns = std::max(options_.config.returns, *returns);
      }
      std::fprintf(stderr, "%s: detected a %s from %s\n", tool,
                   std::string(sim::hesai::to_string(*model)).c_str(),
                   sender_.address().to_string().c_str());
      if (auto code = create_stream()) {
        exit_code_ = *code;
        io_.stop();
        return;
      }
    }
    if (last_packet_ns_ != 0 && now - last_packet_ns_ > silence_timeout_ns()) {
      // The sensor was silent: the revolution in progress is stale. Readers kept the last
      // frame meanwhile (stale by its publish time); start over with fresh packets.
      stream_->reset();
      ++resumes_;
      if (!terminal_) {
        std::fprintf(stderr, "%s: packets resumed after %.1f s of silence\n", tool,
                     static_cast<double>(now - last_packet_ns_) / 1e9);
      }
    }
    last_packet_ns_ = now;
    stream_->push(payload, host_ns);
  }

  std::int64_t silence_timeout_ns() const {
    return static_cast<std::int64_t>(network_.silence_timeout_s * 1e9);
  }

  double status_interval() const {
    if (network_.status_interval_s >= 0) return network_.status_interval_s;
    return terminal_ ? 1.0 : 10.0;
  }

  void schedule_status() {
    const double interval = status_interval();
    if (interval <= 0) return;
    status_timer_.expires_after(std::chrono::milliseconds(static_cast<long>(interval * 1000)));
    status_timer_.async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      print_status(false);
      schedule_status();
    });
  }

  void print_status(bool final_line) {
    std::string line;
    if (stream_) {
      line = stream_->writer().name() + " " + std::string(sim::hesai::to_string(stream_->model())) +
             ": " + stream_->describe_counters();
    } else {
      line = "waiting for Hesai packets on port " + std::to_string(socket_.local_endpoint().port());
    }
    if (other_source_ != 0) line += " other-source " + std::to_string(other_source_);
    if (unrecognised_ != 0) line += " unrecognised " + std::to_string(unrecognised_);
    const std::int64_t now = sim::monotonic_ns();
    if (!final_line && last_packet_ns_ != 0 && now - last_packet_ns_ > silence_timeout_ns()) {
      line += "  (no packets for " + std::to_string((now - last_packet_ns_) / 1'000'000'000) + " s)";
    } else if (!final_line && last_packet_ns_ == 0 && stream_) {
      line += "  (no packets yet)";
    }
    if (terminal_) {
      std::fprintf(stderr, "\r\033[K%s", line.c_str());
    } else {
      std::fprintf(stderr, "%s: %s\n", tool, line.c_str());
    }
    std::fflush(stderr);
  }

  sim::hesai::StreamOptions options_;
  sim::hesai::NetworkOptions network_;
  bool summary_;
  asio::io_context io_;
  udp::socket socket_;
  udp::endpoint sender_;
  asio::steady_timer status_timer_;
  asio::signal_set signals_;
  bool terminal_;
  std::optional<asio::ip::address> source_;
  std::optional<sim::hesai::LidarStream> stream_;
  std::array<std::uint8_t, receive_buffer_size> buffer_{};
  std::int64_t last_packet_ns_ = 0;
  std::uint64_t datagrams_ = 0;
  std::uint64_t other_source_ = 0;
  std::uint64_t unrecognised_ = 0;
  std::uint64_t resumes_ = 0;
  int exit_code_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  sim::hesai::StreamOptions stream;
  stream.config.heartbeat_period = std::chrono::milliseconds(500);
  sim::hesai::NetworkOptions network;
  std::optional<sim::Error> config_error;
  bool summary = false;

  CLI::App app{
      "Receives a Hesai Pandar LiDAR's UDP packets and publishes one SIM frame per revolution "
      "(points decoded straight into shared memory). Settings come from --config and/or the "
      "options below (options win).\nExit codes: 0 stopped by SIGINT/SIGTERM, 1 failure, "
      "2 usage error.",
      tool};
  // Declared first: CLI11 applies options in declaration order, so the file's values are in
  // place before the command-line options override them.
  app.add_option_function<std::string>(
         "--config",
         [&](const std::string& path) { config_error = sim::hesai::load_config_file(path, stream, network); },
         "YAML settings file, e.g. config/hesai/pandar64.yaml")
      ->type_name("FILE");
  sim::hesai::add_stream_options(app, stream);
  app.add_option_function<std::string>("--bind", [&](const std::string& v) { network.bind = v; },
                                        "local address to receive on [0.0.0.0]")
      ->type_name("ADDR");
  app.add_option_function<int>("--port", [&](int v) { network.port = v; },
                               "UDP port the sensor sends to; 0 picks a free one [2368]")
      ->check(CLI::Range(0, 65535));
  app.add_option_function<std::string>("--multicast", [&](const std::string& v) { network.multicast_group = v; },
                                        "join this multicast group")
      ->type_name("GROUP");
  app.add_option_function<std::string>("--source", [&](const std::string& v) { network.source = v; },
                                        "accept packets only from this sender address")
      ->type_name("ADDR");
  app.add_option_function<int>("--receive-buffer", [&](int v) { network.receive_buffer = v; },
                               "SO_RCVBUF to ask for, bytes [16 MiB]")
      ->check(CLI::Range(65536, 1 << 30));
  app.add_option_function<double>("--status-interval", [&](double v) { network.status_interval_s = v; },
                                  "seconds between status lines; 0 for none [1 on a terminal, 10 otherwise]")
      ->check(CLI::NonNegativeNumber);
  app.add_option_function<double>("--silence-timeout", [&](double v) { network.silence_timeout_s = v; },
                                  "a gap this long (s) means the sensor stopped: the next packet starts a new frame [0.5]")
      ->check(CLI::PositiveNumber);
  app.add_flag("--summary", summary, "print one line of counters on exit: summary frames=… packets=… lost=… malformed=…");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (config_error) {
    std::fprintf(stderr, "%s: %s\n", tool, config_error->message.c_str());
    return 2;
  }
  if (stream.config.calibration.empty()) {
    std::fprintf(stderr, "%s: no calibration file given; pass the sensor's angle-correction CSV "
                         "with --calibration or in the --config file (every unit has its own).\n", tool);
    return 2;
  }

  Driver driver(std::move(stream), std::move(network), summary);
  if (auto code = driver.open()) return *code;
  return driver.run();
}
