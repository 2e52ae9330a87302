// SPDX-License-Identifier: Apache-2.0
// Regression tests for the defects an adversarial review of the core found (issue 11). Each test
// fails on the code before the fix. Where a defect needs another process or another user, the
// test makes one: sim_test_peer, or a forked child that drops to the user "nobody".
#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "../../sim/period_estimate.hpp"
#include "../../sim/region.hpp"
#include "sim/sim.h"
#include "sim/sim.hpp"
#include "sim_test/process.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using namespace std::chrono_literals;
using sim::testing::Process;
using test::StreamGuard;
using test::unique_name;

namespace {

const std::string kPeer = SIM_TEST_PEER;
constexpr std::uint32_t kNobody = 65534;

std::string path_of(const std::string& name) { return "/dev/shm/sim." + name.substr(1); }

std::span<const std::byte> bytes_of(const char* text) {
  return {reinterpret_cast<const std::byte*>(text), std::strlen(text)};
}

Writer make_writer(const std::string& name, std::uint64_t capacity = 4096,
                   std::uint32_t mode = 0600) {
  auto w = Writer::create({.name = name, .capacity = capacity, .mode = mode});
  EXPECT_TRUE(w) << w.error().message;
  return std::move(*w);
}

// Waits (bounded, never asserting how long it took) until `done` holds.
bool eventually(const std::function<bool()>& done, std::chrono::seconds limit = 20s) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

std::uint32_t sleeping_readers(const std::string& name) {
  auto status = inspect(name);
  return status ? status->sleeping_readers : ~0u;
}

// Runs `body` in a forked child as user nobody (and group `gid`), returning its exit code, or -1
// if it did not finish in time (it is then killed: a hang is a failure, not a stuck suite).
int run_as_nobody(gid_t gid, const std::function<int()>& body) {
  const pid_t child = fork();
  if (child == 0) {
    if (setgroups(0, nullptr) != 0 || setgid(gid) != 0 || setuid(kNobody) != 0) _exit(100);
    _exit(body());
  }
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  int status = 0;
  while (waitpid(child, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(child, SIGKILL);
      waitpid(child, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(5ms);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Whether the kernel lets users hard-link only files they own or may write (fs.protected_hardlinks).
bool hard_links_protected() {
  std::FILE* f = std::fopen("/proc/sys/fs/protected_hardlinks", "r");
  if (f == nullptr) return false;
  int value = 0;
  const bool read = std::fscanf(f, "%d", &value) == 1;
  std::fclose(f);
  return read && value == 1;
}

char process_state(pid_t pid) {
  std::FILE* f = std::fopen(("/proc/" + std::to_string(pid) + "/stat").c_str(), "r");
  if (f == nullptr) return '?';
  char state = '?';
  if (std::fscanf(f, "%*d (%*[^)]) %c", &state) != 1) state = '?';
  std::fclose(f);
  return state;
}

// Ends `sleeper` with `sig` at a moment it provably counts as asleep on `name`: it is stopped
// first, so the count cannot change while it is looked at (between two wait slices a waiting
// reader briefly does not count). A stopped process runs no code of its own before it dies.
void kill_while_asleep(Process& sleeper, const std::string& name, int sig) {
  for (int tries = 0; tries < 1000; ++tries) {
    ASSERT_TRUE(eventually([&] { return sleeping_readers(name) == 1; }));
    sleeper.signal(SIGSTOP);
    ASSERT_TRUE(eventually([&] { return process_state(sleeper.pid()) == 'T'; }));
    if (sleeping_readers(name) == 1) {
      sleeper.signal(sig);
      sleeper.signal(SIGCONT);
      return;
    }
    sleeper.signal(SIGCONT);
  }
  FAIL() << "the reader never stayed asleep";
}

}  // namespace

// Defect 1: a replaced region whose new writer has not published yet carries the old numbering;
// wait() used to report a "new frame" that read() could not find, so waiting readers spun.
TEST(Hardening, WaitAfterAReplacementSleepsUntilTheNewWriterPublishes) {
  StreamGuard g{unique_name("replaced_idle")};
  std::optional<Writer> first = make_writer(g.name, 4096);
  auto opened = Reader::open(g.name);
  ASSERT_TRUE(opened);
  Reader& reader = *opened;
  ASSERT_EQ(first->write(bytes_of("one"), 1), WriteStatus::ok);
  ASSERT_EQ(first->write(bytes_of("two"), 2), WriteStatus::ok);
  std::vector<std::byte> buf(8192);
  FrameInfo info;
  ASSERT_EQ(reader.read(buf, info), ReadStatus::new_frame);
  ASSERT_EQ(first->write(bytes_of("three"), 3), WriteStatus::ok);  // not read by the reader
  first.reset();
  Writer second = make_writer(g.name, 8192);  // another capacity: the region is replaced
  EXPECT_EQ(reader.wait(50ms), ReadStatus::no_new_frame);
  EXPECT_EQ(reader.read(buf, info), ReadStatus::no_new_frame);
  EXPECT_EQ(reader.read_next(buf, info, 20ms), ReadStatus::no_new_frame);
  ASSERT_EQ(second.write(bytes_of("four"), 4), WriteStatus::ok);
  ASSERT_EQ(reader.wait(10s), ReadStatus::new_frame);
  ASSERT_EQ(reader.read(buf, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 4u);
  EXPECT_EQ(info.size, 4u);
}

// Defect 1, as a user meets it: a reader waiting on a replaced region whose new writer never
// publishes sleeps (it gets no frame and is told when that writer dies), it does not spin.
TEST(Hardening, AReaderOfASilentReplacementGetsNoPhantomFrames) {
  StreamGuard g{unique_name("replaced_silent")};
  std::optional<Writer> first = make_writer(g.name, 4096);
  ASSERT_EQ(first->write(bytes_of("a"), 1), WriteStatus::ok);
  auto reader = Reader::open(g.name);
  ASSERT_TRUE(reader);
  ASSERT_EQ(first->write(bytes_of("b"), 2), WriteStatus::ok);
  first.reset();
  std::optional<Writer> silent = make_writer(g.name, 1 << 16);
  int phantom = 0;
  for (int i = 0; i < 20; ++i) {
    if (reader->wait(5ms) == ReadStatus::new_frame) ++phantom;
  }
  EXPECT_EQ(phantom, 0);
  silent.reset();
  EXPECT_EQ(reader->wait(200ms), ReadStatus::writer_gone);
}

// Defect 2: sim_rm --dead racing a writer's (re)start used to unlink the region the new writer
// had just taken over, leaving it publishing into a file no reader could open.
TEST(Hardening, RemovalRacingWriterRestartsNeverOrphansAWriter) {
  StreamGuard g{unique_name("rm_race")};
  const int rounds = std::getenv("SIM_STRESS_FRAMES") != nullptr &&
                             std::stoll(std::getenv("SIM_STRESS_FRAMES")) >= 1'000'000
                         ? 2000
                         : 400;
  Process remover({kPeer, "remove", g.name});
  int orphaned = 0, started = 0;
  for (int i = 0; i < rounds; ++i) {
    auto writer = Writer::create({.name = g.name, .capacity = 4096});
    if (!writer) {
      ADD_FAILURE() << writer.error().message;
      break;
    }
    ++started;
    ASSERT_EQ(writer->write(bytes_of("alive"), i), WriteStatus::ok);
    // While this writer lives, its stream must be reachable by name and be this writer's.
    auto reader = Reader::open(g.name);
    if (!reader || !reader->writer_alive() || reader->status().writer_pid != getpid()) ++orphaned;
  }
  remover.signal(SIGTERM);
  EXPECT_EQ(remover.wait(), 0) << remover.err();
  EXPECT_EQ(started, rounds);
  EXPECT_EQ(orphaned, 0);
  EXPECT_GT(test::field(remover.unread(), "removed"), 0u);  // the two really raced
}

// Defect 3: a FIFO planted under a stream's name made open() block, so every consumer hung.
TEST(Hardening, AFifoAtAStreamPathIsRefusedWithoutBlocking) {
  StreamGuard g{unique_name("fifo")};
  ASSERT_EQ(mkfifo(path_of(g.name).c_str(), 0444), 0);
  const auto consumers = [&] {
    int code = 0;
    auto reader = Reader::open(g.name);
    if (reader || reader.error().message.find("not a regular file") == std::string::npos) code |= 1;
    if (inspect(g.name)) code |= 2;
    if (SIM_readerInit(g.name.c_str(), 0) != nullptr) code |= 4;
    auto trusting = Reader::open(g.name, {.trust = Trust::any_owner()});
    if (trusting) code |= 8;
    return code;
  };
  if (geteuid() == 0) {
    // Root opens a FIFO read-write without blocking; the users who hung were the others.
    ASSERT_EQ(chmod(path_of(g.name).c_str(), 0644), 0);
    EXPECT_EQ(run_as_nobody(kNobody, consumers), 0);
  } else {
    EXPECT_EQ(consumers(), 0);
  }
  EXPECT_TRUE(destroy(g.name));  // sim_rm removes it, without blocking either
  EXPECT_EQ(access(path_of(g.name).c_str(), F_OK), -1);
}

// Defect 4: a group reader accepted any owner, so a squatter's region fed it forged frames.
TEST(Hardening, AReaderTrustsOnlyTheOwnerItNamesAndSaysWhoTheRealOwnerIs) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to hand a region to another user";
  StreamGuard g{unique_name("squat")};
  {
    Writer squatter = make_writer(g.name, 64, 0644);
    ASSERT_EQ(squatter.write(bytes_of("forged"), 0), WriteStatus::ok);
  }
  ASSERT_EQ(chown(path_of(g.name).c_str(), kNobody, kNobody), 0);
  auto refused = Reader::open(g.name, {.trust = Trust::user(0)});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::permission_denied);
  EXPECT_NE(refused.error().message.find("uid 65534"), std::string::npos) << refused.error().message;
  EXPECT_NE(refused.error().message.find("trusts only user root"), std::string::npos)
      << refused.error().message;
  EXPECT_FALSE(Reader::open(g.name));  // the default trusts this user only
  EXPECT_TRUE(Reader::open(g.name, {.trust = Trust::user(kNobody)}));
  EXPECT_TRUE(Reader::open(g.name, {.trust = Trust::group(kNobody)}));
  EXPECT_FALSE(Reader::open(g.name, {.trust = Trust::group(0)}));
  EXPECT_FALSE(Reader::open(g.name, {.trust = {.owner_uid = kNobody, .group_gid = 0}}));

  EXPECT_EQ(SIM_readerInitTrusting(g.name.c_str(), 0, "root", nullptr), nullptr);
  EXPECT_NE(std::string(SIM_lastError()).find("uid 65534"), std::string::npos) << SIM_lastError();
  sim_reader* trusted = SIM_readerInitTrusting(g.name.c_str(), 0, "65534", "");
  EXPECT_NE(trusted, nullptr) << SIM_lastError();
  SIM_readerClose(trusted);
  EXPECT_EQ(SIM_readerInitTrusting(g.name.c_str(), 0, "no-such-user-here", nullptr), nullptr);
  EXPECT_NE(std::string(SIM_lastError()).find("no user named"), std::string::npos);

  // The real writer is refused the name with a sentence that names the squatter.
  auto real = Writer::create({.name = g.name, .capacity = 64});
  ASSERT_FALSE(real);
  EXPECT_NE(real.error().message.find("uid 65534"), std::string::npos) << real.error().message;
}

TEST(Hardening, TrustIsParsedFromNamesAndNumbersWithASentenceForUnknownOnes) {
  auto root = Trust::parse("root", "");
  ASSERT_TRUE(root);
  EXPECT_EQ(root->owner_uid, 0u);
  EXPECT_FALSE(root->group_gid);
  auto numeric = Trust::parse("1234", "5678");
  ASSERT_TRUE(numeric);
  EXPECT_EQ(numeric->owner_uid, 1234u);
  EXPECT_EQ(numeric->group_gid, 5678u);
  EXPECT_NE(numeric->describe().find("uid 1234"), std::string::npos);
  auto unknown = Trust::parse("", "no_such_group_\x01");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("no group named"), std::string::npos);
  EXPECT_EQ(unknown.error().message.find('\x01'), std::string::npos);  // shown escaped
}

// Defect 5: group readers needed a group-writable region, and write access is the power to
// truncate it under the writer (SIGBUS) or hard-link it under another stream's name.
TEST(Hardening, GroupReadersCannotWriteTheRegionYetSleepUntilAFrameComes) {
  EXPECT_EQ(Writer::create({.name = unique_name("x"), .capacity = 64, .mode = 0660}).error().code,
            ErrorCode::invalid_argument);
  EXPECT_EQ(Writer::create({.name = unique_name("x"), .capacity = 64, .mode = 0662}).error().code,
            ErrorCode::invalid_argument);
  if (geteuid() != 0) GTEST_SKIP() << "needs root to read as another user";
  StreamGuard g{unique_name("group")};
  Writer w = make_writer(g.name, 4096, 0640);
  constexpr gid_t kGroup = 4242;
  ASSERT_EQ(chown(path_of(g.name).c_str(), 0, kGroup), 0);
  ASSERT_EQ(w.write(bytes_of("before"), 1), WriteStatus::ok);

  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  std::thread publisher([&] {
    char byte;
    ASSERT_EQ(read(ready[0], &byte, 1), 1);  // the child is about to wait
    std::this_thread::sleep_for(300ms);      // let it sleep a while first
    ASSERT_EQ(w.write(bytes_of("after"), 2), WriteStatus::ok);
  });
  const int code = run_as_nobody(kGroup, [&] {
    const std::string path = path_of(g.name);
    if (open(path.c_str(), O_RDWR) >= 0 || errno != EACCES) return 1;  // no write access at all
    if (truncate(path.c_str(), 0) == 0) return 2;
    if (hard_links_protected() && link(path.c_str(), (path + "_alias").c_str()) == 0) return 3;
    auto reader = Reader::open(g.name, {.trust = Trust::user(0)});
    if (!reader) return 4;
    std::vector<std::byte> buf(4096);
    FrameInfo info;
    if (reader->read(buf, info) != ReadStatus::new_frame || info.seq != 1) return 5;
    rusage before{}, after{};
    getrusage(RUSAGE_SELF, &before);
    if (write(ready[1], "w", 1) != 1) return 6;
    if (reader->read_next(buf, info, 30s) != ReadStatus::new_frame || info.seq != 2) return 7;
    getrusage(RUSAGE_SELF, &after);
    // A reader that polls wakes about every millisecond of the 300 ms; a sleeping one a few
    // times (the writer's wake-up, and its own 100 ms slices).
    if (after.ru_nvcsw - before.ru_nvcsw > 60) return 8;
    return 0;
  });
  publisher.join();
  close(ready[0]);
  close(ready[1]);
  EXPECT_EQ(code, 0);
}

TEST(Hardening, AHardLinkedRegionIsRefusedAndReplacedAtTakeover) {
  StreamGuard real{unique_name("linked")};
  StreamGuard alias{unique_name("alias")};
  {
    Writer w = make_writer(real.name, 64);
    ASSERT_EQ(w.write(bytes_of("lidar"), 1), WriteStatus::ok);
  }
  ASSERT_EQ(link(path_of(real.name).c_str(), path_of(alias.name).c_str()), 0);
  auto through_alias = Reader::open(alias.name);
  ASSERT_FALSE(through_alias);
  EXPECT_NE(through_alias.error().message.find("hard link"), std::string::npos)
      << through_alias.error().message;
  struct stat before {};
  ASSERT_EQ(stat(path_of(real.name).c_str(), &before), 0);
  Writer restarted = make_writer(real.name, 64);  // same layout, but linked twice: replaced
  struct stat after {};
  ASSERT_EQ(stat(path_of(real.name).c_str(), &after), 0);
  EXPECT_NE(after.st_ino, before.st_ino);
  EXPECT_EQ(after.st_nlink, 1u);
  EXPECT_EQ(restarted.last_seq(), 1u);  // numbering carries on
  EXPECT_TRUE(Reader::open(real.name));
}

// Defect 6: a Borrow pointed into a mapping its Reader dropped after two replacements.
TEST(Hardening, ABorrowStaysSafeThroughReplacementsAndOutlivesItsReader) {
  StreamGuard g{unique_name("borrow_replaced")};
  std::optional<Writer> w = make_writer(g.name, 64);
  ASSERT_EQ(w->write(bytes_of("kept"), 1), WriteStatus::ok);
  std::optional<Reader> reader = [&] {
    auto opened = Reader::open(g.name);
    EXPECT_TRUE(opened);
    return std::optional<Reader>(std::move(*opened));
  }();
  const Borrow held = reader->borrow();
  ASSERT_EQ(held.status(), ReadStatus::new_frame);
  std::vector<std::byte> buf(1 << 20);
  FrameInfo info;
  for (std::uint64_t capacity : {128u, 256u, 512u}) {
    w.reset();
    w = make_writer(g.name, capacity);
    ASSERT_EQ(w->write(bytes_of("newer"), 2), WriteStatus::ok);
    ASSERT_EQ(reader->read(buf, info), ReadStatus::new_frame);  // moves to the new region
  }
  EXPECT_EQ(reader->stats().reopens, 3u);
  EXPECT_TRUE(held.still_valid());  // nobody writes the region it points into any more
  reader.reset();
  EXPECT_TRUE(held.still_valid());
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(held.bytes().data()), held.bytes().size()),
            "kept");
}

