// polyheal — vector arithmetic on double points (Point3d), for measurements
// and choices: costs, orderings, shapes to prefer. Never for a predicate
// (those are exact: inspect/exact_predicates.h).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "polyheal/mesh/soup.h"

namespace polyheal {

inline constexpr double kPi = 3.14159265358979323846;

inline Point3d sub(const Point3d& a, const Point3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Point3d add(const Point3d& a, const Point3d& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Point3d mul(const Point3d& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Point3d& a, const Point3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Point3d cross(const Point3d& a, const Point3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
/// (b - a) x (c - a): twice triangle abc's area vector (doubles; a measurement).
inline Point3d normal(const Point3d& a, const Point3d& b, const Point3d& c) { return cross(sub(b, a), sub(c, a)); }
inline double squared_norm(const Point3d& a) { return dot(a, a); }
inline double norm(const Point3d& a) { return std::sqrt(dot(a, a)); }
/// The angle between a and b in radians (atan2: accurate near 0 and pi).
inline double angle_between(const Point3d& a, const Point3d& b) { return std::atan2(norm(cross(a, b)), dot(a, b)); }

/// Triangle abc's smallest and largest angles, in degrees (an angle at a
/// corner with a zero-length side counts as 0).
inline std::pair<double, double> angle_range(const Point3d& a, const Point3d& b, const Point3d& c) {
  const std::array<Point3d, 3> p{a, b, c};
  double lo = 180.0, hi = 0.0;
  for (int k = 0; k < 3; ++k) {
    const Point3d u = sub(p[(k + 1) % 3], p[k]), v = sub(p[(k + 2) % 3], p[k]);
    const double n = std::sqrt(dot(u, u) * dot(v, v));
    const double angle = n > 0 ? std::acos(std::clamp(dot(u, v) / n, -1.0, 1.0)) * 180.0 / kPi : 0.0;
    lo = std::min(lo, angle);
    hi = std::max(hi, angle);
  }
  return {lo, hi};
}

/// Whether triangle abc's angles lie within [needle, cap] degrees, on
/// doubles (for choices, not a predicate).
inline bool angles_within(const Point3d& a, const Point3d& b, const Point3d& c, double needle, double cap) {
  const auto [lo, hi] = angle_range(a, b, c);
  return lo >= needle && hi <= cap;
}

}  // namespace polyheal
