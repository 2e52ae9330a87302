// SPDX-License-Identifier: Apache-2.0
// IPv4 fragment reassembly in the capture reader (replay/pcap), as Ouster's 6–33 kB datagrams
// need: a capture whose datagrams travel as 1,500-byte fragments (in any order) reads as the
// same datagrams; fragments that never complete, too many at once, or absurd ones are counted
// and dropped, never returned as a datagram.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "lidar_test/capture_frames.hpp"
#include "ip_reassembly.hpp"
#include "ouster_test_support.hpp"
#include "sim/pcap/capture.hpp"

namespace {

using namespace sim::pcap;
using sim::pcap::testing::Bytes;
using sim::pcap::testing::Record;

constexpr std::array<std::uint8_t, 4> sensor_ip{192, 168, 1, 100};
constexpr std::array<std::uint8_t, 4> host_ip{192, 168, 1, 1};

// The IPv4 fragments of one UDP datagram (`udp` = UDP header + payload), `chunk` IP payload bytes each.
std::vector<Bytes> fragments(std::uint16_t id, const Bytes& udp, std::size_t chunk = 1480) {
  std::vector<Bytes> out;
  for (std::size_t offset = 0; offset < udp.size(); offset += chunk) {
    const std::size_t size = std::min(chunk, udp.size() - offset);
    const bool more = offset + size < udp.size();
    Bytes ip;
    ip.push_back(0x45);
    ip.push_back(0);
    sim::pcap::testing::put16(ip, static_cast<std::uint16_t>(20 + size));
    sim::pcap::testing::put16(ip, id);
    sim::pcap::testing::put16(ip, static_cast<std::uint16_t>((more ? 0x2000 : 0) | (offset / 8)));
    ip.push_back(64);
    ip.push_back(17);
    sim::pcap::testing::put16(ip, 0);
    ip.insert(ip.end(), sensor_ip.begin(), sensor_ip.end());
    ip.insert(ip.end(), host_ip.begin(), host_ip.end());
    ip.insert(ip.end(), udp.begin() + static_cast<long>(offset), udp.begin() + static_cast<long>(offset + size));
    out.push_back(sim::pcap::testing::ethernet(0x0800, ip));
  }
  return out;
}

struct TempFile {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("sim_reassembly_" + std::to_string(::getpid()) + ".pcap");
  ~TempFile() { std::filesystem::remove(path); }
};

struct ReadBack {
  std::vector<Bytes> payloads;
  CaptureStats stats;
};

ReadBack read_back(const std::filesystem::path& path, CaptureOptions options = {}) {
  auto reader = CaptureReader::open(path.string(), options);
  EXPECT_TRUE(reader) << (reader ? "" : reader.error().message);
  ReadBack r;
  Datagram d;
  while (reader->next(d) == NextStatus::datagram) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(d.payload.data());
    r.payloads.emplace_back(p, p + d.payload.size());
  }
  r.stats = reader->stats();
  return r;
}

