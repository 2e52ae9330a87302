// SPDX-License-Identifier: Apache-2.0
// The one interface every transport in sim_bench sits behind, so a single writer loop and a
// single reader loop measure them all (the iceoryx2 way: one suite over every backend).
//
// What is measured, for every backend alike:
//   writer: fill the payload (in the loan, or in its own buffer), stamp CLOCK_MONOTONIC into the
//           frame header, publish. Copy-in backends copy inside publish, so their copy is timed.
//   reader: receive; a copying backend has copied the whole payload into the reader's buffer, a
//           zero-copy backend hands out the bytes in place and the reader loop checksums every
//           byte once; then the reader stamps CLOCK_MONOTONIC. Latency = reader stamp − writer stamp.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sim::bench {

// The first bytes of every payload. The writer also repeats `seq` in the last 8 bytes, so a
// reader can tell a whole frame from one whose head and tail come from different frames.
struct FrameHeader {
  std::uint64_t seq;       // 1, 2, … in publishing order
  std::int64_t stamp_ns;   // CLOCK_MONOTONIC taken immediately before publish
  std::uint64_t size;      // payload bytes, header included
  std::uint64_t reserved;
};
static_assert(sizeof(FrameHeader) == 32);
inline constexpr std::size_t kMinPayload = sizeof(FrameHeader) + sizeof(std::uint64_t);

// Stamps and fills the header and the tail word of a frame about to be published.
inline void seal_frame(std::span<std::byte> frame, std::uint64_t seq, std::int64_t stamp_ns) {
  const FrameHeader header{seq, stamp_ns, frame.size(), 0};
  std::memcpy(frame.data(), &header, sizeof(header));
  std::memcpy(frame.data() + frame.size() - sizeof(seq), &seq, sizeof(seq));
}

enum class Transport {
  sim_poll,
  sim_block,
  sim_zero,
  sim_adaptive,       // copy-out, WaitMode::adaptive (issue 12)
  sim_zero_adaptive,  // borrow, WaitMode::adaptive
  sim_poll_described, // sim_poll on a stream with a sensor description; the reader follows its
                      // generation on every frame (issue 21: what the description costs per frame)
  iceoryx,
  fastdds,
  cyclone
};

std::string_view to_string(Transport t) noexcept;
bool parse_transport(std::string_view name, Transport& out) noexcept;
// Whether this build has the backend (peers are optional at configure time).
bool available(Transport t) noexcept;
// Whether the backend needs an iceoryx RouDi daemon running.
bool needs_roudi(Transport t) noexcept;

// Everything a backend needs to set itself up; the same for the writer and its readers.
struct Endpoint {
  std::string topic;         // unique per configuration and run, e.g. "simbench_1234_7"
  std::size_t payload = 0;   // bytes per frame, header included
  int readers = 1;           // how many reader processes will subscribe
  int domain = 0;            // DDS domain id
  int reader_index = -1;     // -1 in the writer
};

class PublisherBackend {
 public:
  virtual ~PublisherBackend() = default;
  // Returns when `readers` readers are connected (DDS matching), or false after `timeout`.
  virtual bool wait_for_readers(int readers, std::chrono::milliseconds timeout) = 0;
  // Publishes one frame with the content of `frame`, the writer's own memory, sealing it with
  // seal_frame() immediately before the publishing call: copy-in backends seal `frame` and copy
  // it in; loaning backends copy it into the loan first (producing the frame in place), then seal
  // the loan. False if it was not published.
  virtual bool publish(std::span<std::byte> frame, std::uint64_t seq) = 0;
  // Whether data went through shared memory only, as far as the backend can tell ("" if unsure).
  virtual std::string path_note() const { return ""; }
};

// One received frame: its bytes are either the reader's own copy, or in place (zero_copy).
struct Delivery {
  enum class Kind { none, frame, error } kind = Kind::none;
  std::span<const std::byte> bytes{};
  std::string error{};  // for Kind::error: one sentence
};

class SubscriberBackend {
 public:
  virtual ~SubscriberBackend() = default;
  // True when the subscription is set up and (DDS) matched with the writer.
  virtual bool ready(std::chrono::milliseconds timeout) = 0;
  // The next frame newer than the last one, waiting (or spinning, for polling backends) up to
  // `timeout`. The bytes stay usable until release().
  virtual Delivery receive(std::chrono::milliseconds timeout) = 0;
  // Gives the frame back. False if zero-copy bytes were overwritten while held: discard them.
  virtual bool release() = 0;
  virtual bool zero_copy() const = 0;
  // Adaptive SIM readers: frames caught while spinning, and the time spent spinning.
  virtual std::uint64_t frames_caught_spinning() const { return 0; }
  virtual double spin_s() const { return 0; }
};

// Backend factories; they return nullptr and set `error` to one sentence when setup fails.
std::unique_ptr<PublisherBackend> make_publisher(Transport t, const Endpoint& e, std::string& error);
std::unique_ptr<SubscriberBackend> make_subscriber(Transport t, const Endpoint& e,
                                                   std::string& error);

// Per-backend factories, each defined in its own file (the peers only when found by CMake).
std::unique_ptr<PublisherBackend> make_sim_publisher(Transport t, const Endpoint& e,
                                                     std::string& error);
std::unique_ptr<SubscriberBackend> make_sim_subscriber(Transport t, const Endpoint& e,
                                                       std::string& error);
std::unique_ptr<PublisherBackend> make_iceoryx_publisher(const Endpoint& e, std::string& error);
std::unique_ptr<SubscriberBackend> make_iceoryx_subscriber(const Endpoint& e, std::string& error);
std::unique_ptr<PublisherBackend> make_fastdds_publisher(const Endpoint& e, std::string& error);
std::unique_ptr<SubscriberBackend> make_fastdds_subscriber(const Endpoint& e, std::string& error);
std::unique_ptr<PublisherBackend> make_cyclone_publisher(const Endpoint& e, std::string& error);
std::unique_ptr<SubscriberBackend> make_cyclone_subscriber(const Endpoint& e, std::string& error);

}  // namespace sim::bench
