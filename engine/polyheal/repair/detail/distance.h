// polyheal — distances to the input surface: the approximation tolerance of
// repairs (Botsch & Kobbelt §5: "stays within a prescribed approximation
// error") and the Hausdorff distance every report states.
//
// These are measurements, not certification predicates: they run in doubles
// on the coordinates as written (an AABB tree of the input triangles).
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal::detail {

/// Distance queries against a fixed triangle soup (the input surface).
class SurfaceDistance {
 public:
  /// Indexes every triangle of `soup` (polygons as fans). Keeps no reference.
  explicit SurfaceDistance(const Soup& soup);
  /// Indexes the given triangles (corner positions).
  explicit SurfaceDistance(const std::vector<std::array<Point3d, 3>>& triangles);
  ~SurfaceDistance();
  SurfaceDistance(const SurfaceDistance&) = delete;
  SurfaceDistance& operator=(const SurfaceDistance&) = delete;

  /// Squared distance from p to the nearest point of the surface.
  double squared_distance(const Point3d& p) const;
  /// The same, given a point of the surface near p (prunes the search).
  double squared_distance(const Point3d& p, const Point3d& hint) const;
  /// Squared distance from p to the surface, and the surface triangle that
  /// realises it (an index for squared_distance_to).
  std::pair<double, std::size_t> nearest(const Point3d& p) const;
  /// The same, starting the search from triangle `hint` (one likely near p).
  std::pair<double, std::size_t> nearest(const Point3d& p, std::size_t hint) const;
  /// Squared distance from p to surface triangle `t`.
  double squared_distance_to(const Point3d& p, std::size_t t) const;
  /// Is some surface triangle within squared distance r2 of p? `hint` (a
  /// triangle index, or anything out of range) is tried first and becomes
  /// the triangle found: neighbouring queries mostly share it.
  bool any_within(const Point3d& p, double r2, std::size_t& hint) const;
  /// The triangles the last searches found, most recent first (hints for
  /// any_within() below).
  struct Recent {
    std::array<std::size_t, 8> triangle{};
    std::size_t count = 0;
  };
  /// The same, trying the triangles `recent` holds before a search, and
  /// keeping the one found there: queries about one region of the surface
  /// (samples of a decimation's candidate triangles across a CAD fan) come
  /// back to a few triangles, not always the last one (ADIS16480: 530k of
  /// 1.3M queries searched after missing the last one).
  bool any_within(const Point3d& p, double r2, Recent& recent) const;
  /// Does triangle `piece` meet a (non-degenerate) surface triangle?
  /// Decided exactly on the doubles; true for a degenerate piece (not decided).
  bool meets(const std::array<Point3d, 3>& piece) const;
  /// Indices of the surface triangles whose bounding boxes meet the box
  /// [lo, hi] (candidates for squared_distance_to), each once, in no
  /// particular order. With `most`, nullopt as soon as more than that many
  /// boxes meet it.
  std::vector<std::size_t> triangles_near(const Point3d& lo, const Point3d& hi) const;
  std::optional<std::vector<std::size_t>> triangles_near(const Point3d& lo, const Point3d& hi, std::size_t most) const;
  /// Distance along the ray from `origin` in direction `direction` to the
  /// first triangle it hits, ignoring the triangles in `skip` (sorted); -1
  /// when it hits none (the local thickness of Yamakawa & Shimada §5.2).
  double ray_distance(const Point3d& origin, const Point3d& direction, const std::vector<std::size_t>& skip) const;
  bool empty() const;

  /// An upper bound on the distance to the surface over the whole triangle
  /// `piece`, seen along the normal of the plane P of surface triangle `t`;
  /// +infinity where it cannot be shown to be at most `limit`. Let U be the
  /// surface triangles whose projections onto P meet the piece's open
  /// projection, and over that part stay within `limit` of the piece along
  /// the normal. When the piece's projection lies in U's, every point x of
  /// the piece is within the height gap g(x) = h_T(x) - h_piece(x) of some
  /// triangle T of U above or below it; g is affine on each T's part, so
  /// its largest size is at a corner of the part (clipped in the plane).
  /// The projection lies in U's when no boundary edge of U (an edge with
  /// triangles of U on one side only) meets its open interior and its
  /// centroid lies inside a triangle of U. This bounds a piece over a
  /// region tessellated by long thin triangles (CAD fans, or a curved
  /// surface tessellated anew), where no single triangle is near all its
  /// corners. Also +infinity, not tried, when more than `most` surface
  /// triangles' boxes meet the piece's (a search that would cost more than
  /// the caller's alternative).
  double cover_bound(const std::array<Point3d, 3>& piece, std::size_t t, double limit,
                     std::size_t most = std::numeric_limits<std::size_t>::max()) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Squared distance from p to triangle abc, a zero-area triangle counting as
/// its edges (doubles; a measurement).
double squared_distance_to_triangle(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c);

/// Symmetric Hausdorff distance between two triangle soups, with bounded
/// error: the true distance lies in [result, result + error_bound] (up to
/// double rounding in the distance queries). Each direction bisects
/// triangles until an upper bound closes the gap: the distance to one fixed
/// triangle is convex, so its maximum over a piece is at a corner (the bound
/// of CGAL's bounded_error_Hausdorff_distance); pieces split at their
/// longest edge, which long thin triangles need. Triangles both soups
/// contain are skipped, so the cost follows what differs. -1 when one soup is
/// empty and the other is not (not measured).
double hausdorff_distance(const Soup& a, const Soup& b, double error_bound);

/// hausdorff_distance() given `b_to_a_at_most`, a rigorous upper bound on
/// the distance from b to a (each triangle of b bounded against a triangle
/// of a, say): b -> a is measured only when that bound exceeds the a -> b
/// distance measured first. The same result and error bound: a one-sided
/// distance known to be at most the other one changes neither. (The
/// directions run one after the other, not side by side.)
double hausdorff_distance(const Soup& a, const Soup& b, double error_bound, double b_to_a_at_most);

/// The two one-sided distances of hausdorff_distance: {from a to b, from b
/// to a} (how far a point of a can be from b, and the other way round).
std::array<double, 2> one_sided_distances(const Soup& a, const Soup& b, double error_bound);

/// The first of them alone: how far a point of a can be from b.
double one_sided_distance(const Soup& a, const Soup& b, double error_bound);

/// The distance from a to b over the points p of a where skip(p) is false
/// (e.g. "inside b's volume": how far the part of a that b does not enclose
/// is from b). `skip` must change only where a crosses b.
double one_sided_distance_skipping(const Soup& a, const Soup& b, double error_bound,
                                   const std::function<bool(const Point3d&)>& skip);

}  // namespace polyheal::detail
