// SPDX-License-Identifier: Apache-2.0
// The Velodyne models SIM decodes and the per-model facts the rest needs: lasers, distance unit,
// how the 12 blocks of a packet hold firings, and the firing tables of the user manuals
// (§9.4 "Discreet Point Timing Calculation"). Wire format: docs/velodyne.md.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace sim::velodyne {

enum class Model : std::uint8_t {
  vlp16,       // VLP-16 and Puck LITE (product ID 0x22)
  puck_hires,  // Puck Hi-Res (0x24): the VLP-16's packet, narrower elevations
  vlp32c,      // VLP-32C (0x28)
  hdl32e,      // HDL-32E (0x21)
  vls128,      // VLS-128 / Alpha Prime (0xA1)
  hdl64e,      // HDL-64E S2/S3: no product ID, upper/lower block flags
};

inline constexpr std::array<Model, 6> all_models{Model::vlp16,  Model::puck_hires, Model::vlp32c,
                                                 Model::hdl32e, Model::vls128,     Model::hdl64e};

// "VLP-16", "Puck-HiRes", "VLP-32C", "HDL-32E", "VLS-128", "HDL-64E".
std::string_view to_string(Model model) noexcept;
// Accepts those names case-insensitively, with or without the dash ("vlp16", "VLS128").
std::optional<Model> parse_model(std::string_view name) noexcept;
// "VLP-16, Puck-HiRes, …", for --help and error messages.
std::string_view model_names() noexcept;

// Every data packet is this many bytes of UDP payload (1248 on the wire), port 2368.
inline constexpr std::size_t packet_size = 1206;
inline constexpr std::size_t blocks_per_packet = 12;
inline constexpr std::size_t block_size = 100;
inline constexpr std::size_t units_per_block = 32;
inline constexpr std::size_t timestamp_offset = 1200;
inline constexpr std::size_t return_mode_offset = 1204;
inline constexpr std::size_t product_id_offset = 1205;
inline constexpr std::uint16_t default_data_port = 2368;
inline constexpr std::uint16_t default_position_port = 8308;

struct ModelInfo {
  Model model;
  std::uint8_t product_id;       // byte 1205 (0 for the HDL-64E, which sends none)
  std::uint16_t lasers;
  float distance_unit_m;         // VLP-16/HDL-32E/HDL-64E 2 mm, VLP-32C/VLS-128 4 mm
  // Firing sequences one block holds (VLP-16: 2 × 16 lasers) and blocks one sequence needs
  // (VLS-128: 4 banks of 32, HDL-64E: upper and lower block).
  std::uint8_t sequences_per_block;
  std::uint8_t blocks_per_sequence;
  // The manual's firing table: a sequence lasts sequence_ns; laser l fires firing_ns(l) into it.
  std::uint32_t sequence_ns;
  float min_range_m;
  float max_range_m;
  std::uint16_t packets_per_second_single;  // at any rpm: the firing rate is fixed

  std::size_t max_points_per_packet() const noexcept { return blocks_per_packet * units_per_block; }
};

const ModelInfo& info(Model model) noexcept;

// Time of laser `laser` (0-based, calibration order) after the start of its firing sequence, ns.
std::uint32_t laser_firing_ns(Model model, unsigned laser) noexcept;

// How many points one revolution can hold at `rpm` (300–1200; lower = more), returns 1 or 2,
// plus `margin` for motor-speed drift and the packet that straddles the cut.
std::size_t frame_capacity(Model model, unsigned returns = 2, unsigned rpm = 300,
                           double margin = 0.10) noexcept;

// The model a data packet comes from (its product ID, or the HDL-64E's upper/lower block
// flags), or nullopt for anything else: another vendor's packet, a position packet, a product
// SIM does not decode, a datagram of another size.
std::optional<Model> detect_model(std::span<const std::uint8_t> payload) noexcept;

// A data packet that does not name its model: twelve FF EE blocks with product ID and return
// mode 0, as an HDL-32E with firmware before 2.2.20.0 (2016) sends it (velodyne_decoder's
// unpack_16_32_beam notes it). Decoded only as an HDL-32E chosen with --model, as strongest.
bool is_unnamed_hdl32e(std::span<const std::uint8_t> payload) noexcept;

}  // namespace sim::velodyne
