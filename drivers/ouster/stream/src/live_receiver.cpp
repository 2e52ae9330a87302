// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/live_receiver.hpp"

#include <array>
#include <utility>

namespace sim::ouster {
namespace {

// Larger than the largest Ouster datagram (128 beams, dual profile: 33 kB), so an oversized one
// arrives whole and is refused by its size rather than cut to a plausible one.
constexpr std::size_t datagram_buffer = 65536;
constexpr std::size_t batch_size = 16;  // 1 MiB of buffers

// The receiver's sockets, in the order they are opened.
constexpr std::size_t data_socket = 0;
constexpr std::size_t imu_socket = 1;

}  // namespace

// The socket side is sim::lidar::UdpReceiver's; this is what an Ouster datagram means.
struct LiveReceiver::Impl final : lidar::DatagramHandler {
  explicit Impl(lidar::UdpReceiver u) : udp(std::move(u)) {}

  lidar::UdpReceiver udp;
  LidarStream* stream = nullptr;     // during run()
  std::int64_t last_packet_ns = 0;  // monotonic time the last datagram was taken
  bool mismatch_noted = false;

  bool on_datagram(const lidar::Datagram& d) override {
    if (d.truncated) {
      ++udp.counters().oversized;
      return true;
    }
    last_packet_ns = d.taken_ns;
    if (d.socket == imu_socket) {
      stream->push_imu(d.payload);
      return true;
    }
    if (udp.resumed_after_silence(d.arrival_ns)) stream->reset();  // the frame is stale
    const PushResult result = stream->push(d.payload, d.arrival_ns);
    if (result.error != PacketError::none && !mismatch_noted) note_mismatch();
    // The packet's own time against its arrival on this host; judged about once a second.
    stream->clock().add(result.packet_ns, stream->stamp_offset(), d.arrival_ns);
    stream->tick_clock(d.arrival_ns);
    return true;
  }

  // Once: the user must learn that the metadata does not fit, not read it 640 times a second.
  void note_mismatch() {
    const std::string problem = stream->mismatch_problem();
    if (problem.empty()) return;
    udp.note(problem);
    mismatch_noted = true;
  }
};

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  const std::array ports{lidar::UdpPort{network.data_port, "the lidar", "--lidar-port"},
                         lidar::UdpPort{network.imu_port, "the IMU", "--imu-port"}};
  auto udp = lidar::UdpReceiver::open(network.listen, ports, datagram_buffer, batch_size);
  if (!udp) return udp.error();
  return LiveReceiver(std::make_unique<Impl>(std::move(udp.value())));
}

LiveReceiver::LiveReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LiveReceiver::LiveReceiver(LiveReceiver&&) noexcept = default;
LiveReceiver& LiveReceiver::operator=(LiveReceiver&&) noexcept = default;
LiveReceiver::~LiveReceiver() = default;

void LiveReceiver::run(LidarStream& stream, int stop_fd, const ReceiverCallbacks& callbacks) {
  impl_->stream = &stream;
  impl_->udp.run(stop_fd, *impl_, callbacks);
  impl_->stream = nullptr;
}

std::uint16_t LiveReceiver::data_port() const noexcept { return impl_->udp.port(data_socket); }
std::uint16_t LiveReceiver::imu_port() const noexcept { return impl_->udp.port(imu_socket); }
int LiveReceiver::receive_buffer() const noexcept { return impl_->udp.receive_buffer(); }
const ReceiveCounters& LiveReceiver::counters() const noexcept { return impl_->udp.counters(); }
std::int64_t LiveReceiver::last_packet_ns() const noexcept { return impl_->last_packet_ns; }

}  // namespace sim::ouster
