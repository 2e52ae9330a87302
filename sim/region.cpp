// SPDX-License-Identifier: Apache-2.0
#include "region.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace sim::detail {

LayoutRecord to_record(const Layout& layout) noexcept {
  LayoutRecord r{};
  r.kind = static_cast<std::uint32_t>(layout.kind);
  r.pixel_format = static_cast<std::uint32_t>(layout.image.format);
  r.width = layout.image.width;
  r.height = layout.image.height;
  r.channels = layout.image.channels;
  r.stride = layout.image.stride;
  r.bit_depth = layout.image.bit_depth;
  r.point_type = static_cast<std::uint32_t>(layout.points.type);
  r.point_size = layout.points.point_size;
  r.max_points = layout.points.max_points;
  return r;
}

Layout from_record(const LayoutRecord& r) noexcept {
  Layout layout;
  layout.kind = static_cast<LayoutKind>(r.kind);
  layout.image = {r.width, r.height, r.channels, r.stride, static_cast<PixelFormat>(r.pixel_format),
                  r.bit_depth};
  layout.points = {static_cast<PointType>(r.point_type), r.point_size, r.max_points};
  return layout;
}

std::string name_problem(std::string_view name) {
  if (name.size() < 2 || name.front() != '/') {
    return "stream name \"" + std::string(name) +
           "\" must start with '/' followed by a name, like \"/lidar_top\"";
  }
  const std::string_view rest = name.substr(1);
  if (rest.size() > 200) {
    return "stream name \"" + std::string(name.substr(0, 40)) +
           "...\" is longer than 200 characters; choose a shorter name";
  }
  if (rest == "." || rest == "..") {
    return "stream name \"" + std::string(name) + "\" is reserved; choose another name";
  }
  for (const char c : rest) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) {
      return "stream name \"" + std::string(name) +
             "\" may only contain letters, digits, '_', '-' and '.' after its leading '/'; "
             "rename it, like \"/camera_front\"";
    }
  }
  return {};
}

std::string region_path(std::string_view name) {
  std::string path(kRegionDir);
  path += '/';
  path += kRegionPrefix;
  path += name.substr(1);
  return path;
}

std::string header_problem(const Identity& id, std::uint64_t file_size) {
  if (file_size < kFirstSlotOffset) return "the region file is too small to hold a SIM header";
  if (id.magic != kMagic) return "the region does not start with the SIM magic number";
  if (id.version != kVersion) {
    return "the region has format version " + std::to_string(id.version) + ", this library reads " +
           std::to_string(kVersion);
  }
  if (id.header_size != sizeof(RegionHeader)) return "the region's header size is wrong";
  if (id.capacity == 0 || id.capacity > kMaxCapacity) return "the region's capacity is impossible";
  const Geometry g = geometry_for(id.capacity);
  if (id.file_size != file_size || g.file_size != file_size) {
    return "the region's capacity (" + std::to_string(id.capacity) +
           " bytes per slot) does not fit its file size (" + std::to_string(file_size) + " bytes)";
  }
  if (id.slot_offset[0] != g.slot_offset[0] || id.slot_offset[1] != g.slot_offset[1]) {
    return "the region's slot offsets are out of place";
  }
  if ((id.flags & ~kKnownFlags) != 0) return "the region uses flags this library does not know";
  const std::string layout_problem = from_record(id.layout).check(id.capacity);
  if (!layout_problem.empty()) return "the region's layout is invalid: " + layout_problem;
  return {};
}

namespace {
struct flock writer_lock_range(short type) {
  struct flock fl {};
  fl.l_type = type;
  fl.l_whence = SEEK_SET;
  fl.l_start = 0;
  fl.l_len = 1;
  return fl;
}
}  // namespace

bool try_lock_writer(int fd) noexcept {
  struct flock fl = writer_lock_range(F_WRLCK);
  return fcntl(fd, F_OFD_SETLK, &fl) == 0;
}

void unlock_writer(int fd) noexcept {
  struct flock fl = writer_lock_range(F_UNLCK);
  fcntl(fd, F_OFD_SETLK, &fl);
}

bool writer_lock_held(int fd) noexcept {
  // A read lock conflicts only with the writer's write lock, so the kernel answers "unlocked"
  // exactly when no live process holds the writer lock. Readers never take the lock.
  struct flock fl = writer_lock_range(F_RDLCK);
  if (fcntl(fd, F_OFD_GETLK, &fl) != 0) return false;
  return fl.l_type != F_UNLCK;
}

void pack_command(std::atomic<std::uint64_t> (&out)[2]) noexcept {
  char name[16] = {};
  const int fd = open("/proc/self/comm", O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    const ssize_t n = read(fd, name, sizeof(name) - 1);
    close(fd);
    for (ssize_t i = 0; i < n; ++i) {
      if (name[i] == '\n') name[i] = '\0';
    }
  }
  std::uint64_t words[2];
  std::memcpy(words, name, sizeof(words));
  out[0].store(words[0], std::memory_order_relaxed);
  out[1].store(words[1], std::memory_order_relaxed);
}

std::string unpack_command(const std::atomic<std::uint64_t> (&in)[2]) {
  const std::uint64_t words[2] = {in[0].load(std::memory_order_relaxed),
                                  in[1].load(std::memory_order_relaxed)};
  char name[17] = {};
  std::memcpy(name, words, 16);
  std::string out;
  for (const char c : std::string_view(name)) out += (c >= 32 && c < 127) ? c : '?';
  return out;
}

Error errno_error(ErrorCode code, std::string what, int err) {
  return {code, std::move(what) + " (" + std::strerror(err) + ")"};
}

}  // namespace sim::detail
