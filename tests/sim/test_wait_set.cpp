// SPDX-License-Identifier: Apache-2.0
// WaitSet (both strategies: futex_waitv and the round-robin fallback forced), StreamNotifier's
// file descriptor, their C API, and ApproximatePairer on streams at different rates. Writers are
// driven explicitly; no assertion depends on timing.
#include <gtest/gtest.h>
#include <poll.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <set>
#include <thread>
#include <vector>

#include "sim/sim.h"
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

struct Stream {
  StreamGuard guard;
  Writer writer;
  Reader reader;
};

std::unique_ptr<Stream> make_stream(const std::string& what) {
  const std::string name = unique_name(what);
  auto w = Writer::create({.name = name, .capacity = 4096});
  if (!w) return nullptr;
  auto r = Reader::open(name);
  if (!r) return nullptr;
  // The guard is built in place: a StreamGuard copied out of a local would remove the stream.
  return std::unique_ptr<Stream>(new Stream{StreamGuard{name}, std::move(*w), std::move(*r)});
}

void publish(Stream& s, std::int64_t stamp_ns = 0) {
  std::vector<std::byte> frame(128, std::byte{7});
  ASSERT_EQ(s.writer.write(std::span<const std::byte>(frame), stamp_ns != 0 ? stamp_ns : realtime_ns()),
            WriteStatus::ok);
}

bool readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) == 1 && (p.revents & POLLIN) != 0;
}

class WaitSetStrategies : public ::testing::TestWithParam<WaitSetStrategy> {};

}  // namespace

TEST_P(WaitSetStrategies, ReportsTheStreamThatHasANewFrame) {
  std::vector<std::unique_ptr<Stream>> streams;
  WaitSet set({.strategy = GetParam()});
  for (int i = 0; i < 3; ++i) {
    streams.push_back(make_stream("set"));
    ASSERT_TRUE(streams.back());
    auto index = set.add(streams.back()->reader);
    ASSERT_TRUE(index);
    ASSERT_EQ(*index, static_cast<std::size_t>(i));
  }
  EXPECT_FALSE(set.wait(0ms).has_value());  // nothing published yet
  publish(*streams[2]);
  EXPECT_EQ(set.wait(30s), std::optional<std::size_t>(2));
  EXPECT_TRUE(set.ready(2));
  EXPECT_FALSE(set.ready(0));
  // The reader keeps its own semantics: reading takes the frame, and the set is quiet again.
  std::vector<std::byte> out(4096);
  FrameInfo info;
  ASSERT_EQ(streams[2]->reader.read(out, info), ReadStatus::new_frame);
  EXPECT_FALSE(set.wait(1ms).has_value());
}

TEST_P(WaitSetStrategies, WakesForAFramePublishedByAnotherThreadWhileItSleeps) {
  auto a = make_stream("sleep_a");
  auto b = make_stream("sleep_b");
  ASSERT_TRUE(a && b);
  WaitSet set({.strategy = GetParam()});
  ASSERT_TRUE(set.add(a->reader));
  ASSERT_TRUE(set.add(b->reader));
  std::thread writer([&] {
    std::this_thread::sleep_for(20ms);  // lets the set fall asleep (not checked)
    publish(*b);
  });
  EXPECT_EQ(set.wait(30s), std::optional<std::size_t>(1));
  writer.join();
}

TEST_P(WaitSetStrategies, TakesReadyStreamsInTurnSoABusyOneHidesNoOther) {
  auto a = make_stream("fair_a");
  auto b = make_stream("fair_b");
  ASSERT_TRUE(a && b);
  WaitSet set({.strategy = GetParam()});
  ASSERT_TRUE(set.add(a->reader));
  ASSERT_TRUE(set.add(b->reader));
  publish(*a);
  publish(*b);
  std::set<std::size_t> seen;
  for (int i = 0; i < 2; ++i) seen.insert(set.wait(1s).value_or(99));
  EXPECT_EQ(seen, (std::set<std::size_t>{0, 1}));
}

