// SPDX-License-Identifier: Apache-2.0
// A small fake Hesai sensor for tests: PTC as Hesai documents it, on the shared accept loop of
// the LiDAR test support (lidar_test/fake_tcp_server.hpp: a real TCP server on loopback, port 0). It serves the recorded QT128 calibration file and the unit's inventory, or
// misbehaves the ways a network and a sensor can (refuses, closes halfway, answers garbage,
// stalls, says no), and answers the clock questions (0x26 PTP config, 0x09 LiDAR status, 0x06
// PTP diagnostics 1–4) from a FakeClock the test changes while it runs. The answers are encoded
// here from the documented layouts (big-endian, as Hesai's PTC manual gives them; docs/hesai.md), not with
// the driver's code.
#pragma once

#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "lidar_test/fake_tcp_server.hpp"

namespace hesai_test {

using lidar_test::AfterAnswer;
using lidar_test::closed_port;
using lidar_test::send_all;

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline const std::string& qt128_calibration() {
  static const std::string text =
      read_file(std::filesystem::path(SIM_HESAI_TEST_DATA) / "pandarqt128.calibration.csv");
  return text;
}

// What the fake sensor says about its clock.
struct FakeClock {
  bool answers_ptp_config = true;  // false: 0x26 answered with return code 5 (older firmware)
  bool ptp_enabled = true;
  std::uint8_t profile = 0;        // 0 1588v2, 1 802.1AS, 2/3 automotive
  std::uint8_t domain = 0;
  bool qt_layout = false;          // 0x09 as a QT128 lays it out (58 B, ptp_status @52)
  std::uint8_t ptp_status = 2;     // 0 free run, 1 tracking, 2 locked, 3 frozen
  bool pps_locked = false;
  bool gprmc_locked = false;
  std::int64_t master_offset_ns = 0;
  std::uint8_t port_state = 9;     // SLAVE
  std::uint8_t delay_mechanism = 1;
  std::int64_t peer_path_delay_ns = 0;
  std::array<std::uint8_t, 8> own{0xbc, 0x0f, 0xa7, 0xff, 0xfe, 0x12, 0x34, 0x56};
  std::array<std::uint8_t, 8> grandmaster{0x00, 0x17, 0x47, 0xff, 0xfe, 0x70, 0x00, 0x38};
  bool gm_present = true;
  std::int16_t utc_offset_s = 37;
  std::uint8_t time_flags = 0x0C;  // UTC offset valid, PTP timescale
  std::size_t cut_to = SIZE_MAX;   // payload bytes sent at most (a reply cut short)
};

inline void put_be(std::string& out, std::uint64_t value, std::size_t bytes) {
  for (std::size_t i = 0; i < bytes; ++i) out += static_cast<char>(value >> (8 * (bytes - 1 - i)));
}

inline std::string ptc_header(std::uint8_t command, std::uint8_t code, std::size_t size) {
  std::string h{'\x47', '\x74', static_cast<char>(command), static_cast<char>(code)};
  put_be(h, size, 4);
  return h;
}

// The PTC payload the clock answers `command` (`query` for 0x06) with.
inline std::string clock_payload(const FakeClock& c, std::uint8_t command, std::uint8_t query) {
  std::string p;
  if (command == 0x26) {
    p = {static_cast<char>(c.ptp_enabled), static_cast<char>(c.profile), static_cast<char>(c.domain), 0};
    p += std::string(4, '\0');  // log intervals and a reserved byte
  } else if (command == 0x09) {
    p.assign(c.qt_layout ? 58 : 54, '\0');
    p[4] = 0x02;  // motor speed 600 (u16 @4), as a real answer has
    p[5] = 0x58;
    if (c.qt_layout) {
      p[52] = static_cast<char>(c.ptp_status);
    } else {
      p[38] = static_cast<char>(c.pps_locked);
      p[39] = static_cast<char>(c.gprmc_locked);
      p[48] = static_cast<char>(c.ptp_status);
    }
  } else if (query == 1) {  // PTP STATUS
    put_be(p, static_cast<std::uint64_t>(c.master_offset_ns), 8);
    put_be(p, c.ptp_status, 4);
    put_be(p, 1234, 4);
  } else if (query == 2) {  // PORT_DATA_SET
    p.append(c.own.begin(), c.own.end());
    put_be(p, 1, 2);
    p += static_cast<char>(c.port_state);
    p += '\0';
    put_be(p, static_cast<std::uint64_t>(c.peer_path_delay_ns) << 16, 8);  // TimeInterval
    p += {1, 3, 0, static_cast<char>(c.delay_mechanism), 0, 2};
  } else if (query == 3) {  // TIME_STATUS_NP
    put_be(p, static_cast<std::uint64_t>(c.master_offset_ns), 8);
    put_be(p, 1'700'000'000'000'000'000ULL, 8);
    p += std::string(22, '\0');
    put_be(p, c.gm_present ? 1 : 0, 4);
    p.append(c.grandmaster.begin(), c.grandmaster.end());
  } else if (query == 4) {  // GRANDMASTER_SETTINGS_NP
    p = {6, 0x21};
    put_be(p, 0x4E5D, 2);
    put_be(p, static_cast<std::uint16_t>(c.utc_offset_s), 2);
    p += static_cast<char>(c.time_flags);
    p += static_cast<char>(0xA0);
  }
  return p;
}

inline std::string clock_answer(const FakeClock& c, std::uint8_t command, std::uint8_t query) {
  if (command == 0x26 && !c.answers_ptp_config) return ptc_header(command, 5, 0);
  if (command == 0x06 && (query < 1 || query > 4)) return ptc_header(command, 1, 0);
  std::string payload = clock_payload(c, command, query);
  if (c.cut_to < payload.size()) {  // announced whole, sent cut: the sensor closes early
    return ptc_header(command, 0, payload.size()) + payload.substr(0, c.cut_to);
  }
  return ptc_header(command, 0, payload.size()) + payload;
}

enum class Behaviour { serve, truncate, garbage, stall, silent, refuse_request };

// A PTC server on the shared accept loop, answering each connection as told. Stalled
// connections stay open until the sensor is destroyed.
class FakeSensor {
 public:
  explicit FakeSensor(Behaviour behaviour, std::string file = qt128_calibration())
      : behaviour_(behaviour), file_(std::move(file)) {}
  std::uint16_t port() const { return server_.port(); }
  int requests() const { return requests_; }
  // What the sensor answers about its clock from now on.
  void set_clock(const FakeClock& clock) {
    std::lock_guard lock(clock_mutex_);
    clock_ = clock;
  }
  int clock_requests() const { return clock_requests_; }