// Defect 7: deadlines overflowed, so "forever" returned at once.
TEST(Hardening, ForeverMeansForeverNotAnOverflowIntoThePast) {
  static_assert(saturating_nanoseconds(std::chrono::hours(100000000)) == kForever);
  static_assert(saturating_nanoseconds(std::chrono::hours(-100000000)) ==
                std::chrono::nanoseconds::min());
  static_assert(saturating_nanoseconds(2s) == 2'000'000'000ns);
  StreamGuard g{unique_name("forever")};
  Writer w = make_writer(g.name, 64);
  auto reader = Reader::open(g.name);
  ASSERT_TRUE(reader);
  for (const auto timeout : {kForever, saturating_nanoseconds(std::chrono::hours(100000000))}) {
    std::thread publisher([&] {
      ASSERT_TRUE(eventually([&] { return sleeping_readers(g.name) == 1; }));
      ASSERT_EQ(w.write(bytes_of("now"), 0), WriteStatus::ok);
    });
    EXPECT_EQ(reader->wait(timeout), ReadStatus::new_frame);
    publisher.join();
    EXPECT_EQ(reader->borrow().status(), ReadStatus::new_frame);
  }
  // The C API: a negative timeout waits for ever.
  sim_reader* r = SIM_readerInit(g.name.c_str(), 0);
  ASSERT_NE(r, nullptr);
  char buf[64];
  ASSERT_GT(SIM_readData(r, buf, sizeof buf, nullptr), 0);  // the newest frame: nothing left unread
  std::thread publisher([&] {
    ASSERT_TRUE(eventually([&] { return sleeping_readers(g.name) == 1; }));
    ASSERT_EQ(w.write(bytes_of("c"), 0), WriteStatus::ok);
  });
  EXPECT_EQ(SIM_waitData(r, -1), 1);
  publisher.join();
  SIM_readerClose(r);
}

// Defect 8: the futex word held the frame number, so a new writer's first publish could write
// the very value the last writer's exit left, and a reader about to sleep slept through it.
TEST(Hardening, TheFutexWordChangesOnEveryPublishAcrossWriterGenerations) {
  StreamGuard g{unique_name("futex_word")};
  const auto word = [&] {
    const int fd = open(path_of(g.name).c_str(), O_RDONLY);
    detail::RegionHeader header{};
    EXPECT_EQ(pread(fd, &header, sizeof header, detail::kHeaderOffset),
              static_cast<ssize_t>(sizeof header));
    close(fd);
    return header.publication.futex_word.load();
  };
  std::uint32_t last = 0;
  for (int generation = 0; generation < 3; ++generation) {
    Writer w = make_writer(g.name, 64);
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t before = word();
      ASSERT_EQ(w.write(bytes_of("f"), 0), WriteStatus::ok);
      EXPECT_NE(word(), before) << "generation " << generation << " frame " << i;
      EXPECT_NE(word(), last);
      last = word();
    }
  }
}

