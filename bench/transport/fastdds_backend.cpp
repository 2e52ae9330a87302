// SPDX-License-Identifier: Apache-2.0
// Fast DDS 2.9 behind the bench interface: a hand-written plain, bounded type (one byte array of
// the payload size, no key), best effort, KEEP_LAST 1, preallocated history, data-sharing on.
// The writer loans its sample from the data-sharing pool (falling back to write() of its own
// buffer if the loan is refused); the reader takes with a loan, so both sides are zero-copy, and
// checks is_sample_valid() after reading the bytes, as SIM's borrow checks still_valid().
#include <fastdds/dds/core/LoanableSequence.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <thread>

#include "sim/clock.hpp"
#include "transport.hpp"

namespace sim::bench {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::SerializedPayload_t;

// Serialized as a 4-byte CDR encapsulation header and the raw bytes; in the data-sharing pool
// (plain type) the sample is the raw bytes.
class FrameType final : public dds::TopicDataType {
 public:
  explicit FrameType(std::size_t bytes) : bytes_(bytes) {
    setName(("SimBenchFrame" + std::to_string(bytes)).c_str());
    m_typeSize = static_cast<std::uint32_t>(bytes + 4);
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, SerializedPayload_t* payload) override {
    if (payload->max_size < bytes_ + 4) return false;
    payload->encapsulation = CDR_LE;
    const unsigned char encapsulation[4] = {0, 1, 0, 0};  // CDR, little endian
    std::memcpy(payload->data, encapsulation, 4);
    std::memcpy(payload->data + 4, data, bytes_);
    payload->length = static_cast<std::uint32_t>(bytes_ + 4);
    return true;
  }
  bool deserialize(SerializedPayload_t* payload, void* data) override {
    if (payload->length < bytes_ + 4) return false;
    std::memcpy(data, payload->data + 4, bytes_);
    return true;
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void*) override {
    const auto n = static_cast<std::uint32_t>(bytes_ + 4);
    return [n] { return n; };
  }
  void* createData() override { return new std::uint64_t[(bytes_ + 7) / 8]; }
  void deleteData(void* data) override { delete[] static_cast<std::uint64_t*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
  bool is_bounded() const override { return true; }
  bool is_plain() const override { return true; }
  bool construct_sample(void*) const override { return true; }  // raw bytes: nothing to build

 private:
  std::size_t bytes_;
};

// A tag for the loaned sequence: the reader only ever uses the pointers it hands out.
struct RawFrame {
  std::byte first;
};

// Participant, type and topic: what a writer and a reader both set up.
class Session {
 public:
  Session(const Endpoint& e, std::string& error) : type_(new FrameType(e.payload)) {
    dds::Log::SetVerbosity(dds::Log::Error);
    participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<dds::DomainId_t>(e.domain), dds::PARTICIPANT_QOS_DEFAULT);
    if (participant_ == nullptr) {
      error = "Fast DDS could not create a participant in domain " + std::to_string(e.domain) + ".";
      return;
    }
    if (type_.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
      error = "Fast DDS refused the frame type.";
      return;
    }
    topic_ = participant_->create_topic("rt/" + e.topic, type_.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    if (topic_ == nullptr) error = "Fast DDS could not create the topic.";
  }
  ~Session() {
    if (participant_ != nullptr) {
      participant_->delete_contained_entities();
      dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
    }
  }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  dds::DomainParticipant* participant_ = nullptr;
  dds::TypeSupport type_;
  dds::Topic* topic_ = nullptr;
};

class FastddsPublisher final : public PublisherBackend {
 public:
  FastddsPublisher(const Endpoint& e, std::string& error) : session_(e, error) {
    if (!error.empty()) return;
    publisher_ = session_.participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    dds::DataWriterQos qos = dds::DATAWRITER_QOS_DEFAULT;
    qos.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
    qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = 1;
    qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    qos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_MEMORY_MODE;
    qos.data_sharing().automatic();
    writer_ = publisher_ == nullptr ? nullptr : publisher_->create_datawriter(session_.topic_, qos);
    if (writer_ == nullptr) error = "Fast DDS could not create the data writer.";
  }

