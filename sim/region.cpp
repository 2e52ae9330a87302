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

std::string name_problem(std::string_view raw_name) {
  // The name may come from anywhere: it is echoed only with its control bytes escaped.
  const std::string name = printable(raw_name.substr(0, 240));
  if (raw_name.size() < 2 || raw_name.front() != '/') {
    return "stream name \"" + name +
           "\" must start with '/' followed by a name, like \"/lidar_top\"";
  }
  const std::string_view rest = raw_name.substr(1);
  if (rest.size() > 200) {
    return "stream name \"" + name.substr(0, 40) +
           "...\" is longer than 200 characters; choose a shorter name";
  }
  if (rest == "." || rest == "..") {
    return "stream name \"" + name + "\" is reserved; choose another name";
  }
  for (const char c : rest) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) {
      return "stream name \"" + name +
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
struct flock one_byte(short type, off_t byte) {
  struct flock fl {};
  fl.l_type = type;
  fl.l_whence = SEEK_SET;
  fl.l_start = byte;
  fl.l_len = 1;
  return fl;
}
}  // namespace

bool try_lock_byte(int fd, off_t byte, bool exclusive) noexcept {
  struct flock fl = one_byte(exclusive ? F_WRLCK : F_RDLCK, byte);
  return fcntl(fd, F_OFD_SETLK, &fl) == 0;
}

void unlock_byte(int fd, off_t byte) noexcept {
  struct flock fl = one_byte(F_UNLCK, byte);
  fcntl(fd, F_OFD_SETLK, &fl);
}

bool byte_locked(int fd, off_t byte) noexcept {
  // A shared probe conflicts only with exclusive locks, so shared locks that any reader could take
  // cannot fake a holder; no pid is involved, so a reused pid cannot either.
  struct flock fl = one_byte(F_RDLCK, byte);
  if (fcntl(fd, F_OFD_GETLK, &fl) != 0) return false;
  return fl.l_type != F_UNLCK;
}

void wait_until_unlocked(int fd, off_t byte) noexcept {
  struct flock fl = one_byte(F_RDLCK, byte);
  while (fcntl(fd, F_OFD_SETLKW, &fl) != 0 && errno == EINTR) {
  }
  unlock_byte(fd, byte);
}

std::string printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 15];
    }
  }
  return out;
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
