// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/live_receiver.hpp"

#include <algorithm>
#include <array>
#include <utility>

#include "sim/lidar/detected_stream.hpp"

namespace sim::hesai {
namespace {

// The largest Hesai payload is 1392 bytes; a larger buffer lets an oversized datagram arrive
// whole and be rejected by its size instead of silently cut to a plausible one.
constexpr std::size_t datagram_buffer = 9000;

}  // namespace

// The socket side is sim::lidar::UdpReceiver's; this is what a Hesai packet means.
struct LiveReceiver::Impl final : lidar::DatagramHandler {
  explicit Impl(lidar::UdpReceiver u) : udp(std::move(u)) {}

  lidar::UdpReceiver udp;
  lidar::DetectedStream<LidarStream, LidarStreamConfig, detect_model, returns_in> stream;
  std::int64_t last_packet_ns = 0;   // monotonic time the last packet was taken
  timing::ClockSources clock_sources;  // for the stream, once it exists
  bool clock_sources_given = false;

  // Waking once per packet (6,000 a second for a dual-return Pandar64) costs more CPU than
  // decoding them. Far from the cut no packet can complete a revolution, so the receiver naps
  // and then takes every queued packet in one recvmmsg; near the cut it wakes for each packet.
  // The kernel stamps each datagram's arrival, so batching does not blur receive times. A nap
  // ends a margin before the cut can come; 0: wait for the next packet.
  std::int64_t nap_ns() const override {
    constexpr std::int64_t longest_nap_ns = 2'000'000;  // ~12 packets; the socket buffer holds seconds
    constexpr std::int64_t wake_margin_ns = 1'000'000;  // timer lateness and motor speed drift
    constexpr std::int64_t shortest_nap_ns = 200'000;   // below this a nap saves nothing
    const LidarStream* published = stream.get();
    if (published == nullptr) return 0;
    const auto to_cut = published->time_to_cut_ns();
    if (!to_cut) return 0;
    const std::int64_t nap = std::min(longest_nap_ns, *to_cut - wake_margin_ns);
    return nap >= shortest_nap_ns ? nap : 0;
  }

  bool on_datagram(const lidar::Datagram& d) override {
    LidarStream* published = stream.for_packet(d, udp);
    if (published == nullptr) return !stream.error();
    if (!clock_sources_given) {
      published->clock().set_sources(clock_sources);
      clock_sources_given = true;
    }
    // The revolution in progress is stale after a silence. Readers kept the last frame
    // meanwhile (stale by its publish time); start over with fresh packets.
    if (udp.resumed_after_silence(d.arrival_ns)) published->reset();
    last_packet_ns = d.taken_ns;
    const PushResult result = published->push(d.payload, d.arrival_ns);
    // The packet's own time against its arrival on this host; judged about once a second.
    published->clock().add(result.packet_ns, published->stamp_offset(), d.arrival_ns);
    published->tick_clock(d.arrival_ns);
    return true;
  }
};

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  const std::array ports{lidar::UdpPort{network.data_port, "UDP", "--port"}};
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

std::uint16_t LiveReceiver::data_port() const noexcept { return impl_->udp.port(); }
std::string LiveReceiver::local_address() const { return impl_->udp.local_address(); }
int LiveReceiver::receive_buffer() const noexcept { return impl_->udp.receive_buffer(); }
const ReceiveCounters& LiveReceiver::counters() const noexcept { return impl_->udp.counters(); }
const LidarStream* LiveReceiver::stream() const noexcept {
  return impl_->stream.get();
}
std::int64_t LiveReceiver::last_packet_ns() const noexcept { return impl_->last_packet_ns; }

}  // namespace sim::hesai
