// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/stop_signal.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "sim/clock.hpp"

namespace sim::apps {
namespace {

StopSignal* g_instance = nullptr;

void on_signal(int) {
  // Async-signal-safe: an atomic store and a write(2).
  if (g_instance != nullptr) g_instance->request();
}

}  // namespace

StopSignal::StopSignal() {
  fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  g_instance = this;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;  // no SA_RESTART: blocked calls return EINTR
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

StopSignal& StopSignal::install() {
  static StopSignal instance;
  return instance;
}

void StopSignal::request() noexcept {
  flag_.store(true, std::memory_order_relaxed);
  const std::uint64_t one = 1;
  if (fd_ >= 0) {
    [[maybe_unused]] const auto written = ::write(fd_, &one, sizeof one);
  }
}

void StopSignal::reset_for_test() noexcept {
  flag_.store(false, std::memory_order_relaxed);
  std::uint64_t count = 0;
  if (fd_ >= 0) {
    [[maybe_unused]] const auto read = ::read(fd_, &count, sizeof count);
  }
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool StopSignal::sleep_until(std::int64_t deadline_ns) const noexcept {
  for (;;) {
    if (requested()) return false;
    const std::int64_t left = deadline_ns - monotonic_ns();
    if (left <= 0) return true;
    // poll on the eventfd: a stop that lands between the check above and the sleep still
    // wakes it (a plain nanosleep would sleep through it).
    const timespec timeout{static_cast<time_t>(left / 1'000'000'000),
                           static_cast<long>(left % 1'000'000'000)};
    pollfd fd{fd_, POLLIN, 0};
    const int rc = ::ppoll(&fd, 1, &timeout, nullptr);
    if (rc > 0) return false;
    if (rc < 0 && errno != EINTR) return !requested();  // cannot wait: go on
  }
}

bool StopSignal::sleep_for(std::chrono::nanoseconds duration) const noexcept {
  return sleep_until(monotonic_ns() + std::max<std::int64_t>(0, duration.count()));
}

bool StopSignal::sleep_for_seconds(double seconds) const noexcept {
  return sleep_for(std::chrono::nanoseconds(static_cast<std::int64_t>(seconds * 1e9)));
}

}  // namespace sim::apps
