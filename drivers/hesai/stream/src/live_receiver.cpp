// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/live_receiver.hpp"

#include <utility>

namespace sim::hesai {

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  auto opened = lidar::LiveReceiver<Route>::open(network.listen, Route{.data_port = network.data_port});
  if (!opened) return opened.error();
  return LiveReceiver(std::move(opened.value()));
}

}  // namespace sim::hesai
