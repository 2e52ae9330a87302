// SPDX-License-Identifier: Apache-2.0
#include "region.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
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

namespace {

constexpr std::size_t kCommandBytes = 16;  // TASK_COMM_LEN: 15 characters and a NUL
constexpr std::size_t kCutCommand = kCommandBytes - 1;

// The start of a small /proc file of this process (empty if it cannot be read).
std::string read_own_proc(const char* path) {
  char text[kProgramField * 2];
  const int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {};
  const ssize_t n = read(fd, text, sizeof text);
  close(fd);
  return n > 0 ? std::string(text, static_cast<std::size_t>(n)) : std::string();
}

std::string base_name(std::string_view path) {
  const std::size_t slash = path.rfind('/');
  return std::string(slash == std::string_view::npos ? path : path.substr(slash + 1));
}

// The program name the kernel cut to 15 characters in `comm`: the base name of argv[0] (a
// symlink's own name, as the kernel took it), else of the executable, whichever continues
// `comm`. Empty when neither does (a process that renamed itself keeps the name it chose).
std::string whole_program_name(std::string_view comm) {
  const std::string cmdline = read_own_proc("/proc/self/cmdline");
  char exe[4096];
  const ssize_t exe_size = readlink("/proc/self/exe", exe, sizeof exe);
  std::string executable = exe_size > 0 ? std::string(exe, static_cast<std::size_t>(exe_size)) : "";
  if (executable.ends_with(" (deleted)")) executable.resize(executable.size() - 10);  // rebuilt
  for (const std::string& candidate :
       {base_name(cmdline.substr(0, cmdline.find('\0'))), base_name(executable)}) {
    if (candidate.size() > comm.size() && candidate.size() < kProgramField &&
        candidate.starts_with(comm)) {
      return candidate;
    }
  }
  return {};
}

template <std::size_t Words>
void store_text(std::atomic<std::uint64_t> (&out)[Words], std::string_view text) noexcept {
  char bytes[Words * 8] = {};
  std::memcpy(bytes, text.data(), std::min(text.size(), sizeof bytes - 1));
  for (std::size_t i = 0; i < Words; ++i) {
    std::uint64_t word;
    std::memcpy(&word, bytes + 8 * i, 8);
    out[i].store(word, std::memory_order_relaxed);
  }
}

// The text up to its first NUL; `terminated` says whether there was one.
template <std::size_t Words>
std::string load_text(const std::atomic<std::uint64_t> (&in)[Words], bool* terminated = nullptr) {
  char bytes[Words * 8 + 1] = {};
  for (std::size_t i = 0; i < Words; ++i) {
    const std::uint64_t word = in[i].load(std::memory_order_relaxed);
    std::memcpy(bytes + 8 * i, &word, 8);
  }
  const std::size_t length = std::strlen(bytes);
  if (terminated != nullptr) *terminated = length < Words * 8;
  return std::string(bytes, length);
}

std::string shown(std::string text) {
  for (char& c : text) {
    if (c < 32 || c >= 127) c = '?';
  }
  return text;
}

}  // namespace

void store_writer_names(WriterIdentity& writer, ProgramName& program) {
  std::string comm = read_own_proc("/proc/self/comm");
  comm = comm.substr(0, std::min(comm.find('\n'), kCutCommand));
  store_text(writer.command, comm);
  // Only a cut name has more to say; anything else clears what an earlier writer left.
  store_text(program.words, comm.size() == kCutCommand ? whole_program_name(comm) : std::string());
}

std::string writer_name(const WriterIdentity& writer, const ProgramName& program) {
  const std::string command = load_text(writer.command);
  bool terminated = false;
  const std::string whole = load_text(program.words, &terminated);
  const bool continues = command.size() == kCutCommand && terminated &&
                         whole.size() > command.size() && whole.starts_with(command);
  return shown(continues ? whole : command);
}

Error errno_error(ErrorCode code, std::string what, int err) {
  return {code, std::move(what) + " (" + std::strerror(err) + ")"};
}

}  // namespace sim::detail
