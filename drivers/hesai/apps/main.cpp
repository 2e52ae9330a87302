// SPDX-License-Identifier: Apache-2.0
// sim_lidar_hesai: receives a Hesai Pandar's UDP packets (socket set up with Boost.Asio, taken in
// batches with recvmmsg) and publishes one SIM frame per revolution through LidarStream, the path
// sim_replay_pcap uses too.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <boost/asio.hpp>

#include <algorithm>
#include <array>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <vector>

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

// Room for one recvmmsg: payloads, sender addresses and the kernel's receive stamps.
struct ReceiveBatch {
  static constexpr std::size_t size = 32;
  std::vector<std::array<std::uint8_t, receive_buffer_size>> payloads =
      std::vector<std::array<std::uint8_t, receive_buffer_size>>(size);
  std::array<sockaddr_storage, size> senders{};
  std::array<iovec, size> vectors{};
  std::array<std::array<char, CMSG_SPACE(sizeof(timespec))>, size> controls{};
  std::array<mmsghdr, size> headers{};

  // recvmmsg overwrites the lengths; set them again before each call.
  void prepare() {
    for (std::size_t i = 0; i < size; ++i) {
      vectors[i] = {payloads[i].data(), payloads[i].size()};
      msghdr& h = headers[i].msg_hdr;
      h = {};
      h.msg_name = &senders[i];
      h.msg_namelen = sizeof(sockaddr_storage);
      h.msg_iov = &vectors[i];
      h.msg_iovlen = 1;
      h.msg_control = controls[i].data();
      h.msg_controllen = controls[i].size();
      headers[i].msg_len = 0;
    }
  }

  std::span<const std::uint8_t> payload(int i) const {
    return {payloads[static_cast<std::size_t>(i)].data(), headers[static_cast<std::size_t>(i)].msg_len};
  }

  asio::ip::address sender(int i) const {
    const sockaddr_storage& from = senders[static_cast<std::size_t>(i)];
    if (from.ss_family == AF_INET6) {
      const auto& v6 = reinterpret_cast<const sockaddr_in6&>(from);
      asio::ip::address_v6::bytes_type bytes;
      std::memcpy(bytes.data(), &v6.sin6_addr, bytes.size());
      const asio::ip::address_v6 address(bytes, v6.sin6_scope_id);
      // A dual-stack socket reports IPv4 senders as ::ffff:a.b.c.d; --source is written as IPv4.
      if (address.is_v4_mapped()) return asio::ip::make_address_v4(asio::ip::v4_mapped, address);
      return address;
    }
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(from);
    return asio::ip::address_v4(ntohl(v4.sin_addr.s_addr));
  }

  // CLOCK_REALTIME of the datagram's arrival, from the kernel; now if it gave none.
  std::int64_t kernel_receive_ns(int i) {
    msghdr& h = headers[static_cast<std::size_t>(i)].msg_hdr;
    for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec t;
        std::memcpy(&t, CMSG_DATA(c), sizeof t);
        return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec;
      }
    }
    return sim::realtime_ns();
  }
};

volatile std::sig_atomic_t stop_requested = 0;

