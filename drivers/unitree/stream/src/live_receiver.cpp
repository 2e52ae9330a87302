// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/live_receiver.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <optional>
#include <ostream>
#include <span>
#include <utility>
#include <vector>

#include "sim/clock.hpp"
#include "sim/lidar/unique_fd.hpp"

namespace sim::unitree {
namespace {

constexpr std::int64_t tick_ns = 1'000'000'000;  // the status line, the clock record, the flush

// A datagram holds any cut of the byte stream (bursts of 1044-B L2 packets, an L1 board's
// pieces): a buffer as large as a UDP payload can be, so none is ever cut. The L2 sends ~250
// datagrams a second, so a small batch is enough.
constexpr std::size_t datagram_size = 65536;
constexpr std::size_t batch_size = 8;
constexpr int receive_buffer = 4 << 20;  // ~18 s of an L2: rides out any scheduling
constexpr std::size_t serial_read_size = 65536;

// The rates termios has a speed for (Linux).
struct Rate {
  unsigned baud;
  speed_t speed;
};
constexpr std::array<Rate, 30> rates{{{50, B50},           {75, B75},           {110, B110},
                                      {134, B134},         {150, B150},         {200, B200},
                                      {300, B300},         {600, B600},         {1200, B1200},
                                      {1800, B1800},       {2400, B2400},       {4800, B4800},
                                      {9600, B9600},       {19200, B19200},     {38400, B38400},
                                      {57600, B57600},     {115200, B115200},   {230400, B230400},
                                      {460800, B460800},   {500000, B500000},   {576000, B576000},
                                      {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
                                      {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000},
                                      {3000000, B3000000}, {3500000, B3500000}, {4000000, B4000000}}};

std::optional<speed_t> speed_of(unsigned baud) {
  const auto rate = std::find_if(rates.begin(), rates.end(), [baud](const Rate& r) { return r.baud == baud; });
  if (rate == rates.end()) return std::nullopt;
  return rate->speed;
}

// Where the bytes go.
struct Sink {
  LidarStream* stream = nullptr;
  std::ostream* record = nullptr;

  // Everything read off the wire goes to the stream, and to the recording when there is one.
  // The arrival of the bytes is the stamp of host-time scans, and what the L2's own clock is
  // measured against; the clock record is written about once a second.
  void bytes(std::span<const std::uint8_t> chunk, std::int64_t arrival_ns) const {
    if (record != nullptr) {
      record->write(reinterpret_cast<const char*>(chunk.data()), static_cast<std::streamsize>(chunk.size()));
    }
    stream->push(chunk, arrival_ns);
    stream->tick_clock(arrival_ns);
  }

  // About once a second, bytes or none.
  void tick(const std::function<void()>& status) const {
    if (status) status();
    stream->tick_clock(realtime_ns());
    if (record != nullptr) record->flush();
  }
};

// Each datagram's payload, whatever it holds, with the kernel's stamp of its arrival. After a
// silence the scan in progress and any partial packet are stale, as for every family: the
// stream starts over with the fresh bytes (the note says the packets resumed).
struct DatagramSink final : lidar::DatagramHandler {
  DatagramSink(const Sink& s, lidar::UdpReceiver& u) noexcept : sink(s), udp(u) {}
  bool on_datagram(const lidar::Datagram& datagram) override {
    if (udp.resumed_after_silence(datagram.arrival_ns)) sink.stream->reset();
    sink.bytes(datagram.payload, datagram.arrival_ns);
    return true;
  }
  const Sink& sink;
  lidar::UdpReceiver& udp;
};

Expected<lidar::UdpReceiver> open_udp(const NetworkConfig& network) {
  lidar::UdpListen listen;
  listen.bind = network.bind;
  listen.source = network.source;
  listen.receive_buffer = receive_buffer;
  listen.versions = lidar::IpVersions::v4_and_v6;
  listen.bind_option = "--bind-address";
  listen.source_option = "--lidar-ip";
  const std::array ports{lidar::UdpPort{network.data_port, "UDP", "--udp-port"}};
  return lidar::UdpReceiver::open(listen, ports, datagram_size, batch_size);
}

// A serial port as a raw terminal, read without blocking in a poll() loop with the stop
// descriptor.
class SerialPort {
 public:
  static Expected<SerialPort> open(const std::string& device, unsigned baud) {
    const auto cannot_open = [&](int error) {
      return Error{ErrorCode::system_error, "cannot open serial port " + device + " at " + std::to_string(baud) +
                                                " baud (" + std::strerror(error) +
                                                "); check the device path and that you may use it (group dialout)"};
    };
    lidar::UniqueFd fd(::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
    if (fd.get() < 0) return cannot_open(errno);
    termios t{};
    if (::tcgetattr(fd.get(), &t) != 0) return cannot_open(errno);  // not a terminal
    ::cfmakeraw(&t);                                    // bytes as they come: 8 bits, no parity, no echo
    t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);  // one stop bit, no hardware flow control
    t.c_cflag |= CLOCAL | CREAD;                        // no modem lines; receive
    t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);  // no software flow control
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    const speed_t speed = *speed_of(baud);  // open() checked the rate
    if (::cfsetispeed(&t, speed) != 0 || ::cfsetospeed(&t, speed) != 0 || ::tcsetattr(fd.get(), TCSANOW, &t) != 0) {
      return cannot_open(errno);
    }
    return SerialPort(std::move(fd), device);
  }

  // Reads until `stop_fd` is readable, ticking about once a second; an error when the port fails.
  Expected<void> run(int stop_fd, const Sink& sink, const std::function<void()>& status) {
    std::array<pollfd, 2> fds{{{stop_fd, POLLIN, 0}, {fd_.get(), POLLIN, 0}}};
    std::int64_t next_tick_ns = monotonic_ns() + tick_ns;
    for (;;) {
      // Rounded up: a wake-up before the tick is due would only poll again.
      const std::int64_t wait_ns = std::max<std::int64_t>(0, next_tick_ns - monotonic_ns());
      const int ready = ::poll(fds.data(), fds.size(), static_cast<int>((wait_ns + 999'999) / 1'000'000));
      if (ready < 0 && errno != EINTR) return failed(errno);
      if (ready > 0 && (fds[0].revents & POLLIN) != 0) return {};
      if (ready > 0 && fds[1].revents != 0) {
        if (auto read = drain(sink); !read) return read;
      }
      if (monotonic_ns() >= next_tick_ns) {
        sink.tick(status);
        next_tick_ns = monotonic_ns() + tick_ns;
      }
    }
  }

  const std::string& device() const noexcept { return device_; }

 private:
  SerialPort(lidar::UniqueFd fd, std::string device) : fd_(std::move(fd)), device_(std::move(device)), buffer_(serial_read_size) {}

  // Everything the port holds now. An unplugged adapter or a closed other side reads as an
  // error (EIO) or the end of the file.
  Expected<void> drain(const Sink& sink) {
    for (;;) {
      const ssize_t n = ::read(fd_.get(), buffer_.data(), buffer_.size());
      if (n > 0) {
        const auto count = static_cast<std::size_t>(n);
        sink.bytes(std::span<const std::uint8_t>(buffer_).first(count), realtime_ns());
        if (count < buffer_.size()) return {};
        continue;
      }
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) return {};
      return failed(n == 0 ? 0 : errno);
    }
  }

  Error failed(int error) const {
    const std::string why = error == 0 ? "end of file" : std::strerror(error);
    return Error{ErrorCode::system_error, "serial port " + device_ + " failed (" + why + "); check the cable and restart"};
  }

  lidar::UniqueFd fd_;
  std::string device_;
  std::vector<std::uint8_t> buffer_;  // one read, allocated once
};

}  // namespace

std::string baud_problem(unsigned baud) {
  if (baud == 0 || speed_of(baud)) return {};
  return "--baud " + std::to_string(baud) +
         " is not a rate a serial port can be set to; give a standard one such as 115200, 921600, 2000000 "
         "(the L1) or 4000000 (the L2)";
}

struct LiveReceiver::Impl {
  std::optional<lidar::UdpReceiver> udp;
  std::optional<SerialPort> serial;
  unsigned baud = 0;
  Sink sink;
};

Expected<LiveReceiver> LiveReceiver::open(const LiveSource& source, Model model) {
  auto impl = std::make_unique<Impl>();
  if (!source.serial_device.empty()) {
    if (auto problem = baud_problem(source.baud); !problem.empty()) {
      return Error{ErrorCode::invalid_argument, std::move(problem)};
    }
    impl->baud = source.baud != 0 ? source.baud : (model == Model::l1 ? 2'000'000U : 4'000'000U);
    auto serial = SerialPort::open(source.serial_device, impl->baud);
    if (!serial) return serial.error();
    impl->serial.emplace(std::move(serial.value()));
  } else {
    auto udp = open_udp(source.network);
    if (!udp) return udp.error();
    impl->udp.emplace(std::move(udp.value()));
  }
  return LiveReceiver(std::move(impl));
}

LiveReceiver::LiveReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LiveReceiver::LiveReceiver(LiveReceiver&&) noexcept = default;
LiveReceiver& LiveReceiver::operator=(LiveReceiver&&) noexcept = default;
LiveReceiver::~LiveReceiver() = default;

void LiveReceiver::publish_to(LidarStream& stream, std::ostream* record) noexcept {
  impl_->sink.stream = &stream;
  impl_->sink.record = record;
}

Expected<void> LiveReceiver::run(int stop_fd, const std::function<void()>& tick,
                                 const std::function<void(std::string_view)>& note) {
  Impl& r = *impl_;
  if (r.sink.stream == nullptr) {
    return Error{ErrorCode::invalid_argument, "the receiver has no stream to publish to; call publish_to() before run()"};
  }
  Expected<void> ran;
  if (r.serial) {
    ran = r.serial->run(stop_fd, r.sink, tick);
  } else {
    DatagramSink handler(r.sink, *r.udp);
    lidar::ReceiverCallbacks callbacks;
    callbacks.note = note;
    callbacks.tick_period = std::chrono::nanoseconds(tick_ns);
    callbacks.tick = [&r, &tick] { r.sink.tick(tick); };
    r.udp->run(stop_fd, handler, callbacks);
  }
  if (r.sink.record != nullptr) r.sink.record->flush();
  return ran;
}

std::string LiveReceiver::where() const {
  if (impl_->serial) return "reading " + impl_->serial->device() + " at " + std::to_string(impl_->baud) + " baud";
  return "listening on udp port " + std::to_string(port());
}

std::uint16_t LiveReceiver::port() const noexcept { return impl_->udp ? impl_->udp->port() : 0; }

std::uint64_t LiveReceiver::other_senders() const noexcept {
  const lidar::ReceiveCounters c = counters();
  return c.other_source + c.other_senders;  // one of the two is always 0 (with or without a source)
}

lidar::ReceiveCounters LiveReceiver::counters() const noexcept {
  return impl_->udp ? impl_->udp->counters() : lidar::ReceiveCounters{};
}

}  // namespace sim::unitree
