// SPDX-License-Identifier: Apache-2.0
#include "sim/sim.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/wait_set.hpp"
#include "sim/writer.hpp"

struct sim_writer {
  sim::Writer writer;
};
struct sim_reader {
  sim::Reader reader;
};
struct sim_waitset {
  sim::WaitSet set;
};
struct sim_notifier {
  sim::StreamNotifier notifier;
};

namespace {

// One fixed buffer per thread, so the pointer SIM_lastError returns never dangles.
thread_local char last_error[512];

void set_last_error(const std::string& message) {
  const std::size_t n = std::min(message.size(), sizeof last_error - 1);
  std::memcpy(last_error, message.data(), n);
  last_error[n] = '\0';
}
void clear_last_error() { last_error[0] = '\0'; }

int fail(int code, const std::string& message) {
  set_last_error(message);
  return code;
}

sim_reader* open_reader(const char* name, size_t capacity, const sim::Trust& trust) {
  if (name == nullptr) {
    fail(SIM_EINVAL, "SIM_readerInit needs a stream name");
    return nullptr;
  }
  sim::ReaderOptions options;
  options.trust = trust;
  auto reader = sim::Reader::open(name, options);
  if (!reader) {
    fail(SIM_EINVAL, reader.error().message);
    return nullptr;
  }
  if (capacity != 0 && reader->capacity() > capacity) {
    fail(SIM_EINVAL, std::string("stream ") + name + " carries frames of up to " +
                         std::to_string(reader->capacity()) + " bytes but the reader was given " +
                         std::to_string(capacity) + "; pass at least that");
    return nullptr;
  }
  clear_last_error();
  return new (std::nothrow) sim_reader{std::move(*reader)};
}

int code_of(sim::ReadStatus status) {
  switch (status) {
    case sim::ReadStatus::new_frame:
    case sim::ReadStatus::no_new_frame: return 0;
    case sim::ReadStatus::writer_gone: return SIM_EWRITERGONE;
    case sim::ReadStatus::stale: return SIM_ESTALE;
    case sim::ReadStatus::checksum_mismatch: return SIM_ECHECKSUM;
    case sim::ReadStatus::buffer_too_small: return SIM_EBUFFER;
    case sim::ReadStatus::overrun: return SIM_EOVERRUN;
    case sim::ReadStatus::region_invalid: return SIM_EREGION;
  }
  return SIM_EINVAL;
}

std::string describe(const sim_reader* r, sim::ReadStatus status) {
  const std::string& name = r->reader.name();
  switch (status) {
    case sim::ReadStatus::writer_gone: return "the writer of " + name + " is gone";
    case sim::ReadStatus::stale: return "the newest frame of " + name + " is stale";
    case sim::ReadStatus::checksum_mismatch:
      return "the newest frame of " + name + " failed its checksum and was dropped";
    case sim::ReadStatus::buffer_too_small:
      return "the buffer is smaller than the newest frame of " + name + "; pass at least " +
             std::to_string(r->reader.capacity()) + " bytes";
    case sim::ReadStatus::overrun:
      return "the writer of " + name + " overwrote every copy attempt; read again";
    case sim::ReadStatus::region_invalid:
      return "the region of " + name + " failed validation; restart its writer";
    default: return {};
  }
}

}  // namespace

