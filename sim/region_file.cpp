// SPDX-License-Identifier: Apache-2.0
#include "region_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>

namespace sim::detail {

RegionFile& RegionFile::operator=(RegionFile&& other) noexcept {
  if (this != &other) {
    reset();
    fd_ = std::exchange(other.fd_, -1);
    base_ = std::exchange(other.base_, nullptr);
    file_size_ = std::exchange(other.file_size_, 0);
    inode_ = std::exchange(other.inode_, 0);
    link_count_ = other.link_count_;
    owner_uid_ = other.owner_uid_;
    owner_gid_ = other.owner_gid_;
    mode_ = other.mode_;
    wait_page_ = std::exchange(other.wait_page_, nullptr);
    wait_page_separate_ = std::exchange(other.wait_page_separate_, false);
    identity_ = other.identity_;
  }
  return *this;
}

RegionFile::~RegionFile() { reset(); }

void RegionFile::reset() noexcept {
  if (wait_page_separate_ && wait_page_ != nullptr) munmap(wait_page_, kPage);
  if (base_ != nullptr) munmap(base_, file_size_);
  if (fd_ >= 0) close(fd_);  // also releases every lock this open file held
  fd_ = -1;
  base_ = nullptr;
  wait_page_ = nullptr;
  wait_page_separate_ = false;
}

void RegionFile::take_stat(const struct stat& st) noexcept {
  inode_ = st.st_ino;
  link_count_ = st.st_nlink;
  owner_uid_ = st.st_uid;
  owner_gid_ = st.st_gid;
  mode_ = st.st_mode & 07777;
  file_size_ = static_cast<std::uint64_t>(st.st_size);
}

namespace {

// Empty when `trust` accepts a region file with this status; otherwise why not, naming the owner.
std::string trust_problem(const Trust& trust, const struct stat& st, const std::string& path,
                          std::string_view name) {
  if (trust.anyone) return {};
  const bool default_trust = !trust.owner_uid && !trust.group_gid;
  const bool owner_ok = default_trust ? st.st_uid == geteuid()
                                      : !trust.owner_uid || st.st_uid == *trust.owner_uid;
  const bool group_ok = !trust.group_gid || (st.st_gid == *trust.group_gid && (st.st_mode & 0040));
  if (owner_ok && group_ok) return {};
  return path + " belongs to user " + user_name(st.st_uid) + " and group " +
         group_name(st.st_gid) + ", but this reader trusts only " + trust.describe() +
         "; if that is the real writer of " + std::string(name) +
         ", trust it (--trust-owner or --trust-group), otherwise remove the impostor's region";
}

// Opens the region by name refusing symlinks, FIFOs and other odd files without ever blocking,
// and checks it is a regular file of someone `trust` accepts. Read-write when allowed; with
// `read_only_fallback`, read-only when only that is allowed.
Expected<int> open_checked(std::string_view name, bool read_only_fallback, const Trust& trust,
                           struct stat& st) {
  if (const std::string problem = name_problem(name); !problem.empty()) {
    return Error{ErrorCode::invalid_name, problem};
  }
  const std::string path = region_path(name);
  // O_NONBLOCK: opening a FIFO someone planted under the name would otherwise wait for its other
  // end forever. It changes nothing for a regular file.
  constexpr int kFlags = O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK;
  int fd = open(path.c_str(), O_RDWR | kFlags);
  if (fd < 0 && (errno == EACCES || errno == ENXIO) && read_only_fallback) {
    fd = open(path.c_str(), O_RDONLY | kFlags);
  }
  if (fd < 0) {
    const int err = errno;
    if (err == ENOENT) {
      return Error{ErrorCode::not_found, "no stream named " + std::string(name) +
                                             " exists; start its writer first"};
    }
    if (err == ELOOP) {
      return Error{ErrorCode::permission_denied,
                   path + " is a symbolic link, which SIM refuses; remove it with sim_rm " +
                       std::string(name)};
    }
    if (err == ENXIO || err == EISDIR) {
      return Error{ErrorCode::permission_denied,
                   path + " is not a regular file; remove it with sim_rm " + std::string(name)};
    }
    if (err == EACCES) {
      return Error{ErrorCode::permission_denied,
                   "no permission to open " + path + "; run as its owner or ask for group access"};
    }
    return errno_error(ErrorCode::system_error, "cannot open " + path, err);
  }
  if (fstat(fd, &st) != 0) {
    const int err = errno;
    close(fd);
    return errno_error(ErrorCode::system_error, "cannot stat " + path, err);
  }
  if (!S_ISREG(st.st_mode)) {
    close(fd);
    return Error{ErrorCode::permission_denied,
                 path + " is not a regular file; remove it with sim_rm " + std::string(name)};
  }
  if (std::string problem = trust_problem(trust, st, path, name); !problem.empty()) {
    close(fd);
    return Error{ErrorCode::permission_denied, std::move(problem)};
  }
  return fd;
}

}  // namespace

Expected<RegionFile> RegionFile::open_for_reading(std::string_view name, const Trust& trust) {
  struct stat st {};
  auto opened = open_checked(name, /*read_only_fallback=*/true, trust, st);
  if (!opened) return opened.error();
  RegionFile file;
  file.fd_ = *opened;
  file.take_stat(st);
  if (file.link_count_ != 1) {
    // SIM's writers give a region exactly one name; a second one is someone's hard link, which
    // would show this stream's frames under another stream's name.
    return Error{ErrorCode::permission_denied,
                 "stream " + std::string(name) +
                     " is a second name (hard link) of another region, which SIM refuses; remove it "
                     "with sim_rm " +
                     std::string(name) + " and restart its writer"};
  }
  if (file.file_size_ < kFirstSlotOffset) {
    return Error{ErrorCode::region_invalid,
                 "stream " + std::string(name) + " is not a valid SIM region (" +
                     std::to_string(file.file_size_) +
                     " bytes is too small for its header); remove it with sim_rm " +
                     std::string(name)};
  }
  void* base = mmap(nullptr, file.file_size_, PROT_READ, MAP_SHARED, file.fd_, 0);
  if (base == MAP_FAILED) {
    return errno_error(ErrorCode::system_error, "cannot map stream " + std::string(name), errno);
  }
  file.base_ = base;
  // Copy the identity once: everything the reader later relies on (capacity, offsets, layout)
  // comes from this private copy, so a writer changing the header afterwards cannot steer reads.
  std::memcpy(&file.identity_, &file.header()->identity, sizeof(Identity));
  if (const std::string problem = header_problem(file.identity_, file.file_size_);
      !problem.empty()) {
    return Error{ErrorCode::region_invalid, "stream " + std::string(name) +
                                                " is not a valid SIM region: " + problem +
                                                "; remove it with sim_rm " + std::string(name)};
  }
  if ((fcntl(file.fd_, F_GETFL) & O_ACCMODE) == O_RDWR) {
    void* wait = mmap(nullptr, kPage, PROT_READ | PROT_WRITE, MAP_SHARED, file.fd_, 0);
    if (wait != MAP_FAILED) {
      file.wait_page_ = static_cast<WaitPage*>(wait);
      file.wait_page_separate_ = true;
    }
  }
  return file;
}

Expected<RegionFile> RegionFile::open_for_writing(std::string_view name) {
  struct stat st {};
  auto opened = open_checked(name, /*read_only_fallback=*/false, Trust{}, st);
  if (!opened) return opened.error();
  RegionFile file;
  file.fd_ = *opened;
  file.take_stat(st);
  return file;
}

bool RegionFile::read_identity(Identity& out) const {
  if (file_size_ < kFirstSlotOffset) return false;
  const ssize_t n = pread(fd_, &out, sizeof(out), static_cast<off_t>(kHeaderOffset));
  return n == static_cast<ssize_t>(sizeof(out));
}

Expected<void> RegionFile::map_read_write() {
  void* base = mmap(nullptr, file_size_, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd_, 0);
  if (base == MAP_FAILED) return errno_error(ErrorCode::system_error, "cannot map region", errno);
  base_ = base;
  wait_page_ = static_cast<WaitPage*>(base);
  reload_identity();
  return {};
}

void RegionFile::reload_identity() noexcept {
  std::memcpy(&identity_, &header()->identity, sizeof(Identity));
}

Expected<RegionFile> RegionFile::create_unnamed(std::uint64_t file_size, std::uint32_t mode) {
  const std::string dir(kRegionDir);
  const int fd = open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, mode & 0777);
  if (fd < 0) return errno_error(ErrorCode::system_error, "cannot create a file in " + dir, errno);
  RegionFile file;
  file.fd_ = fd;
  fchmod(fd, mode & 0777);  // the umask must not narrow a mode the caller chose on purpose
  // Reserve the memory now: on a full /dev/shm this fails here with a message instead of
  // killing a reader or the writer later with SIGBUS.
  if (const int err = posix_fallocate(fd, 0, static_cast<off_t>(file_size)); err != 0) {
    return errno_error(ErrorCode::system_error,
                       "cannot reserve " + std::to_string(file_size) + " bytes in " + dir +
                           "; free space there or make it larger",
                       err);
  }
  struct stat st {};
  fstat(fd, &st);
  file.take_stat(st);
  file.file_size_ = file_size;
  if (auto mapped = file.map_read_write(); !mapped) return mapped.error();
  return file;
}

