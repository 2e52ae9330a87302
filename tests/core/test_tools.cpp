// SPDX-License-Identifier: Apache-2.0
// sim_echo, sim_ls and sim_rm run as real processes against real streams.
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <optional>
#include <thread>

#include "sim/sim.hpp"
#include "sim_test/process.hpp"
#include "support.hpp"

using namespace sim;
using sim::testing::Process;
using test::StreamGuard;
using test::unique_name;

namespace {

const std::string kPeer = SIM_TEST_PEER;
const std::string kEcho = SIM_ECHO;
const std::string kLs = SIM_LS;
const std::string kRm = SIM_RM;

std::unique_ptr<Process> start_writer(const std::string& name, int frames, double rate,
                                      int linger_ms) {
  auto child = std::make_unique<Process>(std::vector<std::string>{
      kPeer, "writer", name, std::to_string(frames), std::to_string(rate), "64", "1024",
      std::to_string(linger_ms)});
  EXPECT_EQ(child->next_line().value_or("").rfind("ready", 0), 0u);
  return child;
}

double json_number(const std::string& line, const std::string& key) {
  const auto at = line.find("\"" + key + "\":");
  if (at == std::string::npos) return -1;
  return std::stod(line.substr(at + key.size() + 3));
}

}  // namespace

TEST(SimEcho, PrintsOneJsonLinePerFrame) {
  StreamGuard g{unique_name("echo")};
  auto writer = start_writer(g.name, 1000000, 100, 0);
  Process echo({kEcho, g.name, "--count", "5"});
  std::uint64_t previous = 0;
  for (int i = 0; i < 5; ++i) {
    const std::string line = echo.next_line().value_or("");
    ASSERT_TRUE(line.starts_with('{')) << line << echo.err();
    const auto seq = static_cast<std::uint64_t>(json_number(line, "seq"));
    EXPECT_GT(seq, previous);
    previous = seq;
    EXPECT_GE(json_number(line, "size"), 64);
    EXPECT_GE(json_number(line, "latency_us"), 0);
    EXPECT_NE(line.find("\"layout\":\"bytes\""), std::string::npos);
  }
  EXPECT_EQ(echo.wait(), 0);
}

TEST(SimEcho, StatsAtOneHundredHertzSeeEveryFrame) {
  StreamGuard g{unique_name("echostats")};
  // sim_echo must be listening before the first frame: create the stream, wait until sim_echo
  // sleeps on it, then hand the stream to the writer process.
  std::optional<Writer> creator = Writer::create({.name = g.name, .capacity = 1024}).value();
  Process echo({kEcho, g.name, "--stats", "--count", "100", "--timeout", "60"});
  for (int i = 0; i < 1000 && inspect(g.name)->sleeping_readers == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  creator.reset();
  auto writer = start_writer(g.name, 100, 100, 5000);
  std::string summary;
  while (const auto line = echo.next_line()) {
    if (line->find("\"summary\"") != std::string::npos) summary = *line;
  }
  ASSERT_EQ(echo.wait(), 0);
  ASSERT_FALSE(summary.empty());
  EXPECT_EQ(json_number(summary, "frames"), 100);
  EXPECT_EQ(json_number(summary, "skipped"), 0);
  EXPECT_GT(json_number(summary, "rate_hz"), 0);
  EXPECT_GE(json_number(summary, "max"), json_number(summary, "min"));
}

TEST(SimEcho, AMissingStreamOrBadOptionGivesAnExitCodeScriptsCanTrust) {
  Process missing({kEcho, unique_name("missing")});
  EXPECT_EQ(missing.wait(), 1);
  Process bad_name({kEcho, "no-slash"});
  EXPECT_EQ(bad_name.wait(), 1);
  Process bad_option({kEcho, "/x", "--no-such-option"});
  EXPECT_EQ(bad_option.wait(), 2);
  Process help({kEcho, "--help"});
  EXPECT_EQ(help.wait(), 0);
  EXPECT_NE(help.out().find("--stats"), std::string::npos);
}

TEST(SimLs, ListsAStreamWithItsWriter) {
  StreamGuard g{unique_name("ls")};
  auto writer = start_writer(g.name, 10, 1000, 60000);
  EXPECT_EQ(writer->next_line().value_or("").rfind("done", 0), 0u);
  Process ls({kLs, "--json"});
  ls.wait();
  const std::string out = ls.out();
  std::string mine;
  std::size_t start = 0;
  while (start < out.size()) {
    const std::size_t end = out.find('\n', start);
    const std::string line = out.substr(start, end - start);
    if (line.find("\"name\":\"" + g.name + "\"") != std::string::npos) mine = line;
    start = end == std::string::npos ? out.size() : end + 1;
  }
  ASSERT_FALSE(mine.empty()) << out;
  EXPECT_EQ(json_number(mine, "frames"), 10);
  EXPECT_EQ(json_number(mine, "capacity"), 1024);
  EXPECT_NE(mine.find("\"writer_alive\":true"), std::string::npos);
  EXPECT_EQ(json_number(mine, "writer_pid"), writer->pid());
}

TEST(SimRm, KeepsLiveStreamsUnlessForcedAndClearsDeadOnes) {
  StreamGuard alive{unique_name("rmalive")};
  StreamGuard dead{unique_name("rmdead")};
  auto writer = start_writer(alive.name, 1, 1000, 60000);
  { ASSERT_TRUE(Writer::create({.name = dead.name, .capacity = 64})); }

  Process refused({kRm, alive.name});
  EXPECT_EQ(refused.wait(), 1);
  EXPECT_TRUE(Reader::open(alive.name));

  Process sweep({kRm, "--dead", alive.name, dead.name});
  EXPECT_EQ(sweep.wait(), 0);
  EXPECT_TRUE(Reader::open(alive.name));
  EXPECT_EQ(Reader::open(dead.name).error().code, ErrorCode::not_found);

  Process forced({kRm, "--force", alive.name});
  EXPECT_EQ(forced.wait(), 0);
  EXPECT_EQ(Reader::open(alive.name).error().code, ErrorCode::not_found);

  Process nothing({kRm});
  EXPECT_EQ(nothing.wait(), 2);
}
