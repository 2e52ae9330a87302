// SPDX-License-Identifier: Apache-2.0
// The invariant SIM exists for: a reader never delivers a torn frame, however slow it is.
// A writer publishes as fast as it can frames whose every word is derived from their sequence
// number; readers copy or borrow them, some deliberately stalled mid-read, and check each frame.
// SIM_STRESS_FRAMES sets the length (default one million frames); CI may run fewer.
#include <gtest/gtest.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <thread>
#include <vector>

#include "sim/sim.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using namespace std::chrono_literals;
using test::StreamGuard;
using test::unique_name;

namespace {

std::uint64_t stress_frames(std::uint64_t fallback) {
  const char* env = std::getenv("SIM_STRESS_FRAMES");
  return env != nullptr ? std::strtoull(env, nullptr, 10) : fallback;
}

struct Tally {
  std::uint64_t delivered = 0;
  std::uint64_t torn_delivered = 0;   // must stay zero
  std::uint64_t out_of_order = 0;     // must stay zero
  std::uint64_t invalidated = 0;      // borrows the writer overwrote mid-read (caught)
  std::uint64_t overruns = 0;         // copies the writer overwrote mid-copy (caught, retried)
};

void copy_reader(const std::string& name, const std::atomic<bool>& done, Tally& t) {
  auto r = Reader::open(name);
  ASSERT_TRUE(r);
  std::vector<std::byte> buf(r->capacity());
  std::uint64_t last = 0;
  while (!done.load(std::memory_order_relaxed)) {
    FrameInfo info;
    if (r->read(buf, info) != ReadStatus::new_frame) continue;
    ++t.delivered;
    if (!test::check_frame(std::span(buf).first(info.size), info.seq)) ++t.torn_delivered;
    if (info.seq <= last) ++t.out_of_order;
    last = info.seq;
  }
  t.overruns = r->stats().overruns;
}

// Borrows in place and stalls half-way through checking each frame, so the writer laps it.
void stalling_borrower(const std::string& name, const std::atomic<bool>& done, Tally& t) {
  auto r = Reader::open(name);
  ASSERT_TRUE(r);
  while (!done.load(std::memory_order_relaxed)) {
    const Borrow b = r->borrow();
    if (b.status() != ReadStatus::new_frame) continue;
    const auto bytes = b.bytes();
    const std::size_t words = bytes.size() / 8;
    const std::uint64_t seq = b.info().seq;
    bool whole = words > 0 && test::racy_word(bytes, 0) == seq;
    for (std::size_t i = 1; i < words && whole; ++i) {
      if (i == words / 2) std::this_thread::sleep_for(200us);  // stalled mid-read
      whole = test::racy_word(bytes, i) == test::pattern_word(seq, i);
    }
    if (!b.still_valid()) {
      ++t.invalidated;
      continue;  // not delivered
    }
    ++t.delivered;
    if (!whole) ++t.torn_delivered;
  }
}

void run_stress(std::uint64_t frames, std::size_t min_bytes, std::size_t max_bytes) {
  StreamGuard g{unique_name("torn")};
  auto w = Writer::create({.name = g.name, .capacity = max_bytes});
  ASSERT_TRUE(w);
  std::atomic<bool> done{false};
  std::vector<Tally> copies(3);
  Tally borrow;
  std::vector<std::thread> readers;
  for (auto& t : copies) readers.emplace_back(copy_reader, g.name, std::cref(done), std::ref(t));
  readers.emplace_back(stalling_borrower, g.name, std::cref(done), std::ref(borrow));

  for (std::uint64_t i = 0; i < frames; ++i) {
    const std::uint64_t seq = w->last_seq() + 1;
    Loan loan = w->loan();
    const std::size_t size = test::frame_size(seq, min_bytes, max_bytes);
    test::fill_frame(loan.bytes().first(size), seq);
    ASSERT_EQ(std::move(loan).commit(size, 0), WriteStatus::ok);
  }
  done.store(true);
  for (auto& t : readers) t.join();

  std::uint64_t delivered = 0, overruns = 0;
  for (const Tally& t : copies) {
    EXPECT_EQ(t.torn_delivered, 0u);
    EXPECT_EQ(t.out_of_order, 0u);
    delivered += t.delivered;
    overruns += t.overruns;
  }
  EXPECT_GT(delivered, 0u);
  EXPECT_EQ(borrow.torn_delivered, 0u);
  // The stalled borrower was lapped (so tearing really happened under it) and caught each time.
  EXPECT_GT(borrow.invalidated, 0u);
  std::printf("frames %llu: copies delivered %llu, copy overruns caught %llu; borrows delivered "
              "%llu, borrows invalidated %llu\n",
              static_cast<unsigned long long>(frames), static_cast<unsigned long long>(delivered),
              static_cast<unsigned long long>(overruns),
              static_cast<unsigned long long>(borrow.delivered),
              static_cast<unsigned long long>(borrow.invalidated));
}

}  // namespace

TEST(TornFrames, NoneDeliveredOverManySmallFrames) {
  run_stress(stress_frames(1'000'000), 64, 16 * 1024);
}

TEST(TornFrames, NoneDeliveredOverLargeFrames) {
  // 4 KB to 4 MB, the sizes at which an unvalidated double buffer tears most.
  run_stress(std::max<std::uint64_t>(stress_frames(1'000'000) / 500, 200), 4096, 4 << 20);
}
