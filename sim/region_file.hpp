// SPDX-License-Identifier: Apache-2.0
// One region file and its mapping: how writers create or take over a region and how readers
// open one without trusting it.
#pragma once

#include <sys/stat.h>
#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "region.hpp"
#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace sim::detail {

class RegionFile {
 public:
  RegionFile() = default;
  RegionFile(RegionFile&& other) noexcept { *this = std::move(other); }
  RegionFile& operator=(RegionFile&& other) noexcept;
  RegionFile(const RegionFile&) = delete;
  RegionFile& operator=(const RegionFile&) = delete;
  ~RegionFile();

  // For a reader: maps the file read-only, plus the wait page writable when the file allows it.
  // Refuses a region whose owner `trust` does not accept. Validates the header; the returned
  // identity is a private copy the reader can trust.
  static Expected<RegionFile> open_for_reading(std::string_view name, const Trust& trust);
  // For a writer: an existing region, opened read-write and not yet validated.
  // Returns not_found when no region has that name.
  static Expected<RegionFile> open_for_writing(std::string_view name);
  // For a writer: a new unnamed region file of `file_size` bytes, memory reserved, mapped
  // read-write. publish_as() gives it its name once the header is complete.
  static Expected<RegionFile> create_unnamed(std::uint64_t file_size, std::uint32_t mode);
  // Links the unnamed file under the stream's name: fails with writer_exists when the name is
  // taken, unless `replace`, in which case an existing region is atomically replaced.
  Expected<void> publish_as(std::string_view name, bool replace);
  // Maps a region opened with open_for_writing read-write (after its header was validated).
  Expected<void> map_read_write();
  // Takes the identity from the mapped header again (after the writer has initialised it).
  void reload_identity() noexcept;

  int fd() const noexcept { return fd_; }
  std::uint64_t file_size() const noexcept { return file_size_; }
  ino_t inode() const noexcept { return inode_; }
  nlink_t link_count() const noexcept { return link_count_; }  // names of the file when opened
  uid_t owner_uid() const noexcept { return owner_uid_; }
  gid_t owner_gid() const noexcept { return owner_gid_; }
  mode_t mode() const noexcept { return mode_; }
  bool wait_page_writable() const noexcept { return wait_page_ != nullptr; }
  // Null until the file is mapped.
  RegionHeader* header() const noexcept {
    if (base_ == nullptr) return nullptr;
    return reinterpret_cast<RegionHeader*>(static_cast<char*>(base_) + kHeaderOffset);
  }
  WaitPage* wait_page() const noexcept { return wait_page_; }
  std::byte* base() const noexcept { return static_cast<std::byte*>(base_); }
  const Identity& identity() const noexcept { return identity_; }  // private, validated copy

  // Reads the identity out of the file with pread (for a writer deciding whether to reuse a
  // region before mapping it). False when the file is too small to hold one.
  bool read_identity(Identity& out) const;

 private:
  void reset() noexcept;
  void take_stat(const struct stat& st) noexcept;
  int fd_ = -1;
  void* base_ = nullptr;
  std::uint64_t file_size_ = 0;
  ino_t inode_ = 0;
  nlink_t link_count_ = 0;
  uid_t owner_uid_ = 0;
  gid_t owner_gid_ = 0;
  mode_t mode_ = 0;
  WaitPage* wait_page_ = nullptr;  // separate writable mapping of page 0 (readers), or in base_
  bool wait_page_separate_ = false;
  Identity identity_{};
};

// Whether the file at the stream's name is the same file as `inode` (for readers noticing that a
// writer replaced the region). False when the name is gone.
bool name_refers_to(std::string_view name, ino_t inode) noexcept;

}  // namespace sim::detail