TEST(PcapReassembly, AFragmentedOusterCaptureReadsAsTheSameDatagramsInAnyFragmentOrder) {
  const auto capture = ouster_test::load_capture("OS-0-32-U1_v2.2.0_1024x10");
  std::vector<Record> records;
  std::int64_t t = 1'600'000'000'000'000'000;
  for (std::size_t i = 0; i < capture.lidar.size(); ++i) {
    auto parts = fragments(static_cast<std::uint16_t>(i), sim::pcap::testing::udp(7502, 7502, capture.lidar[i]));
    if (i % 2 == 1) std::reverse(parts.begin(), parts.end());  // some senders send the tail first
    for (auto& p : parts) records.push_back({std::move(p), t += 10'000});
  }
  TempFile file;
  sim::pcap::testing::write_capture(file.path.string(), DLT_EN10MB, records);
  // --port 7502: the later fragments have no UDP header, the port filter must let them through.
  CaptureOptions options;
  options.port = 7502;
  const ReadBack r = read_back(file.path, options);
  ASSERT_EQ(r.payloads.size(), capture.lidar.size());
  for (std::size_t i = 0; i < r.payloads.size(); ++i) EXPECT_EQ(r.payloads[i], capture.lidar[i]) << i;
  EXPECT_EQ(r.stats.reassembled, capture.lidar.size());
  EXPECT_EQ(r.stats.fragments, records.size());
  EXPECT_EQ(r.stats.fragments_incomplete, 0u);
  EXPECT_EQ(r.stats.skipped(), 0u);
}

TEST(PcapReassembly, FragmentsThatNeverCompleteAreCountedAndDroppedAndTheRestIsRead) {
  const Bytes lost = sim::pcap::testing::udp(7502, 7502, sim::pcap::testing::payload_of(8448, 1));
  const Bytes whole = sim::pcap::testing::udp(7502, 7502, sim::pcap::testing::payload_of(8448, 2));
  auto first = fragments(1, lost);
  first.erase(first.begin() + 2);  // a middle fragment never came
  auto second = fragments(2, whole);
  std::vector<Record> records;
  std::int64_t t = 1'000'000'000;
  for (auto& p : first) records.push_back({p, t += 1000});
  for (auto& p : second) records.push_back({p, t += 1000});
  TempFile file;
  sim::pcap::testing::write_capture(file.path.string(), DLT_EN10MB, records);
  const ReadBack r = read_back(file.path);
  ASSERT_EQ(r.payloads.size(), 1u);
  EXPECT_EQ(r.payloads[0], sim::pcap::testing::payload_of(8448, 2));
  EXPECT_EQ(r.stats.fragments_incomplete, 1u);
  EXPECT_EQ(r.stats.skipped(), first.size());
}

std::vector<std::byte> bytes(std::size_t n, std::uint8_t value = 0) {
  return std::vector<std::byte>(n, std::byte{value});
}

Ipv4Fragment piece(std::uint16_t id, std::uint32_t offset, bool more, const std::vector<std::byte>& data) {
  Ipv4Fragment f;
  f.source = sensor_ip;
  f.destination = host_ip;
  f.id = id;
  f.protocol = 17;
  f.offset = offset;
  f.more = more;
  f.data = data;
  return f;
}

TEST(PcapReassembly, PendingDatagramsAreBoundedAndExpireByCaptureTime) {
  Ipv4Reassembler reassembler({.max_pending = 64, .timeout_ns = 30'000'000'000});
  const auto data = bytes(1480);
  for (std::uint16_t id = 0; id < 100; ++id) {
    EXPECT_TRUE(reassembler.add(piece(id, 0, true, data), id).empty());
  }
  EXPECT_EQ(reassembler.pending(), 64u);
  EXPECT_EQ(reassembler.counters().evicted, 36u);
  // 31 s of capture time later every pending one has expired.
  EXPECT_TRUE(reassembler.add(piece(500, 0, true, data), 31'000'000'000).empty());
  EXPECT_EQ(reassembler.counters().timed_out, 64u);
  EXPECT_EQ(reassembler.pending(), 1u);
  reassembler.finish();
  EXPECT_EQ(reassembler.counters().abandoned, 1u);
  EXPECT_EQ(reassembler.counters().completed, 0u);
}

// Whether any byte of a returned datagram is `value`.
bool holds(std::span<const std::byte> datagram, std::uint8_t value) {
  return std::find(datagram.begin(), datagram.end(), std::byte{value}) != datagram.end();
}

TEST(PcapReassembly, AHoleBeforeTheLastFragmentNeverCompletesWithAnEarlierDatagramsBytes) {
  Ipv4Reassembler reassembler;
  // A first datagram leaves 0xAA in the slot's buffer.
  EXPECT_TRUE(reassembler.add(piece(1, 0, true, bytes(1480, 0xAA)), 0).empty());
  EXPECT_EQ(reassembler.add(piece(1, 1480, false, bytes(1000, 0xAA)), 0).size(), 2480u);
  // A fragment at 2000 that says more follow, then a last fragment 800–2000 that ends before it,
  // then 0–400: bytes 400–799 never came.
  EXPECT_TRUE(reassembler.add(piece(2, 2000, true, bytes(400, 1)), 1).empty());
  EXPECT_TRUE(reassembler.add(piece(2, 800, false, bytes(1200, 2)), 2).empty());
  EXPECT_TRUE(reassembler.add(piece(2, 0, true, bytes(400, 3)), 3).empty());
  EXPECT_EQ(reassembler.counters().completed, 1u);
  EXPECT_EQ(reassembler.counters().refused, 1u) << "the last fragment ending before received bytes";
  // The same pieces in the order where the end comes first: refused on the fragment past it.
  EXPECT_TRUE(reassembler.add(piece(3, 800, false, bytes(1200, 2)), 4).empty());
  EXPECT_TRUE(reassembler.add(piece(3, 2000, true, bytes(400, 1)), 5).empty());
  EXPECT_TRUE(reassembler.add(piece(3, 0, true, bytes(400, 3)), 6).empty());
  EXPECT_EQ(reassembler.counters().completed, 1u);
}

TEST(PcapReassembly, TwoDatagramsWithOneIpIdAreNeverMergedAndAnOverlapWithOtherBytesDropsTheDatagram) {
  Ipv4Reassembler reassembler;
  // Datagram A (ID 7) lost its middle fragment; 25 s later datagram B uses ID 7 again, with no
  // other fragment in between (the overlap, not the distance, tells them apart).
  EXPECT_TRUE(reassembler.add(piece(7, 0, true, bytes(1480, 0xA1)), 0).empty());
  EXPECT_TRUE(reassembler.add(piece(7, 2960, false, bytes(100, 0xA2)), 1).empty());
  const std::int64_t later = 25'000'000'000;
  for (std::uint32_t offset : {0u, 1480u, 2960u}) {
    const auto whole = reassembler.add(piece(7, offset, offset != 2960, bytes(offset == 2960 ? 100 : 1480, 0xB1)), later);
    EXPECT_FALSE(holds(whole, 0xA1) || holds(whole, 0xA2)) << "A's bytes in a datagram returned at " << offset;
  }
  EXPECT_EQ(reassembler.counters().overlapping, 1u);
  EXPECT_EQ(reassembler.counters().completed, 0u) << "B's first fragment went with A (as Linux drops it)";
  // An identical resend is no overlap: the datagram completes.
  EXPECT_TRUE(reassembler.add(piece(8, 0, true, bytes(1480, 5)), later).empty());
  EXPECT_TRUE(reassembler.add(piece(8, 0, true, bytes(1480, 5)), later).empty());
  EXPECT_EQ(reassembler.add(piece(8, 1480, false, bytes(8, 6)), later).size(), 1488u);
  EXPECT_EQ(reassembler.counters().overlapping, 1u);
}

TEST(PcapReassembly, AnIpIdThatComesRoundAgainAfterThousandsOfFragmentsStartsANewDatagram) {
  Ipv4Reassembler reassembler;
  EXPECT_TRUE(reassembler.add(piece(7, 0, true, bytes(1480, 0xA1)), 0).empty());
  EXPECT_TRUE(reassembler.add(piece(7, 2960, false, bytes(100, 0xA2)), 0).empty());
  // A sensor's stream goes on: 5,000 datagrams of two fragments each.
  for (std::uint16_t id = 100; id < 5100; ++id) {
    EXPECT_TRUE(reassembler.add(piece(id, 0, true, bytes(8, 1)), id).empty());
    EXPECT_EQ(reassembler.add(piece(id, 8, false, bytes(8, 1)), id).size(), 16u);
  }
  // B reuses ID 7 and comes whole, in a different order than A.
  EXPECT_TRUE(reassembler.add(piece(7, 1480, true, bytes(1480, 0xB1)), 6000).empty());
  EXPECT_TRUE(reassembler.add(piece(7, 2960, false, bytes(100, 0xB2)), 6000).empty());
  const auto whole = reassembler.add(piece(7, 0, true, bytes(1480, 0xB0)), 6000);
  ASSERT_EQ(whole.size(), 3060u);
  EXPECT_FALSE(holds(whole, 0xA1) || holds(whole, 0xA2));
  EXPECT_EQ(whole[3059], std::byte{0xB2});
  EXPECT_EQ(reassembler.counters().stale, 1u);
}

TEST(PcapReassembly, AbsurdFragmentsAreRefusedAndNeverMakeADatagram) {
  Ipv4Reassembler reassembler;
  // Past the largest IPv4 datagram.
  EXPECT_TRUE(reassembler.add(piece(1, 65528, false, bytes(16)), 0).empty());
  // A middle fragment not in 8-byte units, and an empty one.
  EXPECT_TRUE(reassembler.add(piece(2, 0, true, bytes(13)), 0).empty());
  EXPECT_TRUE(reassembler.add(piece(3, 0, true, bytes(0)), 0).empty());
  EXPECT_EQ(reassembler.counters().refused, 3u);
  // Two "last" fragments that disagree on the datagram's length: the datagram is dropped.
  EXPECT_TRUE(reassembler.add(piece(4, 1480, false, bytes(100)), 0).empty());
  EXPECT_TRUE(reassembler.add(piece(4, 1480, false, bytes(200)), 0).empty());
  EXPECT_TRUE(reassembler.add(piece(4, 0, true, bytes(1480)), 0).empty());
  EXPECT_EQ(reassembler.counters().refused, 4u);
  EXPECT_EQ(reassembler.counters().completed, 0u);
  // And a well-formed pair still completes.
  EXPECT_TRUE(reassembler.add(piece(5, 0, true, bytes(1480, 7)), 0).empty());
  const auto whole = reassembler.add(piece(5, 1480, false, bytes(20, 8)), 0);
  ASSERT_EQ(whole.size(), 1500u);
  EXPECT_EQ(whole[0], std::byte{7});
  EXPECT_EQ(whole[1499], std::byte{8});
}

}  // namespace
