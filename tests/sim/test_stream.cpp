// SPDX-License-Identifier: Apache-2.0
// One writer and its readers in one process: the API contract, error paths and recovery.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>
#include <vector>

#include "sim/sim.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using namespace std::chrono_literals;
using test::StreamGuard;
using test::unique_name;

namespace {

std::vector<std::byte> bytes_of(std::string_view text) {
  const auto* p = reinterpret_cast<const std::byte*>(text.data());
  return {p, p + text.size()};
}

Writer make_writer(const std::string& name, std::uint64_t capacity = 1024, bool checksum = false) {
  auto w = Writer::create({.name = name, .capacity = capacity, .checksum = checksum});
  EXPECT_TRUE(w.has_value()) << (w ? "" : w.error().message);
  return std::move(*w);
}

Reader make_reader(const std::string& name, ReaderOptions options = {}) {
  auto r = Reader::open(name, options);
  EXPECT_TRUE(r.has_value()) << (r ? "" : r.error().message);
  return std::move(*r);
}

}  // namespace

TEST(Names, AcceptsPlainNamesAndRejectsEverythingElse) {
  for (const char* bad : {"", "/", "lidar", "/a/b", "/..", "/.", "/with space", "/ü", "//x"}) {
    auto w = Writer::create({.name = bad, .capacity = 16});
    ASSERT_FALSE(w) << bad;
    EXPECT_EQ(w.error().code, ErrorCode::invalid_name) << bad;
    EXPECT_FALSE(w.error().message.empty());
    auto r = Reader::open(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_EQ(r.error().code, ErrorCode::invalid_name);
  }
  EXPECT_EQ(Writer::create({.name = "/" + std::string(201, 'a'), .capacity = 16}).error().code,
            ErrorCode::invalid_name);
  StreamGuard g{unique_name("Name.ok-1")};
  EXPECT_TRUE(Writer::create({.name = g.name, .capacity = 16}));
}

TEST(Layouts, CapacityFollowsLayoutAndBadLayoutsAreRefused) {
  const auto image = ImageLayout::packed(640, 480, PixelFormat::bgr8);
  EXPECT_EQ(image.stride, 1920u);
  EXPECT_EQ(Layout::of(image).min_capacity(), 921600u);
  EXPECT_EQ(Layout::of(PointLayout::of(PointType::lidar_point, 1000)).min_capacity(), 24000u);
  EXPECT_EQ(Layout::of(PointLayout::of(PointType::xyz32, 10)).min_capacity(), 120u);

  StreamGuard g{unique_name("layout")};
  auto w = Writer::create({.name = g.name, .layout = Layout::of(image)});
  ASSERT_TRUE(w) << w.error().message;
  EXPECT_EQ(w->capacity(), 921600u);
  auto r = Reader::open(g.name);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->layout(), Layout::of(image));
  EXPECT_EQ(r->layout().describe(), "image 640x480 bgr8 stride 1920");

  ImageLayout short_stride = image;
  short_stride.stride = 100;
  EXPECT_EQ(Writer::create({.name = unique_name("bad"), .layout = Layout::of(short_stride)})
                .error()
                .code,
            ErrorCode::invalid_argument);
  EXPECT_EQ(Writer::create({.name = unique_name("bad"), .capacity = 100, .layout = Layout::of(image)})
                .error()
                .code,
            ErrorCode::invalid_argument);
  EXPECT_EQ(Writer::create({.name = unique_name("bad")}).error().code, ErrorCode::invalid_argument);
}

