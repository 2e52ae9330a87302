// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap: replays a LiDAR capture into a SIM stream through the decoder of the live
// driver of its family (Hesai, Ouster, Unitree), paced by the capture's timestamps.
#include <charconv>
#include <cstdio>
#include <string>
#include <string_view>
#include <system_error>

#include "hesai_replay.hpp"
#include "ouster_replay.hpp"
#include "unitree_replay.hpp"
#include "velodyne_replay.hpp"
#include "sim/unitree/decoder.hpp"


// The family is chosen before anything else is parsed: Unitree models (--model) take their own
// options; a metadata JSON (--calibration FILE.json) or a capture of Ouster packets is Ouster;
// everything else is Hesai (the model detected from the capture when --model is absent).
int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    std::string_view value;
    if (arg == "--model" && i + 1 < argc) value = argv[i + 1];
    if (arg.rfind("--model=", 0) == 0) value = arg.substr(8);
    if (!value.empty() && sim::unitree::parse_model(value)) {
      return sim::pcap::run_unitree_replay(argc, argv);
    }
  }
  if (sim::pcap::is_velodyne_replay(argc, argv)) return sim::pcap::run_velodyne_replay(argc, argv);
  if (sim::pcap::is_ouster_capture(argc, argv)) return sim::pcap::run_ouster_replay(argc, argv);
  return sim::pcap::run_hesai_replay(argc, argv);
}
