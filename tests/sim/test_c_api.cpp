// SPDX-License-Identifier: Apache-2.0
// The C API: the paper's five calls, their error codes and SIM_lastError.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <thread>

#include "../../sim/region.hpp"
#include "sim/sim.h"
#include "sim_test/frames.hpp"

using sim::test::StreamGuard;
using sim::test::unique_name;

TEST(CApi, WriteReadWaitAndClose) {
  StreamGuard g{unique_name("capi")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 128);
  ASSERT_NE(w, nullptr) << SIM_lastError();
  sim_reader* r = SIM_readerInit(g.name.c_str(), 128);
  ASSERT_NE(r, nullptr) << SIM_lastError();
  char buf[128];
  sim_frame_info info{};
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), 0);
  EXPECT_EQ(SIM_waitData(r, 1), 0);

  const char frame[] = "hello";
  ASSERT_EQ(SIM_writeData(w, frame, sizeof frame), 0);
  EXPECT_EQ(SIM_waitData(r, 1000), 1);
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), static_cast<long long>(sizeof frame));
  EXPECT_STREQ(buf, "hello");
  EXPECT_EQ(info.seq, 1u);
  EXPECT_EQ(info.size, sizeof frame);
  EXPECT_GT(info.stamp_ns, 0);

  char big[129] = {};
  EXPECT_EQ(SIM_writeData(w, big, sizeof big), SIM_ETOOLARGE);
  EXPECT_NE(std::string(SIM_lastError()).find("capacity"), std::string::npos);
  ASSERT_EQ(SIM_writeData(w, frame, sizeof frame), 0);
  char small[2];
  EXPECT_EQ(SIM_readData(r, small, sizeof small, &info), SIM_EBUFFER);
  EXPECT_NE(std::string(SIM_lastError()).find("at least 128"), std::string::npos);

  EXPECT_LT(SIM_destroy(g.name.c_str()), 0);  // its writer is alive
  SIM_writerClose(w);
  std::this_thread::sleep_for(std::chrono::milliseconds(25));
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), static_cast<long long>(sizeof frame));
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), SIM_EWRITERGONE);
  SIM_readerClose(r);
  EXPECT_EQ(SIM_destroy(g.name.c_str()), 0);
}

TEST(CApi, BadArgumentsGiveNullOrNegativeCodesWithAMessage) {
  EXPECT_EQ(SIM_writerInit("no-slash", 16), nullptr);
  EXPECT_NE(std::string(SIM_lastError()).find("must start with '/'"), std::string::npos);
  EXPECT_EQ(SIM_writerInit(nullptr, 16), nullptr);
  EXPECT_EQ(SIM_readerInit(unique_name("absent").c_str(), 16), nullptr);
  EXPECT_NE(std::string(SIM_lastError()).find("start its writer first"), std::string::npos);
  EXPECT_EQ(SIM_writeData(nullptr, "x", 1), SIM_EINVAL);
  EXPECT_EQ(SIM_readData(nullptr, nullptr, 0, nullptr), SIM_EINVAL);
  EXPECT_EQ(SIM_waitData(nullptr, 0), SIM_EINVAL);
  SIM_writerClose(nullptr);
  SIM_readerClose(nullptr);

  StreamGuard g{unique_name("capismall")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 4096);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(SIM_readerInit(g.name.c_str(), 100), nullptr);  // frames may not fit its buffer
  EXPECT_NE(std::string(SIM_lastError()).find("4096"), std::string::npos);
  SIM_writerClose(w);
}

