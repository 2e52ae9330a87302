// SPDX-License-Identifier: Apache-2.0
#include "process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <thread>

extern char** environ;

namespace sim::bench {
namespace {
volatile std::sig_atomic_t* stop_flag_ = nullptr;
}  // namespace

void ChildProcess::set_stop_flag(volatile std::sig_atomic_t* flag) noexcept { stop_flag_ = flag; }

ChildProcess::ChildProcess(const std::vector<std::string>& argv) {
  int in_pipe[2];
  int out_pipe[2];
  if (pipe2(in_pipe, O_CLOEXEC) != 0) return;
  if (pipe2(out_pipe, O_CLOEXEC) != 0) {
    close(in_pipe[0]);
    close(in_pipe[1]);
    return;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in_pipe[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  std::vector<std::string> args_copy = argv;
  std::vector<char*> args;
  for (auto& a : args_copy) args.push_back(a.data());
  args.push_back(nullptr);
  if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
  posix_spawn_file_actions_destroy(&actions);
  close(in_pipe[0]);
  close(out_pipe[1]);
  in_fd_ = in_pipe[1];
  out_fd_ = out_pipe[0];
}

ChildProcess::~ChildProcess() {
  // Closing its stdin first lets a role process waiting for "go" or "stop" leave by itself and
  // clean up (a SIM writer removes its region); only a child that does not is killed.
  if (in_fd_ >= 0) close(in_fd_);
  in_fd_ = -1;
  if (pid_ > 0 && !reaped_ && wait(std::chrono::milliseconds(2000)) < 0) {
    kill(pid_, SIGKILL);
    wait(std::chrono::milliseconds(5000));
  }
  if (out_fd_ >= 0) close(out_fd_);
}

std::optional<std::string> ChildProcess::line(std::chrono::milliseconds timeout) {
  timed_out_ = false;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto nl = pending_.find('\n');
    if (nl != std::string::npos) {
      std::string l = pending_.substr(0, nl);
      pending_.erase(0, nl + 1);
      return l;
    }
    if (eof_ || out_fd_ < 0) {
      if (pending_.empty()) return std::nullopt;
      std::string l;
      l.swap(pending_);
      return l;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0 || (stop_flag_ != nullptr && *stop_flag_ != 0)) {
      timed_out_ = true;
      return std::nullopt;
    }
    pollfd p{out_fd_, POLLIN, 0};
    const int r = poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (r <= 0) continue;
    char buf[65536];
    const ssize_t n = read(out_fd_, buf, sizeof(buf));
    if (n <= 0) {
      eof_ = true;
    } else {
      pending_.append(buf, static_cast<std::size_t>(n));
    }
  }
}

bool ChildProcess::send(const std::string& l) {
  if (in_fd_ < 0) return false;
  const std::string data = l + "\n";
  return write(in_fd_, data.data(), data.size()) == static_cast<ssize_t>(data.size());
}

void ChildProcess::signal(int sig) noexcept {
  if (pid_ > 0 && !reaped_) kill(pid_, sig);
}

int ChildProcess::wait(std::chrono::milliseconds timeout) {
  if (reaped_) return status_;
  if (pid_ <= 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      reaped_ = true;
      status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return status_;
    }
    if (r < 0 || std::chrono::steady_clock::now() >= deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace sim::bench
