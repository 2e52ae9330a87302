// SPDX-License-Identifier: Apache-2.0
// One Fast DDS participant the way ROS 2 nodes can talk to it: UDPv4 only (Fast DDS's
// shared-memory transport differs between versions and would bypass SIM anyway), the ROS 2 type
// names registered on demand, and what discovery tells about remote writers, so a --subscribe
// learns which of the three messages a topic carries.
#pragma once

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "sim/result.hpp"
#include "sim/ros2/message.hpp"

namespace sim::bridge {

struct QosChoice {
  bool reliable = false;  // default: ROS 2's sensor-data profile (best effort, keep last 5)
  int depth = 5;
};

class DdsSession final : private eprosima::fastdds::dds::DomainParticipantListener {
 public:
  static Expected<std::unique_ptr<DdsSession>> create(int domain);
  ~DdsSession() override;
  DdsSession(const DdsSession&) = delete;
  DdsSession& operator=(const DdsSession&) = delete;

  // A writer on the DDS topic `dds_topic` ("rt/lidar_top"); nullptr with a sentence in `error`.
  eprosima::fastdds::dds::DataWriter* create_writer(const std::string& dds_topic,
                                                    ros2::MessageType type, const QosChoice& qos,
                                                    std::string& error);
  eprosima::fastdds::dds::DataReader* create_reader(const std::string& dds_topic,
                                                    ros2::MessageType type, const QosChoice& qos,
                                                    std::string& error);
  void delete_writer(eprosima::fastdds::dds::DataWriter* writer);
  void delete_reader(eprosima::fastdds::dds::DataReader* reader);

  // The message type a remote writer announced for `dds_topic`, once one was discovered.
  // Writers of this participant are not counted; types other than the three are ignored.
  std::optional<ros2::MessageType> discovered_type(const std::string& dds_topic) const;

 private:
  DdsSession() = default;
  eprosima::fastdds::dds::Topic* topic(const std::string& dds_topic, ros2::MessageType type,
                                       std::string& error);
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;

  std::mutex mutex_;  // entity creation and deletion
  // Apart from mutex_: Fast DDS calls discovery back from its own threads, possibly while it
  // holds locks a creation under mutex_ waits for.
  mutable std::mutex discovery_mutex_;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::map<std::string, ros2::MessageType> discovered_;  // under discovery_mutex_
};

}  // namespace sim::bridge
