// SPDX-License-Identifier: Apache-2.0
// Regions that are corrupt or hostile: readers must refuse them with a sentence, never crash
// or read out of bounds (this suite runs under AddressSanitizer in CI).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <random>
#include <vector>

#include "../../sim/region.hpp"
#include "sim/sim.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using sim::detail::Identity;
using sim::detail::RegionHeader;
using test::StreamGuard;
using test::unique_name;

namespace {

std::string path_of(const std::string& name) { return "/dev/shm/sim." + name.substr(1); }

// A real region left behind by a writer, with one frame in it.
void make_region(const std::string& name, std::uint64_t capacity = 4096) {
  auto w = Writer::create({.name = name, .capacity = capacity});
  ASSERT_TRUE(w);
  std::vector<std::byte> frame(capacity / 2, std::byte{1});
  EXPECT_EQ(w->write(std::span<const std::byte>(frame), 0), WriteStatus::ok);
}

template <typename T>
void poke(const std::string& name, std::size_t offset, T value) {
  const int fd = open(path_of(name).c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(pwrite(fd, &value, sizeof(value), static_cast<off_t>(offset)),
            static_cast<ssize_t>(sizeof(value)));
  close(fd);
}

constexpr std::size_t kHeader = detail::kHeaderOffset;
constexpr std::size_t identity_field(std::size_t offset_in_identity) { return kHeader + offset_in_identity; }

void expect_refused(const std::string& name, const std::string& words) {
  auto r = Reader::open(name);
  ASSERT_FALSE(r) << "a corrupt region was accepted";
  EXPECT_EQ(r.error().code, ErrorCode::region_invalid);
  EXPECT_NE(r.error().message.find(words), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("sim_rm"), std::string::npos) << r.error().message;
}

}  // namespace

TEST(Hostile, BadMagicIsRefused) {
  StreamGuard g{unique_name("magic")};
  make_region(g.name);
  poke<std::uint64_t>(g.name, identity_field(offsetof(Identity, magic)), 0xdeadbeef);
  expect_refused(g.name, "magic");
}

TEST(Hostile, OtherVersionIsRefused) {
  StreamGuard g{unique_name("version")};
  make_region(g.name);
  poke<std::uint32_t>(g.name, identity_field(offsetof(Identity, version)), 99);
  expect_refused(g.name, "version");
}

TEST(Hostile, CapacityLargerThanTheFileIsRefused) {
  StreamGuard g{unique_name("capacity")};
  make_region(g.name);
  poke<std::uint64_t>(g.name, identity_field(offsetof(Identity, capacity)), 1ull << 30);
  expect_refused(g.name, "capacity");
}

TEST(Hostile, SlotOffsetOutOfPlaceIsRefused) {
  StreamGuard g{unique_name("offset")};
  make_region(g.name);
  poke<std::uint64_t>(g.name, identity_field(offsetof(Identity, slot_offset) + 8), 1ull << 40);
  expect_refused(g.name, "offsets");
}

TEST(Hostile, ImpossibleLayoutIsRefused) {
  StreamGuard g{unique_name("layout")};
  make_region(g.name);
  poke<std::uint32_t>(g.name, identity_field(offsetof(Identity, layout)), 7);  // no such kind
  expect_refused(g.name, "layout");
}

TEST(Hostile, TruncatedFileIsRefused) {
  StreamGuard g{unique_name("truncated")};
  make_region(g.name);
  ASSERT_EQ(truncate(path_of(g.name).c_str(), 4096 + 100), 0);
  expect_refused(g.name, "too small");
  ASSERT_EQ(truncate(path_of(g.name).c_str(), 3 * 4096), 0);  // header whole, slots cut off
  expect_refused(g.name, "file size");
}

TEST(Hostile, EmptyAndRandomFilesAreRefused) {
  StreamGuard g{unique_name("random")};
  {
    const int fd = open(path_of(g.name).c_str(), O_CREAT | O_RDWR | O_EXCL, 0600);
    ASSERT_GE(fd, 0);
    close(fd);
  }
  expect_refused(g.name, "too small");
  std::mt19937_64 rng(42);
  for (int round = 0; round < 20; ++round) {
    std::vector<std::uint64_t> junk(3 * 4096 / 8);
    for (auto& word : junk) word = rng();
    if (round % 2 == 0) junk[4096 / 8] = detail::kMagic;  // get past the first check
    const int fd = open(path_of(g.name).c_str(), O_RDWR | O_TRUNC);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(write(fd, junk.data(), junk.size() * 8), static_cast<ssize_t>(junk.size() * 8));
    close(fd);
    EXPECT_FALSE(Reader::open(g.name));
  }
}

TEST(Hostile, PublishedLengthBeyondCapacityIsAnErrorNotARead) {
  StreamGuard g{unique_name("length")};
  make_region(g.name);
  auto r = Reader::open(g.name);
  ASSERT_TRUE(r);
  // Frame 1 sits in slot 1; claim it is a terabyte long.
  poke<std::uint64_t>(g.name, kHeader + offsetof(RegionHeader, slots) + sizeof(detail::SlotMeta) +
                                  offsetof(detail::SlotMeta, size),
                      1ull << 40);
  std::vector<std::byte> buf(4096);
  FrameInfo info;
  EXPECT_EQ(r->read(buf, info), ReadStatus::region_invalid);
  EXPECT_EQ(r->borrow().status(), ReadStatus::region_invalid);
}

TEST(Hostile, ASequenceNumberPointingAtAnEmptySlotDeliversNothing) {
  StreamGuard g{unique_name("slotseq")};
  make_region(g.name);
  auto r = Reader::open(g.name);
  ASSERT_TRUE(r);
  // The newest frame claims to be number 1000, which neither slot holds.
  poke<std::uint64_t>(g.name, kHeader + offsetof(RegionHeader, publication), 1000);
  std::vector<std::byte> buf(4096);
  FrameInfo info;
  EXPECT_NE(r->read(buf, info), ReadStatus::new_frame);
  EXPECT_NE(r->borrow().status(), ReadStatus::new_frame);
}

TEST(Hostile, AWriterReplacesACorruptRegion) {
  StreamGuard g{unique_name("rewrite")};
  make_region(g.name);
  poke<std::uint64_t>(g.name, identity_field(offsetof(Identity, magic)), 0);
  auto w = Writer::create({.name = g.name, .capacity = 4096});
  ASSERT_TRUE(w) << w.error().message;
  EXPECT_TRUE(Reader::open(g.name));
}

namespace {

// Writes `text` NUL-padded into the `size` bytes of the region at `offset` (a name field).
void poke_text(const std::string& name, std::size_t offset, std::size_t size, const std::string& text) {
  std::vector<char> bytes(size, '\0');
  std::memcpy(bytes.data(), text.data(), std::min(size, text.size()));
  const int fd = open(path_of(name).c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(pwrite(fd, bytes.data(), size, static_cast<off_t>(offset)), static_cast<ssize_t>(size));
  close(fd);
}

}  // namespace

// The whole program name lives in the header's old padding: regions of older writers (zero
// there) and names an earlier writer left behind must show the kernel's 15 characters instead.
TEST(Hostile, AStoredProgramNameIsShownOnlyWhereItContinuesTheProcessName) {
  StreamGuard g{unique_name("program")};
  make_region(g.name);
  const std::size_t command =
      kHeader + offsetof(RegionHeader, writer) + offsetof(detail::WriterIdentity, command);
  const std::size_t program = kHeader + offsetof(RegionHeader, program);
  auto shown = [&] {
    auto status = inspect(g.name);
    return status ? status->writer_command : status.error().message;
  };
  poke_text(g.name, command, 16, "sim_replay_vide");
  poke_text(g.name, program, detail::kProgramField, "");  // a writer that predates the field
  EXPECT_EQ(shown(), "sim_replay_vide");
  poke_text(g.name, program, detail::kProgramField, "sim_replay_video");
  EXPECT_EQ(shown(), "sim_replay_video");
  poke_text(g.name, program, detail::kProgramField, "sim_dds_bridge_node");  // an earlier writer's
  EXPECT_EQ(shown(), "sim_replay_vide");
  poke_text(g.name, program, detail::kProgramField, "sim_replay_vide" + std::string(241, 'o'));
  EXPECT_EQ(shown(), "sim_replay_vide");  // not NUL-terminated
  poke_text(g.name, program, detail::kProgramField, "sim_replay_video\x1b]0;x");
  EXPECT_EQ(shown(), "sim_replay_video?]0;x");
  poke_text(g.name, command, 16, "sim_replay");  // not cut by the kernel: nothing more to say
  EXPECT_EQ(shown(), "sim_replay");
}
