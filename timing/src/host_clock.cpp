// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/host_clock.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/timex.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <random>
#include <thread>
#include <utility>

#include "sim/clock.hpp"

namespace sim::timing {
namespace {

using ptp::ManagementId;
using ptp::PortState;

constexpr std::array<ManagementId, 6> kAsked = {
    ManagementId::port_data_set,  ManagementId::current_data_set,
    ManagementId::parent_data_set, ManagementId::time_properties_data_set,
    ManagementId::time_status_np, ManagementId::default_data_set};

// The domain and transportSpecific each socket answered in, so the sweep over every domain
// happens once per socket and process, not once a second.
struct Learned {
  std::uint8_t domain = 0;
  std::uint8_t transport_specific = 0;
};
std::mutex learned_mutex;
std::map<std::string, Learned>& learned() {
  static std::map<std::string, Learned> map;
  return map;
}

// The client's own socket, bound in a private temporary folder (ptp4l replies to the sender's
// path; linuxptp up to 3.1 cannot reply to an abstract address). Both are removed on close.
class ClientSocket {
 public:
  static Expected<ClientSocket> open() {
    ClientSocket client;
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/sim-pmc.XXXXXX";
    if (pattern.size() + 4 >= sizeof(sockaddr_un{}.sun_path)) pattern = "/tmp/sim-pmc.XXXXXX";
    if (!mkdtemp(pattern.data())) {
      return Error{ErrorCode::system_error,
                   "cannot create a folder for the ptp4l client socket in /tmp: " +
                       std::string(std::strerror(errno))};
    }
    client.folder_ = pattern;
    client.path_ = pattern + "/pmc";
    client.fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, client.path_.c_str(), client.path_.size() + 1);
    if (client.fd_ < 0 ||
        ::bind(client.fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      return Error{ErrorCode::system_error, "cannot open a Unix socket to ask ptp4l: " +
                                                std::string(std::strerror(errno))};
    }
    return client;
  }
  ClientSocket() = default;
  ClientSocket(ClientSocket&& other) noexcept
      : fd_(std::exchange(other.fd_, -1)),
        folder_(std::move(other.folder_)),
        path_(std::move(other.path_)) {
    other.folder_.clear();
    other.path_.clear();
  }
  ClientSocket& operator=(ClientSocket&&) = delete;
  ~ClientSocket() {
    if (fd_ >= 0) ::close(fd_);
    if (!path_.empty()) ::unlink(path_.c_str());
    if (!folder_.empty()) ::rmdir(folder_.c_str());
  }
  int fd() const noexcept { return fd_; }

 private:
  int fd_ = -1;
  std::string folder_;
  std::string path_;
};

sockaddr_un socket_address(const std::string& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(),
              std::min(path.size() + 1, sizeof address.sun_path - 1));
  return address;
}

// One conversation with one ptp4l socket: GETs sent, answers gathered until all came or the
// deadline passed.
class Conversation {
 public:
  Conversation(const ClientSocket& client, std::string path,
               std::chrono::steady_clock::time_point deadline)
      : client_(client), path_(std::move(path)), deadline_(deadline),
        target_(socket_address(path_)) {
    std::random_device random;
    sequence_ = static_cast<std::uint16_t>(random());
    source_port_ = static_cast<std::uint16_t>(::getpid());
  }