  bool wait_for_readers(int readers, std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      dds::PublicationMatchedStatus status;
      writer_->get_publication_matched_status(status);
      if (status.current_count >= readers) return true;
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  bool publish(std::span<std::byte> frame, std::uint64_t seq) override {
    void* sample = nullptr;
    if (writer_->loan_sample(sample) == ReturnCode_t::RETCODE_OK) {
      loans_ok_ = true;
      std::memcpy(sample, frame.data(), frame.size());  // producing the frame in place
      seal_frame({static_cast<std::byte*>(sample), frame.size()}, seq, sim::monotonic_ns());
      return writer_->write(sample);
    }
    loans_ok_ = false;
    seal_frame(frame, seq, sim::monotonic_ns());
    return writer_->write(frame.data());
  }

  std::string path_note() const override { return loans_ok_ ? "loan" : "copy"; }

 private:
  Session session_;
  dds::Publisher* publisher_ = nullptr;
  dds::DataWriter* writer_ = nullptr;
  bool loans_ok_ = false;
};

class FastddsSubscriber final : public SubscriberBackend {
 public:
  FastddsSubscriber(const Endpoint& e, std::string& error) : session_(e, error) {
    if (!error.empty()) return;
    subscriber_ = session_.participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    dds::DataReaderQos qos = dds::DATAREADER_QOS_DEFAULT;
    qos.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
    qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = 1;
    qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    qos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_MEMORY_MODE;
    qos.data_sharing().automatic();
    reader_ = subscriber_ == nullptr ? nullptr : subscriber_->create_datareader(session_.topic_, qos);
    if (reader_ == nullptr) error = "Fast DDS could not create the data reader.";
  }

  bool ready(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      dds::SubscriptionMatchedStatus status;
      reader_->get_subscription_matched_status(status);
      if (status.current_count >= 1) return true;
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  Delivery receive(std::chrono::milliseconds timeout) override {
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (reader_->take(data_, infos_, 1) == ReturnCode_t::RETCODE_OK) {
        if (infos_.length() > 0 && infos_[0].valid_data) {
          held_ = data_.buffer()[0];
          return {Delivery::Kind::frame, {static_cast<const std::byte*>(held_), payload()}, {}};
        }
        reader_->return_loan(data_, infos_);
      }
      if (attempt == 0) {
        reader_->wait_for_unread_message(
            eprosima::fastrtps::Duration_t(static_cast<double>(timeout.count()) / 1e3));
      }
    }
    return {};
  }

  bool release() override {
    const bool valid = reader_->is_sample_valid(held_, &infos_[0]);
    reader_->return_loan(data_, infos_);
    held_ = nullptr;
    return valid;
  }
  bool zero_copy() const override { return true; }

 private:
  std::size_t payload() const { return session_.type_->m_typeSize - 4; }

  Session session_;
  dds::Subscriber* subscriber_ = nullptr;
  dds::DataReader* reader_ = nullptr;
  dds::LoanableSequence<RawFrame> data_;
  dds::SampleInfoSeq infos_;
  const void* held_ = nullptr;
};

}  // namespace

std::unique_ptr<PublisherBackend> make_fastdds_publisher(const Endpoint& e, std::string& error) {
  auto p = std::make_unique<FastddsPublisher>(e, error);
  return error.empty() ? std::move(p) : nullptr;
}

std::unique_ptr<SubscriberBackend> make_fastdds_subscriber(const Endpoint& e, std::string& error) {
  auto s = std::make_unique<FastddsSubscriber>(e, error);
  return error.empty() ? std::move(s) : nullptr;
}

}  // namespace sim::bench
