// SPDX-License-Identifier: Apache-2.0
// A ROS 2 node that publishes a SIM LiDAR stream as sensor_msgs/PointCloud2 (C++17).
//   ros2 run sim_ros2_example sim_lidar_to_ros --ros-args -p stream:=/lidar_top -p frame_id:=lidar_top
// The SIM part is four lines: open a Reader, wait for and borrow a frame, use it, check it.
#include <sim/sim.hpp>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include <rclcpp/rclcpp.hpp>
#include <sensor_msgs/msg/point_cloud2.hpp>

namespace {

sensor_msgs::msg::PointField field(const char* name, std::uint32_t offset, std::uint8_t type) {
  sensor_msgs::msg::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = 1;
  return f;
}

class SimLidarToRos : public rclcpp::Node {
 public:
  SimLidarToRos() : Node("sim_lidar_to_ros") {
    stream_ = declare_parameter<std::string>("stream", "/lidar_top");
    frame_id_ = declare_parameter<std::string>("frame_id", "lidar_top");
    publisher_ = create_publisher<sensor_msgs::msg::PointCloud2>("points", rclcpp::SensorDataQoS());
    worker_ = std::thread([this] { run(); });
  }
  ~SimLidarToRos() override {
    stop_ = true;
    worker_.join();
  }

 private:
  void run() {
    auto reader = sim::Reader::open(stream_);                       // 1. open the stream
    if (!reader) {
      RCLCPP_ERROR(get_logger(), "%s", reader.error().message.c_str());
      rclcpp::shutdown();
      return;
    }
    while (!stop_ && rclcpp::ok()) {
      if (reader->wait(std::chrono::milliseconds(100)) != sim::ReadStatus::new_frame) continue;
      const sim::Borrow frame = reader->borrow();                  // 2. the frame, in place
      if (frame.status() != sim::ReadStatus::new_frame) continue;
      auto message = to_message(frame);                            // 3. use it (one copy)
      if (!frame.still_valid()) continue;                          // 4. overwritten meanwhile?
      publisher_->publish(std::move(message));
    }
  }

  std::unique_ptr<sensor_msgs::msg::PointCloud2> to_message(const sim::Borrow& frame) const {
    using sensor_msgs::msg::PointField;
    auto m = std::make_unique<sensor_msgs::msg::PointCloud2>();
    m->header.frame_id = frame_id_;
    m->header.stamp = rclcpp::Time(frame.info().stamp_ns);
    const auto points = frame.as<sim::LidarPoint>();
    m->height = 1;
    m->width = static_cast<std::uint32_t>(points.size());
    m->fields = {field("x", 0, PointField::FLOAT32), field("y", 4, PointField::FLOAT32),
                 field("z", 8, PointField::FLOAT32), field("intensity", 12, PointField::FLOAT32),
                 field("t", 16, PointField::UINT32), field("ring", 20, PointField::UINT16)};
    m->is_bigendian = false;
    m->point_step = sizeof(sim::LidarPoint);
    m->row_step = m->point_step * m->width;
    m->is_dense = true;
    m->data.resize(frame.bytes().size());
    std::memcpy(m->data.data(), frame.bytes().data(), frame.bytes().size());
    return m;
  }

  std::string stream_;
  std::string frame_id_;
  rclcpp::Publisher<sensor_msgs::msg::PointCloud2>::SharedPtr publisher_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace

int main(int argc, char** argv) {
  rclcpp::init(argc, argv);
  rclcpp::spin(std::make_shared<SimLidarToRos>());
  rclcpp::shutdown();
  return 0;
}
