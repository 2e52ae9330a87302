// SPDX-License-Identifier: Apache-2.0
// The one thread that makes the page's pictures (camera JPEGs, top-down views, projections), so
// the io threads that write WebSocket frames never render: a browser asking for pictures can
// delay other browsers' pictures, never a Foxglove client (review L5). Its queue is bounded; a
// request beyond it is refused at once (the page answers 503 with Retry-After) rather than
// waiting, so a hammering page cannot build up a backlog.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

namespace sim::foxglove {

class RenderWorker {
 public:
  using Job = std::function<void()>;

  // Pictures that may wait while one is being made.
  static constexpr std::size_t kQueueLimit = 16;

  RenderWorker();
  RenderWorker(const RenderWorker&) = delete;
  RenderWorker& operator=(const RenderWorker&) = delete;
  ~RenderWorker();  // stop()

  // Queues the job for the worker thread; false (the job is not kept) when kQueueLimit jobs wait
  // already or the worker has stopped.
  bool try_post(Job job);
  // Lets the running job finish, drops the waiting ones and joins the thread. Idempotent.
  void stop();

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Job> jobs_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace sim::foxglove
