// SPDX-License-Identifier: Apache-2.0
// The C API: the paper's five calls, their error codes and SIM_lastError.
#include <gtest/gtest.h>

#include <string>
#include <thread>

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