class Driver {
 public:
  Driver(sim::hesai::StreamOptions stream_options, sim::hesai::NetworkOptions network, bool summary)
      : options_(std::move(stream_options)),
        network_(std::move(network)),
        summary_(summary),
        socket_(io_),
        terminal_(isatty(STDERR_FILENO) != 0) {
    // SIGINT and SIGTERM are blocked from the start, before the stream's heartbeat thread
    // exists (it inherits the mask), and let in only inside ppoll: so the handler runs on the
    // receiving thread, a stop request cannot slip in between checking the flag and going to
    // sleep, and one during setup still ends the driver cleanly. A nap (≤ 2 ms) is waited out.
    struct sigaction on_stop {};
    on_stop.sa_handler = [](int) { stop_requested = 1; };
    sigaction(SIGINT, &on_stop, nullptr);
    sigaction(SIGTERM, &on_stop, nullptr);
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, &while_waiting_);
    sigdelset(&while_waiting_, SIGINT);
    sigdelset(&while_waiting_, SIGTERM);
  }

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
    const int on = 1;
    ::setsockopt(socket_.native_handle(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
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
    if (auto placed = sim::hesai::apply_thread_placement(options_); !placed) {
      return failure(placed.error().message);
    }
    return std::nullopt;
  }

  // The loop is ppoll and clock_nanosleep rather than io_context::run(): Asio's reactor watches
  // the socket even with no read pending, so every datagram would wake a napping driver.
  int run() {
    const auto interval_ns = static_cast<std::int64_t>(status_interval() * 1e9);
    std::int64_t next_status_ns = sim::monotonic_ns() + interval_ns;
    while (stop_requested == 0 && exit_code_ == 0) {
      if (const std::int64_t nap_ns = nap_length_ns(); nap_ns > 0) {
        const timespec nap{0, static_cast<long>(nap_ns)};
        clock_nanosleep(CLOCK_MONOTONIC, 0, &nap, nullptr);
      } else {
        // Sleep until a datagram arrives, a stop signal, or the next status line.
        pollfd readable{socket_.native_handle(), POLLIN, 0};
        timespec until_status{};
        const timespec* timeout = nullptr;
        if (interval_ns > 0) {
          const std::int64_t left = std::max<std::int64_t>(0, next_status_ns - sim::monotonic_ns());
          until_status = {static_cast<time_t>(left / 1'000'000'000), static_cast<long>(left % 1'000'000'000)};
          timeout = &until_status;
        }
        ppoll(&readable, 1, timeout, &while_waiting_);
      }
      take_queued_packets();
      if (interval_ns > 0 && sim::monotonic_ns() >= next_status_ns) {
        print_status(false);
        next_status_ns = sim::monotonic_ns() + interval_ns;
      }
    }
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

  // Waking once per packet (6,000 a second for a dual-return Pandar64) costs more CPU than
  // decoding them. Far from the cut no packet can complete a revolution, so the driver naps
  // and then takes every queued packet in one recvmmsg; near the cut it wakes for each packet,
  // so a finished revolution is published as soon as its last packet lands. The kernel stamps
  // each datagram's arrival (SO_TIMESTAMPNS), so batching does not blur receive times.
  //
  // 0: wait for the next packet. A nap ends a margin before the cut can come, and never
  // follows an empty take (the sensor may have stopped: then the driver sleeps until it sends).
  std::int64_t nap_length_ns() const {
    constexpr std::int64_t longest_nap_ns = 2'000'000;  // ~12 packets; the socket buffer holds seconds
    constexpr std::int64_t wake_margin_ns = 1'000'000;  // timer lateness and motor speed drift
    constexpr std::int64_t shortest_nap_ns = 200'000;   // below this a nap saves nothing
    if (!stream_ || last_take_ == 0) return 0;
    const auto to_cut = stream_->time_to_cut_ns();
    if (!to_cut) return 0;
    const std::int64_t nap = std::min(longest_nap_ns, *to_cut - wake_margin_ns);
    return nap >= shortest_nap_ns ? nap : 0;
  }

  void take_queued_packets() {
    last_take_ = 0;
    for (;;) {
      batch_.prepare();
      const int count = ::recvmmsg(socket_.native_handle(), batch_.headers.data(),
                                   static_cast<unsigned>(batch_.headers.size()), MSG_DONTWAIT, nullptr);
      // EAGAIN: all taken. Other errors on an unconnected UDP socket are transient (e.g. an
      // ICMP error queued for it); the next wake-up tries again.
      if (count <= 0) return;
      const std::int64_t now = sim::monotonic_ns();
      for (int i = 0; i < count && exit_code_ == 0; ++i) {
        on_packet(batch_.payload(i), batch_.sender(i), batch_.kernel_receive_ns(i), now);
      }
      last_take_ += static_cast<unsigned>(count);
      if (static_cast<std::size_t>(count) < batch_.headers.size() || exit_code_ != 0) return;
    }
  }

  void on_packet(std::span<const std::uint8_t> payload, const asio::ip::address& sender,
                 std::int64_t host_ns, std::int64_t now) {
    ++datagrams_;
    if (source_ && sender != *source_) {
      ++other_source_;
      return;
    }
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
                   std::string(sim::hesai::to_string(*model)).c_str(), sender.to_string().c_str());
      if (auto code = create_stream()) {
        exit_code_ = *code;
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
  asio::io_context io_;  // only for the socket's setup; never run (see run())
  udp::socket socket_;
  ReceiveBatch batch_;
  sigset_t while_waiting_{};  // the signal mask inside ppoll: SIGINT and SIGTERM let in
  unsigned last_take_ = 0;  // packets the last take_queued_packets() found
  bool terminal_;
  std::optional<asio::ip::address> source_;
  std::optional<sim::hesai::LidarStream> stream_;
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
