// SPDX-License-Identifier: Apache-2.0
// The capture reader on real recordings (pcap and pcapng, raw Ethernet) and on hand-built files
// for every encapsulation it claims to parse, plus the damaged and foreign files users do have.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "lidar_test/capture_frames.hpp"
#include "sim/pcap/capture.hpp"

namespace sim::pcap {
namespace {

using namespace sim::pcap::testing;
namespace fs = std::filesystem;

const fs::path data_dir = SIM_HESAI_TEST_DATA;

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("sim_pcap_test_" + std::to_string(::getpid()) + "_" +
                                         std::to_string(counter_++));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

struct ReadAll {
  std::vector<Datagram> datagrams;        // payload spans are not kept valid: use payloads
  std::vector<Bytes> payloads;
  NextStatus last = NextStatus::end;
  std::string error;
  CaptureStats stats;
};

ReadAll read_all(CaptureReader& reader) {
  ReadAll all;
  Datagram d;
  while ((all.last = reader.next(d)) == NextStatus::datagram) {
    all.datagrams.push_back(d);
    const auto* p = reinterpret_cast<const std::uint8_t*>(d.payload.data());
    all.payloads.emplace_back(p, p + d.payload.size());
  }
  if (all.last == NextStatus::error) all.error = reader.error().message;
  all.stats = reader.stats();
  return all;
}

ReadAll read_file(const std::string& path, const CaptureOptions& options = {}) {
  auto reader = CaptureReader::open(path, options);
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return {};
  }
  return read_all(*reader);
}

const std::array<std::uint8_t, 4> sensor_ip{192, 168, 1, 201};
const std::array<std::uint8_t, 4> host_ip{192, 168, 1, 100};

// ---- real recordings -------------------------------------------------------------------------

TEST(CaptureReader, RawEthernetPandar40PPcapngThroughTheLinkLayer) {
  auto reader = CaptureReader::open((data_dir / "pandar40p_last_20hz_raw.pcapng").string());
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_EQ(reader->link_type().dlt, DLT_EN10MB);
  const ReadAll all = read_all(*reader);
  ASSERT_EQ(all.last, NextStatus::end) << all.error;
  ASSERT_EQ(all.datagrams.size(), 200u);
  for (std::size_t i = 0; i < all.datagrams.size(); ++i) {
    const Datagram& d = all.datagrams[i];
    EXPECT_EQ(all.payloads[i].size(), 1266u);
    EXPECT_EQ(d.source.to_string(), "192.168.100.202:10000");
    EXPECT_EQ(d.destination.to_string(), "192.168.100.151:2369");
    if (i > 0) {
      EXPECT_GE(d.timestamp_ns, all.datagrams[i - 1].timestamp_ns);
    }
  }
  // The payload starts at a Pandar40P block (SOB FF EE), wherever the headers ended.
  EXPECT_EQ(all.payloads.front()[0], 0xff);
  EXPECT_EQ(all.payloads.front()[1], 0xee);
  // 200 packets at 20 Hz: whole seconds apart is impossible, so the stamps carry sub-µs digits
  // from a real clock and the span is a few hundred milliseconds.
  const std::int64_t span = all.datagrams.back().timestamp_ns - all.datagrams.front().timestamp_ns;
  EXPECT_GT(span, 0);
  EXPECT_LT(span, 2'000'000'000);
  EXPECT_EQ(all.stats.records, 200u);
  EXPECT_EQ(all.stats.skipped(), 0u);
}

TEST(CaptureReader, Pandar64PcapWithPortFilter) {
  CaptureOptions options;
  options.port = 2368;
  const ReadAll all = read_file((data_dir / "pandar64_dual.pcap").string(), options);
  ASSERT_EQ(all.last, NextStatus::end) << all.error;
  ASSERT_EQ(all.datagrams.size(), 2400u);
  for (std::size_t i = 0; i < all.datagrams.size(); ++i) {
    ASSERT_EQ(all.payloads[i].size(), 1198u);
    ASSERT_EQ(all.payloads[i][0], 0xee);
    ASSERT_EQ(all.payloads[i][1], 0xff);
    ASSERT_EQ(all.datagrams[i].destination.port, 2368);
  }
  EXPECT_EQ(all.datagrams.front().source.to_string(), "192.168.1.201:10000");
}

TEST(CaptureReader, PortFilterDropsOtherPorts) {
  CaptureOptions options;
  options.port = 2368;  // the 40P capture is on 2369
  const ReadAll all = read_file((data_dir / "pandar40p_last_20hz_raw.pcapng").string(), options);
  EXPECT_EQ(all.last, NextStatus::end);
  EXPECT_TRUE(all.datagrams.empty());
}

TEST(CaptureReader, SinglePacketPcapng) {
  const ReadAll all = read_file((data_dir / "pandar40p_single_packet_raw.pcapng").string());
  ASSERT_EQ(all.last, NextStatus::end) << all.error;
  ASSERT_EQ(all.datagrams.size(), 1u);
  EXPECT_TRUE(all.payloads[0].size() == 1262u || all.payloads[0].size() == 1266u);
}

// ---- hand-built encapsulations ---------------------------------------------------------------

struct Encapsulation {
  const char* name;
  int dlt;
  Bytes frame;
  std::size_t payload_size;
  std::uint8_t ip_version;
};

std::vector<Encapsulation> encapsulations() {
  const Bytes p = payload_of(1198, 7);
  const Bytes datagram4 = ipv4(sensor_ip, host_ip, udp(10000, 2368, p));
  const Bytes datagram6 = ipv6(1, 2, udp(10000, 2368, p));
  Bytes options_4 = {0x94, 0x04, 0x00, 0x00};                 // router alert: IHL 6
  Bytes options_40(40, 0x01);                                 // 40 NOPs: the largest IHL, 15
  return {
      {"ethernet", DLT_EN10MB, ethernet(0x0800, datagram4), p.size(), 4},
      {"ethernet_padded_trailer", DLT_EN10MB, cat({ethernet(0x0800, datagram4), Bytes(6, 0xaa)}),
       p.size(), 4},
      {"vlan_8021q", DLT_EN10MB, ethernet(0x0800, datagram4, {{0x8100, 0x0064}}), p.size(), 4},
      {"qinq_88a8", DLT_EN10MB, ethernet(0x0800, datagram4, {{0x88a8, 0x00c8}, {0x8100, 0x0064}}),
       p.size(), 4},
      {"ipv4_options_ihl6", DLT_EN10MB,
       ethernet(0x0800, ipv4(sensor_ip, host_ip, udp(10000, 2368, p), 17, options_4)), p.size(), 4},
      {"ipv4_options_ihl15", DLT_EN10MB,
       ethernet(0x0800, ipv4(sensor_ip, host_ip, udp(10000, 2368, p), 17, options_40)), p.size(), 4},
      {"ipv6_ethernet", DLT_EN10MB, ethernet(0x86dd, datagram6), p.size(), 6},
      {"ipv6_hop_by_hop", DLT_EN10MB,
       ethernet(0x86dd, ipv6(1, 2, cat({Bytes{17, 0, 5, 2, 0, 0, 1, 0}, udp(10000, 2368, p)}), 0)),
       p.size(), 6},
      {"linux_sll", DLT_LINUX_SLL, sll(0x0800, datagram4), p.size(), 4},
      {"linux_sll2", DLT_LINUX_SLL2, sll2(0x0800, datagram4), p.size(), 4},
      {"linux_sll2_ipv6", DLT_LINUX_SLL2, sll2(0x86dd, datagram6), p.size(), 6},
      {"raw_ipv4", DLT_RAW, datagram4, p.size(), 4},
      {"raw_ipv6", DLT_RAW, datagram6, p.size(), 6},
      {"dlt_ipv4", DLT_IPV4, datagram4, p.size(), 4},
      {"bsd_loopback", DLT_NULL, cat({Bytes{2, 0, 0, 0}, datagram4}), p.size(), 4},
  };
}

class EveryEncapsulation : public ::testing::TestWithParam<Encapsulation> {};

TEST_P(EveryEncapsulation, FindsThePayloadWithAndWithoutThePortFilter) {
  const Encapsulation& e = GetParam();
  TempDir dir;
  const std::string path = dir.file("capture.pcap");
  write_capture(path, e.dlt, {{e.frame, 1'600'000'000'123'456'000}, {e.frame, 1'600'000'000'223'456'000}});
  for (const bool filtered : {false, true}) {
    CaptureOptions options;
    if (filtered) options.port = 2368;
    const ReadAll all = read_file(path, options);
    ASSERT_EQ(all.last, NextStatus::end) << all.error;
    ASSERT_EQ(all.datagrams.size(), 2u) << e.name << (filtered ? " filtered" : "");
    EXPECT_EQ(all.payloads[0], payload_of(e.payload_size, 7)) << e.name;
    EXPECT_EQ(all.datagrams[0].source.port, 10000);
    EXPECT_EQ(all.datagrams[0].destination.port, 2368);
    EXPECT_EQ(all.datagrams[0].source.ip_version, e.ip_version);
    if (e.ip_version == 4) {
      EXPECT_EQ(all.datagrams[0].source.to_string(), "192.168.1.201:10000");
      EXPECT_EQ(all.datagrams[0].destination.to_string(), "192.168.1.100:2368");
    } else {
      EXPECT_EQ(all.datagrams[0].destination.to_string(), "[fe80::2]:2368");
    }
    EXPECT_EQ(all.datagrams[0].timestamp_ns, 1'600'000'000'123'456'000);
    EXPECT_EQ(all.datagrams[1].timestamp_ns, 1'600'000'000'223'456'000);
  }
  // A filter on another port keeps nothing, whatever the encapsulation.
  CaptureOptions other;
  other.port = 2369;
  EXPECT_TRUE(read_file(path, other).datagrams.empty()) << e.name;
}

INSTANTIATE_TEST_SUITE_P(CaptureReader, EveryEncapsulation, ::testing::ValuesIn(encapsulations()),
                         [](const auto& test) { return std::string(test.param.name); });

TEST(CaptureReader, NanosecondAndMicrosecondFilesGiveNanoseconds) {
  TempDir dir;
  const Bytes frame = ethernet(0x0800, ipv4(sensor_ip, host_ip, udp(1, 2368, payload_of(10, 0))));
  write_capture(dir.file("ns.pcap"), DLT_EN10MB, {{frame, 1'700'000'000'000'000'123}}, true);
  write_capture(dir.file("us.pcap"), DLT_EN10MB, {{frame, 1'700'000'000'000'123'000}}, false);
  const ReadAll ns = read_file(dir.file("ns.pcap"));
  const ReadAll us = read_file(dir.file("us.pcap"));
  ASSERT_EQ(ns.datagrams.size(), 1u);
  ASSERT_EQ(us.datagrams.size(), 1u);
  EXPECT_EQ(ns.datagrams[0].timestamp_ns, 1'700'000'000'000'000'123);
  EXPECT_EQ(us.datagrams[0].timestamp_ns, 1'700'000'000'000'123'000);
}

TEST(CaptureReader, SkipsAndCountsFramesWithoutAUsableDatagram) {
  TempDir dir;
  const Bytes p = payload_of(100, 1);
  const Bytes good = ethernet(0x0800, ipv4(sensor_ip, host_ip, udp(10000, 2368, p)));
  Bytes cut = good;
  cut.resize(good.size() - 30);  // a snaplen shorter than the frame
  Bytes short_udp_length = good;
  short_udp_length[14 + 20 + 4] = 0;
  short_udp_length[14 + 20 + 5] = 4;  // UDP length 4 < 8
  Bytes bad_ihl = good;
  bad_ihl[14] = 0x44;  // IHL 4 < 5
  Bytes udp_longer_than_ip = good;
  udp_longer_than_ip[14 + 20 + 5] = static_cast<std::uint8_t>(udp_longer_than_ip[14 + 20 + 5] + 50);
  const std::vector<Record> records = {
      {good, 1},
      {ethernet(0x0806, Bytes(28, 0)), 2},                                       // ARP
      {ethernet(0x0800, ipv4(sensor_ip, host_ip, Bytes(40, 0), 6)), 3},          // TCP
      {ethernet(0x0800, ipv4(sensor_ip, host_ip, udp(1, 2368, p), 17, {}, 0x2000)), 4},  // fragment
      {cut, 5, static_cast<std::uint32_t>(good.size())},
      {short_udp_length, 6},
      {bad_ihl, 7},
      {udp_longer_than_ip, 8},
      {good, 9},
  };
  write_capture(dir.file("mixed.pcap"), DLT_EN10MB, records);
  const ReadAll all = read_file(dir.file("mixed.pcap"));
  ASSERT_EQ(all.last, NextStatus::end) << all.error;
  ASSERT_EQ(all.datagrams.size(), 2u);
  EXPECT_EQ(all.payloads[0], p);
  EXPECT_EQ(all.payloads[1], p);
  EXPECT_EQ(all.stats.records, 9u);
  EXPECT_EQ(all.stats.not_ip, 1u);
  EXPECT_EQ(all.stats.not_udp, 1u);
  EXPECT_EQ(all.stats.fragments, 1u);
  EXPECT_EQ(all.stats.truncated, 2u);  // the cut frame, and the UDP length past the IP packet
  EXPECT_EQ(all.stats.malformed, 2u);
}

TEST(CaptureReader, CaptureOfAnotherProtocolYieldsNoDatagrams) {
  TempDir dir;
  std::vector<Record> records;
  for (int i = 0; i < 5; ++i) {
    records.push_back({ethernet(0x0800, ipv4(sensor_ip, host_ip, Bytes(60, 0), 6)), i});
  }
  write_capture(dir.file("tcp.pcap"), DLT_EN10MB, records);
  const ReadAll all = read_file(dir.file("tcp.pcap"));
  EXPECT_EQ(all.last, NextStatus::end);
  EXPECT_TRUE(all.datagrams.empty());
  EXPECT_EQ(all.stats.not_udp, 5u);
}

// ---- files users should be told about --------------------------------------------------------

TEST(CaptureReader, TruncatedFileIsAnErrorAfterTheWholeRecords) {
  TempDir dir;
  std::ifstream in(data_dir / "pandar64_dual.pcap", std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // 24-byte file header, then records of 16 + 1240 bytes (Ethernet+IPv4+UDP+1198): cut in the
  // middle of record 11.
  const std::size_t record = 16 + 14 + 20 + 8 + 1198;
  bytes.resize(24 + 10 * record + 600);
  std::ofstream(dir.file("cut.pcap"), std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  auto reader = CaptureReader::open(dir.file("cut.pcap"));
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadAll all = read_all(*reader);
  EXPECT_EQ(all.datagrams.size(), 10u);
  ASSERT_EQ(all.last, NextStatus::error);
  EXPECT_NE(all.error.find("cut short"), std::string::npos) << all.error;
  EXPECT_NE(all.error.find("after record 10"), std::string::npos) << all.error;

  // Cut inside a record header too.
  bytes.resize(24 + 3 * record + 5);
  std::ofstream(dir.file("cut2.pcap"), std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  auto reader2 = CaptureReader::open(dir.file("cut2.pcap"));
  ASSERT_TRUE(reader2);
  const ReadAll all2 = read_all(*reader2);
  EXPECT_EQ(all2.datagrams.size(), 3u);
  EXPECT_EQ(all2.last, NextStatus::error);
}

TEST(CaptureReader, UnsupportedLinkTypeIsRefusedAtOpen) {
  TempDir dir;
  write_capture(dir.file("wifi.pcap"), DLT_IEEE802_11, {{Bytes(40, 0), 1}});
  auto reader = CaptureReader::open(dir.file("wifi.pcap"));
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.error().message.find("link type IEEE802_11"), std::string::npos)
      << reader.error().message;
  EXPECT_NE(reader.error().message.find("Ethernet"), std::string::npos);
}

TEST(CaptureReader, NotACaptureFile) {
  TempDir dir;
  std::ofstream(dir.file("notes.txt")) << "Laser id,Elevation,Azimuth\n1,14.9,-1.042\n";
  auto reader = CaptureReader::open(dir.file("notes.txt"));
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.error().message.find("not a capture file"), std::string::npos)
      << reader.error().message;
  auto empty = CaptureReader::open(dir.file("missing.pcap"));
  ASSERT_FALSE(empty);
  EXPECT_EQ(empty.error().code, ErrorCode::not_found);
  auto directory = CaptureReader::open(dir.file(""));
  ASSERT_FALSE(directory);
  EXPECT_NE(directory.error().message.find("directory"), std::string::npos);
}

TEST(CaptureReader, BadFilterExpressionIsRefused) {
  CaptureOptions options;
  options.filter = "udp portt 12";
  auto reader = CaptureReader::open((data_dir / "pandar64_dual.pcap").string(), options);
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.error().message.find("does not compile"), std::string::npos)
      << reader.error().message;
}

TEST(CaptureReader, UserFilterIsAndedWithThePort) {
  CaptureOptions options;
  options.port = 2368;
  options.filter = "src host 192.168.1.201";
  EXPECT_EQ(read_file((data_dir / "pandar64_dual.pcap").string(), options).datagrams.size(), 2400u);
  options.filter = "src host 10.0.0.1";
  EXPECT_TRUE(read_file((data_dir / "pandar64_dual.pcap").string(), options).datagrams.empty());
}

TEST(CaptureReader, ReadsFromAMemoryStream) {
  std::ifstream in(data_dir / "pandar40p_single_packet_raw.pcapng", std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::FILE* stream = fmemopen(bytes.data(), bytes.size(), "rb");
  auto reader = CaptureReader::open(stream, "memory");
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_EQ(read_all(*reader).datagrams.size(), 1u);
}

TEST(LinkLayer, EndpointsAndStatusNames) {
  Endpoint e;
  e.ip_version = 4;
  e.address = {10, 0, 0, 1};
  e.port = 2368;
  EXPECT_EQ(e.to_string(), "10.0.0.1:2368");
  EXPECT_STREQ(to_string(FrameStatus::fragment), "IP fragment");
  EXPECT_EQ(describe(LinkType{DLT_EN10MB}), "EN10MB (Ethernet)");
  EXPECT_FALSE(is_supported(LinkType{DLT_IEEE802_11}));
}

TEST(LinkLayer, EveryPrefixOfAFrameIsHandled) {
  // Cutting a valid frame anywhere must give a status, never a read past the end (ASan checks).
  for (const Encapsulation& e : encapsulations()) {
    for (std::size_t n = 0; n < e.frame.size(); ++n) {
      Bytes prefix(e.frame.begin(), e.frame.begin() + static_cast<std::ptrdiff_t>(n));
      Datagram d;
      const FrameStatus status =
          parse_frame(LinkType{e.dlt}, std::as_bytes(std::span(prefix)), d);
      if (n < e.frame.size() - (e.name == std::string("ethernet_padded_trailer") ? 6 : 0)) {
        ASSERT_NE(status, FrameStatus::ok) << e.name << " cut at " << n;
      }
    }
  }
}

}  // namespace
}  // namespace sim::pcap