TEST(Stream, DeliversEachNewFrameOnceWithItsMetadata) {
  StreamGuard g{unique_name("roundtrip")};
  Writer w = make_writer(g.name);
  Reader r = make_reader(g.name);
  std::vector<std::byte> buf(1024);
  FrameInfo info;
  EXPECT_EQ(r.read(buf, info), ReadStatus::no_new_frame);

  const auto frame = bytes_of("first frame");
  const std::int64_t before = monotonic_ns();
  ASSERT_EQ(w.write(std::span<const std::byte>(frame), 1234), WriteStatus::ok);
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 1u);
  EXPECT_EQ(info.stamp_ns, 1234);
  EXPECT_EQ(info.receive_ns, 0);  // the writer did not say when the data arrived
  EXPECT_GE(info.publish_ns, before);
  EXPECT_EQ(info.size, frame.size());
  EXPECT_EQ(std::string(reinterpret_cast<char*>(buf.data()), info.size), "first frame");
  EXPECT_EQ(r.read(buf, info), ReadStatus::no_new_frame);  // not twice

  // A reader that falls behind gets the newest frame and counts what it skipped.
  for (int i = 0; i < 5; ++i) {
    // append(), not "x" + std::to_string(i): GCC 12 -O3 -Wrestrict false positive (GCC bug 105651).
    EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of(std::string("x").append(std::to_string(i)))),
                      i, 1000 + i),
              WriteStatus::ok);
  }
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 6u);
  EXPECT_EQ(info.stamp_ns, 4);
  EXPECT_EQ(info.receive_ns, 1004);  // the host time travels with its own frame
  EXPECT_EQ(std::string(reinterpret_cast<char*>(buf.data()), info.size), "x4");
  EXPECT_EQ(r.stats().skipped, 4u);
  EXPECT_EQ(r.stats().frames, 2u);
}

TEST(Stream, FramesLargerThanCapacityOrBufferAreRefusedWithoutLoss) {
  StreamGuard g{unique_name("sizes")};
  Writer w = make_writer(g.name, 64);
  Reader r = make_reader(g.name);
  std::vector<std::byte> big(65);
  EXPECT_EQ(w.write(std::span<const std::byte>(big), 0), WriteStatus::too_large);
  EXPECT_EQ(w.last_seq(), 0u);

  std::vector<std::byte> frame(64, std::byte{7});
  ASSERT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
  std::vector<std::byte> small(10);
  FrameInfo info;
  EXPECT_EQ(r.read(small, info), ReadStatus::buffer_too_small);
  std::vector<std::byte> enough(64);
  ASSERT_EQ(r.read(enough, info), ReadStatus::new_frame);  // the frame was not consumed
  EXPECT_EQ(enough, frame);
}

TEST(Stream, LoanPublishesOnlyOnCommitAndAnOvertakenLoanPublishesNothing) {
  StreamGuard g{unique_name("loan")};
  Writer w = make_writer(g.name, 4096);
  Reader r = make_reader(g.name);
  std::vector<std::byte> buf(4096);
  FrameInfo info;
  {
    Loan dropped = w.loan();
    std::fill(dropped.bytes().begin(), dropped.bytes().end(), std::byte{1});
  }
  EXPECT_EQ(r.read(buf, info), ReadStatus::no_new_frame);

  Loan loan = w.loan();
  ASSERT_EQ(loan.bytes().size(), 4096u);
  auto words = loan.as<std::uint32_t>();
  for (std::size_t i = 0; i < 10; ++i) words[i] = static_cast<std::uint32_t>(i * i);
  EXPECT_EQ(std::move(loan).commit(40, 99, 77), WriteStatus::ok);
  EXPECT_EQ(std::move(loan).commit(40, 99), WriteStatus::closed);  // NOLINT(bugprone-use-after-move): once only
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(info.size, 40u);
  EXPECT_EQ(info.stamp_ns, 99);
  EXPECT_EQ(info.receive_ns, 77);
  std::uint32_t ninth;
  std::memcpy(&ninth, buf.data() + 36, 4);
  EXPECT_EQ(ninth, 81u);

  Loan too_big = w.loan();
  EXPECT_EQ(std::move(too_big).commit(4097, 0), WriteStatus::too_large);
  EXPECT_FALSE(too_big.valid());  // NOLINT(bugprone-use-after-move): a commit ends the loan
  EXPECT_EQ(w.last_seq(), 1u);
}

