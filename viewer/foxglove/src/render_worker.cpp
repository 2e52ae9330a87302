// SPDX-License-Identifier: Apache-2.0
#include "render_worker.hpp"

#include <utility>

namespace sim::foxglove {

RenderWorker::RenderWorker() : thread_([this] { run(); }) {}

RenderWorker::~RenderWorker() { stop(); }

bool RenderWorker::try_post(Job job) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || jobs_.size() >= kQueueLimit) return false;
    jobs_.push_back(std::move(job));
  }
  wake_.notify_one();
  return true;
}

void RenderWorker::stop() {
  std::deque<Job> dropped;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    dropped.swap(jobs_);
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
  // `dropped` goes after the join, outside the lock: a job may hold what its destructor closes.
}

void RenderWorker::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
    if (stopping_) return;
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    lock.unlock();
    job();
    job = nullptr;  // what it holds (a client's session) is let go outside the lock
    lock.lock();
  }
}

}  // namespace sim::foxglove