// Defect 9: C could not tell an empty frame from "nothing new".
TEST(Hardening, TheCApiDeliversAnEmptyFrameAndSaysItIsOne) {
  StreamGuard g{unique_name("empty_c")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 64);
  ASSERT_NE(w, nullptr);
  sim_reader* r = SIM_readerInit(g.name.c_str(), 64);
  ASSERT_NE(r, nullptr);
  char buf[64];
  sim_frame_info info{};
  info.seq = 99;
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), 0);
  EXPECT_EQ(info.seq, 0u);  // nothing new
  ASSERT_EQ(SIM_writeData(w, nullptr, 0), 0);
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), 0);
  EXPECT_EQ(info.seq, 1u);  // a frame, with no bytes
  EXPECT_EQ(info.size, 0u);
  EXPECT_EQ(SIM_readData(r, buf, sizeof buf, &info), 0);
  EXPECT_EQ(info.seq, 0u);
  SIM_readerClose(r);
  SIM_writerClose(w);
}

// Defect 10: names with ".tmp" were hidden; control characters reached terminals raw;
// SIM_lastError's pointer died at the next failure; sim_ls's rate counted earlier writers.
TEST(Hardening, StreamsNamedLikeTemporaryFilesAreListed) {
  StreamGuard g{unique_name("calib.tmp1")};
  Writer w = make_writer(g.name, 64);
  const auto names = list_streams();
  EXPECT_NE(std::find(names.begin(), names.end(), g.name), names.end());
}

