// SPDX-License-Identifier: Apache-2.0
// The list of backends and which of them this build has.
#include <array>
#include <utility>

#include "transport.hpp"

namespace sim::bench {
namespace {
constexpr std::array<std::pair<Transport, std::string_view>, 9> kNames{{
    {Transport::sim_poll, "sim-poll"},
    {Transport::sim_block, "sim-block"},
    {Transport::sim_zero, "sim-zero"},
    {Transport::sim_adaptive, "sim-adaptive"},
    {Transport::sim_zero_adaptive, "sim-zero-adaptive"},
    {Transport::sim_poll_described, "sim-poll-described"},
    {Transport::iceoryx, "iceoryx"},
    {Transport::fastdds, "fastdds"},
    {Transport::cyclone, "cyclone"},
}};
}  // namespace

std::string_view to_string(Transport t) noexcept {
  for (const auto& [value, name] : kNames) {
    if (value == t) return name;
  }
  return "?";
}

bool parse_transport(std::string_view name, Transport& out) noexcept {
  for (const auto& [value, n] : kNames) {
    if (n == name) {
      out = value;
      return true;
    }
  }
  return false;
}

bool available(Transport t) noexcept {
  switch (t) {
    case Transport::sim_poll:
    case Transport::sim_block:
    case Transport::sim_zero:
    case Transport::sim_adaptive:
    case Transport::sim_zero_adaptive:
    case Transport::sim_poll_described:
      return true;
    case Transport::iceoryx:
#ifdef SIM_BENCH_HAVE_ICEORYX
      return true;
#else
      return false;
#endif
    case Transport::fastdds:
#ifdef SIM_BENCH_HAVE_FASTDDS
      return true;
#else
      return false;
#endif
    case Transport::cyclone:
#ifdef SIM_BENCH_HAVE_CYCLONE
      return true;
#else
      return false;
#endif
  }
  return false;
}

bool needs_roudi(Transport t) noexcept {
  // Cyclone 0.10 carries data over iceoryx when its shared memory is enabled (see its backend).
  return t == Transport::iceoryx || t == Transport::cyclone;
}

std::unique_ptr<PublisherBackend> make_publisher(Transport t, const Endpoint& e,
                                                 std::string& error) {
  switch (t) {
    case Transport::sim_poll:
    case Transport::sim_block:
    case Transport::sim_zero:
    case Transport::sim_adaptive:
    case Transport::sim_zero_adaptive:
    case Transport::sim_poll_described:
      return make_sim_publisher(t, e, error);
#ifdef SIM_BENCH_HAVE_ICEORYX
    case Transport::iceoryx:
      return make_iceoryx_publisher(e, error);
#endif
#ifdef SIM_BENCH_HAVE_FASTDDS
    case Transport::fastdds:
      return make_fastdds_publisher(e, error);
#endif
#ifdef SIM_BENCH_HAVE_CYCLONE
    case Transport::cyclone:
      return make_cyclone_publisher(e, error);
#endif
    default:
      break;
  }
  error = std::string(to_string(t)) + " is not in this build: install its Debian package "
                                      "(scripts/deps/bench.txt) and reconfigure.";
  return nullptr;
}

std::unique_ptr<SubscriberBackend> make_subscriber(Transport t, const Endpoint& e,
                                                   std::string& error) {
  switch (t) {
    case Transport::sim_poll:
    case Transport::sim_block:
    case Transport::sim_zero:
    case Transport::sim_adaptive:
    case Transport::sim_zero_adaptive:
    case Transport::sim_poll_described:
      return make_sim_subscriber(t, e, error);
#ifdef SIM_BENCH_HAVE_ICEORYX
    case Transport::iceoryx:
      return make_iceoryx_subscriber(e, error);
#endif
#ifdef SIM_BENCH_HAVE_FASTDDS
    case Transport::fastdds:
      return make_fastdds_subscriber(e, error);
#endif
#ifdef SIM_BENCH_HAVE_CYCLONE
    case Transport::cyclone:
      return make_cyclone_subscriber(e, error);
#endif
    default:
      break;
  }
  error = std::string(to_string(t)) + " is not in this build: install its Debian package "
                                      "(scripts/deps/bench.txt) and reconfigure.";
  return nullptr;
}

}  // namespace sim::bench
