// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: a whole capture file (pcap or pcapng, any link type) through libpcap and
// the link-layer parser, as sim_replay_pcap reads it; then the same bytes as one frame of each
// supported link type straight into parse_frame. Any crash, out-of-bounds read or payload span
// outside the input is a finding.
#include <pcap/pcap.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>

#include "sim/pcap/capture.hpp"

namespace {

void check_inside(std::span<const std::byte> frame, const sim::pcap::Datagram& d) {
  if (d.payload.empty()) return;
  const auto* begin = frame.data();
  const auto* end = frame.data() + frame.size();
  if (d.payload.data() < begin || d.payload.data() + d.payload.size() > end) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);

  // The bytes as a frame of every link type the parser knows.
  for (const int dlt : {DLT_EN10MB, DLT_LINUX_SLL, DLT_LINUX_SLL2, DLT_RAW, DLT_IPV4, DLT_IPV6,
                        DLT_NULL, DLT_LOOP}) {
    sim::pcap::Datagram d;
    if (sim::pcap::parse_frame(sim::pcap::LinkType{dlt}, bytes, d) == sim::pcap::FrameStatus::ok) {
      check_inside(bytes, d);
    }
  }

  // The bytes as a capture file, read from memory as the replay tool reads a file.
  if (size == 0) return 0;
  std::FILE* stream = fmemopen(const_cast<std::uint8_t*>(data), size, "rb");
  if (stream == nullptr) return 0;
  sim::pcap::CaptureOptions options;
  if ((data[size - 1] & 1u) != 0) options.port = 2368;  // exercise the BPF path too
  auto reader = sim::pcap::CaptureReader::open(stream, "fuzz input", options);
  if (!reader) return 0;
  sim::pcap::Datagram d;
  for (int i = 0; i < 10000 && reader->next(d) == sim::pcap::NextStatus::datagram; ++i) {
    // Touch every payload byte so ASan sees any read outside libpcap's buffer.
    volatile std::uint8_t sum = 0;
    for (const std::byte b : d.payload) sum = static_cast<std::uint8_t>(sum + std::to_integer<std::uint8_t>(b));
    (void)sum;
  }
  return 0;
}