TEST(Hardening, ControlCharactersInNamesAreShownEscaped) {
  auto opened = Reader::open("/evil\x1b[2J\x07name");
  ASSERT_FALSE(opened);
  EXPECT_EQ(opened.error().message.find('\x1b'), std::string::npos) << opened.error().message;
  EXPECT_NE(opened.error().message.find("\\x1b[2J\\x07"), std::string::npos) << opened.error().message;
  EXPECT_EQ(SIM_readerInit("\x1b]0;title\x07", 0), nullptr);
  EXPECT_EQ(std::string(SIM_lastError()).find('\x1b'), std::string::npos);
}

TEST(Hardening, TheLastErrorPointerStaysValidAcrossCalls) {
  EXPECT_EQ(SIM_readerInit("no-slash", 0), nullptr);
  const char* first = SIM_lastError();
  const std::string first_text = first;
  EXPECT_NE(first_text.find("must start with '/'"), std::string::npos);
  const std::string long_name = "/" + std::string(300, 'n');  // a longer sentence
  EXPECT_EQ(SIM_readerInit(long_name.c_str(), 0), nullptr);
  EXPECT_EQ(SIM_lastError(), first);  // same storage, new text (ASan checks the read)
  EXPECT_NE(std::string(first).find("longer than 200"), std::string::npos);
}