 private:
  static std::string header(std::uint8_t code, std::size_t size, char command = '\x05') {
    const auto n = static_cast<std::uint32_t>(size);
    return {'\x47', '\x74', command, static_cast<char>(code), static_cast<char>(n >> 24),
            static_cast<char>(n >> 16), static_cast<char>(n >> 8), static_cast<char>(n)};
  }

 public:
  // A QT128's inventory as the PTC manual lays it out: NUL-padded text fields (serial, date,
  // MAC, software, hardware, control firmware, sensor firmware), then model and line count.
  static std::string inventory() {
    std::string payload(120, '\0');
    auto put = [&](std::size_t at, const std::string& text) { payload.replace(at, text.size(), text); };
    put(0, "QT12800TEST01");
    put(18, "2024-03-01");
    put(40, "3.1.8");
    put(56, "HW-2.0");
    put(72, "CTRL-1.4.2");
    put(88, "SENS-3.2.9");
    payload[106] = 32;   // QT128C2X
    payload[108] = static_cast<char>(128);
    return payload;
  }

 private:
  AfterAnswer answer(int fd) {
    // The request: 47 74 05 00 00 00 00 00.
    unsigned char request[8];
    std::size_t got = 0;
    while (got < sizeof request) {
      const ssize_t n = ::recv(fd, request + got, sizeof request - got, 0);
      if (n <= 0) break;
      got += static_cast<std::size_t>(n);
    }
    if (got == 8 && request[0] == 0x47 && request[1] == 0x74 && request[2] == 0x05) ++requests_;
    if (got == 8 && behaviour_ == Behaviour::serve && is_clock_command(request[2])) {
      // The request's payload: the 0x06 query byte.
      const std::size_t size = std::min<std::size_t>((std::size_t{request[6]} << 8) | request[7], 16);
      unsigned char payload[16] = {};
      std::size_t have = 0;
      while (have < size) {
        const ssize_t n = ::recv(fd, payload + have, size - have, 0);
        if (n <= 0) break;
        have += static_cast<std::size_t>(n);
      }
      ++clock_requests_;
      FakeClock clock;
      {
        std::lock_guard lock(clock_mutex_);
        clock = clock_;
      }
      send_all(fd, clock_answer(clock, request[2], have > 0 ? payload[0] : 0));
      return AfterAnswer::close;
    }
    if (got == 8 && request[2] == 0x07) {  // the inventory, whatever the behaviour
      if (behaviour_ == Behaviour::serve) send_all(fd, header(0, 120, '\x07') + inventory());
      return AfterAnswer::close;
    }
    switch (behaviour_) {
      case Behaviour::serve:
        send_all(fd, header(0, file_.size()) + file_);
        break;
      case Behaviour::truncate:
        send_all(fd, header(0, file_.size()) + file_.substr(0, file_.size() / 2));
        break;
      case Behaviour::garbage:
        send_all(fd, "HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n");
        break;
      case Behaviour::stall:
        send_all(fd, header(0, file_.size()) + file_.substr(0, 100));
        return AfterAnswer::hold;  // open, silent, until the test ends
      case Behaviour::silent:
        return AfterAnswer::hold;
      case Behaviour::refuse_request:
        send_all(fd, header(3, 0));
        break;
    }
    return AfterAnswer::close;
  }

  static bool is_clock_command(std::uint8_t command) {
    return command == 0x06 || command == 0x09 || command == 0x26;
  }

  Behaviour behaviour_;
  std::mutex clock_mutex_;
  FakeClock clock_;
  std::atomic<int> clock_requests_{0};
  std::string file_;
  std::atomic<int> requests_{0};
  lidar_test::FakeTcpServer server_{[this](int fd) { return answer(fd); }};  // last: it serves the members above
};

}  // namespace hesai_test
