// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/live_receiver.hpp"

#include <utility>

namespace sim::velodyne {

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  auto opened = lidar::LiveReceiver<Route>::open(
      network.listen, Route{.data_port = network.data_port, .position_port = network.position_port});
  if (!opened) return opened.error();
  return LiveReceiver(std::move(opened.value()));
}

}  // namespace sim::velodyne
