// SPDX-License-Identifier: Apache-2.0
// A real child process for the multi-process and tool tests: spawned with its stdout and stderr
// on pipes, so a test can read its output line by line, wait for a line ("ready", "listening on
// …"), signal it, and check its exit code and messages. The one helper every test suite uses.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace sim::testing {

// Limits against hangs, not timing checks: a test that reaches one has failed anyway.
inline constexpr std::chrono::milliseconds line_timeout{30'000};
inline constexpr std::chrono::milliseconds exit_timeout{120'000};

namespace detail {

// The children alive now. A test that aborts (a sanitizer's report, a failed assert, terminate)
// never runs ~Process, and its drivers would go on listening with their streams open: the abort
// takes them along. Only SIGABRT: the sanitizers report segmentation faults with handlers of
// their own, which must stay.
inline std::array<std::atomic<pid_t>, 64> children{};

inline void kill_children_then_abort(int) {
  for (auto& child : children) {
    const pid_t pid = child.load();
    if (pid > 0) ::kill(pid, SIGKILL);
  }
  ::raise(SIGABRT);  // SA_RESETHAND: now the default action
}

inline void remember_child(pid_t pid) {
  static const bool handler_installed = [] {
    struct sigaction action {};
    action.sa_handler = kill_children_then_abort;
    action.sa_flags = static_cast<int>(SA_RESETHAND);
    sigemptyset(&action.sa_mask);
    return ::sigaction(SIGABRT, &action, nullptr) == 0;
  }();
  static_cast<void>(handler_installed);
  for (auto& child : children) {
    pid_t none = 0;
    if (child.compare_exchange_strong(none, pid)) return;
  }
}

inline void forget_child(pid_t pid) {
  for (auto& child : children) {
    pid_t expected = pid;
    if (child.compare_exchange_strong(expected, 0)) return;
  }
}

}  // namespace detail

class Process {
 public:
  // Throws if the program cannot be started (the test then fails with that message).
  explicit Process(const std::vector<std::string>& argv) {
    int out[2], err[2];
    if (pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
    if (pipe2(err, O_CLOEXEC) != 0) {
      ::close(out[0]);
      ::close(out[1]);
      throw std::runtime_error("pipe2 failed");
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, err[1], STDERR_FILENO);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int rc = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(out[1]);
    ::close(err[1]);
    out_ = out[0];
    err_ = err[0];
    if (rc != 0) {
      pid_ = -1;
      throw std::runtime_error("cannot start " + argv.at(0));
    }
    detail::remember_child(pid_);
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;
  ~Process() {
    if (pid_ > 0 && !exit_code_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      detail::forget_child(pid_);
    }
    ::close(out_);
    ::close(err_);
  }

  // The next line of stdout (without its newline); nullopt at end of output or after `timeout`.
  std::optional<std::string> next_line(std::chrono::milliseconds timeout = line_timeout) {
    return wait_for_line("", timeout);
  }

  // Reads stdout until a line containing `needle` arrives and returns that line; nullopt at end
  // of output or after `timeout`. Stderr is collected meanwhile, so a child that logs a lot
  // cannot stall on a full pipe.
  std::optional<std::string> wait_for_line(const std::string& needle,
                                           std::chrono::milliseconds timeout = line_timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      std::size_t newline;
      while ((newline = out_buffer_.find('\n')) != std::string::npos) {
        std::string line = out_buffer_.substr(0, newline);
        out_text_ += line + "\n";
        out_buffer_.erase(0, newline + 1);
        if (line.find(needle) != std::string::npos) return line;
      }
      if (!out_open_ || !pump(deadline)) return std::nullopt;
    }
  }

  void signal(int sig) { ::kill(pid_, sig); }

  // Collects all output until the child ends (killing it after `timeout`) and returns its exit
  // code, or 128 + the signal that ended it.
  int wait(std::chrono::milliseconds timeout = exit_timeout) {
    if (exit_code_) return *exit_code_;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (out_open_ || err_open_) {
      if (!pump(deadline)) {
        ::kill(pid_, SIGKILL);
        deadline_passed_ = true;
        break;
      }
    }
    int status = 0;
    ::waitpid(pid_, &status, 0);
    detail::forget_child(pid_);
    unread_ = out_buffer_;
    out_text_ += out_buffer_;
    out_buffer_.clear();
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return *exit_code_;
  }

  // All of stdout so far; after wait(), all of it.
  const std::string& out() const { return out_text_; }
  // After wait(): the stdout that next_line()/wait_for_line() had not returned.
  const std::string& unread() const { return unread_; }
  // All of stderr so far; after wait(), all of it.
  const std::string& err() const { return err_text_; }
  bool deadline_passed() const { return deadline_passed_; }
  pid_t pid() const { return pid_; }

 private:
  // Waits for output on either pipe until `deadline` and appends what came; false once the
  // deadline has passed. A pipe at end of output is marked closed.
  bool pump(std::chrono::steady_clock::time_point deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p[2] = {{out_open_ ? out_ : -1, POLLIN, 0}, {err_open_ ? err_ : -1, POLLIN, 0}};
    if (::poll(p, 2, static_cast<int>(left.count())) <= 0) return true;  // timeout or EINTR: look again
    char chunk[4096];
    for (int i = 0; i < 2; ++i) {
      if (p[i].fd < 0 || (p[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      const ssize_t n = ::read(p[i].fd, chunk, sizeof chunk);
      if (n <= 0) {
        (i == 0 ? out_open_ : err_open_) = false;
      } else {
        (i == 0 ? out_buffer_ : err_text_).append(chunk, static_cast<std::size_t>(n));
      }
    }
    return true;
  }

  pid_t pid_ = -1;
  int out_ = -1;
  int err_ = -1;
  std::string out_buffer_;
  std::string out_text_;
  std::string unread_;
  std::string err_text_;
  bool out_open_ = true;
  bool err_open_ = true;
  std::optional<int> exit_code_;
  bool deadline_passed_ = false;
};

// Runs a command to its end.
struct Run {
  int code;
  std::string out;
  std::string err;
};
inline Run run(const std::vector<std::string>& argv) {
  Process p(argv);
  const int code = p.wait();
  return {code, p.out(), p.err()};
}

}  // namespace sim::testing