namespace {

// Only a wakeup ends a wait with no frame to come before this: ending well before it is the proof.
constexpr auto kLongWait = 120s;

// A wait set that watches a wakeup of its own.
struct WatchingSet {
  explicit WatchingSet(WaitSetStrategy strategy) : set({.strategy = strategy}) { set.watch(wakeup); }
  Wakeup wakeup;
  WaitSet set;
};

// Ends the set's wait from another thread, which first lets the set fall asleep (not checked: a
// notify() before the wait ends it as well). True when the wait ended by the wakeup.
bool woken_from_another_thread(WatchingSet& watching) {
  Wakeup& wakeup = watching.wakeup;
  WaitSet& set = watching.set;
  std::thread other([&] {
    std::this_thread::sleep_for(20ms);
    wakeup.notify();
  });
  const auto start = std::chrono::steady_clock::now();
  const auto ready = set.wait(kLongWait);
  const bool early = std::chrono::steady_clock::now() - start < kLongWait;
  other.join();
  return !ready.has_value() && early && set.woken();
}

}  // namespace

TEST_P(WaitSetStrategies, AWakeupFromAnotherThreadEndsAWaitOnIdleStreams) {
  auto a = make_stream("wake_a");
  auto b = make_stream("wake_b");
  ASSERT_TRUE(a && b);
  WatchingSet watching(GetParam());
  ASSERT_TRUE(watching.set.add(a->reader));
  ASSERT_TRUE(watching.set.add(b->reader));
  EXPECT_TRUE(woken_from_another_thread(watching));
  // The set still waits for frames afterwards.
  publish(*b);
  EXPECT_EQ(watching.set.wait(kLongWait), std::optional<std::size_t>(1));
}

TEST_P(WaitSetStrategies, AWakeupEndsTheWaitOfASetWithNoReaders) {
  WatchingSet watching(GetParam());
  EXPECT_TRUE(woken_from_another_thread(watching));
}

// futex_waitv takes at most 128 words, all of them the readers' here: the wakeup is looked at
// between shorter sleeps instead.
TEST_P(WaitSetStrategies, AWakeupEndsTheWaitOfAFullSet) {
  auto s = make_stream("wake_full");
  ASSERT_TRUE(s);
  std::vector<Reader> readers;
  for (std::size_t i = 0; i < WaitSet::kMaxReaders; ++i) {
    auto r = Reader::open(s->guard.name);
    ASSERT_TRUE(r);
    readers.push_back(std::move(*r));
  }
  WatchingSet watching(GetParam());
  for (Reader& r : readers) ASSERT_TRUE(watching.set.add(r));
  EXPECT_TRUE(woken_from_another_thread(watching));
}

TEST_P(WaitSetStrategies, AWakeupComesBeforeAReadyStreamAndOneWaitTakesEveryNotifyBeforeIt) {
  auto s = make_stream("wake_first");
  ASSERT_TRUE(s);
  WatchingSet watching(GetParam());
  Wakeup& wakeup = watching.wakeup;
  WaitSet& set = watching.set;
  ASSERT_TRUE(set.add(s->reader));
  publish(*s);
  wakeup.notify();
  wakeup.notify();
  EXPECT_FALSE(set.wait(kLongWait).has_value());
  EXPECT_TRUE(set.woken());
  // The frame stayed ready, and both notifies were taken by that one wait.
  EXPECT_EQ(set.wait(kLongWait), std::optional<std::size_t>(0));
  EXPECT_FALSE(set.woken());
  std::vector<std::byte> out(4096);
  FrameInfo info;
  ASSERT_EQ(s->reader.read(out, info), ReadStatus::new_frame);
  EXPECT_FALSE(set.wait(0ms).has_value());
  EXPECT_FALSE(set.woken()) << "a timeout is not a wakeup";
}

