// SPDX-License-Identifier: Apache-2.0
#include "udp_transport.hpp"

#include <fastdds/rtps/transport/ChainingTransport.h>
#include <fastdds/rtps/transport/ChainingTransportDescriptor.h>
#include <fastdds/rtps/network/SenderResource.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <algorithm>
#include <mutex>
#include <vector>

namespace sim::bridge {

namespace {

namespace fr = eprosima::fastdds::rtps;
using eprosima::fastrtps::rtps::Locator_t;
using eprosima::fastrtps::rtps::LocatorsIterator;
using eprosima::fastrtps::rtps::octet;
using eprosima::fastrtps::rtps::SenderResource;

// Walks a vector of locators for SenderResource::send.
class VectorLocators final : public LocatorsIterator {
 public:
  explicit VectorLocators(std::vector<Locator_t>::const_iterator at) : at_(at) {}
  LocatorsIterator& operator++() override {
    ++at_;
    return *this;
  }
  bool operator==(const LocatorsIterator& other) const override {
    return at_ == static_cast<const VectorLocators&>(other).at_;
  }
  bool operator!=(const LocatorsIterator& other) const override { return !(*this == other); }
  const Locator_t& operator*() const override { return *at_; }

 private:
  std::vector<Locator_t>::const_iterator at_;
};

// Fast DDS's UDPv4 transport (the low level) with one addition: a datagram's destinations all
// have an output channel before it goes out (udp_transport.hpp says why).
class OpenedLocatorsTransport final : public fr::ChainingTransport {
 public:
  explicit OpenedLocatorsTransport(const fr::ChainingTransportDescriptor& descriptor)
      : fr::ChainingTransport(descriptor) {}

  bool OpenOutputChannel(fr::SendResourceList& resources, const Locator_t& locator) override {
    const bool opened = fr::ChainingTransport::OpenOutputChannel(resources, locator);
    if (opened) {
      std::lock_guard lock(mutex_);
      remember(locator);
    }
    return opened;
  }

  bool send(SenderResource* low_level, const octet* buffer, std::uint32_t size,
            LocatorsIterator* begin, LocatorsIterator* end,
            const std::chrono::steady_clock::time_point& timeout) override {
    // The iterators are Fast DDS's own (one pass): copy the destinations, open what is new, and
    // send to the copy. The vector is this thread's and keeps its capacity: no allocation per send.
    thread_local std::vector<Locator_t> destinations;
    destinations.clear();
    for (LocatorsIterator& it = *begin; it != *end; ++it) destinations.push_back(*it);
    open_unknown(destinations);
    VectorLocators first(destinations.cbegin());
    VectorLocators last(destinations.cend());
    return low_level->send(buffer, size, &first, &last, timeout);
  }

  // The UDP transport's settings (buffer sizes, message size) are the ones in force.
  fr::TransportDescriptorInterface* get_configuration() override {
    return low_level_transport_->get_configuration();
  }

  // Received datagrams are passed on as they came.
  void receive(fr::TransportReceiverInterface* next, const octet* buffer, std::uint32_t size,
               const Locator_t& local, const Locator_t& remote) override {
    next->OnDataReceived(buffer, size, local, remote);
  }

 private:
  bool known(const Locator_t& locator) const {
    return std::find(opened_.begin(), opened_.end(), locator) != opened_.end();
  }
  void remember(const Locator_t& locator) {
    if (!known(locator)) opened_.push_back(locator);
  }

  void open_unknown(const std::vector<Locator_t>& destinations) {
    std::lock_guard lock(mutex_);
    for (const Locator_t& locator : destinations) {
      if (known(locator) || !low_level_transport_->IsLocatorSupported(locator)) continue;
      // The sockets exist already: this adds the locator to Fast DDS's table of opened
      // locators. Sockets it may open for interfaces that appeared meanwhile stay in
      // spare_resources_ (never in the list Fast DDS is iterating while it sends).
      if (low_level_transport_->OpenOutputChannel(spare_resources_, locator)) remember(locator);
    }
  }

  std::mutex mutex_;
  std::vector<Locator_t> opened_;             // the output channels opened, by locator
  fr::SendResourceList spare_resources_;      // what opening a channel while sending created
};

struct OpenedLocatorsDescriptor final : fr::ChainingTransportDescriptor {
  using fr::ChainingTransportDescriptor::ChainingTransportDescriptor;
  fr::TransportInterface* create_transport() const override { return new OpenedLocatorsTransport(*this); }
};

}  // namespace

std::shared_ptr<fr::TransportDescriptorInterface> udp_transport(std::uint32_t send_buffer_size,
                                                                std::uint32_t receive_buffer_size) {
  auto udp = std::make_shared<fr::UDPv4TransportDescriptor>();
  udp->sendBufferSize = send_buffer_size;
  udp->receiveBufferSize = receive_buffer_size;
  return std::make_shared<OpenedLocatorsDescriptor>(udp);
}

}  // namespace sim::bridge
