// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's table of families (replay/pcap/src/families.cpp): which family a command line
// and a capture's first datagrams choose, on the bundled recordings of every family, and the
// capture's head that every claim reads, read once.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "families.hpp"
#include "sniff.hpp"

namespace {

using sim::pcap::Request;
using sim::pcap::Sniff;

const std::string hesai_capture = std::string(SIM_HESAI_TEST_DATA) + "/pandar64_dual.pcap";
const std::string velodyne_capture = std::string(VELODYNE_TEST_DATA) + "/vlp16_dual.pcap";
const std::string ouster_capture = std::string(OUSTER_TEST_DATA) + "/OS-1-32-G_v2.1.1_1024x10.pcap";

// The family sim_replay_pcap would run for these arguments (the program's name first).
std::string chosen(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "sim_replay_pcap");
  std::vector<char*> argv;
  for (auto& a : arguments) argv.push_back(a.data());
  const Request request = sim::pcap::read_request(static_cast<int>(argv.size()), argv.data());
  const Sniff sniff = Sniff::read(request.file, request.capture);
  return std::string(sim::pcap::claimant(request, sniff).name);
}

TEST(ReplayFamilies, EveryRowHasItsOwnNameAClaimAndARun) {
  std::set<std::string_view> names;
  for (const auto& family : sim::pcap::families()) {
    EXPECT_TRUE(names.insert(family.name).second) << family.name;
    EXPECT_NE(family.claim, nullptr) << family.name;
    EXPECT_NE(family.run, nullptr) << family.name;
  }
  EXPECT_EQ(names, (std::set<std::string_view>{"Hesai", "Velodyne", "Ouster", "Unitree"}));
}

TEST(ReplayFamilies, EachBundledCaptureIsClaimedByItsFamilyFromItsPackets) {
  EXPECT_EQ(chosen({hesai_capture, "--stream", "/x"}), "Hesai");
  EXPECT_EQ(chosen({velodyne_capture, "--stream", "/x"}), "Velodyne");
  EXPECT_EQ(chosen({ouster_capture, "--stream", "/x"}), "Ouster");
}

TEST(ReplayFamilies, TheModelNamedBeatsTheCalibrationsKindWhichBeatsThePackets) {
  // A Velodyne calibration with a Hesai capture: the Velodyne replay explains the capture.
  EXPECT_EQ(chosen({hesai_capture, "--calibration", "VLP16.yaml"}), "Velodyne");
  EXPECT_EQ(chosen({hesai_capture, "--calibration=db.xml"}), "Velodyne");
  EXPECT_EQ(chosen({velodyne_capture, "--metadata", "os1.json"}), "Ouster");
  // --model wins wherever it stands on the command line.
  EXPECT_EQ(chosen({hesai_capture, "--calibration", "VLP16.yaml", "--model", "Pandar64"}), "Hesai");
  EXPECT_EQ(chosen({"--model=VLP-16", hesai_capture, "--calibration", "p64.csv"}), "Velodyne");
  EXPECT_EQ(chosen({velodyne_capture, "--model", "unitree-l2"}), "Unitree");
  // auto and an unknown model name no family: the packets choose (and the family's parser
  // refuses the unknown one).
  EXPECT_EQ(chosen({velodyne_capture, "--model", "auto"}), "Velodyne");
  EXPECT_EQ(chosen({ouster_capture, "--model", "VLP-64"}), "Ouster");
}

TEST(ReplayFamilies, ACaptureNoFamilyClaimsIsLeftToTheFirstRowWhoseDetectionExplainsIt) {
  const std::string first(sim::pcap::families().front().name);
  EXPECT_EQ(chosen({"/nonexistent/capture.pcap", "--stream", "/x"}), first);
  EXPECT_EQ(chosen({"--stream", "/x"}), first);
  // --port keeps datagrams of no sensor: the head is empty.
  EXPECT_EQ(chosen({velodyne_capture, "--port", "9"}), first);
  EXPECT_EQ(chosen({velodyne_capture, "--port", "2368"}), "Velodyne");
}

TEST(ReplayFamilies, TheCommandLineIsReadOnceForTheChoiceWithBothSpellingsOfAnOption) {
  std::vector<std::string> arguments{"sim_replay_pcap", "--model=VLP-16", "run.pcapng", "--calibration",
                                     "a.yaml", "--port", "2368", "--filter=src host 10.0.0.1", "--loop"};
  std::vector<char*> argv;
  for (auto& a : arguments) argv.push_back(a.data());
  const Request r = sim::pcap::read_request(static_cast<int>(argv.size()), argv.data());
  EXPECT_EQ(r.file, "run.pcapng");
  EXPECT_EQ(r.model, "VLP-16");
  EXPECT_EQ(r.calibration, "a.yaml");
  EXPECT_EQ(r.capture.port, std::uint16_t{2368});
  EXPECT_EQ(r.capture.filter, "src host 10.0.0.1");
  EXPECT_EQ(r.argc, 9);
  // An option's value is never taken for the capture, and a port that is none chooses none.
  std::vector<std::string> tricky{"sim_replay_pcap", "--calibration", "x.pcap", "--port", "70000", "real.pcap"};
  argv.clear();
  for (auto& a : tricky) argv.push_back(a.data());
  const Request t = sim::pcap::read_request(static_cast<int>(argv.size()), argv.data());
  EXPECT_EQ(t.file, "real.pcap");
  EXPECT_EQ(t.calibration, "x.pcap");
  EXPECT_FALSE(t.capture.port.has_value());
}

TEST(ReplayFamilies, TheHeadHoldsTheFirstDatagramsAndFindReadsOnPastItAsOftenAsAsked) {
  Sniff sniff = Sniff::read(hesai_capture, {});
  ASSERT_EQ(sniff.head().size(), Sniff::head_size);
  EXPECT_FALSE(sniff.open_error());
  // Every datagram of the file, the head's and the rest, in order of capture time.
  const auto count_all = [&] {
    std::uint64_t visited = 0;
    std::int64_t last = 0;
    bool ordered = true;
    auto found = sniff.find([&](const sim::pcap::Datagram& d) {
      ordered = ordered && d.timestamp_ns >= last;
      last = d.timestamp_ns;
      ++visited;
      return false;
    });
    EXPECT_TRUE(found.has_value());
    EXPECT_FALSE(found.has_value() && *found);
    EXPECT_TRUE(ordered);
    return visited;
  };
  const std::uint64_t first = count_all();
  EXPECT_GT(first, Sniff::head_size);
  EXPECT_EQ(sniff.seen(), first);
  EXPECT_EQ(count_all(), first);  // a second walk reopens the file past the head
  // The head's payloads are copies that outlive the reader's buffer: its first is the file's.
  auto reader = sim::pcap::CaptureReader::open(hesai_capture);
  ASSERT_TRUE(reader.has_value());
  sim::pcap::Datagram d;
  ASSERT_EQ(reader->next(d), sim::pcap::NextStatus::datagram);
  const auto head = sniff.head().front().payload;
  EXPECT_TRUE(std::equal(head.begin(), head.end(), d.payload.begin(), d.payload.end()));

  Sniff missing = Sniff::read("/nonexistent/capture.pcap", {});
  EXPECT_TRUE(missing.head().empty());
  ASSERT_TRUE(missing.open_error());
  EXPECT_NE(missing.open_error()->message.find("/nonexistent/capture.pcap"), std::string::npos);
  EXPECT_FALSE(missing.find([](const sim::pcap::Datagram&) { return true; }).has_value());
}

}  // namespace
