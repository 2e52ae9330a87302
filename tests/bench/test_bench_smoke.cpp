// SPDX-License-Identifier: Apache-2.0
// sim_bench --quick over every transport this build has, as real processes: each configuration
// must deliver frames to every reader. SIM must also lose none (a newer frame may replace one:
// that is a skip, by design). Timings are printed by sim_bench but never asserted.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::string run(const std::string& command, int& exit_code) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    exit_code = -1;
    return out;
  }
  char buf[4096];
  while (fgets(buf, sizeof(buf), pipe) != nullptr) out += buf;
  const int status = pclose(pipe);
  exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, sep)) out.push_back(item);
  return out;
}

struct TempDir {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("sim_bench_smoke_" + std::to_string(getpid()));
  TempDir() { std::filesystem::create_directories(path); }
  ~TempDir() { std::filesystem::remove_all(path); }
};

TEST(BenchSmoke, EveryTransportDeliversFrames) {
  int code = 0;
  const std::string listed = run(std::string(SIM_BENCH) + " --list-transports", code);
  ASSERT_EQ(code, 0);
  std::vector<std::string> transports;
  for (const auto& t : split(listed, '\n')) {
    if (!t.empty()) transports.push_back(t);
  }
  ASSERT_GE(transports.size(), 3u) << "the three SIM transports are always built";
  std::string list;
  for (const auto& t : transports) list += (list.empty() ? "" : ",") + t;

  TempDir dir;
  const std::string csv = (dir.path / "smoke.csv").string();
  const std::string output = run(std::string(SIM_BENCH) + " --quick --transports " + list +
                                     " --payloads 25920,921600 --readers 1,2 --csv " + csv + " 2>&1",
                                 code);
  ASSERT_EQ(code, 0) << output;

  std::ifstream in(csv);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "transport,payload_bytes,readers,run,min_us,mean_us,p50_us,p95_us,p99_us,p999_us,"
                  "max_us,std_us,received,skipped,lost,writer_cpu_s,reader_cpu_s");
  std::map<std::string, int> rows_per_transport;
  while (std::getline(in, line)) {
    const auto f = split(line, ',');
    ASSERT_EQ(f.size(), 17u) << line;
    const std::string& transport = f[0];
    const int readers = std::stoi(f[2]);
    const unsigned long received = std::stoul(f[12]);
    const unsigned long skipped = std::stoul(f[13]);
    const unsigned long lost = std::stoul(f[14]);
    ++rows_per_transport[transport];
    // --quick: 60 frames, the first 10 left out, per reader.
    const unsigned long expected = 50ul * static_cast<unsigned long>(readers);
    EXPECT_GT(received, 0u) << line;
    EXPECT_LE(received + skipped + lost, expected) << line;
    if (transport.rfind("sim-", 0) == 0) {
      EXPECT_EQ(lost, 0u) << "SIM readers always get the newest frame: " << line;
      EXPECT_EQ(received + skipped, expected) << line;
    }
  }
  for (const auto& t : transports) {
    EXPECT_EQ(rows_per_transport[t], 4) << t << ": 2 payloads x 2 reader counts";
  }
  EXPECT_EQ(rows_per_transport["memcpy"], 2) << "the floor, once per payload";
}

TEST(BenchSmoke, BadOptionsAreUsageErrors) {
  int code = 0;
  const std::string out = run(std::string(SIM_BENCH) + " --transports carrier-pigeon 2>&1", code);
  EXPECT_EQ(code, 2);
  EXPECT_NE(out.find("unknown transport"), std::string::npos) << out;
  run(std::string(SIM_BENCH) + " --payloads 8 --transports sim-poll 2>&1", code);
  EXPECT_EQ(code, 2);
  run(std::string(SIM_BENCH) + " --frames 10 --warmup 10 2>&1", code);
  EXPECT_EQ(code, 2);
}

}  // namespace
