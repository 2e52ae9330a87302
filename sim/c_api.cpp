// SPDX-License-Identifier: Apache-2.0
#include "sim/sim.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <string>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/writer.hpp"

struct sim_writer {
  sim::Writer writer;
};
struct sim_reader {
  sim::Reader reader;
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

}  // extern "C"