TEST(Hardening, TheRateComesFromTheCurrentWritersOwnRecentFrames) {
  StreamGuard g{unique_name("rate")};
  {
    Writer earlier = make_writer(g.name, 64);
    for (int i = 0; i < 10; ++i) ASSERT_EQ(earlier.write(bytes_of("e"), 0), WriteStatus::ok);
  }
  Writer current = make_writer(g.name, 64);
  auto reader = Reader::open(g.name);
  ASSERT_TRUE(reader);
  std::vector<std::byte> buf(64);
  FrameInfo first, second;
  ASSERT_EQ(current.write(bytes_of("1"), 0), WriteStatus::ok);
  ASSERT_EQ(reader->read(buf, first), ReadStatus::new_frame);
  EXPECT_EQ(reader->status().period_ns, 0);  // one frame is no rate yet
  EXPECT_EQ(reader->status().rate_hz(first.publish_ns), 0.0);
  std::this_thread::sleep_for(2ms);
  ASSERT_EQ(current.write(bytes_of("2"), 0), WriteStatus::ok);
  ASSERT_EQ(reader->read(buf, second), ReadStatus::new_frame);
  const StreamStatus status = reader->status();
  EXPECT_EQ(status.frames_this_writer, 2u);
  EXPECT_EQ(status.frames_published, 12u);
  EXPECT_EQ(status.period_ns, second.publish_ns - first.publish_ns);  // CLOCK_MONOTONIC
  EXPECT_DOUBLE_EQ(status.rate_hz(second.publish_ns), 1e9 / static_cast<double>(status.period_ns));
  EXPECT_EQ(status.rate_hz(second.publish_ns + 4 * status.period_ns), 0.0);  // it stopped
}

