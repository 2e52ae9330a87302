// SPDX-License-Identifier: Apache-2.0
// A C++ consumer that uses the public C++ API the way C++17 code can (no designated
// initializers), built both as C++17 and as C++20 against the same library: it writes LiDAR
// points through a loan and raw bytes from a vector, and reads them back by copy and by borrow.
// Usage: consumer_cxx [/stream_name]. Built with SIM_EXPECT_CPLUSPLUS=201703L (or 202002L) it
// also proves the build did not quietly switch to another standard.
#include <sim/sim.hpp>

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#ifdef SIM_EXPECT_CPLUSPLUS
static_assert(__cplusplus == SIM_EXPECT_CPLUSPLUS, "compiled as another C++ standard than asked");
#endif

namespace {

int fail(const char* what) {
  std::fprintf(stderr, "consumer_cxx: %s\n", what);
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string name = argc > 1 ? argv[1] : "/consumer_cxx";
  sim::StreamSpec spec;
  spec.name = name;
  spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::lidar_point, 64));
  auto writer = sim::Writer::create(spec);
  if (!writer) return fail(writer.error().message.c_str());

  sim::Loan loan = writer->loan();
  sim::span<sim::LidarPoint> slot = loan.as<sim::LidarPoint>();
  for (std::size_t i = 0; i < 10; ++i) {
    slot[i] = sim::LidarPoint{float(i), 2.0f, 3.0f, 4.0f, 5, std::uint16_t(i), 0, 0};
  }
  if (std::move(loan).commit(10 * sizeof(sim::LidarPoint), 42) != sim::WriteStatus::ok) {
    return fail("commit failed");
  }

  auto reader = sim::Reader::open(name);
  if (!reader) return fail(reader.error().message.c_str());
  if (reader->layout() != spec.layout || !(reader->layout() == spec.layout)) {
    return fail("the reader sees another layout");
  }
  const sim::Borrow borrow = reader->borrow();
  if (borrow.status() != sim::ReadStatus::new_frame) return fail(sim::to_string(borrow.status()));
  const sim::span<const sim::LidarPoint> points = borrow.as<sim::LidarPoint>();
  if (points.size() != 10 || points[7].x != 7.0f || points[7].ring != 7 || !borrow.still_valid()) {
    return fail("borrowed points differ");
  }

  const std::vector<sim::LidarPoint> more(3, sim::LidarPoint{1, 1, 1, 1, 1, 1, 1, 0});
  if (writer->write(sim::span<const sim::LidarPoint>(more), 43) != sim::WriteStatus::ok) {
    return fail("write failed");
  }
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  if (reader->read_next(buffer, info, std::chrono::seconds(5)) != sim::ReadStatus::new_frame ||
      info.size != 3 * sizeof(sim::LidarPoint) || info.stamp_ns != 43) {
    return fail("copied frame differs");
  }
  (void)sim::destroy(name, true);  // readers keep their mapping; the name goes
  std::printf("consumer_cxx (C++ %ld): loan, borrow, write and read all work\n", long(__cplusplus));
  return 0;
}
