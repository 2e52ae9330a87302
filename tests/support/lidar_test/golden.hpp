// SPDX-License-Identifier: Apache-2.0
// Test-only: the one shape of every family's golden tests, as nebula writes them: a table of
// cases (capture, calibration, model options, reference, tolerance), one parameterised test
// over it, and one comparison of a decoded cloud with its reference, point by point in order.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <ostream>
#include <string>

namespace lidar_test {

// How far a decoded point may be from its reference point, and how many points must be that
// close: `share` 1.0 is every point.
struct Tolerance {
  enum class Distance {
    largest_axis,  // max(|dx|, |dy|, |dz|)
    euclidean,     // sqrt(dx² + dy² + dz²)
  };
  Distance distance = Distance::largest_axis;
  double within_m = 1e-3;
  double share = 1.0;
};

inline std::ostream& operator<<(std::ostream& out, const Tolerance& t) {
  return out << (t.distance == Tolerance::Distance::euclidean ? "euclidean" : "largest axis") << " < "
             << t.within_m << " m for " << t.share * 100 << " % of the points";
}

// Point-by-point comparison of a decoded cloud with its reference: add() each pair in order.
// The reference may be in float (a PCD) or double (a formula evaluated by the test).
class CloudComparison {
 public:
  explicit CloudComparison(Tolerance tolerance) : tolerance_(tolerance) {}

  template <typename Point, typename Reference>
  void add(const Point& got, const Reference& want) {
    const double dx = static_cast<double>(got.x) - static_cast<double>(want.x);
    const double dy = static_cast<double>(got.y) - static_cast<double>(want.y);
    const double dz = static_cast<double>(got.z) - static_cast<double>(want.z);
    const double d = tolerance_.distance == Tolerance::Distance::euclidean
                         ? std::sqrt(dx * dx + dy * dy + dz * dz)
                         : std::max({std::fabs(dx), std::fabs(dy), std::fabs(dz)});
    if (d < tolerance_.within_m) ++within_;
    if (d > largest_) {
      largest_ = d;
      largest_index_ = compared_;
    }
    ++compared_;
  }

  std::size_t compared() const { return compared_; }
  double largest_m() const { return largest_; }
  double share_within() const {
    return compared_ == 0 ? 0.0 : static_cast<double>(within_) / static_cast<double>(compared_);
  }
  // Holds when enough points are close enough (and at least one point was compared).
  bool holds() const { return compared_ > 0 && share_within() >= tolerance_.share; }

  // For a failing EXPECT: what was asked and what the cloud did.
  std::string describe() const {
    return std::to_string(compared_ - within_) + " of " + std::to_string(compared_) +
           " points are farther than allowed; the farthest, point " + std::to_string(largest_index_) + ", is " +
           std::to_string(largest_) + " m off";
  }

 private:
  Tolerance tolerance_;
  std::size_t compared_ = 0;
  std::size_t within_ = 0;
  double largest_ = 0;
  std::size_t largest_index_ = 0;
};

// Every point of `decoded` against `reference`, in order; the sizes are the caller's check.
template <typename Points, typename ReferencePoints>
CloudComparison compare_clouds(const Points& decoded, const ReferencePoints& reference, Tolerance tolerance) {
  CloudComparison c(tolerance);
  const std::size_t n = std::min<std::size_t>(std::size(decoded), std::size(reference));
  for (std::size_t i = 0; i < n; ++i) c.add(decoded[i], reference[i]);
  return c;
}

// INSTANTIATE_TEST_SUITE_P's names: the table row's `name` field.
struct CaseName {
  template <typename Info>
  std::string operator()(const Info& info) const {
    return info.param.name;
  }
};

}  // namespace lidar_test