  // 0 sent; else the errno of the first send that failed (ENOENT: no socket, ECONNREFUSED:
  // nobody listens, EACCES, EAGAIN: ptp4l's queue is full).
  // ptp4l's queue holds a few datagrams (net.unix.max_dgram_qlen, 10 by default): a full one is
  // waited for until `until`, never blocked on.
  int send(ManagementId id, std::uint8_t domain, std::uint8_t transport_specific,
           std::chrono::steady_clock::time_point until) {
    const auto message = ptp::encode_get({id, sequence_, domain, transport_specific, source_port_});
    for (;;) {
      const ssize_t sent = ::sendto(client_.fd(), message.data(), message.size(), MSG_DONTWAIT,
                                    reinterpret_cast<const sockaddr*>(&target_), sizeof target_);
      if (sent >= 0) break;
      if (errno != EAGAIN || std::chrono::steady_clock::now() >= std::min(until, deadline_)) {
        return errno;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    ++sequence_;
    return 0;
  }

  // Waits for answers until `until` (or the deadline), folding them into `answer`; whether any
  // came. Stops early once every asked id answered (and the ports had a moment to follow).
  bool gather(Ptp4lAnswer& answer, std::chrono::steady_clock::time_point until) {
    bool any = false;
    std::array<std::uint8_t, 2048> buffer{};
    for (;;) {
      // The deadline holds even against a socket that floods answers.
      const auto now = std::chrono::steady_clock::now();
      const auto end = std::min(until, deadline_);
      if (now >= end) return any;
      const bool complete = answered_all();  // then only what already arrived (other ports)
      const auto wait = complete ? std::chrono::milliseconds(0)
                                 : std::chrono::ceil<std::chrono::milliseconds>(end - now);
      pollfd p{client_.fd(), POLLIN, 0};
      const int ready = ::poll(&p, 1, static_cast<int>(wait.count()));
      if (ready < 0 && errno == EINTR) continue;
      if (ready <= 0) return any;
      const ssize_t got = ::recv(client_.fd(), buffer.data(), buffer.size(), MSG_DONTWAIT);
      if (got <= 0) continue;
      auto response = ptp::parse_response(
          sim::span<const std::uint8_t>(buffer.data(), static_cast<std::size_t>(got)));
      any = true;
      if (!response) {
        if (answer.problem.empty()) answer.problem = response.error().message;
        continue;
      }
      answered_[static_cast<std::uint16_t>(response->id)] = true;
      answer.socket = path_;
      fold_response(*response, answer);
    }
  }

  const std::string& path() const noexcept { return path_; }

 private:
  bool answered_all() const noexcept { return answered_.size() >= kAsked.size(); }

  const ClientSocket& client_;
  std::string path_;
  std::chrono::steady_clock::time_point deadline_;
  sockaddr_un target_;
  std::uint16_t sequence_ = 0;
  std::uint16_t source_port_ = 0;
  std::map<std::uint16_t, bool> answered_;
};

std::string errno_sentence(const std::string& path, int error) {
  if (error == ENOENT) return "no ptp4l socket at " + path;
  if (error == ECONNREFUSED) return "ptp4l is not running (nobody listens on " + path + ")";
  if (error == EACCES || error == EPERM) {
    return "may not talk to ptp4l at " + path + " (permission denied): run as root or in its group";
  }
  return "cannot talk to ptp4l at " + path + ": " + std::strerror(error);
}

// Asks every id in `domain` with both transportSpecific values (ptp4l ignores the other one).
int send_all(Conversation& talk, std::uint8_t domain,
             std::chrono::steady_clock::time_point until) {
  for (const auto id : kAsked) {
    for (std::uint8_t ts : {std::uint8_t{0}, std::uint8_t{1}}) {
      if (const int error = talk.send(id, domain, ts, until); error != 0) return error;
    }
  }
  return 0;
}

// ptp4l in another domain than 0, and nothing learned: one DEFAULT_DATA_SET GET per domain
// (1…127) and transportSpecific, without blocking; then the rest in the domain that answered.
bool sweep_domains(Conversation& talk, Ptp4lAnswer& answer,
                   std::chrono::steady_clock::time_point deadline) {
  const auto half =
      std::chrono::steady_clock::now() + (deadline - std::chrono::steady_clock::now()) / 2;
  int error = 0;
  for (int domain = 1; domain < 128 && error == 0; ++domain) {
    for (std::uint8_t ts : {std::uint8_t{0}, std::uint8_t{1}}) {
      error = talk.send(ManagementId::default_data_set, static_cast<std::uint8_t>(domain), ts, half);
      if (error != 0) break;  // time is up, or the socket went away: ask what was sent
    }
  }
  if (!talk.gather(answer, half) || answer.socket.empty()) return false;
  for (const auto id : kAsked) talk.send(id, answer.domain, answer.transport_specific, deadline);
  talk.gather(answer, deadline);
  return true;
}

std::vector<std::string> sockets_to_try(const HostClockOptions& options) {
  if (!options.ptp4l_socket.empty()) return {options.ptp4l_socket};
  return {std::begin(kPtp4lSockets), std::end(kPtp4lSockets)};
}

}  // namespace

void fold_response(const ptp::Response& r, Ptp4lAnswer& answer) {
  answer.domain = r.domain;
  answer.transport_specific = r.transport_specific;
  if (r.error) {
    if (answer.problem.empty()) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "ptp4l refused the management GET 0x%04x (error 0x%04x); check its version",
                    static_cast<unsigned>(r.id), static_cast<unsigned>(*r.error));
      answer.problem = text;
    }
    return;
  }
  if (r.default_ds) answer.default_ds = r.default_ds;
  if (r.current_ds) answer.current_ds = r.current_ds;
  if (r.parent_ds) answer.parent_ds = r.parent_ds;
  if (r.time_properties_ds) answer.time_properties_ds = r.time_properties_ds;
  if (r.time_status) answer.time_status = r.time_status;
  if (r.port_ds) {
    auto same = std::find_if(answer.ports.begin(), answer.ports.end(), [&](const auto& p) {
      return p.port_number == r.port_ds->port_number;
    });
    if (same != answer.ports.end()) {
      *same = *r.port_ds;
    } else if (answer.ports.size() < 256) {
      answer.ports.push_back(*r.port_ds);
    }
  }
}

