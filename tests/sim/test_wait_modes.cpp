// SPDX-License-Identifier: Apache-2.0
// WaitMode::adaptive and WaitMode::poll with real processes and real threads: frames arrive
// whole and in order, a reader that may not spin never does, a silent stream is waited for
// without spinning. Nothing here measures time.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "sim/sim.hpp"
#include "sim_test/process.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using namespace std::chrono_literals;
using sim::testing::Process;
using test::field;
using test::StreamGuard;
using test::unique_name;

namespace {

const std::string kPeer = SIM_TEST_PEER;

// One peer writer at 200 Hz and `readers` peer readers in `mode`; checks what every reader got.
void run_peers(const std::string& mode, int readers, std::uint64_t* spins_of_first = nullptr) {
  StreamGuard g{unique_name("waitmode")};
  constexpr int kFrames = 120;
  ASSERT_TRUE(Writer::create({.name = g.name, .capacity = 32 * 1024}));
  std::vector<std::unique_ptr<Process>> children;
  for (int i = 0; i < readers; ++i) {
    children.push_back(std::make_unique<Process>(std::vector<std::string>{
        kPeer, "reader", g.name, std::to_string(kFrames), "60000", mode}));
    ASSERT_EQ(children.back()->next_line().value_or(""), "ready") << children.back()->err();
  }
  Process writer({kPeer, "writer", g.name, std::to_string(kFrames), "200", "1024", "32768", "500"});
  ASSERT_EQ(writer.next_line().value_or("").rfind("ready", 0), 0u);
  for (auto& child : children) {
    ASSERT_EQ(child->wait(), 0) << child->err();
    const std::string summary = child->unread();
    EXPECT_EQ(field(summary, "torn"), 0u) << summary;
    EXPECT_EQ(field(summary, "disorder"), 0u) << summary;
    EXPECT_EQ(field(summary, "last"), static_cast<std::uint64_t>(kFrames)) << summary;
    EXPECT_EQ(field(summary, "received") + field(summary, "skipped"),
              field(summary, "last") - field(summary, "first") + 1)
        << summary;
    if (spins_of_first != nullptr && child == children.front()) *spins_of_first = field(summary, "spins");
  }
  EXPECT_EQ(writer.wait(), 0);
}

}  // namespace

TEST(WaitModes, AnAdaptiveReaderInAnotherProcessGetsEveryFrameWholeAndInOrder) { run_peers("adaptive", 1); }

TEST(WaitModes, ThreeAdaptiveReadersShareTheCoresAndAllGetTheWholeStream) { run_peers("adaptive", 3); }

TEST(WaitModes, APollingReaderGetsEveryFrameWholeAndInOrder) { run_peers("spin", 1); }

TEST(WaitModes, AnAdaptiveReaderPinnedToOneCoreSleepsInsteadOfSpinning) {
  std::uint64_t spins = ~0ull;
  run_peers("adaptive-one-core", 1, &spins);
  EXPECT_EQ(spins, 0u);  // no core to spare: it never takes the writer's
}

TEST(WaitModes, AnAdaptiveReaderDoesNotSpinWhileTheStreamIsSilent) {
  StreamGuard g{unique_name("silent")};
  auto writer = Writer::create({.name = g.name, .capacity = 4096});
  ASSERT_TRUE(writer);
  auto reader = Reader::open(g.name, ReaderOptions{.wait_mode = WaitMode::adaptive});
  ASSERT_TRUE(reader);
  std::vector<std::byte> frame(64), out(4096);
  // A steady 500 Hz stream (the pacing only gives the writer a period; nothing checks time).
  for (int i = 0; i < 30; ++i) {
    ASSERT_EQ(writer->write(std::span<const std::byte>(frame), realtime_ns()), WriteStatus::ok);
    FrameInfo info;
    ASSERT_EQ(reader->read_next(out, info, 5s), ReadStatus::new_frame);
    std::this_thread::sleep_for(2ms);
  }
  // The writer goes quiet (alive, publishing nothing) for far longer than its period.
  const std::uint64_t spins_before = reader->stats().spins;
  EXPECT_EQ(reader->wait(400ms), ReadStatus::no_new_frame);
  // At most the spin windows of the few periods before the stream counts as silent
  // (WakePlanner::Params::silent_after_periods); after that it blocks on the futex.
  EXPECT_LE(reader->stats().spins - spins_before, 5u);
  // And it wakes for the next frame like any blocking reader.
  std::thread late([&] {
    std::this_thread::sleep_for(20ms);
    (void)writer->write(std::span<const std::byte>(frame), realtime_ns());
  });
  EXPECT_EQ(reader->wait(30s), ReadStatus::new_frame);
  late.join();
}

TEST(WaitModes, AdaptiveAndPollingReadersInThreadsNeverSeeATornFrame) {
  StreamGuard g{unique_name("threads")};
  constexpr std::uint64_t kFrames = 400;
  auto writer = Writer::create({.name = g.name, .capacity = 16 * 1024});
  ASSERT_TRUE(writer);
  std::atomic<int> bad{0};
  std::atomic<int> finished{0};
  std::vector<std::thread> readers;
  std::atomic<int> ready{0};
  for (WaitMode mode : {WaitMode::adaptive, WaitMode::adaptive, WaitMode::poll}) {
    readers.emplace_back([&, mode] {
      auto reader = Reader::open(g.name, ReaderOptions{.wait_mode = mode});
      if (!reader) {
        ++bad;
        ++ready;
        return;
      }
      ++ready;
      std::vector<std::byte> out(16 * 1024);
      std::uint64_t last = 0;
      while (last < kFrames) {
        FrameInfo info;
        const ReadStatus s = reader->read_next(out, info, 10s);
        if (s != ReadStatus::new_frame) {
          ++bad;
          break;
        }
        if (info.seq <= last || !test::check_frame(std::span(out).first(info.size), info.seq)) ++bad;
        last = info.seq;
      }
      ++finished;
    });
  }
  while (ready.load() < 3) std::this_thread::yield();
  std::vector<std::byte> frame(16 * 1024);
  for (std::uint64_t seq = 1; seq <= kFrames; ++seq) {
    const std::size_t size = test::frame_size(seq, 1024, frame.size());
    test::fill_frame(std::span(frame).first(size), seq);
    ASSERT_EQ(writer->write(std::span<const std::byte>(frame).first(size), realtime_ns()), WriteStatus::ok);
    std::this_thread::sleep_for(1ms);
  }
  for (auto& t : readers) t.join();
  EXPECT_EQ(bad.load(), 0);
  EXPECT_EQ(finished.load(), 3);
}