TEST(Loan, WhileOneIsOpenTheWriterHandsOutNoOtherViewOfTheSlot) {
  StreamGuard g{unique_name("twoloans")};
  Writer w = make_writer(g.name, 64);
  Reader r = make_reader(g.name);
  Loan first = w.loan();
  ASSERT_TRUE(first.valid());
  Loan second = w.loan();
  EXPECT_FALSE(second.valid());
  EXPECT_TRUE(second.bytes().empty());
  // A plain write would publish the slot the loan is still writing into: refused too.
  EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("copy")), 0), WriteStatus::loan_open);
  std::memcpy(first.bytes().data(), "loan", 4);
  EXPECT_EQ(std::move(first).commit(4, 1), WriteStatus::ok);
  EXPECT_EQ(std::move(second).commit(4, 2), WriteStatus::closed);
  EXPECT_EQ(w.last_seq(), 1u);
  std::vector<std::byte> buf(64);
  FrameInfo info;
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(buf.data()), info.size), "loan");
  {
    Loan dropped = w.loan();  // given up uncommitted: the writer is free again
    ASSERT_TRUE(dropped.valid());
  }
  EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("next")), 3), WriteStatus::ok);
  Loan moved_from = w.loan();
  Loan moved_to = std::move(moved_from);
  EXPECT_FALSE(w.loan().valid());  // still open, under its new owner
  EXPECT_EQ(std::move(moved_to).commit(1, 4), WriteStatus::ok);
  EXPECT_EQ(w.last_seq(), 3u);
}

// Committing twice must not compile: commit() takes the loan as an rvalue.
template <typename T>
concept CommitsOnAnLvalue = requires(T& loan) { loan.commit(0, 0); };
static_assert(!CommitsOnAnLvalue<Loan>);

TEST(Stream, BorrowIsValidUntilTheWriterReusesTheSlot) {
  StreamGuard g{unique_name("borrow")};
  Writer w = make_writer(g.name, 64);
  Reader r = make_reader(g.name);
  EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("one")), 1), WriteStatus::ok);
  const Borrow b = r.borrow();
  ASSERT_EQ(b.status(), ReadStatus::new_frame);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.bytes().data()), b.bytes().size()), "one");
  EXPECT_TRUE(b.still_valid());
  EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("two")), 2), WriteStatus::ok);  // the other slot
  EXPECT_TRUE(b.still_valid());
  EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("three")), 3), WriteStatus::ok);  // reuses the borrowed slot
  EXPECT_FALSE(b.still_valid());
  EXPECT_EQ(r.borrow().info().seq, 3u);
  EXPECT_EQ(r.borrow().status(), ReadStatus::no_new_frame);
}

TEST(Stream, ChecksumMismatchIsReportedAndTheFrameNotDelivered) {
  StreamGuard g{unique_name("checksum")};
  Writer w = make_writer(g.name, 4096, /*checksum=*/true);
  Reader r = make_reader(g.name);
  EXPECT_TRUE(r.checksum());
  std::vector<std::byte> frame(4096, std::byte{0x5a});
  EXPECT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
  std::vector<std::byte> buf(4096);
  FrameInfo info;
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);

  // Corrupt the payload of the next frame behind the writer's back, as a stray write would.
  EXPECT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
  {
    std::fstream region("/dev/shm/sim." + g.name.substr(1),
                        std::ios::in | std::ios::out | std::ios::binary);
    region.seekp(2 * 4096 + 100);  // frame 2 is in slot 0, after the wait page and the header
    region.put('X');
  }
  EXPECT_EQ(r.read(buf, info), ReadStatus::checksum_mismatch);
  EXPECT_EQ(r.stats().checksum_failures, 1u);
  EXPECT_EQ(r.read(buf, info), ReadStatus::no_new_frame);  // the bad frame is not offered again
  EXPECT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
  EXPECT_EQ(r.read(buf, info), ReadStatus::new_frame);

  // The same corruption through borrow.
  EXPECT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);  // frame 4, slot 0
  {
    std::fstream region("/dev/shm/sim." + g.name.substr(1),
                        std::ios::in | std::ios::out | std::ios::binary);
    region.seekp(2 * 4096 + 7);
    region.put('Y');
  }
  EXPECT_EQ(r.borrow().status(), ReadStatus::checksum_mismatch);
}

