// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/live_receiver.hpp"

#include <utility>

namespace sim::ouster {

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  auto opened = lidar::LiveReceiver<Route>::open(network.listen,
                                                 Route{.data_port = network.data_port, .imu_port = network.imu_port});
  if (!opened) return opened.error();
  return LiveReceiver(std::move(opened.value()));
}

}  // namespace sim::ouster
