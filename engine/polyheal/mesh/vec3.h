// polyheal — vector arithmetic on double points (Point3d), for measurements
// and choices: costs, orderings, shapes to prefer. Never for a predicate
// (those are exact: inspect/exact_predicates.h).
#pragma once

#include <cmath>

#include "polyheal/mesh/soup.h"

namespace polyheal {

inline Point3d sub(const Point3d& a, const Point3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Point3d add(const Point3d& a, const Point3d& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Point3d mul(const Point3d& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Point3d& a, const Point3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Point3d cross(const Point3d& a, const Point3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double squared_norm(const Point3d& a) { return dot(a, a); }
inline double norm(const Point3d& a) { return std::sqrt(dot(a, a)); }

}  // namespace polyheal