TEST(CApi, SensorDescriptionGoesFromWriterToReaderWithItsGeneration) {
  StreamGuard g{unique_name("capisensor")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 64);
  ASSERT_NE(w, nullptr) << SIM_lastError();
  sim_reader* r = SIM_readerInit(g.name.c_str(), 64);
  ASSERT_NE(r, nullptr) << SIM_lastError();
  sim_sensor_info got{};
  EXPECT_EQ(SIM_readerSensorInfo(r, &got), 0);  // none yet

  sim_sensor_info info{};
  std::strcpy(info.frame_id, "camera_front_optical");
  std::strcpy(info.parent_frame, "base_link");
  info.has_mounting = 1;
  info.translation[0] = 1.5;
  info.rotation[0] = -0.5;
  info.rotation[1] = 0.5;
  info.rotation[2] = -0.5;
  info.rotation[3] = 0.5;
  info.has_calibration = 1;
  info.calibration.width = 640;
  info.calibration.height = 480;
  std::strcpy(info.calibration.distortion_model, "plumb_bob");
  info.calibration.distortion_count = 5;
  info.calibration.d[0] = -0.25;
  const double k[9] = {500, 0, 320, 0, 501, 240, 0, 0, 1};
  std::copy(k, k + 9, info.calibration.k);
  info.calibration.r[0] = info.calibration.r[4] = info.calibration.r[8] = 1;
  std::strcpy(info.serial, "SN42");
  info.time_base = SIM_TIME_BASE_SENSOR_SYNCHRONIZED;
  ASSERT_EQ(SIM_writerSetSensorInfo(w, &info), 0) << SIM_lastError();

  char buf[64];
  sim_frame_info frame{};
  ASSERT_EQ(SIM_writeData(w, "x", 1), 0);
  ASSERT_EQ(SIM_readData(r, buf, sizeof buf, &frame), 1);
  const uint64_t generation = SIM_readerSensorGeneration(r);
  EXPECT_NE(generation, 0u);
  ASSERT_EQ(SIM_readerSensorInfo(r, &got), 1) << SIM_lastError();
  EXPECT_STREQ(got.frame_id, "camera_front_optical");
  EXPECT_EQ(got.has_mounting, 1);
  EXPECT_EQ(got.rotation[3], 0.5);
  EXPECT_EQ(got.calibration.distortion_count, 5u);
  EXPECT_EQ(got.calibration.d[0], -0.25);
  EXPECT_EQ(got.calibration.k[4], 501);
  EXPECT_STREQ(got.serial, "SN42");
  EXPECT_EQ(got.time_base, SIM_TIME_BASE_SENSOR_SYNCHRONIZED);

  std::strcpy(info.frame_id, "camera_rear_optical");
  ASSERT_EQ(SIM_writerSetSensorInfo(w, &info), 0) << SIM_lastError();
  ASSERT_EQ(SIM_writeData(w, "y", 1), 0);
  ASSERT_EQ(SIM_readData(r, buf, sizeof buf, &frame), 1);
  EXPECT_NE(SIM_readerSensorGeneration(r), generation);
  SIM_readerClose(r);
  SIM_writerClose(w);
}

TEST(CApi, BadSensorDescriptionIsRefusedWithOneSentence) {
  StreamGuard g{unique_name("capisensorbad")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 64);
  ASSERT_NE(w, nullptr) << SIM_lastError();
  sim_sensor_info info{};
  std::strcpy(info.frame_id, "lidar_top");
  std::strcpy(info.parent_frame, "base_link");
  info.has_mounting = 1;  // a zero quaternion
  EXPECT_EQ(SIM_writerSetSensorInfo(w, &info), SIM_EINVAL);
  EXPECT_NE(std::string(SIM_lastError()).find("unit quaternion"), std::string::npos) << SIM_lastError();

  info.has_mounting = 0;
  std::memset(info.serial, 'x', sizeof info.serial);  // no NUL
  EXPECT_EQ(SIM_writerSetSensorInfo(w, &info), SIM_EINVAL);
  EXPECT_NE(std::string(SIM_lastError()).find("serial has no NUL"), std::string::npos) << SIM_lastError();
  info.serial[0] = '\0';
  info.time_base = 42;
  EXPECT_EQ(SIM_writerSetSensorInfo(w, &info), SIM_EINVAL);
  EXPECT_NE(std::string(SIM_lastError()).find("SIM_TIME_BASE_"), std::string::npos) << SIM_lastError();
  EXPECT_EQ(SIM_writerSetSensorInfo(w, nullptr), SIM_EINVAL);
  EXPECT_EQ(SIM_readerSensorInfo(nullptr, &info), SIM_EINVAL);
  EXPECT_EQ(SIM_readerSensorGeneration(nullptr), 0u);
  SIM_writerClose(w);
}

TEST(CApi, DamagedSensorDescriptionIsAnErrorWhileFramesFlow) {
  StreamGuard g{unique_name("capisensordamaged")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 64);
  ASSERT_NE(w, nullptr) << SIM_lastError();
  sim_sensor_info info{};
  std::strcpy(info.frame_id, "lidar_top");
  std::strcpy(info.parent_frame, "base_link");
  ASSERT_EQ(SIM_writerSetSensorInfo(w, &info), 0) << SIM_lastError();
  sim_reader* r = SIM_readerInit(g.name.c_str(), 64);
  ASSERT_NE(r, nullptr) << SIM_lastError();
  // Another process turns the frame name into one that starts with '/'.
  const int fd = open(("/dev/shm/sim." + g.name.substr(1)).c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  const char digit = '/';
  const off_t at = static_cast<off_t>(sim::detail::kHeaderOffset + offsetof(sim::detail::RegionHeader, sensor) +
                                      offsetof(sim::detail::SensorBlock, record) +
                                      offsetof(sim::detail::SensorRecord, frame_id));
  ASSERT_EQ(pwrite(fd, &digit, 1, at), 1);
  close(fd);

  sim_sensor_info got{};
  EXPECT_EQ(SIM_readerSensorInfo(r, &got), SIM_EREGION);
  EXPECT_NE(std::string(SIM_lastError()).find("sensor description is damaged"), std::string::npos)
      << SIM_lastError();
  char buf[64];
  sim_frame_info frame{};
  ASSERT_EQ(SIM_writeData(w, "ok", 2), 0);
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &frame), 2) << SIM_lastError();
  SIM_readerClose(r);
  SIM_writerClose(w);
}