TEST_P(WaitSetStrategies, APeerProcessReadsTwoStreamsAtDifferentRatesWhole) {
  StreamGuard fast{unique_name("ws_fast")}, slow{unique_name("ws_slow")};
  ASSERT_TRUE(Writer::create({.name = fast.name, .capacity = 16384}));
  ASSERT_TRUE(Writer::create({.name = slow.name, .capacity = 16384}));
  const std::string strategy = GetParam() == WaitSetStrategy::round_robin ? "round_robin" : "futex_waitv";
  Process reader({kPeer, "waitset", fast.name + "," + slow.name, "40", "60000", strategy});
  ASSERT_EQ(reader.next_line().value_or(""), "ready") << reader.err();
  Process w1({kPeer, "writer", fast.name, "60", "300", "1024", "16384", "0"});
  Process w2({kPeer, "writer", slow.name, "40", "100", "1024", "16384", "0"});
  ASSERT_EQ(reader.wait(), 0) << reader.unread() << reader.err();
  const std::string out = reader.unread();
  const auto at0 = out.find("stream=0"), at1 = out.find("stream=1");
  ASSERT_NE(at0, std::string::npos);
  ASSERT_NE(at1, std::string::npos);
  EXPECT_EQ(field(out.substr(at0), "torn"), 0u);
  EXPECT_EQ(field(out.substr(at1), "torn"), 0u);
  EXPECT_GE(field(out.substr(at0), "last"), 40u);
  EXPECT_GE(field(out.substr(at1), "last"), 40u);
  EXPECT_NE(out.find("strategy=" + strategy), std::string::npos) << out;
  EXPECT_EQ(w1.wait(), 0);
  EXPECT_EQ(w2.wait(), 0);
}

INSTANTIATE_TEST_SUITE_P(BothKernels, WaitSetStrategies,
                         ::testing::Values(WaitSetStrategy::futex_waitv, WaitSetStrategy::round_robin),
                         [](const auto& param_info) {
                           return param_info.param == WaitSetStrategy::futex_waitv ? std::string("FutexWaitv")
                                                                             : std::string("RoundRobin");
                         });

// Review M5: the same reader twice counted itself as a sleeper twice per sleep and took itself out
// once, so the stream's sleeper count grew with every sleep and never came back down.
TEST_P(WaitSetStrategies, TheSameReaderTwiceIsRefusedAndSleepsLeaveNoSleeperBehind) {
  auto s = make_stream("ws_dup");
  ASSERT_TRUE(s);
  WaitSet set({.strategy = GetParam()});
  ASSERT_TRUE(set.add(s->reader));
  auto again = set.add(s->reader);
  ASSERT_FALSE(again) << "a reader was added twice";
  EXPECT_NE(again.error().message.find("already in the wait set (index 0)"), std::string::npos)
      << again.error().message;
  EXPECT_EQ(set.size(), 1u);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(set.wait(1ms));
  auto status = inspect(s->guard.name);
  ASSERT_TRUE(status);
  EXPECT_EQ(status->sleeping_readers, 0u);
}

TEST(WaitSet, AutomaticPicksFutexWaitvOnlyWhereTheKernelHasIt) {
  const WaitSet set;
  // Where the kernel lacks futex_waitv the set falls back; either way it is one of the two.
  EXPECT_TRUE(set.strategy() == WaitSetStrategy::futex_waitv ||
              set.strategy() == WaitSetStrategy::round_robin);
  const long rc = syscall(449, nullptr, 0, 0, nullptr, CLOCK_MONOTONIC);
  const bool has = !(rc < 0 && errno == ENOSYS);
  EXPECT_EQ(set.strategy() == WaitSetStrategy::futex_waitv, has);
}

