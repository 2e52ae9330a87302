// SPDX-License-Identifier: Apache-2.0
// DetectedStream: the stream of a live receiver whose sensor model is either given or named by
// the first packet of the family (Hesai, Velodyne). With a model the stream is created at once;
// without, from the first packet that names one, whose number of returns raises the
// configured one. The family gives its LidarStream, its config and its two packet functions:
//
//   lidar::DetectedStream<LidarStream, LidarStreamConfig, detect_model, returns_in> stream;
//   stream.publish_to(config, model);            // model nullopt: from the first packet
//   if (LidarStream* s = stream.for_packet(datagram, udp)) s->push(…);
#pragma once

#include <algorithm>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"

namespace sim::lidar {

// `detect_model(payload)` -> optional<Model>; `returns_in(payload, model)` -> optional<unsigned>;
// `Stream::create(config)` -> Expected<Stream>; config.assembler.model and config.returns.
template <class Stream, class Config, auto detect_model, auto returns_in>
class DetectedStream {
 public:
  using Model = std::remove_cvref_t<decltype(std::declval<Config&>().assembler.model)>;

  // Where packets go. With a model the stream is created now and its error returned
  // (calibration, stream name, a live writer); without one, for_packet() creates it.
  Expected<void> publish_to(Config config, std::optional<Model> model) {
    stream_.reset();
    config_ = std::move(config);
    if (model) return create(*model);
    return {};
  }

  // The stream for a data packet, created when this packet names the model. nullptr while no
  // packet did (this one is counted unrecognised) or when creating the stream failed (error();
  // the receiver should stop).
  Stream* for_packet(const Datagram& d, UdpReceiver& udp) {
    if (stream_) return &*stream_;
    const auto model = detect_model(d.payload);
    if (!model) {
      ++udp.counters().unrecognised;
      return nullptr;
    }
    if (const auto returns = returns_in(d.payload, *model)) config_.returns = std::max(config_.returns, *returns);
    udp.note("detected a " + std::string(to_string(*model)) + " from " + address_text(*d.sender));
    if (auto created = create(*model); !created) {
      error_ = created.error();
      return nullptr;
    }
    return &*stream_;
  }

  Stream* get() noexcept { return stream_ ? &*stream_ : nullptr; }
  const Stream* get() const noexcept { return stream_ ? &*stream_ : nullptr; }
  const std::optional<Error>& error() const noexcept { return error_; }

 private:
  Expected<void> create(Model model) {
    Config config = config_;
    config.assembler.model = model;
    auto created = Stream::create(config);
    if (!created) return created.error();
    stream_.emplace(std::move(created.value()));
    return {};
  }

  Config config_;
  std::optional<Stream> stream_;
  std::optional<Error> error_;
};

}  // namespace sim::lidar
