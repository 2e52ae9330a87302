// SPDX-License-Identifier: Apache-2.0
#include "dds_session.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include <algorithm>
#include <cstring>
#include <sstream>

#include "ros_message_type.hpp"
#include "udp_transport.hpp"
#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/graph.hpp"
#include "sim/ros2/metadata.hpp"
#include "sim/ros2/type_hash.hpp"

namespace sim::bridge {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

constexpr ros2::MessageType frame_types[] = {ros2::MessageType::point_cloud2,
                                             ros2::MessageType::image,
                                             ros2::MessageType::compressed_image};

// Every DDS type the bridge speaks, with its ROS name (for the endpoint's type hash).
struct KnownType {
  std::string_view dds_name;
  std::string_view ros_name;
};
constexpr KnownType serialized_types[] = {
    {ros2::camera_info_dds_type_name, ros2::camera_info_type_name},
    {ros2::tf_message_dds_type_name, ros2::tf_message_type_name},
    {ros2::participant_entities_info_dds_type_name, ros2::participant_entities_info_type_name},
    {ros2::diagnostic_array_dds_type_name, ros2::diagnostic_array_type_name},
};

std::string_view ros_name_of(std::string_view dds_type) {
  for (ros2::MessageType t : frame_types) {
    if (ros2::dds_type_name(t) == dds_type) return ros2::ros_type_name(t);
  }
  for (const KnownType& t : serialized_types) {
    if (t.dds_name == dds_type) return t.ros_name;
  }
  return {};
}

std::vector<rtps::octet> octets(std::string_view text) { return {text.begin(), text.end()}; }

// The QoS a ROS 2 sensor topic uses (rmw_qos_profile_sensor_data), reliable on request, latched
// (transient local) for /tf_static and the graph; USER_DATA "typehash=…;" as rmw sets it.
template <typename Qos>
void apply(Qos& qos, const QosChoice& choice, std::string_view dds_type) {
  qos.reliability().kind =
      choice.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
  qos.durability().kind =
      choice.transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
  qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  qos.history().depth = choice.depth;
  // Messages are as large as the frames: payloads are allocated to fit and then reused.
  qos.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
  qos.user_data().setValue(octets("typehash=" + std::string(ros2::rihs01_type_hash(ros_name_of(dds_type))) + ";"));
  qos.data_sharing().off();
}

// XCDR1, what every ROS 2 rmw speaks (docs/bridge.md).
void only_xcdr1(dds::DataRepresentationQosPolicy& representation) {
  representation.m_value.clear();
  representation.m_value.push_back(dds::XCDR_DATA_REPRESENTATION);
}

bool accepts_xcdr1(const dds::DataRepresentationQosPolicy& representation) {
  const auto& v = representation.m_value;
  return v.empty() || std::find(v.begin(), v.end(), dds::XCDR_DATA_REPRESENTATION) != v.end();
}

std::string guid_text(const rtps::GUID_t& guid) {
  std::ostringstream out;
  out << guid;
  return out.str();
}

std::array<std::uint8_t, 16> gid_of(const rtps::GUID_t& guid) {
  std::array<std::uint8_t, 16> gid{};
  std::memcpy(gid.data(), guid.guidPrefix.value, 12);
  std::memcpy(gid.data() + 12, guid.entityId.value, 4);
  return gid;
}

}  // namespace

