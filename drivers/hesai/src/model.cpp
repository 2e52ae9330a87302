// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace sim::hesai {
namespace {

// Reference §2–§6 and hesai-qt128-xt32m.md §6.3. Range limits are nebula's per-sensor
// defaults. QT128: 12 + 2 × (2 + 128 × 4) + 4 (body CRC) + 17 (functional safety) + 34 (tail)
// = 1095 bytes, 1127 with the signature; 900 firings of 0.4° per revolution (observed), each
// lighting 96 lasers. XT32M: 12 + 6 × (2 + 32 × 4) + 24 + 4 = 820 bytes.
constexpr std::array<ModelInfo, 7> model_table{{
    // model, channels, blocks, size, long size, min m, max m, step, lasers/firing, returns, crc
    {Model::pandar64, 64, 6, 1194, 1198, 0.3f, 200.0f, 20, 64, 2, false},
    {Model::pandar40p, 40, 10, 1262, 1266, 0.3f, 200.0f, 20, 40, 2, false},
    {Model::pandar_xt32, 32, 8, 1080, 1080, 0.05f, 120.0f, 18, 32, 2, false},
    {Model::pandar_xt16, 16, 8, 568, 568, 0.05f, 120.0f, 18, 16, 2, false},
    {Model::pandar_qt64, 64, 4, 1068, 1072, 0.1f, 60.0f, 60, 64, 2, false},
    {Model::pandar_qt128, 128, 2, 1095, 1127, 0.05f, 50.0f, 40, 96, 2, true},
    {Model::pandar_xt32m, 32, 6, 820, 820, 0.5f, 300.0f, 18, 32, 3, false},
}};

bool iequals(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

std::string_view to_string(Model model) noexcept {
  switch (model) {
    case Model::pandar64: return "Pandar64";
    case Model::pandar40p: return "Pandar40P";
    case Model::pandar_xt32: return "PandarXT32";
    case Model::pandar_xt16: return "PandarXT16";
    case Model::pandar_qt64: return "PandarQT64";
    case Model::pandar_qt128: return "PandarQT128";
    case Model::pandar_xt32m: return "PandarXT32M";
  }
  return "unknown";
}

std::optional<Model> parse_model(std::string_view name) noexcept {
  if (name.size() > 6 && iequals(name.substr(0, 6), "pandar")) name.remove_prefix(6);
  for (Model m : all_models) {
    std::string_view full = to_string(m);
    if (iequals(name, full.substr(6))) return m;
  }
  return std::nullopt;
}

std::string_view model_names() noexcept {
  return "Pandar64, Pandar40P, PandarXT32, PandarXT16, PandarQT64, PandarQT128, PandarXT32M";
}

const ModelInfo& info(Model model) noexcept {
  return model_table[static_cast<std::size_t>(model)];
}

std::size_t frame_capacity(Model model, unsigned returns, unsigned rpm, double margin) noexcept {
  const ModelInfo& m = info(model);
  returns = std::clamp(returns, 1u, unsigned{m.max_returns});
  rpm = std::clamp(rpm, 60u, 1200u);
  margin = std::clamp(margin, 0.0, 10.0);
  // The firing rate is fixed: the azimuth step grows with rpm, the firings per second do not.
  const double firings_per_second = 36000.0 / m.azimuth_step_10hz * 10.0;
  const double firings_per_revolution = firings_per_second * 60.0 / rpm;
  const double points = std::ceil(firings_per_revolution) * m.channels_per_firing * returns;
  // One extra packet: the straddling packet's points can land on either side of the cut.
  return static_cast<std::size_t>(std::ceil(points * (1.0 + margin))) + m.max_points_per_packet();
}

std::optional<Model> detect_model(std::span<const std::uint8_t> p) noexcept {
  const std::size_t n = p.size();
  if (n < 12) return std::nullopt;
  const bool pre_header = p[0] == 0xEE && p[1] == 0xFF;
  if ((n == 1194 || n == 1198) && pre_header && p[2] == 64 && p[3] == 6) return Model::pandar64;
  if ((n == 1262 || n == 1266) && p[0] == 0xFF && p[1] == 0xEE) return Model::pandar40p;
  if (pre_header && p[2] == 6 && p[3] == 1) {
    if (n == 1080 && p[6] == 32) return Model::pandar_xt32;
    if (n == 568 && p[6] == 16) return Model::pandar_xt16;
  }
  if ((n == 1068 || n == 1072) && pre_header && p[2] == 3 && p[3] == 1 && p[6] == 64) {
    return Model::pandar_qt64;
  }
  if ((n == 1095 || n == 1127) && pre_header && p[2] == 3 && p[3] == 2 && p[6] == 128 &&
      p[7] == 2) {
    return Model::pandar_qt128;
  }
  if (n == 820 && pre_header && p[2] == 6 && p[3] == 1 && p[6] == 32 && p[7] == 6) {
    return Model::pandar_xt32m;
  }
  return std::nullopt;
}

}  // namespace sim::hesai