TEST(Stream, WaitSleepsUntilAPublishOrTheTimeout) {
  StreamGuard g{unique_name("wait")};
  Writer w = make_writer(g.name);
  Reader r = make_reader(g.name);
  EXPECT_EQ(r.wait(10ms), ReadStatus::no_new_frame);

  std::thread publisher([&] {
    std::this_thread::sleep_for(50ms);
    EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("wake")), 0), WriteStatus::ok);
  });
  EXPECT_EQ(r.wait(30s), ReadStatus::new_frame);
  publisher.join();
  std::vector<std::byte> buf(64);
  FrameInfo info;
  EXPECT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(r.read_next(buf, info, 1ms), ReadStatus::no_new_frame);
}

TEST(Liveness, ReadersSeeTheWriterGoAndAStaleStream) {
  StreamGuard g{unique_name("liveness")};
  std::optional<Writer> w = make_writer(g.name);
  Reader r = make_reader(g.name, {.stale_after = 30ms});
  EXPECT_TRUE(r.writer_alive());
  std::vector<std::byte> buf(64);
  FrameInfo info;
  EXPECT_EQ(w->write(std::span<const std::byte>(bytes_of("a")), 0), WriteStatus::ok);
  EXPECT_EQ(r.read(buf, info), ReadStatus::new_frame);
  std::this_thread::sleep_for(40ms);
  EXPECT_EQ(r.read(buf, info), ReadStatus::stale);
  EXPECT_GE(r.newest_age(), 30ms);

  w.reset();
  EXPECT_FALSE(r.writer_alive());
  std::this_thread::sleep_for(25ms);  // past the reader's liveness cache
  EXPECT_EQ(r.read(buf, info), ReadStatus::writer_gone);
  EXPECT_EQ(r.wait(5ms), ReadStatus::writer_gone);
}

TEST(Liveness, HeartbeatThreadKeepsTheHeartbeatMovingWhileIdle) {
  StreamGuard g{unique_name("heartbeat")};
  auto w = Writer::create({.name = g.name, .capacity = 64, .heartbeat_period = 5ms});
  ASSERT_TRUE(w);
  Reader r = make_reader(g.name);
  const std::int64_t first = r.status().heartbeat_ns;
  std::int64_t later = first;
  for (int i = 0; i < 500 && later == first; ++i) {
    std::this_thread::sleep_for(10ms);
    later = r.status().heartbeat_ns;
  }
  EXPECT_GT(later, first);
  EXPECT_EQ(r.status().latest_publish_ns, 0);
}

TEST(Ownership, ASecondWriterIsRefusedAndATakeoverContinuesTheSequence) {
  StreamGuard g{unique_name("owner")};
  std::optional<Writer> first = make_writer(g.name);
  auto second = Writer::create({.name = g.name, .capacity = 1024});
  ASSERT_FALSE(second);
  EXPECT_EQ(second.error().code, ErrorCode::writer_exists);
  EXPECT_NE(second.error().message.find("pid " + std::to_string(getpid())), std::string::npos)
      << second.error().message;

  Reader r = make_reader(g.name);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(first->write(std::span<const std::byte>(bytes_of("f")), 0), WriteStatus::ok);
  }
  first.reset();
  Writer next = make_writer(g.name);
  EXPECT_EQ(next.last_seq(), 3u);
  EXPECT_EQ(next.write(std::span<const std::byte>(bytes_of("after restart")), 0), WriteStatus::ok);
  std::vector<std::byte> buf(1024);
  FrameInfo info;
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 4u);
  EXPECT_EQ(r.stats().reopens, 0u);  // same region, reused
}