TEST(PeriodEstimate, FollowsJitterMissedFramesAndRealRateChanges) {
  detail::PeriodEstimate estimate;
  constexpr std::int64_t kTenHz = 100'000'000;
  for (int i = 0; i < 200; ++i) estimate.add(kTenHz + (i % 2 ? 5'000'000 : -5'000'000));
  EXPECT_LE(std::abs(estimate.period_ns() - (kTenHz)), 2'000'000);
  EXPECT_LE(std::abs(estimate.jitter_ns() - (5'000'000)), 1'500'000);
  estimate.add(3 * kTenHz);  // two frames lost on the way: still a 10 Hz sensor
  EXPECT_LE(std::abs(estimate.period_ns() - (kTenHz)), 2'000'000);
  for (int i = 0; i < 8; ++i) estimate.add(2 * kTenHz);  // now it really runs at 5 Hz
  EXPECT_LE(std::abs(estimate.period_ns() - (2 * kTenHz)), 4'000'000);
  for (int i = 0; i < 100; ++i) estimate.add(kTenHz / 3);  // and then at 30 Hz
  EXPECT_LE(std::abs(estimate.period_ns() - (kTenHz / 3)), 1'000'000);
}

// Defect 11: a reader killed asleep left the sleeper count raised for good, so the writer made
// a FUTEX_WAKE system call on every frame until the stream was removed.
TEST(Hardening, ASleeperKilledAsleepIsTakenOutOfTheCountByTheNextPublish) {
  for (const int sig : {SIGKILL, SIGTERM}) {
    StreamGuard g{unique_name("dead_sleeper")};
    std::optional<Writer> w = make_writer(g.name, 64);
    Process sleeper({kPeer, "reader", g.name, "1000000", "600000", "wait"});
    ASSERT_EQ(sleeper.next_line().value_or(""), "ready");
    kill_while_asleep(sleeper, g.name, sig);
    EXPECT_EQ(sleeper.wait(), 128 + sig);
    EXPECT_EQ(sleeping_readers(g.name), 1u);  // nobody could take it out yet
    ASSERT_EQ(w->write(bytes_of("x"), 0), WriteStatus::ok);
    EXPECT_EQ(sleeping_readers(g.name), 0u) << "signal " << sig;
    // Also after a writer restart: the count stays right and wake-ups still arrive.
    w.reset();
    w = make_writer(g.name, 64);
    auto reader = Reader::open(g.name);
    ASSERT_TRUE(reader);
    ASSERT_EQ(reader->borrow().status(), ReadStatus::new_frame);  // nothing left unread
    std::thread publisher([&] {
      ASSERT_TRUE(eventually([&] { return sleeping_readers(g.name) == 1; }));
      ASSERT_EQ(w->write(bytes_of("y"), 0), WriteStatus::ok);
    });
    EXPECT_EQ(reader->wait(30s), ReadStatus::new_frame);
    publisher.join();
    EXPECT_EQ(sleeping_readers(g.name), 0u);
  }
}

