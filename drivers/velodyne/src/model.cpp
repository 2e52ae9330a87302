// SPDX-License-Identifier: Apache-2.0
// Model facts from the user manuals (VLP-16 §9, VLP-32C §9, HDL-32E appendix, VLS-128 §9,
// HDL-64E S2/S3 §"Packet format") and the reference note lidar-velodyne-ouster.md §1.
#include "sim/velodyne/model.hpp"

#include <cctype>
#include <cmath>

namespace sim::velodyne {
namespace {

// The HDL-64E: the reference note gives no per-laser table (the manuals' tables differ between
// the S2 and the S3, and a data packet does not say which it is; docs/velodyne.md bounds the
// error). The upper and lower blocks fire together about 20,800 times a second (1.33 M
// points/s ÷ 64), so a firing is taken as 48 µs and its 64 lasers share its time.
constexpr std::uint32_t hdl64e_firing_ns = 48'000;

constexpr std::array<ModelInfo, all_models.size()> infos{{
    // model, product, lasers, unit, seq/block, blocks/seq, sequence ns, min, max, packets/s
    {Model::vlp16, 0x22, 16, 0.002f, 2, 1, 55'296, 0.3f, 300.0f, 754},
    {Model::puck_hires, 0x24, 16, 0.002f, 2, 1, 55'296, 0.3f, 300.0f, 754},
    {Model::vlp32c, 0x28, 32, 0.004f, 1, 1, 55'296, 0.3f, 300.0f, 1507},
    {Model::hdl32e, 0x21, 32, 0.002f, 1, 1, 46'080, 0.3f, 300.0f, 1808},
    {Model::vls128, 0xA1, 128, 0.004f, 1, 4, 53'300, 0.3f, 300.0f, 6254},
    {Model::hdl64e, 0x00, 64, 0.002f, 1, 2, hdl64e_firing_ns, 0.3f, 300.0f, 3472},
}};

bool same_name(std::string_view a, std::string_view b) noexcept {
  // Compares ignoring case and dashes: "vlp16" == "VLP-16".
  std::size_t i = 0;
  std::size_t j = 0;
  while (true) {
    while (i < a.size() && a[i] == '-') ++i;
    while (j < b.size() && b[j] == '-') ++j;
    if (i == a.size() || j == b.size()) return i == a.size() && j == b.size();
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[j]))) {
      return false;
    }
    ++i;
    ++j;
  }
}

}  // namespace

std::string_view to_string(Model model) noexcept {
  switch (model) {
    case Model::vlp16: return "VLP-16";
    case Model::puck_hires: return "Puck-HiRes";
    case Model::vlp32c: return "VLP-32C";
    case Model::hdl32e: return "HDL-32E";
    case Model::vls128: return "VLS-128";
    case Model::hdl64e: return "HDL-64E";
  }
  return "?";
}

std::optional<Model> parse_model(std::string_view name) noexcept {
  for (Model m : all_models) {
    if (same_name(name, to_string(m))) return m;
  }
  if (same_name(name, "Puck-LITE") || same_name(name, "Puck")) return Model::vlp16;
  return std::nullopt;
}

std::string_view model_names() noexcept {
  return "VLP-16 (Puck, Puck-LITE), Puck-HiRes, VLP-32C, HDL-32E, VLS-128, HDL-64E";
}

const ModelInfo& info(Model model) noexcept { return infos[static_cast<std::size_t>(model)]; }

std::uint32_t laser_firing_ns(Model model, unsigned laser) noexcept {
  switch (model) {
    case Model::vlp16:
    case Model::puck_hires: return laser * 2'304;
    case Model::vlp32c: return (laser / 2) * 2'304;  // lasers fire in pairs
    case Model::hdl32e: return laser * 1'152;
    // Firing groups of 8 lasers, 2.665 µs apart, with a maintenance slot after group 8.
    case Model::vls128: return (laser / 8 + laser / 64) * 2'665;
    case Model::hdl64e: return 0;
  }
  return 0;
}

std::size_t frame_capacity(Model model, unsigned returns, unsigned rpm, double margin) noexcept {
  const ModelInfo& i = info(model);
  if (rpm == 0) rpm = 300;
  if (returns == 0) returns = 1;
  if (returns > 2) returns = 2;
  const double packets = static_cast<double>(i.packets_per_second_single) * returns * 60.0 / rpm;
  return static_cast<std::size_t>(std::ceil(packets * (1.0 + margin))) * i.max_points_per_packet();
}

bool is_unnamed_hdl32e(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != packet_size || payload[product_id_offset] != 0 || payload[return_mode_offset] != 0) {
    return false;
  }
  for (std::size_t b = 0; b < blocks_per_packet; ++b) {
    if (payload[b * block_size] != 0xFF || payload[b * block_size + 1] != 0xEE) return false;
  }
  return true;
}

std::optional<Model> detect_model(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != packet_size) return std::nullopt;
  if (payload[0] != 0xFF || payload[1] != 0xEE) return std::nullopt;
  // The HDL-64E sends no product ID (its status bytes may hold any value); its blocks, and only
  // its, alternate upper (FF EE) and lower (FF DD).
  bool upper_lower = true;
  for (std::size_t b = 0; b < blocks_per_packet && upper_lower; ++b) {
    const std::uint8_t* flag = payload.data() + b * block_size;
    upper_lower = flag[0] == 0xFF && flag[1] == ((b % 2) == 0 ? 0xEE : 0xDD);
  }
  if (upper_lower) return Model::hdl64e;
  const std::uint8_t product = payload[product_id_offset];
  for (Model m : all_models) {
    if (info(m).product_id != 0 && info(m).product_id == product) return m;
  }
  return std::nullopt;
}

}  // namespace sim::velodyne
