// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap: replays a LiDAR capture into a SIM stream through the decoder of the live
// driver of its family (families.cpp: Hesai, Velodyne, Ouster, Unitree), paced by the capture's
// timestamps.
#include "families.hpp"
#include "sniff.hpp"

// The family is chosen before anything else is parsed, for each takes its own options: main
// reads --model, --calibration and the capture's first datagrams once, and the family with the
// strongest claim on them parses the command line and replays.
int main(int argc, char** argv) {
  const sim::pcap::Request request = sim::pcap::read_request(argc, argv);
  sim::pcap::Sniff sniff = sim::pcap::Sniff::read(request.file, request.capture);
  return sim::pcap::claimant(request, sniff).run(request, sniff);
}
