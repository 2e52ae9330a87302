// SPDX-License-Identifier: Apache-2.0
// Cyclone DDS 0.10 behind the bench interface: best effort, KEEP_LAST 1, volatile, a fixed-size
// type (one octet array of the payload size, described at run time, so no idlc step), and its
// iceoryx shared-memory path switched on. When Cyclone accepts the shared-memory path for an
// endpoint the writer loans (dds_loan_sample) and the reader takes a loan (zero-copy, the reader
// loop reads every byte in place); otherwise data goes over the network stack (UDP on this host),
// which path_note() and the UDP datagram count in the *_extra.csv say plainly.
#include <dds/dds.h>
#include <dds/ddsc/dds_loan_api.h>

#include <thread>

#include "sim/clock.hpp"
#include "transport.hpp"

namespace sim::bench {
namespace {

// The type descriptor of `struct Frame { octet data[N]; }`, built for this run's N. Cyclone
// keeps pointers to it, so it lives for the whole process.
struct FrameDescriptor {
  explicit FrameDescriptor(std::size_t bytes)
      : name("SimBenchFrame" + std::to_string(bytes)),
        ops{static_cast<std::uint32_t>(DDS_OP_ADR) | static_cast<std::uint32_t>(DDS_OP_TYPE_ARR) |
                static_cast<std::uint32_t>(DDS_OP_SUBTYPE_1BY),
            0u,
            static_cast<std::uint32_t>(bytes), static_cast<std::uint32_t>(DDS_OP_RTS)},
        descriptor{static_cast<std::uint32_t>(bytes),
                   8,
                   DDS_TOPIC_FIXED_SIZE,
                   0u,
                   name.c_str(),
                   nullptr,
                   2,
                   ops,
                   "",
                   {nullptr, 0},
                   {nullptr, 0},
                   0} {}
  std::string name;
  std::uint32_t ops[4];
  dds_topic_descriptor_t descriptor;
};

std::string domain_config() {
  // Shared memory through iceoryx (sim_bench runs RouDi); the network stays as Cyclone's default
  // so discovery works, and so does a fallback we can detect.
  return "<CycloneDDS><Domain id=\"any\">"
         "<SharedMemory><Enable>true</Enable><LogLevel>warn</LogLevel></SharedMemory>"
         "</Domain></CycloneDDS>";
}

dds_qos_t* frame_qos() {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  return qos;
}

class Session {
 public:
  Session(const Endpoint& e, std::string& error) : type_(e.payload) {
    domain_ = dds_create_domain(static_cast<dds_domainid_t>(e.domain), domain_config().c_str());
    if (domain_ < 0) {
      error = std::string("Cyclone DDS could not create its domain: ") + dds_strretcode(domain_);
      return;
    }
    participant_ = dds_create_participant(static_cast<dds_domainid_t>(e.domain), nullptr, nullptr);
    if (participant_ < 0) {
      error = std::string("Cyclone DDS could not create a participant: ") + dds_strretcode(participant_);
      return;
    }
    topic_ = dds_create_topic(participant_, &type_.descriptor, ("rt/" + e.topic).c_str(), nullptr,
                              nullptr);
    if (topic_ < 0) error = std::string("Cyclone DDS could not create the topic: ") + dds_strretcode(topic_);
  }
  ~Session() {
    if (participant_ > 0) dds_delete(participant_);
    if (domain_ > 0) dds_delete(domain_);
  }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  FrameDescriptor type_;
  dds_entity_t domain_ = 0;
  dds_entity_t participant_ = 0;
  dds_entity_t topic_ = 0;
};

class CyclonePublisher final : public PublisherBackend {
 public:
  CyclonePublisher(const Endpoint& e, std::string& error) : session_(e, error) {
    if (!error.empty()) return;
    dds_qos_t* qos = frame_qos();
    writer_ = dds_create_writer(session_.participant_, session_.topic_, qos, nullptr);
    dds_delete_qos(qos);
    if (writer_ < 0) {
      error = std::string("Cyclone DDS could not create the writer: ") + dds_strretcode(writer_);
      return;
    }
    loans_ = dds_is_loan_available(writer_);
  }

