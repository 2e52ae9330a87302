// SPDX-License-Identifier: Apache-2.0
// A LiDAR-style stream from C++: the writer decodes straight into shared memory through a loan;
// the reader borrows the frame in place and checks it is still valid after using it.
// Usage: sim_example_points [/stream_name]
#include <cstdio>
#include <sim/sim.hpp>

int main(int argc, char** argv) {
  const std::string name = argc > 1 ? argv[1] : "/example_points";
  const auto layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::lidar_point, 1000));

  auto writer = sim::Writer::create({.name = name, .layout = layout, .checksum = true});
  if (!writer) {
    std::fprintf(stderr, "sim_example_points: %s\n", writer.error().message.c_str());
    return 1;
  }
  sim::Loan loan = writer->loan();
  auto points = loan.as<sim::LidarPoint>();
  for (std::size_t i = 0; i < 100; ++i) {
    points[i] = {static_cast<float>(i), 0.0f, 1.0f, 50.0f, 0, static_cast<std::uint16_t>(i % 64), 0, 0};
  }
  if (std::move(loan).commit(100 * sizeof(sim::LidarPoint), sim::realtime_ns()) != sim::WriteStatus::ok) {
    return 1;
  }

  auto reader = sim::Reader::open(name);
  if (!reader) {
    std::fprintf(stderr, "sim_example_points: %s\n", reader.error().message.c_str());
    return 1;
  }
  const sim::Borrow frame = reader->borrow();
  if (frame.status() != sim::ReadStatus::new_frame) {
    std::fprintf(stderr, "sim_example_points: %s\n", sim::to_string(frame.status()));
    return 1;
  }
  float sum_x = 0;
  for (const sim::LidarPoint& p : frame.as<sim::LidarPoint>()) sum_x += p.x;
  const bool valid = frame.still_valid();  // the writer did not overwrite it meanwhile
  std::printf("frame %llu: %zu points, sum of x %.0f, %s\n",
              static_cast<unsigned long long>(frame.info().seq), frame.as<sim::LidarPoint>().size(),
              static_cast<double>(sum_x), valid ? "valid" : "overwritten");
  if (!sim::destroy(name, /*force=*/true)) return 1;
  return valid && sum_x == 4950.0f ? 0 : 1;
}