Expected<void> RegionFile::publish_as(std::string_view name, bool replace) {
  const std::string path = region_path(name);
  const std::string self = "/proc/self/fd/" + std::to_string(fd_);
  if (!replace) {
    if (linkat(AT_FDCWD, self.c_str(), AT_FDCWD, path.c_str(), AT_SYMLINK_FOLLOW) == 0) return {};
    const int err = errno;
    if (err == EEXIST) return Error{ErrorCode::writer_exists, "the name was taken meanwhile"};
    return errno_error(ErrorCode::system_error, "cannot create " + path, err);
  }
  // Link under a unique temporary name, then rename over the old region in one step. The
  // temporary name lacks the region prefix, so no listing ever shows it, and no stream name can
  // clash with it.
  std::random_device entropy;
  const std::string temp = std::string(kRegionDir) + "/.sim-new." + std::to_string(getpid()) + "." +
                           std::to_string(entropy());
  if (linkat(AT_FDCWD, self.c_str(), AT_FDCWD, temp.c_str(), AT_SYMLINK_FOLLOW) != 0) {
    return errno_error(ErrorCode::system_error, "cannot create " + temp, errno);
  }
  if (rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    unlink(temp.c_str());
    return errno_error(ErrorCode::system_error, "cannot replace " + path, err);
  }
  return {};
}

bool name_refers_to(std::string_view name, ino_t inode) noexcept {
  const std::string path = region_path(name);
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) return false;
  return st.st_ino == inode;
}

}  // namespace sim::detail
