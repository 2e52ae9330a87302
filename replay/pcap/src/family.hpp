// SPDX-License-Identifier: Apache-2.0
// What a family of sim_replay_pcap is to main: a name, a claim on the capture (from the command
// line's --model and --calibration and from the capture's first datagrams) and a run. main reads
// the command line and the capture's head once, asks every family of the table (families.cpp)
// for its claim, and runs the strongest claimant. Adding a family is one row there plus its
// file (<family>_replay.{hpp,cpp}); no family includes another's header.
#pragma once

#include <compare>
#include <cstdint>
#include <string>
#include <string_view>

#include "sim/pcap/capture.hpp"

namespace sim::pcap {

class Sniff;

// What main reads of the command line before any family parses it.
struct Request {
  int argc = 0;
  char** argv = nullptr;
  std::string file;         // the capture (an argument ending in .pcap or .pcapng); "" none
  std::string model;        // --model as given; "" none
  std::string calibration;  // --calibration (or --metadata) as given; "" none
  // --port and --filter as given (an unparsable port: none): the datagrams the user chose to
  // reach the sensor, which the head is read through. The family's parser refuses bad ones.
  CaptureOptions capture;
};

Request read_request(int argc, char** argv);

// Why a family claims the capture, weakest first: what the user named beats what the packets
// look like, so a capture the family cannot decode is explained by that family.
enum class Evidence : std::uint8_t {
  none,
  packets,      // some of the capture's first datagrams are the family's packets
  calibration,  // the calibration file's kind is the family's (Velodyne YAML, Ouster JSON)
  model,        // --model names one of the family's models
};

struct Claim {
  Evidence evidence = Evidence::none;
  std::uint32_t packets = 0;  // of the head, how many datagrams are the family's packets

  // The stronger claim is the greater: evidence first, then the packets it recognised.
  friend auto operator<=>(const Claim&, const Claim&) = default;
};

// The claim that `packets` datagrams of the head are the family's (none when 0).
Claim packets_claim(std::uint32_t packets) noexcept;

struct Family {
  std::string_view name;  // "Hesai", for messages and tests
  Claim (*claim)(const Request&, const Sniff&);
  // Parses the family's own options (the whole command line) and replays; the exit code.
  int (*run)(const Request&, Sniff&);
};

}  // namespace sim::pcap
