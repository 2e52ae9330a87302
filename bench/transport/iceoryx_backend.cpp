// SPDX-License-Identifier: Apache-2.0
// iceoryx 2.0 (classic) behind the bench interface: UntypedPublisher loan()/publish(),
// UntypedSubscriber take()/release() with queue capacity 1 (the newest sample, like KEEP_LAST 1),
// woken by a WaitSet. Zero-copy: the reader loop reads every byte of the chunk in place.
// sim_bench starts the RouDi daemon these processes register with.
#include <unistd.h>

#include <thread>

#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"
#include "sim/clock.hpp"
#include "transport.hpp"

namespace sim::bench {
namespace {

iox::capro::ServiceDescription service_of(const Endpoint& e) {
  return {"SimBench", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, e.topic.c_str()),
          "Frame"};
}

void init_runtime(const char* role) {
  const std::string name = std::string("sim_bench_") + role + "_" + std::to_string(getpid());
  // Its debug chatter (segment addresses) would bury the benchmark's output.
  iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kWarn);
  iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name.c_str()));
}

class IceoryxPublisher final : public PublisherBackend {
 public:
  explicit IceoryxPublisher(const Endpoint& e) : publisher_(service_of(e), options()) {}

  static iox::popo::PublisherOptions options() {
    iox::popo::PublisherOptions o;
    o.historyCapacity = 0;  // no late-joiner history: only fresh frames
    return o;
  }

  bool wait_for_readers(int, std::chrono::milliseconds timeout) override {
    // Readers report ready only once SUBSCRIBED, so one connected means all are.
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!publisher_.hasSubscribers()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }

  bool publish(std::span<std::byte> frame, std::uint64_t seq) override {
    auto loan = publisher_.loan(static_cast<std::uint32_t>(frame.size()), 8);
    if (loan.has_error()) return false;
    void* chunk = loan.value();
    std::memcpy(chunk, frame.data(), frame.size());  // producing the frame in place
    seal_frame({static_cast<std::byte*>(chunk), frame.size()}, seq, sim::monotonic_ns());
    publisher_.publish(chunk);
    return true;
  }

  std::string path_note() const override { return "shm"; }

 private:
  iox::popo::UntypedPublisher publisher_;
};

class IceoryxSubscriber final : public SubscriberBackend {
 public:
  explicit IceoryxSubscriber(const Endpoint& e) : subscriber_(service_of(e), options()) {
    waitset_.attachState(subscriber_, iox::popo::SubscriberState::HAS_DATA).or_else([this](auto) {
      attached_ = false;
    });
  }

  static iox::popo::SubscriberOptions options() {
    iox::popo::SubscriberOptions o;
    o.queueCapacity = 1;  // the newest frame only; older ones are discarded (skipped)
    o.historyRequest = 0;
    o.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
    return o;
  }

  bool ready(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (subscriber_.getSubscriptionState() != iox::SubscribeState::SUBSCRIBED) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return attached_;
  }

  Delivery receive(std::chrono::milliseconds timeout) override {
    auto taken = subscriber_.take();
    if (taken.has_error()) {
      waitset_.timedWait(iox::units::Duration::fromMilliseconds(timeout.count()));
      taken = subscriber_.take();
      if (taken.has_error()) return {};
    }
    held_ = taken.value();
    const auto* header = iox::mepoo::ChunkHeader::fromUserPayload(held_);
    return {Delivery::Kind::frame,
            {static_cast<const std::byte*>(held_), header->userPayloadSize()},
            {}};
  }

  bool release() override {
    if (held_ != nullptr) subscriber_.release(held_);
    held_ = nullptr;
    return true;  // a taken chunk is never reused while held
  }
  bool zero_copy() const override { return true; }

 private:
  iox::popo::UntypedSubscriber subscriber_;
  iox::popo::WaitSet<> waitset_;
  const void* held_ = nullptr;
  bool attached_ = true;
};

}  // namespace

std::unique_ptr<PublisherBackend> make_iceoryx_publisher(const Endpoint& e, std::string&) {
  init_runtime("w");
  return std::make_unique<IceoryxPublisher>(e);
}

std::unique_ptr<SubscriberBackend> make_iceoryx_subscriber(const Endpoint& e, std::string&) {
  init_runtime("r");
  return std::make_unique<IceoryxSubscriber>(e);
}

}  // namespace sim::bench