namespace {

// One socket asked: its answer, or the errno of sending to it (0: sent, and no answer came).
struct Asked {
  std::optional<Ptp4lAnswer> answer;
  int error = 0;
};

Asked ask_socket(const ClientSocket& client, const std::string& path,
                 const HostClockOptions& options, std::chrono::steady_clock::time_point deadline) {
  std::optional<Learned> known;
  if (options.ptp_domain) {
    known = Learned{*options.ptp_domain, 0};
  } else {
    std::lock_guard lock(learned_mutex);
    if (auto it = learned().find(path); it != learned().end()) known = it->second;
  }
  Conversation talk(client, path, deadline);
  Ptp4lAnswer answer;
  const bool may_sweep = !known;
  const auto first_until =
      may_sweep ? std::chrono::steady_clock::now() + (deadline - std::chrono::steady_clock::now()) / 2
                : deadline;
  // EAGAIN: its queue stayed full (nobody reads it): below, that is "did not answer".
  if (const int error = send_all(talk, known ? known->domain : 0, first_until);
      error != 0 && error != EAGAIN) {
    return {std::nullopt, error};
  }
  bool answered = talk.gather(answer, first_until);
  if (!answered && may_sweep) answered = sweep_domains(talk, answer, deadline);
  std::lock_guard lock(learned_mutex);
  if (!answered) {
    if (known && !options.ptp_domain) learned().erase(path);  // restarted in another domain?
    return {};
  }
  if (answer.socket.empty()) {
    answer.socket = path;  // it answered, with nothing readable
  } else {
    learned()[path] = Learned{answer.domain, answer.transport_specific};
  }
  return {std::move(answer), 0};
}

// "no ptp4l socket at A, B or C".
std::string missing_sentence(const std::vector<std::string>& missing) {
  std::string sentence = "no ptp4l socket at ";
  for (std::size_t i = 0; i < missing.size(); ++i) {
    if (i > 0) sentence += i + 1 == missing.size() ? " or " : ", ";
    sentence += missing[i];
  }
  return sentence;
}

}  // namespace

Expected<Ptp4lAnswer> ask_ptp4l(const HostClockOptions& options) {
  const auto timeout = std::max(options.ptp4l_timeout, std::chrono::milliseconds(1));
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  auto client = ClientSocket::open();
  if (!client) return client.error();
  std::vector<std::string> missing;
  std::string refused;
  for (const auto& path : sockets_to_try(options)) {
    if (path.size() >= sizeof(sockaddr_un{}.sun_path)) {
      return Error{ErrorCode::invalid_argument,
                   "the ptp4l socket path " + path + " is too long for a Unix socket"};
    }
    Asked asked = ask_socket(*client, path, options, deadline);
    if (asked.answer) return std::move(*asked.answer);
    if (asked.error == 0) {
      return Error{ErrorCode::not_found, "ptp4l at " + path + " did not answer within " +
                                             std::to_string(timeout.count()) +
                                             " ms (another domain? set it)"};
    }
    if (asked.error == ENOENT) {
      missing.push_back(path);
    } else if (refused.empty()) {
      refused = errno_sentence(path, asked.error);
    }
    const bool next = options.ptp4l_socket.empty() &&
                      (asked.error == ENOENT || asked.error == ECONNREFUSED ||
                       asked.error == EACCES || asked.error == EPERM);
    if (!next) break;  // try the next default socket only past a missing or closed one
  }
  // A refusal (permission, nobody listening) says more than the sockets that do not exist.
  return Error{ErrorCode::not_found, refused.empty() ? missing_sentence(missing) : refused};
}

KernelClock read_kernel_clock() noexcept {
  KernelClock kernel;
  timex tx{};
  tx.modes = 0;
  const int state = ::adjtimex(&tx);
  if (state < 0) return kernel;
  kernel.read = true;
  kernel.unsynchronised = state == TIME_ERROR || (tx.status & STA_UNSYNC) != 0;
  kernel.max_error_us = tx.maxerror;
  kernel.tai_offset_s = tx.tai;
  return kernel;
}

HostClock read_host_clock_details(const HostClockOptions& options) {
  auto answer = ask_ptp4l(options);
  const KernelClock kernel = read_kernel_clock();
  if (answer) return host_clock_from(std::move(*answer), {}, kernel, sim::realtime_ns());
  return host_clock_from(std::nullopt, answer.error().message, kernel, sim::realtime_ns());
}

ClockStatus read_host_clock(const HostClockOptions& options) {
  return read_host_clock_details(options).status;
}

}  // namespace sim::timing
