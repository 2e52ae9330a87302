// SPDX-License-Identifier: Apache-2.0
// Fuzzes what a reader does with a region file it must not trust: open (header validation),
// read, borrow, wait, status and the sensor description (a damaged one must come back as an
// Error sentence, never a crash). Any crash or out-of-bounds access is a finding. Seeds: a region
// with a checksum, and one with a full camera description (corpus/region).
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/reader.hpp"
#include "sim/sensor_info.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string name = "/fuzz_region_" + std::to_string(getpid());
  static const std::string path = "/dev/shm/sim." + name.substr(1);
  const int fd = open(path.c_str(), O_CREAT | O_TRUNC | O_RDWR | O_CLOEXEC, 0600);
  if (fd < 0) return 0;
  if (size > 0 && write(fd, data, size) != static_cast<ssize_t>(size)) {
    close(fd);
    return 0;
  }
  close(fd);
  auto reader = sim::Reader::open(name);
  if (reader) {
    std::vector<std::byte> buf(reader->capacity() < (1u << 20) ? reader->capacity() : (1u << 20));
    sim::FrameInfo info;
    (void)reader->read(buf, info);
    const sim::Borrow borrowed = reader->borrow();
    if (borrowed.status() == sim::ReadStatus::new_frame) {
      volatile std::uint8_t sink = 0;
      for (const std::byte b : borrowed.bytes()) sink = sink ^ static_cast<std::uint8_t>(b);
      (void)borrowed.still_valid();
    }
    (void)reader->wait(std::chrono::nanoseconds(0));
    (void)reader->status();
    auto sensor = reader->sensor_info();
    if (sensor && sensor->has_value()) {
      // What the reader accepted must be a description a writer could have stored.
      if (!sim::sensor_info_problem(**sensor).empty()) __builtin_trap();
    } else if (!sensor && sensor.error().message.empty()) {
      __builtin_trap();  // a refusal always says why
    }
  }
  unlink(path.c_str());
  return 0;
}
