// SPDX-License-Identifier: Apache-2.0
// One Fast DDS participant the way ROS 2 nodes can talk to it: UDPv4 only (Fast DDS's
// shared-memory transport differs between versions and would bypass SIM anyway), the ROS 2 types
// registered once, and what discovery tells about remote endpoints, so a --subscribe learns which
// message a topic carries and both directions can say why a remote endpoint does not match.
//
// It also makes the bridge a node of the ROS 2 graph: participant USER_DATA "enclave=/;", every
// endpoint's USER_DATA "typehash=RIHS01_…;", and the node "sim_dds_bridge" with all its endpoint
// GIDs on ros_discovery_info (rmw_dds_common's ParticipantEntitiesInfo), republished whenever an
// endpoint is created or deleted (docs/bridge.md, "In the ROS 2 graph").
#pragma once

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <array>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "sim/result.hpp"
#include "ros_message_type.hpp"
#include "sim/ros2/message.hpp"

namespace sim::bridge {

struct QosChoice {
  bool reliable = false;  // default: ROS 2's sensor-data profile (best effort, keep last 5)
  int depth = 5;
  bool transient_local = false;  // latched topics: /tf_static, ros_discovery_info
};

// A remote endpoint as discovery announced it.
struct RemoteEndpoint {
  std::string type_name;  // DDS type name, "sensor_msgs::msg::dds_::Image_"
  bool reliable = false;
  bool xcdr1 = true;      // it accepts XCDR1 (what ROS 2 and the bridge speak)
};

class DdsSession final : private eprosima::fastdds::dds::DomainParticipantListener {
 public:
  static Expected<std::unique_ptr<DdsSession>> create(int domain);
  ~DdsSession() override;
  DdsSession(const DdsSession&) = delete;
  DdsSession& operator=(const DdsSession&) = delete;

  // A writer (reader) on the DDS topic `dds_topic` ("rt/lidar_top") of the DDS type `dds_type`
  // (one of registered_types()); nullptr with a sentence in `error`.
  eprosima::fastdds::dds::DataWriter* create_writer(
      const std::string& dds_topic, std::string_view dds_type, const QosChoice& qos,
      std::string& error, eprosima::fastdds::dds::DataWriterListener* listener = nullptr);
  eprosima::fastdds::dds::DataReader* create_reader(const std::string& dds_topic,
                                                    std::string_view dds_type,
                                                    const QosChoice& qos, std::string& error);
  // The same for a frame message type.
  eprosima::fastdds::dds::DataWriter* create_writer(const std::string& dds_topic,
                                                    ros2::MessageType type, const QosChoice& qos,
                                                    std::string& error) {
    return create_writer(dds_topic, ros2::dds_type_name(type), qos, error);
  }
  void delete_writer(eprosima::fastdds::dds::DataWriter* writer);
  void delete_reader(eprosima::fastdds::dds::DataReader* reader);

  // The frame message a remote writer announced for `dds_topic`, once one was discovered.
  // Writers of this participant are not counted.
  std::optional<ros2::MessageType> discovered_type(const std::string& dds_topic) const;
  // Every remote writer (reader) of `dds_topic` discovery announced and has not removed.
  std::vector<RemoteEndpoint> remote_writers(const std::string& dds_topic) const;
  std::vector<RemoteEndpoint> remote_readers(const std::string& dds_topic) const;

  // True for a sample one of this participant's own writers wrote (review H1: the bridge never
  // takes its own messages back).
  bool own_sample(const eprosima::fastdds::dds::SampleInfo& info) const;

  // Review M1: Debian's Fast DDS never unmatches a Cyclone DDS (rmw_cyclonedds) reader that is
  // deleted while its participant lives. A ROS 2 node also lists its readers on
  // ros_discovery_info; true when the reader's participant does so and no longer lists it.
  bool graph_says_gone(const eprosima::fastrtps::rtps::GUID_t& reader) const;
  // Changes whenever a ros_discovery_info message was taken; 0: none yet.
  std::uint64_t graph_generation() const noexcept { return graph_generation_.load(); }

 private:
  DdsSession() = default;
  eprosima::fastdds::dds::Topic* topic(const std::string& dds_topic, std::string_view dds_type,
                                       std::string& error);
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;
  void on_subscriber_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                               eprosima::fastrtps::rtps::ReaderDiscoveryInfo&& info) override;
  bool start_graph_writer();
  // Sends the node's endpoints on ros_discovery_info; under mutex_.
  void announce_graph();

  using Gid = std::array<std::uint8_t, 16>;
  using GuidPrefix = std::array<std::uint8_t, 12>;
  // Takes the ros_discovery_info messages of other participants as they arrive.
  struct GraphListener final : eprosima::fastdds::dds::DataReaderListener, MessageSink {
    DdsSession* session = nullptr;
    void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
    void deliver(std::span<const std::byte> message) override;
  };
  bool start_graph_reader();
  GraphListener graph_listener_;
  eprosima::fastdds::dds::DataReader* graph_reader_ = nullptr;
  std::map<GuidPrefix, std::set<Gid>> graph_readers_;  // under discovery_mutex_
  std::atomic<std::uint64_t> graph_generation_{0};
  std::mutex mutex_;  // entity creation and deletion, and the GID sets
  // Apart from mutex_: Fast DDS calls discovery back from its own threads, possibly while it
  // holds locks a creation under mutex_ waits for.
  mutable std::mutex discovery_mutex_;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  eprosima::fastdds::dds::DataWriter* graph_writer_ = nullptr;  // ros_discovery_info
  std::set<Gid> writer_gids_;
  std::set<Gid> reader_gids_;
  // Under discovery_mutex_: remote endpoints by DDS topic, then by GUID.
  std::map<std::string, std::map<std::string, RemoteEndpoint>> remote_writers_;
  std::map<std::string, std::map<std::string, RemoteEndpoint>> remote_readers_;
};

}  // namespace sim::bridge
