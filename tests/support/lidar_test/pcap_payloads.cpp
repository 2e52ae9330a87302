// SPDX-License-Identifier: Apache-2.0
#include "lidar_test/pcap_payloads.hpp"

#include <pcap/pcap.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace lidar_test {

std::vector<UdpPayload> read_udp_payloads(const std::filesystem::path& path) {
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  std::unique_ptr<pcap_t, decltype(&pcap_close)> pcap(
      pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, errbuf),
      &pcap_close);
  if (!pcap) throw std::runtime_error(std::string("pcap: ") + errbuf);
  if (pcap_datalink(pcap.get()) != DLT_EN10MB) throw std::runtime_error("not Ethernet");

  std::vector<UdpPayload> out;
  pcap_pkthdr* header = nullptr;
  const u_char* data = nullptr;
  int rc = 0;
  while ((rc = pcap_next_ex(pcap.get(), &header, &data)) == 1) {
    std::size_t n = header->caplen;
    std::size_t off = 14;
    if (n < off) continue;
    std::uint16_t ethertype = static_cast<std::uint16_t>((data[12] << 8) | data[13]);
    while (ethertype == 0x8100 && n >= off + 4) {
      ethertype = static_cast<std::uint16_t>((data[off + 2] << 8) | data[off + 3]);
      off += 4;
    }
    if (ethertype != 0x0800 || n < off + 20) continue;
    const std::size_t ihl = std::size_t{data[off] & 0x0Fu} * 4;
    if (data[off + 9] != 17 || ihl < 20 || n < off + ihl + 8) continue;
    const std::size_t ip_total = static_cast<std::size_t>((data[off + 2] << 8) | data[off + 3]);
    const std::uint8_t* udp = data + off + ihl;
    const std::size_t udp_len = static_cast<std::size_t>((udp[4] << 8) | udp[5]);
    if (udp_len < 8 || off + ihl + udp_len > n || ihl + udp_len > ip_total) continue;
    UdpPayload p;
    p.capture_ns = std::int64_t{header->ts.tv_sec} * 1'000'000'000 + header->ts.tv_usec;
    p.dst_port = static_cast<std::uint16_t>((udp[2] << 8) | udp[3]);
    p.bytes.assign(udp + 8, udp + udp_len);
    out.push_back(std::move(p));
  }
  if (rc == PCAP_ERROR) throw std::runtime_error(pcap_geterr(pcap.get()));
  return out;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace lidar_test
