// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/live_receiver.hpp"

#include <utility>
#include <vector>

#include "sim/lidar/detected_stream.hpp"

namespace sim::velodyne {
namespace {

// Data packets are 1206 bytes, position packets 512 or 554: a larger buffer lets an oversized
// datagram arrive whole and be refused by its size instead of cut to a plausible one.
constexpr std::size_t datagram_buffer = 2048;

// The receiver's sockets, in the order they are opened.
constexpr std::size_t data_socket = 0;
constexpr std::size_t position_socket = 1;

// The live stamps are the sensor's clock; nothing is known of it before a position packet.
ClockStatus sensor_stamps() {
  ClockStatus clock;
  clock.stamps = sim::StampClock::sensor;
  return clock;
}

}  // namespace

// The socket side is sim::lidar::UdpReceiver's; this is what a Velodyne packet means.
struct LiveReceiver::Impl final : lidar::DatagramHandler {
  explicit Impl(lidar::UdpReceiver u) : udp(std::move(u)) {}

  lidar::UdpReceiver udp;
  lidar::DetectedStream<LidarStream, LidarStreamConfig, detect_model, returns_in> stream;
  std::int64_t last_packet_ns = 0;   // monotonic time the last data packet was taken
  timing::ClockSources clock_sources;  // for the stream, once it exists
  bool clock_sources_given = false;
  // The stream's reported clock, readable before the stream exists (its model may come with the
  // first data packet); copied from the stream after each position packet.
  ReportedClock reported{sensor_stamps()};

  bool on_datagram(const lidar::Datagram& d) override {
    if (d.socket == position_socket) {
      if (LidarStream* published = stream.get()) {
        if (published->push_position(d.payload, d.arrival_ns)) reported.set(published->reported_clock()());
      }
      return true;
    }
    LidarStream* published = stream.for_packet(d, udp);
    if (published == nullptr) return !stream.error();
    if (!clock_sources_given) {
      timing::ClockSources sources = clock_sources;
      if (!sources.reported) sources.reported = reported;  // what the position packets say
      published->clock().set_sources(std::move(sources));
      clock_sources_given = true;
    }
    if (udp.resumed_after_silence(d.arrival_ns)) published->reset();  // the revolution is stale
    last_packet_ns = d.taken_ns;
    const PushResult result = published->push(d.payload, d.arrival_ns);
    // The packet's own time against its arrival on this host; judged about once a second. Its
    // hour is the arrival's (a Velodyne counts µs past the hour): an hour off cannot show.
    published->clock().add(result.packet_ns, published->stamp_offset(), d.arrival_ns);
    published->tick_clock(d.arrival_ns);
    return true;
  }
};

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  std::vector<lidar::UdpPort> ports{{network.data_port, "UDP", "--port"}};
  if (network.position_port) ports.push_back({*network.position_port, "the position", "--position-port"});
  auto udp = lidar::UdpReceiver::open(network.listen, ports, datagram_buffer);
  if (!udp) return udp.error();
  return LiveReceiver(std::make_unique<Impl>(std::move(udp.value())));
}

LiveReceiver::LiveReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LiveReceiver::LiveReceiver(LiveReceiver&&) noexcept = default;
LiveReceiver& LiveReceiver::operator=(LiveReceiver&&) noexcept = default;
LiveReceiver::~LiveReceiver() = default;

void LiveReceiver::set_clock_sources(timing::ClockSources sources) {
  impl_->clock_sources = std::move(sources);
  impl_->clock_sources_given = false;
}

Expected<void> LiveReceiver::publish_to(LidarStreamConfig config, std::optional<Model> model) {
  impl_->clock_sources_given = false;
  return impl_->stream.publish_to(std::move(config), model);
}

Expected<void> LiveReceiver::run(int stop_fd, const ReceiverCallbacks& callbacks) {
  impl_->udp.run(stop_fd, *impl_, callbacks);
  if (const auto& error = impl_->stream.error()) return *error;
  return {};
}

std::uint16_t LiveReceiver::data_port() const noexcept { return impl_->udp.port(data_socket); }
std::uint16_t LiveReceiver::position_port() const noexcept { return impl_->udp.port(position_socket); }
std::string LiveReceiver::local_address() const { return impl_->udp.local_address(data_socket); }
int LiveReceiver::receive_buffer() const noexcept { return impl_->udp.receive_buffer(); }
const ReceiveCounters& LiveReceiver::counters() const noexcept { return impl_->udp.counters(); }
const LidarStream* LiveReceiver::stream() const noexcept { return impl_->stream.get(); }
ReportedClock LiveReceiver::reported_clock() const { return impl_->reported; }
std::int64_t LiveReceiver::last_packet_ns() const noexcept { return impl_->last_packet_ns; }

}  // namespace sim::velodyne
