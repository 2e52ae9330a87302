// SPDX-License-Identifier: Apache-2.0
#include "dds_session.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include "ros_message_type.hpp"

namespace sim::bridge {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

constexpr ros2::MessageType all_types[] = {ros2::MessageType::point_cloud2, ros2::MessageType::image,
                                           ros2::MessageType::compressed_image};

// The QoS a ROS 2 sensor topic uses (rmw_qos_profile_sensor_data), or reliable on request.
template <typename Qos>
void apply(Qos& qos, const QosChoice& choice) {
  qos.reliability().kind =
      choice.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
  qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  qos.history().depth = choice.depth;
  // Messages are as large as the frames: payloads are allocated to fit and then reused.
  qos.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
}

// XCDR1, what every ROS 2 rmw speaks (docs/bridge.md).
void only_xcdr1(dds::DataRepresentationQosPolicy& representation) {
  representation.m_value.clear();
  representation.m_value.push_back(dds::XCDR_DATA_REPRESENTATION);
}

}  // namespace

Expected<std::unique_ptr<DdsSession>> DdsSession::create(int domain) {
  dds::Log::SetVerbosity(dds::Log::Error);
  std::unique_ptr<DdsSession> session(new DdsSession());
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name("sim_dds_bridge");
  qos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  // Large frames arrive as bursts of 64 kB fragments: ask for socket buffers that hold a few
  // (the kernel caps them at net.core.{r,w}mem_max; docs/bridge.md).
  udp->sendBufferSize = 8 * 1024 * 1024;
  udp->receiveBufferSize = 8 * 1024 * 1024;
  qos.transport().user_transports.push_back(udp);
  session->participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
      static_cast<dds::DomainId_t>(domain), qos, session.get(), dds::StatusMask::none());
  if (session->participant_ == nullptr) {
    return Error{ErrorCode::system_error, "Fast DDS could not create a participant in domain " +
                                              std::to_string(domain) +
                                              "; check that the domain is 0-232 and UDP works"};
  }
  session->publisher_ = session->participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  session->subscriber_ = session->participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  if (session->publisher_ == nullptr || session->subscriber_ == nullptr) {
    return Error{ErrorCode::system_error, "Fast DDS could not create a publisher or subscriber"};
  }
  for (ros2::MessageType type : all_types) {
    dds::TypeSupport support(new RosMessageType(type));
    if (support.register_type(session->participant_) != ReturnCode_t::RETCODE_OK) {
      return Error{ErrorCode::system_error, "Fast DDS refused the type " +
                                                std::string(ros2::dds_type_name(type))};
    }
  }
  return session;
}

DdsSession::~DdsSession() {
  if (participant_ != nullptr) {
    participant_->set_listener(nullptr);
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
}

dds::Topic* DdsSession::topic(const std::string& dds_topic, ros2::MessageType type,
                              std::string& error) {
  auto it = topics_.find(dds_topic);
  if (it != topics_.end()) {
    if (it->second->get_type_name() == ros2::dds_type_name(type)) return it->second;
    // The stream changed its kind (points became images): the topic takes the new type.
    participant_->delete_topic(it->second);
    topics_.erase(it);
  }
  dds::Topic* t = participant_->create_topic(dds_topic, std::string(ros2::dds_type_name(type)),
                                             dds::TOPIC_QOS_DEFAULT);
  if (t == nullptr) {
    error = "Fast DDS could not create the topic " + dds_topic;
    return nullptr;
  }
  topics_[dds_topic] = t;
  return t;
}

dds::DataWriter* DdsSession::create_writer(const std::string& dds_topic, ros2::MessageType type,
                                           const QosChoice& choice, std::string& error) {
  std::lock_guard lock(mutex_);
  dds::Topic* t = topic(dds_topic, type, error);
  if (t == nullptr) return nullptr;
  dds::DataWriterQos qos = dds::DATAWRITER_QOS_DEFAULT;
  apply(qos, choice);
  only_xcdr1(qos.representation());
  // Never make the SIM side wait long for DDS: a full reliable history blocks write() at most this.
  qos.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0, 50'000'000);
  qos.data_sharing().off();
  dds::DataWriter* w = publisher_->create_datawriter(t, qos);
  if (w == nullptr) error = "Fast DDS could not create a writer on " + dds_topic;
  return w;
}

dds::DataReader* DdsSession::create_reader(const std::string& dds_topic, ros2::MessageType type,
                                           const QosChoice& choice, std::string& error) {
  std::lock_guard lock(mutex_);
  dds::Topic* t = topic(dds_topic, type, error);
  if (t == nullptr) return nullptr;
  dds::DataReaderQos qos = dds::DATAREADER_QOS_DEFAULT;
  apply(qos, choice);
  only_xcdr1(qos.type_consistency().representation);
  qos.data_sharing().off();
  dds::DataReader* r = subscriber_->create_datareader(t, qos);
  if (r == nullptr) error = "Fast DDS could not create a reader on " + dds_topic;
  return r;
}

void DdsSession::delete_writer(dds::DataWriter* writer) {
  std::lock_guard lock(mutex_);
  if (writer != nullptr) publisher_->delete_datawriter(writer);
}

void DdsSession::delete_reader(dds::DataReader* reader) {
  std::lock_guard lock(mutex_);
  if (reader != nullptr) {
    reader->delete_contained_entities();
    subscriber_->delete_datareader(reader);
  }
}

std::optional<ros2::MessageType> DdsSession::discovered_type(const std::string& dds_topic) const {
  std::lock_guard lock(discovery_mutex_);
  auto it = discovered_.find(dds_topic);
  if (it == discovered_.end()) return std::nullopt;
  return it->second;
}

void DdsSession::on_publisher_discovery(dds::DomainParticipant* participant,
                                        rtps::WriterDiscoveryInfo&& info) {
  if (info.status != rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) return;
  if (info.info.guid().guidPrefix == participant->guid().guidPrefix) return;  // our own
  const std::string type_name = info.info.typeName().to_string();
  for (ros2::MessageType type : all_types) {
    if (type_name == ros2::dds_type_name(type)) {
      std::lock_guard lock(discovery_mutex_);
      discovered_[info.info.topicName().to_string()] = type;
    }
  }
}

}  // namespace sim::bridge
