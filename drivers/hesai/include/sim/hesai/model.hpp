// SPDX-License-Identifier: Apache-2.0
// The Hesai Pandar models SIM decodes, and the per-model facts every other part needs
// (packet sizes, channel and block counts, range limits, capacity of one revolution).
// Byte layouts: docs/hesai.md (read from tier4/nebula's packet structs and Hesai's SDKs).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace sim::hesai {

enum class Model : std::uint8_t {
  pandar64,
  pandar40p,
  pandar_xt32,
  pandar_xt16,
  pandar_qt64,
  pandar_qt128,
  pandar_xt32m,
};

inline constexpr std::array<Model, 7> all_models{Model::pandar64,    Model::pandar40p,
                                                 Model::pandar_xt32, Model::pandar_xt16,
                                                 Model::pandar_qt64, Model::pandar_qt128,
                                                 Model::pandar_xt32m};

// Hesai's own spelling: "Pandar64", "Pandar40P", "PandarXT32", "PandarXT16", "PandarQT64",
// "PandarQT128", "PandarXT32M".
std::string_view to_string(Model model) noexcept;

// Accepts Hesai's spelling case-insensitively, with or without "Pandar" ("XT32", "pandar64").
std::optional<Model> parse_model(std::string_view name) noexcept;

// "Pandar64, Pandar40P, …, PandarXT32M", for --help and error messages.
std::string_view model_names() noexcept;

struct ModelInfo {
  Model model;
  std::uint16_t channels;            // lasers
  std::uint16_t blocks_per_packet;   // firing blocks in one UDP payload
  // Bytes of the short form, and of the long form that adds an optional trailer: the 4-byte
  // UDP sequence (Pandar40P/64, QT64) or the 32-byte signature (QT128). Equal when the model
  // has no optional trailer (XT: the sequence is always there).
  std::uint16_t payload_size;
  std::uint16_t long_payload_size;
  float min_range_m;                 // manufacturer's limits (nebula's defaults)
  float max_range_m;
  std::uint16_t azimuth_step_10hz;   // 0.01° between firings at 10 Hz (observed)
  // Lasers that fire in one firing: all channels, except the QT128 whose two alternating
  // firing loops each leave 32 of its 128 channels dark.
  std::uint16_t channels_per_firing;
  std::uint8_t max_returns;          // returns per firing the model can send
  bool has_crc;                      // body/functional-safety/tail CRCs (QT128)

  bool has_optional_trailer() const noexcept { return long_payload_size != payload_size; }
  std::size_t max_points_per_packet() const noexcept {
    return std::size_t{channels} * blocks_per_packet;
  }
};

const ModelInfo& info(Model model) noexcept;

// Largest number of points one UDP payload of any model can carry (Pandar40P: 10 × 40).
inline constexpr std::size_t max_points_per_packet = 400;

// How many points one revolution can hold, to size a SIM stream once:
// lasers per firing × firings per revolution × returns (at most the model's), plus `margin` (default 10 %) for rpm drift and
// the firing that straddles the cut. `rpm` is the motor speed the sensor is configured for
// (600 = 10 Hz, 1200 = 20 Hz); lower rpm means more firings per revolution, so pass the lowest.
std::size_t frame_capacity(Model model, unsigned returns = 2, unsigned rpm = 600,
                           double margin = 0.10) noexcept;

// The model whose packet this payload is, from its length and header bytes, or nullopt when it
// is none of them (another device on the port, a truncated datagram, a GPS packet).
std::optional<Model> detect_model(std::span<const std::uint8_t> payload) noexcept;

}  // namespace sim::hesai