extern "C" {

sim_writer* SIM_writerInit(const char* name, size_t capacity) {
  if (name == nullptr) {
    fail(SIM_EINVAL, "SIM_writerInit needs a stream name");
    return nullptr;
  }
  sim::StreamSpec spec;
  spec.name = name;
  spec.capacity = capacity;
  auto writer = sim::Writer::create(spec);
  if (!writer) {
    fail(SIM_EINVAL, writer.error().message);
    return nullptr;
  }
  clear_last_error();
  return new (std::nothrow) sim_writer{std::move(*writer)};
}

int SIM_writeData(sim_writer* w, const void* data, size_t size) {
  if (w == nullptr || (data == nullptr && size != 0)) {
    return fail(SIM_EINVAL, "SIM_writeData needs a writer and data");
  }
  const auto status = w->writer.write(
      std::span<const std::byte>(static_cast<const std::byte*>(data), size), sim::realtime_ns());
  if (status == sim::WriteStatus::too_large) {
    return fail(SIM_ETOOLARGE, "a frame of " + std::to_string(size) + " bytes does not fit " +
                                   w->writer.name() + ", whose capacity is " +
                                   std::to_string(w->writer.capacity()) + " bytes");
  }
  clear_last_error();
  return 0;
}

void SIM_writerClose(sim_writer* w) { delete w; }

sim_reader* SIM_readerInit(const char* name, size_t capacity) {
  return open_reader(name, capacity, sim::Trust{});
}

sim_reader* SIM_readerInitTrusting(const char* name, size_t capacity, const char* trust_owner,
                                   const char* trust_group) {
  auto trust = sim::Trust::parse(trust_owner != nullptr ? trust_owner : "",
                                 trust_group != nullptr ? trust_group : "");
  if (!trust) {
    fail(SIM_EINVAL, trust.error().message);
    return nullptr;
  }
  return open_reader(name, capacity, *trust);
}

long long SIM_readData(sim_reader* r, void* buf, size_t size, sim_frame_info* info) {
  if (r == nullptr || buf == nullptr) return fail(SIM_EINVAL, "SIM_readData needs a reader and a buffer");
  sim::FrameInfo frame;
  const auto status = r->reader.read(std::span<std::byte>(static_cast<std::byte*>(buf), size), frame);
  if (info != nullptr) *info = sim_frame_info{};  // seq 0: nothing delivered
  if (status == sim::ReadStatus::new_frame) {
    if (info != nullptr) {
      *info = {frame.seq, frame.stamp_ns, frame.publish_ns, frame.size, frame.receive_ns};
    }
    clear_last_error();
    return static_cast<long long>(frame.size);  // 0 for an empty frame: info->seq says it is one
  }
  const int code = code_of(status);
  if (code < 0) return fail(code, describe(r, status));
  clear_last_error();
  return 0;
}

int SIM_waitData(sim_reader* r, int timeout_ms) {
  if (r == nullptr) return fail(SIM_EINVAL, "SIM_waitData needs a reader");
  const auto timeout = timeout_ms < 0 ? sim::kForever
                                     : std::chrono::nanoseconds(std::chrono::milliseconds(timeout_ms));
  const auto status = r->reader.wait(timeout);
  clear_last_error();
  if (status == sim::ReadStatus::new_frame) return 1;
  const int code = code_of(status);
  if (code < 0) return fail(code, describe(r, status));
  return 0;
}

void SIM_readerClose(sim_reader* r) { delete r; }

int SIM_destroy(const char* name) {
  if (name == nullptr) return fail(SIM_EINVAL, "SIM_destroy needs a stream name");
  if (auto removed = sim::destroy(name); !removed) return fail(SIM_EINVAL, removed.error().message);
  clear_last_error();
  return 0;
}

const char* SIM_lastError(void) { return last_error; }

// --- waiting (issue 12) ---

int SIM_readerSetWaitMode(sim_reader* r, int mode) {
  if (r == nullptr) return fail(SIM_EINVAL, "SIM_readerSetWaitMode needs a reader");
  switch (mode) {
    case SIM_WAIT_BLOCK: r->reader.set_wait_mode(sim::WaitMode::block); break;
    case SIM_WAIT_POLL: r->reader.set_wait_mode(sim::WaitMode::poll); break;
    case SIM_WAIT_ADAPTIVE: r->reader.set_wait_mode(sim::WaitMode::adaptive); break;
    default:
      return fail(SIM_EINVAL, "wait mode " + std::to_string(mode) +
                                  " is unknown; use SIM_WAIT_BLOCK, SIM_WAIT_POLL or SIM_WAIT_ADAPTIVE");
  }
  clear_last_error();
  return 0;
}

sim_waitset* SIM_waitsetCreate(void) {
  clear_last_error();
  return new (std::nothrow) sim_waitset{sim::WaitSet()};
}

int SIM_waitsetAdd(sim_waitset* ws, sim_reader* r) {
  if (ws == nullptr || r == nullptr) return fail(SIM_EINVAL, "SIM_waitsetAdd needs a wait set and a reader");
  auto index = ws->set.add(r->reader);
  if (!index) return fail(SIM_EINVAL, index.error().message);
  clear_last_error();
  return static_cast<int>(*index);
}

int SIM_waitsetWait(sim_waitset* ws, int timeout_ms) {
  if (ws == nullptr) return fail(SIM_EINVAL, "SIM_waitsetWait needs a wait set");
  const auto timeout = timeout_ms < 0 ? sim::kForever
                                     : std::chrono::nanoseconds(std::chrono::milliseconds(timeout_ms));
  clear_last_error();
  const auto ready = ws->set.wait(timeout);
  return ready ? static_cast<int>(*ready) : SIM_ETIMEDOUT;
}

int SIM_waitsetReady(const sim_waitset* ws, int index) {
  if (ws == nullptr || index < 0) return 0;
  return ws->set.ready(static_cast<std::size_t>(index)) ? 1 : 0;
}

void SIM_waitsetClose(sim_waitset* ws) { delete ws; }

sim_notifier* SIM_notifierOpen(const char* const* names, size_t count) {
  if (names == nullptr || count == 0) {
    fail(SIM_EINVAL, "SIM_notifierOpen needs at least one stream name");
    return nullptr;
  }
  std::vector<std::string> list;
  for (size_t i = 0; i < count; ++i) {
    if (names[i] == nullptr) {
      fail(SIM_EINVAL, "SIM_notifierOpen was given a NULL stream name");
      return nullptr;
    }
    list.emplace_back(names[i]);
  }
  auto notifier = sim::StreamNotifier::open(list);
  if (!notifier) {
    fail(SIM_EINVAL, notifier.error().message);
    return nullptr;
  }
  clear_last_error();
  return new (std::nothrow) sim_notifier{std::move(*notifier)};
}

int SIM_notifierFd(const sim_notifier* n) {
  if (n == nullptr) return fail(SIM_EINVAL, "SIM_notifierFd needs a notifier");
  return n->notifier.fd();
}

int SIM_notifierDrain(sim_notifier* n, int* arrived, size_t count) {
  if (n == nullptr) return fail(SIM_EINVAL, "SIM_notifierDrain needs a notifier");
  const std::vector<bool> which = n->notifier.drain();
  int streams = 0;
  for (size_t i = 0; i < which.size(); ++i) {
    if (which[i]) ++streams;
    if (arrived != nullptr && i < count) arrived[i] = which[i] ? 1 : 0;
  }
  clear_last_error();
  return streams;
}

void SIM_notifierClose(sim_notifier* n) { delete n; }

}  // extern "C"