// A later reader that inherits a dead sleeper's slot takes its mark out too, with no writer.
TEST(Hardening, TheNextReaderHealsADeadSleepersSlotWithoutTheWriter) {
  StreamGuard g{unique_name("dead_sleeper_slot")};
  Writer w = make_writer(g.name, 64);
  Process sleeper({kPeer, "reader", g.name, "1000000", "600000", "wait"});
  ASSERT_EQ(sleeper.next_line().value_or(""), "ready");
  kill_while_asleep(sleeper, g.name, SIGKILL);
  EXPECT_EQ(sleeper.wait(), 128 + SIGKILL);
  // Every slot gets claimed in turn by new readers; the one that lands on the dead reader's slot
  // removes its mark.
  std::vector<Reader> readers;
  for (std::size_t i = 0; i < detail::kReaderSlots && sleeping_readers(g.name) != 0; ++i) {
    auto r = Reader::open(g.name);
    ASSERT_TRUE(r);
    readers.push_back(std::move(*r));
  }
  EXPECT_EQ(sleeping_readers(g.name), 0u);
}

// The flaky "killed mid-copy" test never proved its kills landed mid-copy. This one does: the
// victim's copy runs into a guard page and reports from inside the copy before it is killed.
TEST(Hardening, AReaderKilledInsideItsCopyOrHoldingABorrowAffectsNobody) {
  StreamGuard g{unique_name("killed_inside")};
  Writer w = make_writer(g.name, 64 * 1024);
  std::vector<std::byte> frame(64 * 1024);
  test::fill_frame(frame, 1);
  ASSERT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
  Process in_copy({kPeer, "stall-in-copy", g.name});
  ASSERT_EQ(in_copy.next_line().value_or(""), "ready");
  // Inside Reader::read's copy; if not, what the peer said (a sanitizer report, say) is the why.
  ASSERT_EQ(in_copy.next_line().value_or(""), "mid-copy") << (in_copy.wait(), in_copy.err());
  Process borrower({kPeer, "hold-borrow", g.name});
  ASSERT_EQ(borrower.next_line().value_or("").rfind("holding seq=1", 0), 0u);
  in_copy.signal(SIGKILL);
  borrower.signal(SIGKILL);
  EXPECT_EQ(in_copy.wait(), 128 + SIGKILL);
  EXPECT_EQ(borrower.wait(), 128 + SIGKILL);

  auto survivor = Reader::open(g.name);
  ASSERT_TRUE(survivor);
  std::vector<std::byte> buf(64 * 1024);
  for (std::uint64_t seq = 2; seq <= 50; ++seq) {
    test::fill_frame(frame, seq);
    ASSERT_EQ(w.write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
    FrameInfo info;
    ASSERT_EQ(survivor->read(buf, info), ReadStatus::new_frame);
    EXPECT_EQ(info.seq, seq);
    EXPECT_TRUE(test::check_frame(buf, seq));
  }
  EXPECT_EQ(sleeping_readers(g.name), 0u);
}
