// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace sim::hesai {
namespace {

// Reference §2–§6. Range limits are nebula's per-sensor defaults (reference §1.1).
constexpr std::array<ModelInfo, 5> model_table{{
    {Model::pandar64, 64, 6, 1194, 1198, true, 0.3f, 200.0f, 20},
    {Model::pandar40p, 40, 10, 1262, 1266, true, 0.3f, 200.0f, 20},
    {Model::pandar_xt32, 32, 8, 1080, 1080, false, 0.05f, 120.0f, 18},
    {Model::pandar_xt16, 16, 8, 568, 568, false, 0.05f, 120.0f, 18},
    {Model::pandar_qt64, 64, 4, 1068, 1072, true, 0.1f, 60.0f, 60},
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
  return "Pandar64, Pandar40P, PandarXT32, PandarXT16, PandarQT64";
}

const ModelInfo& info(Model model) noexcept {
  return model_table[static_cast<std::size_t>(model)];
}

std::size_t frame_capacity(Model model, unsigned returns, unsigned rpm, double margin) noexcept {
  const ModelInfo& m = info(model);
  returns = std::clamp(returns, 1u, 3u);
  rpm = std::clamp(rpm, 60u, 1200u);
  margin = std::clamp(margin, 0.0, 10.0);
  // The firing rate is fixed: the azimuth step grows with rpm, the firings per second do not.
  const double firings_per_second = 36000.0 / m.azimuth_step_10hz * 10.0;
  const double firings_per_revolution = firings_per_second * 60.0 / rpm;
  const double points = std::ceil(firings_per_revolution) * m.channels * returns;
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
  return std::nullopt;
}

}  // namespace sim::hesai
