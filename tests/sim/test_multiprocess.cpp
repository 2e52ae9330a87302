// SPDX-License-Identifier: Apache-2.0
// Writers and readers in separate processes (sim_test_peer), including killed ones.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <thread>

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

std::unique_ptr<Process> spawn_writer(const std::string& name, int frames, double rate,
                                      std::size_t min_bytes, std::size_t max_bytes, int linger_ms) {
  auto child = std::make_unique<Process>(std::vector<std::string>{
      kPeer, "writer", name, std::to_string(frames), std::to_string(rate),
      std::to_string(min_bytes), std::to_string(max_bytes), std::to_string(linger_ms)});
  EXPECT_EQ(child->next_line().value_or("").rfind("ready", 0), 0u);
  return child;
}

std::unique_ptr<Process> spawn_reader(const std::string& name, std::uint64_t until,
                                      int timeout_ms, const std::string& mode) {
  auto child = std::make_unique<Process>(std::vector<std::string>{
      kPeer, "reader", name, std::to_string(until), std::to_string(timeout_ms), mode});
  EXPECT_EQ(child->next_line().value_or(""), "ready");
  return child;
}

struct ReaderResult {
  std::uint64_t received, overwritten, torn, disorder, skipped, first, last;
};
ReaderResult finish(Process& reader) {
  EXPECT_EQ(reader.wait(), 0) << reader.err();
  const std::string summary = reader.unread();
  return {field(summary, "received"), field(summary, "overwritten"), field(summary, "torn"),
          field(summary, "disorder"), field(summary, "skipped"), field(summary, "first"), field(summary, "last")};
}

void fan_out(int readers, const std::string& mode) {
  StreamGuard g{unique_name("fanout")};
  constexpr int kFrames = 300;
  {
    // Create the stream first so readers can open it before the peer writer takes it over.
    auto created = Writer::create({.name = g.name, .capacity = 64 * 1024});
    ASSERT_TRUE(created);
  }
  std::vector<std::unique_ptr<Process>> children;
  for (int i = 0; i < readers; ++i) children.push_back(spawn_reader(g.name, kFrames, 60000, mode));
  auto writer = spawn_writer(g.name, kFrames, 200, 4096, 64 * 1024, 3000);
  for (auto& child : children) {
    const ReaderResult r = finish(*child);
    EXPECT_EQ(r.torn, 0u);
    EXPECT_EQ(r.disorder, 0u);
    EXPECT_EQ(r.last, static_cast<std::uint64_t>(kFrames));
    EXPECT_GE(r.received, 1u);
    // Every published frame was delivered, counted as skipped, or (a borrow) overwritten while
    // the reader checked it, which the reader counts itself: nothing is lost unnoticed.
    EXPECT_EQ(r.received + r.overwritten + r.skipped, r.last - r.first + 1);
  }
  EXPECT_EQ(writer->wait(), 0);
}

}  // namespace

TEST(MultiProcess, OneWriterOneReader) { fan_out(1, "wait"); }
TEST(MultiProcess, OneWriterTenBlockingReaders) { fan_out(10, "wait"); }
TEST(MultiProcess, OneWriterTenBorrowingReaders) { fan_out(10, "borrow"); }

TEST(MultiProcess, AKilledWriterIsSeenGoneAndItsSuccessorResumesTheSequence) {
  StreamGuard g{unique_name("killwriter")};
  auto first = spawn_writer(g.name, 1000000, 500, 64, 4096, 0);
  auto reader = spawn_reader(g.name, 1000000000, 60000, "wait");
  std::this_thread::sleep_for(200ms);
  first->signal(SIGKILL);
  EXPECT_EQ(first->wait(), 128 + SIGKILL);

  const std::string gone = reader->next_line().value_or("");
  ASSERT_EQ(gone.rfind("event=writer_gone", 0), 0u) << gone;
  const std::uint64_t seen_before = field(gone, "seq");
  EXPECT_GT(seen_before, 0u);

  auto second = spawn_writer(g.name, 20, 200, 64, 4096, 60000);
  const std::string resumed = reader->next_line().value_or("");
  ASSERT_EQ(resumed.rfind("event=resumed", 0), 0u) << resumed;
  EXPECT_GT(field(resumed, "seq"), seen_before);  // numbers keep rising across the restart
  reader->signal(SIGKILL);
}

// A reader killed provably inside its copy, or while holding a borrow: see
// Hardening.AReaderKilledInsideItsCopyOrHoldingABorrowAffectsNobody (test_hardening.cpp).

TEST(MultiProcess, ASecondWriterProcessIsRefused) {
  StreamGuard g{unique_name("second")};
  Process holder({kPeer, "hold", g.name});
  const std::string ready = holder.next_line().value_or("");
  ASSERT_EQ(ready.rfind("ready", 0), 0u);
  auto refused = Writer::create({.name = g.name, .capacity = 4096});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::writer_exists);
  EXPECT_NE(refused.error().message.find("pid " + std::to_string(holder.pid())), std::string::npos)
      << refused.error().message;
  Process other({kPeer, "hold", g.name});
  EXPECT_NE(other.next_line().value_or("").find("already has a live writer"), std::string::npos);
  EXPECT_EQ(other.wait(), 1);
  holder.signal(SIGKILL);
  holder.wait();
  EXPECT_TRUE(Writer::create({.name = g.name, .capacity = 4096}));  // free once it died
}

// Foxglove review L6: the kernel keeps 15 characters of a process name ("sim_replay_vide"); the
// stream keeps the writer's whole program name for every reader and tool, also once it died.
TEST(MultiProcess, AWriterWhoseProgramNameIsLongerThan15CharactersIsNamedInFullAlsoAfterItDied) {
  StreamGuard g{unique_name("longname")};
  char dir_template[] = "/tmp/sim_test_longname_XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::string dir = dir_template;
  const std::string program = "sim_test_peer_with_a_long_program_name";
  const std::string link = dir + "/" + program;  // the kernel takes the name run, the symlink's
  ASSERT_EQ(::symlink(kPeer.c_str(), link.c_str()), 0);
  {
    Process writer({link, "hold", g.name});
    ASSERT_EQ(writer.next_line().value_or("").rfind("ready", 0), 0u);
    auto live = inspect(g.name);
    ASSERT_TRUE(live) << live.error().message;
    EXPECT_TRUE(live->writer_alive);
    EXPECT_EQ(live->writer_command, program);
    auto refused = Writer::create({.name = g.name, .capacity = 4096});
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find(", " + program + ")"), std::string::npos)
        << refused.error().message;
    writer.signal(SIGKILL);
    EXPECT_EQ(writer.wait(), 128 + SIGKILL);
  }
  ::unlink(link.c_str());
  ::rmdir(dir.c_str());
  auto dead = inspect(g.name);
  ASSERT_TRUE(dead) << dead.error().message;
  EXPECT_FALSE(dead->writer_alive);
  EXPECT_EQ(dead->writer_command, program);
  const auto listed = sim::testing::run({SIM_LS, g.name});
  EXPECT_NE(listed.out.find("gone (was " + program + ")"), std::string::npos) << listed.out;
  const auto json = sim::testing::run({SIM_LS, "--json", g.name});
  EXPECT_NE(json.out.find("\"writer\":\"" + program + "\""), std::string::npos) << json.out;
}