Expected<std::unique_ptr<DdsSession>> DdsSession::create(int domain) {
  dds::Log::SetVerbosity(dds::Log::Error);
  std::unique_ptr<DdsSession> session(new DdsSession());
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name("sim_dds_bridge");
  // What rmw puts there: a participant without it is no part of the ROS 2 graph.
  qos.user_data().setValue(octets("enclave=/;"));
  qos.transport().use_builtin_transports = false;
  // Large frames arrive as bursts of 64 kB fragments: ask for socket buffers that hold a few
  // (the kernel caps them at net.core.{r,w}mem_max; docs/bridge.md).
  qos.transport().user_transports.push_back(udp_transport(8 * 1024 * 1024, 8 * 1024 * 1024));
  session->participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
      static_cast<dds::DomainId_t>(domain), qos, session.get(),
      dds::StatusMask::none());
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
  std::vector<dds::TypeSupport> types;
  for (ros2::MessageType type : frame_types) types.emplace_back(new RosMessageType(type));
  for (const KnownType& type : serialized_types) {
    types.emplace_back(new SerializedMessageType(type.dds_name));
  }
  for (dds::TypeSupport& support : types) {
    if (support.register_type(session->participant_) != ReturnCode_t::RETCODE_OK) {
      return Error{ErrorCode::system_error, "Fast DDS refused the type " + support.get_type_name()};
    }
  }
  if (!session->start_graph_writer() || !session->start_graph_reader()) {
    return Error{ErrorCode::system_error, "Fast DDS could not create the ros_discovery_info endpoints"};
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

dds::Topic* DdsSession::topic(const std::string& dds_topic, std::string_view dds_type,
                              std::string& error) {
  auto it = topics_.find(dds_topic);
  if (it != topics_.end()) {
    if (it->second->get_type_name() == dds_type) return it->second;
    // The stream changed its kind (points became images): the topic takes the new type.
    participant_->delete_topic(it->second);
    topics_.erase(it);
  }
  dds::Topic* t = participant_->create_topic(dds_topic, std::string(dds_type), dds::TOPIC_QOS_DEFAULT);
  if (t == nullptr) {
    error = "Fast DDS could not create the topic " + dds_topic;
    return nullptr;
  }
  topics_[dds_topic] = t;
  return t;
}

bool DdsSession::start_graph_writer() {
  std::lock_guard lock(mutex_);
  std::string error;
  dds::Topic* t = topic(std::string(ros2::graph_dds_topic),
                        ros2::participant_entities_info_dds_type_name, error);
  if (t == nullptr) return false;
  dds::DataWriterQos qos = dds::DATAWRITER_QOS_DEFAULT;
  apply(qos, QosChoice{.reliable = true, .depth = 1, .transient_local = true},
        ros2::participant_entities_info_dds_type_name);
  only_xcdr1(qos.representation());
  graph_writer_ = publisher_->create_datawriter(t, qos);
  if (graph_writer_ == nullptr) return false;
  announce_graph();
  return true;
}

void DdsSession::announce_graph() {
  if (graph_writer_ == nullptr) return;
  const std::vector<Gid> readers(reader_gids_.begin(), reader_gids_.end());
  const std::vector<Gid> writers(writer_gids_.begin(), writer_gids_.end());
  const ros2::NodeEntities node{"/", "sim_dds_bridge", readers, writers};
  const auto bytes = ros2::encode_participant_entities_info(gid_of(participant_->guid()), {&node, 1});
  SerializedMessage message{bytes};
  graph_writer_->write(&message);
}

bool DdsSession::start_graph_reader() {
  graph_listener_.session = this;
  std::lock_guard lock(mutex_);
  std::string error;
  dds::Topic* t = topic(std::string(ros2::graph_dds_topic),
                        ros2::participant_entities_info_dds_type_name, error);
  if (t == nullptr) return false;
  dds::DataReaderQos qos = dds::DATAREADER_QOS_DEFAULT;
  apply(qos, QosChoice{.reliable = true, .depth = 100, .transient_local = true},
        ros2::participant_entities_info_dds_type_name);
  only_xcdr1(qos.type_consistency().representation);
  graph_reader_ = subscriber_->create_datareader(t, qos, &graph_listener_,
                                                 dds::StatusMask::data_available());
  return graph_reader_ != nullptr;
}

void DdsSession::GraphListener::on_data_available(dds::DataReader* reader) {
  IncomingMessage sample{this};
  IncomingMessage ignored{nullptr};
  dds::SampleInfo info;
  while (reader->get_first_untaken_info(&info) == ReturnCode_t::RETCODE_OK) {
    if (reader->take_next_sample(session->own_sample(info) ? &ignored : &sample, &info) !=
        ReturnCode_t::RETCODE_OK) {
      break;
    }
  }
}

void DdsSession::GraphListener::deliver(std::span<const std::byte> message) {
  auto entities = ros2::decode_participant_entities_info(message);
  if (!entities) return;  // another participant's business; nothing of the bridge's depends on it
  GuidPrefix prefix;
  std::memcpy(prefix.data(), entities->participant.data(), prefix.size());
  {
    std::lock_guard lock(session->discovery_mutex_);
    session->graph_readers_[prefix] = {entities->readers.begin(), entities->readers.end()};
  }
  session->graph_generation_.fetch_add(1);
}

bool DdsSession::graph_says_gone(const rtps::GUID_t& reader) const {
  GuidPrefix prefix;
  std::memcpy(prefix.data(), reader.guidPrefix.value, prefix.size());
  std::lock_guard lock(discovery_mutex_);
  auto it = graph_readers_.find(prefix);
  return it != graph_readers_.end() && it->second.count(gid_of(reader)) == 0;
}

dds::DataWriter* DdsSession::create_writer(const std::string& dds_topic, std::string_view dds_type,
                                           const QosChoice& choice, std::string& error,
                                           dds::DataWriterListener* listener) {
  std::lock_guard lock(mutex_);
  dds::Topic* t = topic(dds_topic, dds_type, error);
  if (t == nullptr) return nullptr;
  dds::DataWriterQos qos = dds::DATAWRITER_QOS_DEFAULT;
  apply(qos, choice, dds_type);
  only_xcdr1(qos.representation());
  // Never make the SIM side wait long for DDS: a full reliable history blocks write() at most this.
  qos.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0, 50'000'000);
  dds::DataWriter* w = listener == nullptr
                           ? publisher_->create_datawriter(t, qos)
                           : publisher_->create_datawriter(t, qos, listener,
                                                           dds::StatusMask::publication_matched());
  if (w == nullptr) {
    error = "Fast DDS could not create a writer on " + dds_topic;
    return nullptr;
  }
  writer_gids_.insert(gid_of(w->guid()));
  announce_graph();
  return w;
}