  bool wait_for_readers(int readers, std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      dds_publication_matched_status_t status{};
      dds_get_publication_matched_status(writer_, &status);
      if (status.current_count >= static_cast<std::uint32_t>(readers)) return true;
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  bool publish(std::span<std::byte> frame, std::uint64_t seq) override {
    if (loans_) {
      void* sample = nullptr;
      if (dds_loan_sample(writer_, &sample) == DDS_RETCODE_OK) {
        std::memcpy(sample, frame.data(), frame.size());  // producing the frame in place
        seal_frame({static_cast<std::byte*>(sample), frame.size()}, seq, sim::monotonic_ns());
        return dds_write(writer_, sample) == DDS_RETCODE_OK;
      }
    }
    seal_frame(frame, seq, sim::monotonic_ns());
    return dds_write(writer_, frame.data()) == DDS_RETCODE_OK;
  }

  std::string path_note() const override {
    return dds_is_shared_memory_available(writer_) ? (loans_ ? "shm-loan" : "shm") : "network";
  }

 private:
  Session session_;
  dds_entity_t writer_ = 0;
  bool loans_ = false;
};

class CycloneSubscriber final : public SubscriberBackend {
 public:
  CycloneSubscriber(const Endpoint& e, std::string& error) : session_(e, error), buffer_(e.payload) {
    if (!error.empty()) return;
    dds_qos_t* qos = frame_qos();
    reader_ = dds_create_reader(session_.participant_, session_.topic_, qos, nullptr);
    dds_delete_qos(qos);
    if (reader_ < 0) {
      error = std::string("Cyclone DDS could not create the reader: ") + dds_strretcode(reader_);
      return;
    }
    loans_ = dds_is_loan_available(reader_);
    waitset_ = dds_create_waitset(session_.participant_);
    condition_ = dds_create_readcondition(reader_, DDS_ANY_STATE);
    dds_waitset_attach(waitset_, condition_, reader_);
  }

  bool ready(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      dds_subscription_matched_status_t status{};
      dds_get_subscription_matched_status(reader_, &status);
      if (status.current_count >= 1) return true;
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  Delivery receive(std::chrono::milliseconds timeout) override {
    for (int attempt = 0; attempt < 2; ++attempt) {
      dds_sample_info_t info{};
      if (loans_) {
        samples_[0] = nullptr;  // asks Cyclone for a loan
        const dds_return_t n = dds_take(reader_, samples_, &info, 1, 1);
        if (n > 0) {
          held_ = true;
          if (info.valid_data) {
            return {Delivery::Kind::frame, {static_cast<const std::byte*>(samples_[0]), buffer_.size()}, {}};
          }
          release();
        }
      } else {
        samples_[0] = buffer_.data();  // Cyclone copies (deserializes) into the reader's buffer
        const dds_return_t n = dds_take(reader_, samples_, &info, 1, 1);
        if (n > 0 && info.valid_data) return {Delivery::Kind::frame, buffer_, {}};
      }
      if (attempt == 0) dds_waitset_wait(waitset_, nullptr, 0, DDS_MSECS(timeout.count()));
    }
    return {};
  }

  bool release() override {
    if (held_) dds_return_loan(reader_, samples_, 1);
    held_ = false;
    return true;
  }
  bool zero_copy() const override { return loans_; }

 private:
  Session session_;
  std::vector<std::byte> buffer_;
  dds_entity_t reader_ = 0;
  dds_entity_t waitset_ = 0;
  dds_entity_t condition_ = 0;
  void* samples_[1] = {nullptr};
  bool loans_ = false;
  bool held_ = false;
};

}  // namespace

std::unique_ptr<PublisherBackend> make_cyclone_publisher(const Endpoint& e, std::string& error) {
  auto p = std::make_unique<CyclonePublisher>(e, error);
  return error.empty() ? std::move(p) : nullptr;
}

std::unique_ptr<SubscriberBackend> make_cyclone_subscriber(const Endpoint& e, std::string& error) {
  auto s = std::make_unique<CycloneSubscriber>(e, error);
  return error.empty() ? std::move(s) : nullptr;
}

}  // namespace sim::bench