TEST(Recovery, ALayoutChangeReplacesTheRegionAndReadersReopenIt) {
  StreamGuard g{unique_name("relayout")};
  std::optional<Writer> w = make_writer(g.name, 64);
  Reader r = make_reader(g.name);
  EXPECT_EQ(w->write(std::span<const std::byte>(bytes_of("small")), 0), WriteStatus::ok);
  std::vector<std::byte> buf(1 << 20);
  FrameInfo info;
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  w.reset();

  const auto image = Layout::of(ImageLayout::packed(32, 16, PixelFormat::mono8));
  auto bigger = Writer::create({.name = g.name, .layout = image});
  ASSERT_TRUE(bigger) << bigger.error().message;
  EXPECT_EQ(bigger->last_seq(), 1u);  // numbering carries over
  std::vector<std::byte> pixels(512, std::byte{3});
  EXPECT_EQ(bigger->write(std::span<const std::byte>(pixels), 0), WriteStatus::ok);
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 2u);
  EXPECT_EQ(info.layout, image);
  EXPECT_EQ(r.layout(), image);
  EXPECT_EQ(r.capacity(), 512u);
  EXPECT_EQ(r.stats().reopens, 1u);
}

TEST(Recovery, ADestroyedAndRecreatedStreamIsPickedUpByWaitingReaders) {
  StreamGuard g{unique_name("recreate")};
  std::optional<Writer> w = make_writer(g.name, 64);
  Reader r = make_reader(g.name);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(w->write(std::span<const std::byte>(bytes_of("old")), 0), WriteStatus::ok);
  }
  std::vector<std::byte> buf(64);
  FrameInfo info;
  ASSERT_EQ(r.read(buf, info), ReadStatus::new_frame);
  w.reset();
  ASSERT_TRUE(destroy(g.name));
  Writer fresh = make_writer(g.name, 64);
  EXPECT_EQ(fresh.last_seq(), 0u);
  EXPECT_EQ(fresh.write(std::span<const std::byte>(bytes_of("new")), 0), WriteStatus::ok);
  ASSERT_EQ(r.read_next(buf, info, 10s), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 1u);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(buf.data()), info.size), "new");
}

TEST(Diagnostics, StatusReportsWhatTheWriterDid) {
  StreamGuard g{unique_name("status")};
  Writer w = make_writer(g.name, 64, true);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(w.write(std::span<const std::byte>(bytes_of("s")), 0), WriteStatus::ok);
    std::this_thread::sleep_for(2ms);
  }
  auto s = inspect(g.name);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->frames_published, 3u);
  EXPECT_EQ(s->latest_seq, 3u);
  EXPECT_TRUE(s->checksum);
  EXPECT_TRUE(s->writer_alive);
  EXPECT_EQ(s->writer_pid, getpid());
  EXPECT_FALSE(s->writer_command.empty());
  EXPECT_GE(s->max_publish_interval_ns, 2'000'000);
  EXPECT_GT(s->writer_start_realtime_ns, 0);
  const auto names = list_streams();
  EXPECT_NE(std::find(names.begin(), names.end(), g.name), names.end());
}

TEST(Destroy, RefusesALiveWriterUnlessForced) {
  StreamGuard g{unique_name("destroy")};
  std::optional<Writer> w = make_writer(g.name);
  auto refused = destroy(g.name);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::writer_exists);
  w.reset();
  EXPECT_TRUE(destroy(g.name));
  EXPECT_EQ(destroy(g.name).error().code, ErrorCode::not_found);
  Writer again = make_writer(g.name);
  EXPECT_TRUE(destroy(g.name, /*force=*/true));
  EXPECT_EQ(Reader::open(g.name).error().code, ErrorCode::not_found);
}

