// SPDX-License-Identifier: Apache-2.0
// The bridge's UDPv4 transport: Fast DDS's own, wrapped so that a send to a locator Fast DDS never
// opened an output channel for cannot abort the process.
//
// Debian's Fast DDS 2.9.1 is built with its statistics module and keeps its asserts. Its UDP
// transport keeps a table of the locators it opened output channels for and looks up the
// destination of every datagram in it; a destination missing from it fails
// `assert(it != collection_.end())` in OutputTrafficManager.hpp and aborts the process.
// When a reader matches, a writer opens channels only for the locators it *selects* for all its
// readers, and readers that share a multicast locator are served by that locator alone. Right
// after, a reliable writer sends the new reader a heartbeat to the reader's own unicast locator.
// ROS 2's rmw_cyclonedds nodes have such a locator of their own (the participant index's user
// port, 7411 + 2i; discovery, which opens a channel, uses 7410 + 2i) and all share
// 239.255.0.1:7401: a node joining while another reads the same reliable topic (ros_discovery_info
// has a reader in every node) aborted the bridge. Fixed upstream by eProsima/Fast-DDS#5704
// (2.10.7, 2.14.5, 3.1.3); docs/ros2-interop.md, "Defect: the bridge aborts in Fast DDS".
//
// The wrapper sends exactly what Fast DDS sends, on Fast DDS's sockets. Before it hands a datagram
// on, it opens the output channel of any destination not opened yet; with the sockets in place
// that only adds the locator to the table.
#pragma once

#include <fastdds/rtps/transport/TransportDescriptorInterface.h>

#include <cstdint>
#include <memory>

namespace sim::bridge {

// A UDPv4 transport for DomainParticipantQos::transport().user_transports, with socket buffers
// of the given sizes (0: the system's default).
std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> udp_transport(
    std::uint32_t send_buffer_size, std::uint32_t receive_buffer_size);

}  // namespace sim::bridge
