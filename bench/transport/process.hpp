// SPDX-License-Identifier: Apache-2.0
// A child process of sim_bench (a writer, a reader or RouDi): its stdin to send "go"/"stop",
// its stdout read line by line with a deadline, so a hung peer cannot hang the benchmark.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <optional>
#include <string>
#include <vector>

namespace sim::bench {

class ChildProcess {
 public:
  // Starts argv[0] (a path) with argv. started() tells whether it worked.
  explicit ChildProcess(const std::vector<std::string>& argv);
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess();  // kills and reaps a child still running

  bool started() const noexcept { return pid_ > 0; }
  pid_t pid() const noexcept { return pid_; }

  // line() gives up early once *flag is non-zero (set from a signal handler).
  static void set_stop_flag(volatile std::sig_atomic_t* flag) noexcept;

  // The next line of output; nullopt at end of output or when the timeout passes (timed_out()).
  std::optional<std::string> line(std::chrono::milliseconds timeout);
  bool timed_out() const noexcept { return timed_out_; }
  // Sends one line to the child's stdin.
  bool send(const std::string& line);
  // Sends a signal (SIGINT, SIGKILL).
  void signal(int sig) noexcept;
  // Waits up to `timeout` for the child to exit: its exit code, 128+signal, or -1 if still running.
  int wait(std::chrono::milliseconds timeout);

 private:
  pid_t pid_ = -1;
  int in_fd_ = -1;
  int out_fd_ = -1;
  std::string pending_;
  bool eof_ = false;
  bool timed_out_ = false;
  bool reaped_ = false;
  int status_ = -1;
};

}  // namespace sim::bench