TEST(StreamNotifier, ItsFdBecomesReadableWhenAnyStreamHasANewFrame) {
  auto a = make_stream("fd_a");
  auto b = make_stream("fd_b");
  ASSERT_TRUE(a && b);
  auto notifier = StreamNotifier::open({a->guard.name, b->guard.name});
  ASSERT_TRUE(notifier) << notifier.error().message;
  EXPECT_FALSE(readable(notifier->fd(), 0));
  publish(*b);
  ASSERT_TRUE(readable(notifier->fd(), 30'000));
  EXPECT_EQ(notifier->drain(), (std::vector<bool>{false, true}));
  EXPECT_FALSE(readable(notifier->fd(), 0));  // drained
  // The caller's own reader still has the frame: the notifier never takes it.
  std::vector<std::byte> out(4096);
  FrameInfo info;
  EXPECT_EQ(b->reader.read(out, info), ReadStatus::new_frame);
  publish(*a);
  ASSERT_TRUE(readable(notifier->fd(), 30'000));
  EXPECT_EQ(notifier->drain(), (std::vector<bool>{true, false}));
}

TEST(StreamNotifier, RefusesAMissingStreamWithASentence) {
  auto notifier = StreamNotifier::open({unique_name("missing")});
  ASSERT_FALSE(notifier);
  EXPECT_NE(notifier.error().message.find("no stream"), std::string::npos) << notifier.error().message;
}

TEST(WaitSetCApi, WaitsOnTwoReadersAndTimesOut) {
  auto a = make_stream("c_a");
  auto b = make_stream("c_b");
  ASSERT_TRUE(a && b);
  sim_reader* ra = SIM_readerInit(a->guard.name.c_str(), 0);
  sim_reader* rb = SIM_readerInit(b->guard.name.c_str(), 0);
  ASSERT_NE(ra, nullptr);
  ASSERT_NE(rb, nullptr);
  EXPECT_EQ(SIM_readerSetWaitMode(ra, SIM_WAIT_ADAPTIVE), 0);
  EXPECT_EQ(SIM_readerSetWaitMode(ra, 42), SIM_EINVAL);
  EXPECT_NE(std::strlen(SIM_lastError()), 0u);
  sim_waitset* ws = SIM_waitsetCreate();
  ASSERT_NE(ws, nullptr);
  EXPECT_EQ(SIM_waitsetAdd(ws, ra), 0);
  EXPECT_EQ(SIM_waitsetAdd(ws, rb), 1);
  EXPECT_EQ(SIM_waitsetAdd(ws, nullptr), SIM_EINVAL);
  EXPECT_EQ(SIM_waitsetWait(ws, 0), SIM_ETIMEDOUT);
  publish(*b);
  EXPECT_EQ(SIM_waitsetWait(ws, 30'000), 1);
  EXPECT_EQ(SIM_waitsetReady(ws, 1), 1);
  EXPECT_EQ(SIM_waitsetReady(ws, 0), 0);
  char buf[4096];
  sim_frame_info info{};
  EXPECT_EQ(SIM_readData(rb, buf, sizeof buf, &info), 128);
  // A wake from another thread ends a long wait early, and says so (a wake that did not work
  // would end it by the timeout, SIM_ETIMEDOUT, instead of hanging the test).
  std::thread other([ws] {
    std::this_thread::sleep_for(20ms);  // lets the set fall asleep (not checked)
    EXPECT_EQ(SIM_waitsetWake(ws), 0);
  });
  EXPECT_EQ(SIM_waitsetWait(ws, 120'000), SIM_EWOKEN);
  other.join();
  EXPECT_EQ(SIM_waitsetWait(ws, 0), SIM_ETIMEDOUT);  // the wake was taken
  EXPECT_EQ(SIM_waitsetWake(ws), 0);
  EXPECT_EQ(SIM_waitsetWait(ws, 0), SIM_EWOKEN);  // even a wait that would not sleep says so
  EXPECT_EQ(SIM_waitsetWake(nullptr), SIM_EINVAL);
  SIM_waitsetClose(ws);

  const char* names[] = {a->guard.name.c_str(), b->guard.name.c_str()};
  sim_notifier* n = SIM_notifierOpen(names, 2);
  ASSERT_NE(n, nullptr) << SIM_lastError();
  publish(*a);
  // Like a new reader, the notifier counts the frame b already had when it opened as new. Its
  // thread may count the two streams in either order, and the fd turns readable at the first:
  // drain until both have been reported (each drain resets the fd).
  int reported[2] = {0, 0};
  for (int drains = 0; drains < 2 && !(reported[0] && reported[1]); ++drains) {
    ASSERT_TRUE(readable(SIM_notifierFd(n), 30'000));
    int arrived[2] = {-1, -1};
    const int streams = SIM_notifierDrain(n, arrived, 2);
    EXPECT_EQ(streams, arrived[0] + arrived[1]);
    for (int i = 0; i < 2; ++i) reported[i] += arrived[i];
  }
  EXPECT_EQ(reported[0], 1);
  EXPECT_EQ(reported[1], 1);
  SIM_notifierClose(n);
  EXPECT_EQ(SIM_notifierOpen(nullptr, 0), nullptr);
  SIM_readerClose(ra);
  SIM_readerClose(rb);
}

// --- pairing ------------------------------------------------------------------------------------

namespace {
constexpr std::int64_t kMs = 1'000'000;
}

TEST(ApproximatePairer, PairsTheFreshestFramesWithinTheTolerance) {
  ApproximatePairer<int, int> pairer(10ms);
  pairer.add_first(100 * kMs, 1);
  pairer.add_first(133 * kMs, 2);
  pairer.add_first(166 * kMs, 3);
  pairer.add_second(105 * kMs, 10);
  pairer.add_second(160 * kMs, 11);
  const auto pair = pairer.take();
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->first, 3);  // 166 with 160: fresher than 100 with 105
  EXPECT_EQ(pair->second, 11);
  EXPECT_FALSE(pairer.take());  // each frame is used once, older ones are dropped
}

TEST(ApproximatePairer, PrefersTheCloserPartnerAmongEquallyFreshPairs) {
  ApproximatePairer<int, int> pairer(20ms);
  pairer.add_second(200 * kMs, 10);
  pairer.add_first(205 * kMs, 1);
  pairer.add_first(215 * kMs, 2);
  const auto pair = pairer.take();
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->first, 1);
  EXPECT_EQ(pair->second, 10);
}

TEST(ApproximatePairer, GivesNothingWhenNoStampsAreCloseEnough) {
  ApproximatePairer<int, int> pairer(5ms);
  pairer.add_first(100 * kMs, 1);
  pairer.add_second(120 * kMs, 10);
  EXPECT_FALSE(pairer.take());
  pairer.add_first(118 * kMs, 2);
  ASSERT_TRUE(pairer.take());
}

TEST(ApproximatePairer, PairsA30HzCameraWithA10HzLidarThroughRealStreams) {
  // The writers are driven explicitly with sensor stamps: camera every 33.3 ms, LiDAR every
  // 100 ms offset by 4 ms. Every LiDAR scan has a camera frame within 17 ms.
  auto camera = make_stream("cam");
  auto lidar = make_stream("lidar");
  ASSERT_TRUE(camera && lidar);
  WaitSet set;
  auto added_camera = set.add(camera->reader);
  auto added_lidar = set.add(lidar->reader);
  ASSERT_TRUE(added_camera && added_lidar);
  const std::size_t cam_index = *added_camera;
  const std::size_t lidar_index = *added_lidar;
  ApproximatePairer<std::uint64_t, std::uint64_t> pairer(17ms);
  const std::int64_t t0 = 1'700'000'000'000'000'000;
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  std::vector<std::byte> out(4096);
  for (std::int64_t k = 0; k < 90; ++k) {  // 3 s of sensor time
    const std::int64_t cam_stamp = t0 + k * 33'333'333;
    publish(*camera, cam_stamp);
    if (k % 3 == 0) publish(*lidar, t0 + (k / 3) * 100 * kMs + 4 * kMs);
    while (auto ready = set.wait(0ms)) {
      FrameInfo info;
      Reader& r = *ready == cam_index ? camera->reader : lidar->reader;
      ASSERT_EQ(r.read(out, info), ReadStatus::new_frame);
      if (*ready == cam_index) pairer.add_first(info.stamp_ns, info.seq);
      if (*ready == lidar_index) pairer.add_second(info.stamp_ns, info.seq);
    }
    while (auto pair = pairer.take()) pairs.emplace_back(pair->first_stamp_ns, pair->second_stamp_ns);
  }
  ASSERT_EQ(pairs.size(), 30u);  // one per LiDAR scan
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_LE(std::abs(pairs[i].first - pairs[i].second), 17 * kMs);
    if (i > 0) {
      EXPECT_GT(pairs[i].first, pairs[i - 1].first);  // never reuses a frame
    }
    // The camera frame taken with scan i at the same moment (k = 3i), 4 ms before the scan.
    EXPECT_EQ(pairs[i].first, t0 + static_cast<std::int64_t>(i) * 3 * 33'333'333);
  }
}