TEST(Security, RegionsAreOwnerOnlyByDefaultAndGroupModeIsKept) {
  StreamGuard g{unique_name("mode")};
  std::optional<Writer> w = make_writer(g.name);
  struct stat st {};
  ASSERT_EQ(stat(("/dev/shm/sim." + g.name.substr(1)).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  w.reset();
  StreamGuard g2{unique_name("groupmode")};
  auto grouped = Writer::create({.name = g2.name, .capacity = 64, .mode = 0640});
  ASSERT_TRUE(grouped);
  ASSERT_EQ(stat(("/dev/shm/sim." + g2.name.substr(1)).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  EXPECT_EQ(Writer::create({.name = unique_name("x"), .capacity = 64, .mode = 0777}).error().code,
            ErrorCode::invalid_argument);
}

TEST(Security, SymlinksAndOtherUsersRegionsAreRefused) {
  StreamGuard target{unique_name("target")};
  Writer w = make_writer(target.name);
  StreamGuard link{unique_name("link")};
  ASSERT_EQ(symlink(("/dev/shm/sim." + target.name.substr(1)).c_str(),
                    ("/dev/shm/sim." + link.name.substr(1)).c_str()),
            0);
  auto r = Reader::open(link.name);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::permission_denied);
  EXPECT_NE(r.error().message.find("symbolic link"), std::string::npos);
  EXPECT_EQ(Writer::create({.name = link.name, .capacity = 64}).error().code,
            ErrorCode::permission_denied);
  EXPECT_TRUE(destroy(link.name));  // sim_rm can clear it
  EXPECT_TRUE(Reader::open(target.name));       // and the target is untouched

  if (geteuid() == 0) {
    StreamGuard other{unique_name("other")};
    std::optional<Writer> ow = make_writer(other.name);
    ASSERT_EQ(chown(("/dev/shm/sim." + other.name.substr(1)).c_str(), 65534, 65534), 0);
    auto refused = Reader::open(other.name);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::permission_denied);
    EXPECT_TRUE(Reader::open(other.name, {.trust = Trust::user(65534)}));
    ow.reset();
    EXPECT_EQ(Writer::create({.name = other.name, .capacity = 1024}).error().code,
              ErrorCode::permission_denied);
  }
}

// Restores the calling thread's CPU affinity when a test that pins it ends, however it ends, so
// the tests after it in the same process run where the system would have put them.
class AffinityGuard {
 public:
  AffinityGuard() { pthread_getaffinity_np(pthread_self(), sizeof(saved_), &saved_); }
  ~AffinityGuard() { pthread_setaffinity_np(pthread_self(), sizeof(saved_), &saved_); }
  AffinityGuard(const AffinityGuard&) = delete;
  AffinityGuard& operator=(const AffinityGuard&) = delete;

 private:
  cpu_set_t saved_{};
};

TEST(Placement, PinningLockingAndPrioritySayWhyTheyFail) {
  const AffinityGuard restore_affinity;
  cpu_set_t before{};
  ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(before), &before), 0);
  int allowed_cpu = 0;
  while (!CPU_ISSET(allowed_cpu, &before)) ++allowed_cpu;
  EXPECT_TRUE(pin_current_thread(allowed_cpu));
  auto no_cpu = pin_current_thread(100000);
  ASSERT_FALSE(no_cpu);
  EXPECT_EQ(no_cpu.error().code, ErrorCode::invalid_argument);
  auto bad_priority = set_realtime_priority(0);
  ASSERT_FALSE(bad_priority);
  EXPECT_NE(bad_priority.error().message.find("1–99"), std::string::npos);
  // The tools' --cpu/--rt-priority: nothing asked, nothing done; the first failure is reported.
  EXPECT_TRUE(apply_thread_placement({}));
  EXPECT_TRUE(apply_thread_placement({.cpu = allowed_cpu, .rt_priority = std::nullopt}));
  auto placed = apply_thread_placement({.cpu = 100000, .rt_priority = 0});
  ASSERT_FALSE(placed);
  EXPECT_NE(placed.error().message.find("CPU 100000"), std::string::npos) << placed.error().message;
  placed = apply_thread_placement({.cpu = allowed_cpu, .rt_priority = 100});
  ASSERT_FALSE(placed);
  EXPECT_NE(placed.error().message.find("1–99"), std::string::npos) << placed.error().message;

  StreamGuard g{unique_name("mlock")};
  auto locked = Writer::create({.name = g.name, .capacity = 1 << 20, .lock_memory = true});
  if (geteuid() == 0) {
    EXPECT_TRUE(locked) << locked.error().message;
  } else if (!locked) {
    EXPECT_NE(locked.error().message.find("RLIMIT_MEMLOCK"), std::string::npos);
  }
}
