// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/live_receiver.hpp"

#include <unistd.h>

#include <array>
#include <chrono>
#include <optional>
#include <ostream>
#include <span>
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange

#include <boost/asio.hpp>

#include "sim/clock.hpp"

namespace asio = boost::asio;

namespace sim::unitree {

struct LiveReceiver::Impl {
  asio::io_context io;
  std::optional<asio::ip::udp::socket> udp;
  std::optional<asio::serial_port> serial;
  std::optional<asio::ip::address> lidar;  // none: datagrams from anyone
  asio::ip::udp::endpoint sender;
  std::string device;
  unsigned baud = 0;
  LidarStream* stream = nullptr;
  std::ostream* record = nullptr;
  std::uint64_t other_senders = 0;
  std::optional<Error> failure;  // the serial port failed
  // Bursts of 1044-B packets at ~64,000 points/s, or a serial read: one buffer, allocated once.
  std::array<std::uint8_t, 65536> buffer{};

  // Everything read off the wire goes to the stream, and to the recording when there is one.
  void on_bytes(std::span<const std::uint8_t> bytes) {
    if (record != nullptr) {
      record->write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
    // The arrival of the bytes: the stamp of host-time scans, and what the L2's own clock is
    // measured against; the clock record is written about once a second.
    const std::int64_t arrival = realtime_ns();
    stream->push(bytes, arrival);
    stream->tick_clock(arrival);
  }

  void receive_udp() {
    udp->async_receive_from(asio::buffer(buffer), sender, [this](const boost::system::error_code& ec, std::size_t n) {
      if (ec == asio::error::operation_aborted) return;
      if (!ec) {
        if (lidar && sender.address() != *lidar) {
          ++other_senders;
        } else {
          on_bytes(std::span(buffer).first(n));
        }
      }
      receive_udp();
    });
  }

  void read_serial() {
    serial->async_read_some(asio::buffer(buffer), [this](const boost::system::error_code& ec, std::size_t n) {
      if (ec == asio::error::operation_aborted) return;
      if (n > 0) on_bytes(std::span(buffer).first(n));
      if (ec) {
        failure = Error{ErrorCode::system_error, "serial port " + device + " failed (" + ec.message() +
                                                     "); check the cable and restart"};
        io.stop();
        return;
      }
      read_serial();
    });
  }

  Expected<void> open_serial(const std::string& path) {
    device = path;
    serial.emplace(io);
    try {
      serial->open(device);
      serial->set_option(asio::serial_port_base::baud_rate(baud));
      serial->set_option(asio::serial_port_base::character_size(8));
      serial->set_option(asio::serial_port_base::parity(asio::serial_port_base::parity::none));
      serial->set_option(asio::serial_port_base::stop_bits(asio::serial_port_base::stop_bits::one));
      serial->set_option(asio::serial_port_base::flow_control(asio::serial_port_base::flow_control::none));
    } catch (const boost::system::system_error& e) {
      return Error{ErrorCode::system_error, "cannot open serial port " + device + " at " + std::to_string(baud) +
                                                " baud (" + e.code().message() +
                                                "); check the device path and that you may use it (group dialout)"};
    }
    return {};
  }

  Expected<void> open_udp(const NetworkConfig& network) {
    boost::system::error_code ec;
    if (!network.source.empty()) {
      lidar = asio::ip::make_address(network.source, ec);
      if (ec) {
        return Error{ErrorCode::invalid_argument,
                     "--lidar-ip '" + network.source + "' is not an IP address; give one like 192.168.1.62"};
      }
    }
    const asio::ip::address bind = asio::ip::make_address(network.bind, ec);
    if (ec) {
      return Error{ErrorCode::invalid_argument,
                   "--bind-address '" + network.bind + "' is not an IP address; give one like 0.0.0.0"};
    }
    const asio::ip::udp::endpoint local(bind, network.data_port);
    udp.emplace(io);
    try {
      udp->open(local.protocol());
      // No SO_REUSEADDR: a second listener on the port must fail loudly, not steal datagrams.
      // A large kernel buffer rides out scheduling.
      udp->set_option(asio::socket_base::receive_buffer_size(4 << 20), ec);
      udp->bind(local);
    } catch (const boost::system::system_error& e) {
      return Error{ErrorCode::system_error, "cannot listen on UDP " + network.bind + ":" +
                                                std::to_string(network.data_port) + " (" + e.code().message() +
                                                "); pick a free port with --udp-port or stop the other listener"};
    }
    return {};
  }
};

Expected<LiveReceiver> LiveReceiver::open(const LiveSource& source, Model model) {
  auto impl = std::make_unique<Impl>();
  impl->baud = source.baud != 0 ? source.baud : (model == Model::l1 ? 2'000'000U : 4'000'000U);
  auto opened = source.serial_device.empty() ? impl->open_udp(source.network) : impl->open_serial(source.serial_device);
  if (!opened) return opened.error();
  return LiveReceiver(std::move(impl));
}

LiveReceiver::LiveReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LiveReceiver::LiveReceiver(LiveReceiver&&) noexcept = default;
LiveReceiver& LiveReceiver::operator=(LiveReceiver&&) noexcept = default;
LiveReceiver::~LiveReceiver() = default;

void LiveReceiver::publish_to(LidarStream& stream, std::ostream* record) noexcept {
  impl_->stream = &stream;
  impl_->record = record;
}

Expected<void> LiveReceiver::run(int stop_fd, const std::function<void()>& tick) {
  Impl& r = *impl_;
  if (r.stream == nullptr) {
    return Error{ErrorCode::invalid_argument, "the receiver has no stream to publish to; call publish_to() before run()"};
  }
  // The stop signal's descriptor ends io.run() like any other event.
  asio::posix::stream_descriptor stop_events(r.io, ::dup(stop_fd));
  stop_events.async_wait(asio::posix::stream_descriptor::wait_read, [&r](const boost::system::error_code& ec) {
    if (!ec) r.io.stop();
  });
  asio::steady_timer timer(r.io);
  std::function<void()> every_second = [&] {
    timer.expires_after(std::chrono::seconds(1));
    timer.async_wait([&](const boost::system::error_code& ec) {
      if (ec) return;
      if (tick) tick();
      r.stream->tick_clock(realtime_ns());
      if (r.record != nullptr) r.record->flush();
      every_second();
    });
  };
  every_second();
  if (r.serial) {
    r.read_serial();
  } else {
    r.receive_udp();
  }
  r.io.run();
  if (r.record != nullptr) r.record->flush();
  if (r.failure) return *r.failure;
  return {};
}

std::string LiveReceiver::where() const {
  if (impl_->serial) return "reading " + impl_->device + " at " + std::to_string(impl_->baud) + " baud";
  return "listening on udp port " + std::to_string(port());
}

std::uint16_t LiveReceiver::port() const noexcept {
  if (!impl_->udp) return 0;
  boost::system::error_code ec;
  return impl_->udp->local_endpoint(ec).port();
}

std::uint64_t LiveReceiver::other_senders() const noexcept { return impl_->other_senders; }

}  // namespace sim::unitree