dds::DataReader* DdsSession::create_reader(const std::string& dds_topic, std::string_view dds_type,
                                           const QosChoice& choice, std::string& error) {
  std::lock_guard lock(mutex_);
  dds::Topic* t = topic(dds_topic, dds_type, error);
  if (t == nullptr) return nullptr;
  dds::DataReaderQos qos = dds::DATAREADER_QOS_DEFAULT;
  apply(qos, choice, dds_type);
  only_xcdr1(qos.type_consistency().representation);
  dds::DataReader* r = subscriber_->create_datareader(t, qos);
  if (r == nullptr) {
    error = "Fast DDS could not create a reader on " + dds_topic;
    return nullptr;
  }
  reader_gids_.insert(gid_of(r->guid()));
  announce_graph();
  return r;
}

void DdsSession::delete_writer(dds::DataWriter* writer) {
  std::lock_guard lock(mutex_);
  if (writer == nullptr) return;
  writer_gids_.erase(gid_of(writer->guid()));
  publisher_->delete_datawriter(writer);
  announce_graph();
}

void DdsSession::delete_reader(dds::DataReader* reader) {
  std::lock_guard lock(mutex_);
  if (reader == nullptr) return;
  reader_gids_.erase(gid_of(reader->guid()));
  reader->delete_contained_entities();
  subscriber_->delete_datareader(reader);
  announce_graph();
}

std::optional<ros2::MessageType> DdsSession::discovered_type(const std::string& dds_topic) const {
  for (const RemoteEndpoint& w : remote_writers(dds_topic)) {
    for (ros2::MessageType type : frame_types) {
      if (w.type_name == ros2::dds_type_name(type)) return type;
    }
  }
  return std::nullopt;
}

namespace {
std::vector<RemoteEndpoint> endpoints_of(
    const std::map<std::string, std::map<std::string, RemoteEndpoint>>& all, const std::string& topic) {
  std::vector<RemoteEndpoint> out;
  if (auto it = all.find(topic); it != all.end()) {
    for (const auto& [guid, endpoint] : it->second) out.push_back(endpoint);
  }
  return out;
}
}  // namespace

std::vector<RemoteEndpoint> DdsSession::remote_writers(const std::string& dds_topic) const {
  std::lock_guard lock(discovery_mutex_);
  return endpoints_of(remote_writers_, dds_topic);
}

std::vector<RemoteEndpoint> DdsSession::remote_readers(const std::string& dds_topic) const {
  std::lock_guard lock(discovery_mutex_);
  return endpoints_of(remote_readers_, dds_topic);
}

bool DdsSession::own_sample(const dds::SampleInfo& info) const {
  return info.sample_identity.writer_guid().guidPrefix == participant_->guid().guidPrefix;
}

void DdsSession::on_publisher_discovery(dds::DomainParticipant* participant,
                                        rtps::WriterDiscoveryInfo&& info) {
  if (info.info.guid().guidPrefix == participant->guid().guidPrefix) return;  // our own
  const std::string topic = info.info.topicName().to_string();
  const std::string guid = guid_text(info.info.guid());
  std::lock_guard lock(discovery_mutex_);
  if (info.status == rtps::WriterDiscoveryInfo::REMOVED_WRITER) {
    remote_writers_[topic].erase(guid);
    return;
  }
  const auto& qos = info.info.m_qos;
  remote_writers_[topic][guid] = {info.info.typeName().to_string(),
                                  qos.m_reliability.kind == dds::RELIABLE_RELIABILITY_QOS,
                                  accepts_xcdr1(qos.representation)};
}

void DdsSession::on_subscriber_discovery(dds::DomainParticipant* participant,
                                         rtps::ReaderDiscoveryInfo&& info) {
  if (info.info.guid().guidPrefix == participant->guid().guidPrefix) return;  // our own
  const std::string topic = info.info.topicName().to_string();
  const std::string guid = guid_text(info.info.guid());
  std::lock_guard lock(discovery_mutex_);
  if (info.status == rtps::ReaderDiscoveryInfo::REMOVED_READER) {
    remote_readers_[topic].erase(guid);
    return;
  }
  const auto& qos = info.info.m_qos;
  remote_readers_[topic][guid] = {info.info.typeName().to_string(),
                                  qos.m_reliability.kind == dds::RELIABLE_RELIABILITY_QOS,
                                  accepts_xcdr1(qos.representation)};
}

}  // namespace sim::bridge
