// SPDX-License-Identifier: Apache-2.0
// SIM behind the bench interface, in its three ways of use:
//   sim-poll  : writer.write() copies in; the reader spins on read(), which copies out.
//   sim-block : the same copies; the reader sleeps in read_next() until the writer's futex wake.
//   sim-zero  : writer.loan() + commit(); the reader sleeps in wait(), then borrow()s in place
//               and checks still_valid() after it has read the bytes.
//   sim-adaptive, sim-zero-adaptive: sim-block and sim-zero with WaitMode::adaptive (sleep until
//               shortly before the next expected publish, then spin briefly).
//   sim-poll-described: sim-poll on a stream whose writer set a camera's sensor description; the
//               reader checks every frame's sensor_generation and fetches the description when it
//               changes (once), as a consumer does. Side by side with sim-poll: its per-frame cost.
#include <chrono>
#include <thread>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/writer.hpp"
#include "transport.hpp"

namespace sim::bench {
namespace {

std::string region_name(const Endpoint& e) { return "/" + e.topic; }

class SimPublisher final : public PublisherBackend {
 public:
  SimPublisher(Writer writer, bool loan) : writer_(std::move(writer)), loan_(loan) {}
  ~SimPublisher() override { (void)sim::destroy(writer_.name(), /*force=*/true); }

  bool wait_for_readers(int, std::chrono::milliseconds) override { return true; }

  bool publish(std::span<std::byte> source, std::uint64_t seq) override {
    if (loan_) {
      Loan loan = writer_.loan();
      const auto slot = loan.bytes().first(source.size());
      std::memcpy(slot.data(), source.data(), source.size());  // "producing" the frame in place
      const std::int64_t now = monotonic_ns();
      seal_frame(slot, seq, now);
      return std::move(loan).commit(source.size(), now) == WriteStatus::ok;
    }
    // Copy-in: write() copies the writer's frame into the slot.
    const std::int64_t now = monotonic_ns();
    seal_frame(source, seq, now);
    return writer_.write(std::span<const std::byte>(source), now) == WriteStatus::ok;
  }

 private:
  Writer writer_;
  bool loan_;
};

class SimSubscriber final : public SubscriberBackend {
 public:
  SimSubscriber(Reader reader, Transport mode)
      : reader_(std::move(reader)), mode_(mode), buffer_(reader_.capacity()) {}

  bool zero() const { return mode_ == Transport::sim_zero || mode_ == Transport::sim_zero_adaptive; }

  bool ready(std::chrono::milliseconds) override { return true; }

  Delivery receive(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      ReadStatus status;
      FrameInfo info;
      if (zero()) {
        status = reader_.wait(timeout);
        if (status == ReadStatus::new_frame) {
          borrow_ = reader_.borrow();
          status = borrow_.status();
          if (status == ReadStatus::new_frame) return {Delivery::Kind::frame, borrow_.bytes(), {}};
        }
      } else if (mode_ == Transport::sim_block || mode_ == Transport::sim_adaptive) {
        status = reader_.read_next(buffer_, info, timeout);
        if (status == ReadStatus::new_frame) {
          return {Delivery::Kind::frame, std::span<const std::byte>(buffer_).first(info.size), {}};
        }
      } else {
        status = reader_.read(buffer_, info);
        if (status == ReadStatus::new_frame && !follow_description(info)) {
          return {Delivery::Kind::error, {}, "SIM reader: the sensor description is missing or damaged"};
        }
        if (status == ReadStatus::new_frame) {
          return {Delivery::Kind::frame, std::span<const std::byte>(buffer_).first(info.size), {}};
        }
      }
      if (status == ReadStatus::region_invalid || status == ReadStatus::buffer_too_small) {
        return {Delivery::Kind::error, {}, std::string("SIM reader: ") + to_string(status)};
      }
      if (std::chrono::steady_clock::now() >= deadline) return {};
    }
  }

  // What a consumer of a described stream does per frame: compare the generation, and fetch the
  // description only when it changed. False if a described stream's description cannot be read.
  bool follow_description(const FrameInfo& info) {
    if (mode_ != Transport::sim_poll_described || info.sensor_generation == generation_) return true;
    generation_ = info.sensor_generation;
    auto description = reader_.sensor_info();
    return description && description->has_value();
  }

  bool release() override { return !zero() || borrow_.still_valid(); }
  bool zero_copy() const override { return zero(); }
  std::uint64_t frames_caught_spinning() const override { return reader_.stats().caught_spinning; }
  double spin_s() const override { return static_cast<double>(reader_.stats().spin_ns) / 1e9; }

 private:
  Reader reader_;
  Transport mode_;
  std::vector<std::byte> buffer_;
  Borrow borrow_{};
  std::uint64_t generation_ = 0;  // sim-poll-described: the description last fetched
};

// A camera's description, as a driver would set it (sim-poll-described).
SensorInfo bench_camera() {
  SensorInfo info;
  info.frame_id = "camera_front_optical";
  info.mounting = Mounting::from_xyz_rpy(1.5, 0.0, 1.2, -1.5707963267948966, 0.0, -1.5707963267948966);
  CameraCalibration c;
  c.width = 1920;
  c.height = 1080;
  c.d = {-0.1, 0.01, 0.0, 0.0, 0.0};
  c.k = {1000, 0, 960, 0, 1000, 540, 0, 0, 1};
  c.p = {1000, 0, 960, 0, 0, 1000, 540, 0, 0, 0, 1, 0};
  info.calibration = c;
  info.time_base = TimeBase::host;
  return info;
}

}  // namespace

std::unique_ptr<PublisherBackend> make_sim_publisher(Transport t, const Endpoint& e,
                                                     std::string& error) {
  StreamSpec spec;
  spec.name = region_name(e);
  spec.capacity = e.payload;
  if (t == Transport::sim_poll_described) spec.sensor = bench_camera();
  auto writer = Writer::create(spec);
  if (!writer) {
    error = writer.error().message;
    return nullptr;
  }
  const bool loan = t == Transport::sim_zero || t == Transport::sim_zero_adaptive;
  return std::make_unique<SimPublisher>(std::move(*writer), loan);
}

std::unique_ptr<SubscriberBackend> make_sim_subscriber(Transport t, const Endpoint& e,
                                                       std::string& error) {
  // The writer process creates the region before any reader is started.
  ReaderOptions options;
  if (t == Transport::sim_adaptive || t == Transport::sim_zero_adaptive) {
    options.wait_mode = WaitMode::adaptive;
  }
  auto reader = Reader::open(region_name(e), options);
  if (!reader) {
    error = reader.error().message;
    return nullptr;
  }
  return std::make_unique<SimSubscriber>(std::move(*reader), t);
}

}  // namespace sim::bench
