#include "polyheal/repair/detail/distance.h"

#include "polyheal/mesh/hash.h"
#include "polyheal/mesh/mesh.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/intersections.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <tuple>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <cstdint>
#include <vector>

namespace polyheal::detail {
namespace {

using K = InputKernel;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

K::Point_3 point(const Point3d& p) { return K::Point_3(p[0], p[1], p[2]); }

using Corners = std::array<Point3d, 3>;

/// Each triangle's corners sorted (sorted_corners), so that the same face
/// in two files compares equal whatever its rotation or orientation
/// (distances do not see orientation; a reoriented face is not a change).
std::vector<Corners> triangles_of(const Soup& soup) {
  std::vector<Corners> out;
  out.reserve(soup.indices.size() / 3);
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const FaceView face = soup.face(f);
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      out.push_back(sorted_corners(soup.points[face[0]], soup.points[face[k]], soup.points[face[k + 1]]));
  }
  return out;
}

double norm(const Point3d& a, const Point3d& b) {
  const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
  return std::sqrt(x * x + y * y + z * z);
}

/// One-sided Hausdorff distance from triangles `from` to the surface `to`,
/// as a lower bound h with the true value in [h, h + error_bound].
///
/// The distance to a surface is 1-Lipschitz, so on a triangle with corner
/// distances d_i and longest edge l every point is within min_i d_i + l of
/// `to`. A triangle whose bound does not exceed the largest distance seen so
/// far (plus the error bound) is done; otherwise its longest edge is
/// bisected (long thin triangles split along their length only).
///
/// With `skip`, points for which skip(p) holds do not count (they raise no
/// lower bound). A piece whose corners are all skipped is done when its
/// longest edge is within the bound (its unskipped points lie beyond a
/// crossing of `to`, so within that edge of it) or when its corners are
/// farther from `to` than that edge (it lies wholly on their side). skip
/// must change only where the piece crosses `to`, as "inside `to`'s volume"
/// does.
double one_sided(const std::vector<Corners>& from, const SurfaceDistance& to, double error_bound,
                 const std::function<bool(const Point3d&)>* skip = nullptr) {
  struct Piece {
    Corners p;
    std::array<double, 3> d;          // distance of each corner to `to`
    std::array<std::size_t, 3> near;  // the triangle of `to` nearest each corner
    std::size_t best;                 // the triangle that gave the parent its bound
    std::array<char, 3> skipped{};    // corners `skip` rules out
    double longest = 0;               // its longest edge (the order of the shared stack with `skip`)
  };
  auto longest_edge = [](const Corners& p) {
    return std::max({norm(p[1], p[2]), norm(p[2], p[0]), norm(p[0], p[1])});
  };
  // With `skip`, one shared heap, largest piece first: should the split
  // budget run out (below), the pieces left are all small, and counting
  // them with their size over-estimates by little. (Depth first, it ran out
  // deep in one region and counted a quarter of a removed wall with its
  // size: two unit cubes touching face to face, their union "moved" 0.35.)
  auto larger = [](const Piece& a, const Piece& b) { return a.longest < b.longest; };
  // Upper bound on a piece: the distance to one triangle is convex, so its
  // maximum over the piece is at a corner; try the triangles nearest the
  // corners and the parent's, no new query needed.
  auto upper_bound = [&](Piece& piece) {
    double bound = std::numeric_limits<double>::infinity();
    for (std::size_t t : {piece.best, piece.near[0], piece.near[1], piece.near[2]}) {
      double m = 0;
      for (const Point3d& v : piece.p) m = std::max(m, to.squared_distance_to(v, t));
      if (m < bound) {
        bound = m;
        piece.best = t;
      }
      if (bound == 0) break;
    }
    return std::sqrt(bound);
  };
  double lower = 0.0;
  // The corners' nearest triangles: one query per distinct corner that
  // needs one (a vertex is a corner of ~6 triangles), in parallel (the
  // index is built and only read).
  std::vector<Point3d> corners;
  corners.reserve(3 * from.size());
  for (const Corners& t : from) corners.insert(corners.end(), t.begin(), t.end());
  tbb::parallel_sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  // Each triangle's corners as indices into `corners`, looked up once.
  std::vector<std::array<std::size_t, 3>> at(from.size());
  tbb::parallel_for(std::size_t(0), from.size(), [&](std::size_t t) {
    for (int k = 0; k < 3; ++k)
      at[t][k] = static_cast<std::size_t>(std::lower_bound(corners.begin(), corners.end(), from[t][k]) - corners.begin());
  });
  std::vector<std::pair<double, std::size_t>> nearest(corners.size());
  std::vector<char> known(corners.size(), 0);
  auto query = [&](const std::vector<std::size_t>& which) {
    tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t i) { nearest[which[i]] = to.nearest(corners[which[i]]); });
  };
  std::vector<std::size_t> every(corners.size());
  std::iota(every.begin(), every.end(), std::size_t(0));
  std::vector<std::size_t> todo;  // the triangles the bisection below starts from
  todo.reserve(from.size());
  if (!skip && !corners.empty()) {
    // A first pass over one corner per cell of a grid (cells of four median
    // longest edges): by the Lipschitz bound, every point of a triangle is
    // within d(r) + |c - r| + its longest edge of `to`, for a corner c of it
    // and the corner r that stands for c's cell. Triangles for which that
    // stays within the distance the first pass found (plus the error bound)
    // are done without a query of their own: most of a deep interior that
    // a repair removed, whose distances are far above its triangles' size.
    std::vector<double> longest(from.size());
    for (std::size_t t = 0; t < from.size(); ++t)
      longest[t] = std::max({norm(from[t][0], from[t][1]), norm(from[t][1], from[t][2]), norm(from[t][2], from[t][0])});
    std::vector<double> sorted = longest;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double cell = 4 * sorted[sorted.size() / 2];
    std::vector<std::size_t> stand_in = every, reps;
    if (cell > 0) {
      std::vector<std::pair<Point3d, std::size_t>> keyed(corners.size());
      for (std::size_t i = 0; i < corners.size(); ++i)
        keyed[i] = {{std::floor(corners[i][0] / cell), std::floor(corners[i][1] / cell), std::floor(corners[i][2] / cell)}, i};
      tbb::parallel_sort(keyed.begin(), keyed.end());
      for (std::size_t i = 0; i < keyed.size(); ++i) {
        if (i == 0 || keyed[i].first != keyed[i - 1].first) reps.push_back(keyed[i].second);
        stand_in[keyed[i].second] = reps.back();
      }
    } else {
      reps = every;
    }
    query(reps);
    for (std::size_t r : reps) {
      known[r] = 1;
      lower = std::max(lower, std::sqrt(nearest[r].first));
    }
    std::vector<std::size_t> needed;
    for (std::size_t t = 0; t < from.size(); ++t) {
      double bound = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k) {
        const std::size_t r = stand_in[at[t][k]];
        bound = std::min(bound, std::sqrt(nearest[r].first) + norm(from[t][k], corners[r]));
      }
      if (bound + longest[t] <= lower + error_bound) continue;
      todo.push_back(t);
      for (std::size_t i : at[t])
        if (!known[i]) {
          known[i] = 1;
          needed.push_back(i);
        }
    }
    query(needed);
  } else {
    todo.resize(from.size());
    std::iota(todo.begin(), todo.end(), std::size_t(0));
    query(every);
  }
  constexpr std::size_t kSkippedSplitBudget = 50000;
  std::vector<char> skipped(corners.size(), 0);
  if (skip)
    tbb::parallel_for(std::size_t(0), corners.size(), [&](std::size_t i) { skipped[i] = (*skip)(corners[i]); });
  std::vector<Piece> stack;
  for (std::size_t t : todo) {
    Piece piece;
    piece.p = from[t];
    for (int k = 0; k < 3; ++k) {
      const std::size_t i = at[t][k];
      const auto [d2, near] = nearest[i];
      piece.d[k] = std::sqrt(d2);
      piece.near[k] = near;
      piece.skipped[k] = skipped[i];
      if (!skipped[i]) lower = std::max(lower, piece.d[k]);
    }
    piece.best = piece.near[0];
    piece.longest = longest_edge(piece.p);
    stack.push_back(piece);
  }
  if (skip) std::make_heap(stack.begin(), stack.end(), larger);
  // What becomes of one piece against the lower bound `bound` (read only).
  struct Step {
    bool split = false;     // into `half`, the midpoint's distance `raise` (0 when skipped)
    double raise = 0;
    std::array<Piece, 2> half;
    bool budgeted = false;  // an all-skipped piece that meets `to`: it counts against the split budget,
    double counted = 0;     // and past it, counts with this bound on all its points instead
  };
  auto step = [&](Piece piece, double bound) {
    Step s;
    const std::array<double, 3> edge{norm(piece.p[1], piece.p[2]), norm(piece.p[2], piece.p[0]),
                                     norm(piece.p[0], piece.p[1])};  // edge k is opposite corner k
    const int k = static_cast<int>(std::max_element(edge.begin(), edge.end()) - edge.begin());
    double convex = -1;  // upper_bound(piece), once asked (it leaves piece.best at its triangle)
    // A point of the piece that is not skipped lies beyond a crossing of
    // `to` on its segment to any skipped corner c, so within |x - c| of
    // `to`; and within d_u + |x - u| of it for an unskipped corner u. Every
    // point of a triangle is within reach = longest edge / sqrt(3) of its
    // nearest corner (the circumradius of an acute triangle, whose largest
    // angle is at least 60 degrees; at most half the longest edge
    // otherwise). So every unskipped point is within reach of `to` plus the
    // largest distance of an unskipped corner (0 for a skipped one): along
    // a crossing of `to`, where mixed pieces have corners on it, this
    // settles pieces ~1.7x longer than the 1-Lipschitz bound below (min d
    // plus the longest edge). Such pieces are most of the measure where a
    // union cut the input along long curves (cycloidal's repair: 2.01M
    // pieces for 23k triangles, 1.72M with this bound).
    const double reach = edge[k] / std::sqrt(3.0);
    if (skip) {
      double farthest = 0;
      for (int c = 0; c < 3; ++c)
        if (!piece.skipped[c]) farthest = std::max(farthest, piece.d[c]);
      if (farthest + reach <= bound + error_bound) return s;
    }
    // All corners skipped (and the bound above not enough): the piece cannot
    // reach `to` at all when its corners are farther than its longest edge.
    if (piece.skipped[0] && piece.skipped[1] && piece.skipped[2]) {
      if (*std::min_element(piece.d.begin(), piece.d.end()) > edge[k]) return s;
      // skip changes only where the piece crosses `to`: crossing nothing,
      // it is skipped whole.
      if (!to.meets(piece.p)) return s;
      // Input running just inside `to` over a large area would take pieces
      // of the error bound's size: past a budget, such a piece counts with
      // a bound on all its points, the smaller of its reach and its
      // convexity bound (the result then over-estimates, never
      // under-estimates).
      s.budgeted = true;
      convex = upper_bound(piece);
      s.counted = std::min(reach, convex);
    }
    // 1-Lipschitz bound first (free), then the convexity bound
    if (*std::min_element(piece.d.begin(), piece.d.end()) + edge[k] <= bound + error_bound) return s;
    if ((convex >= 0 ? convex : upper_bound(piece)) <= bound + error_bound) return s;
    // A piece over a region tessellated by thin triangles (a CAD fan, or
    // the same curved surface tessellated anew): no one triangle is near
    // all its corners, but the region is. (Asked only of pieces longer
    // than the distance sought: smaller ones are done by a few bisections,
    // cheaper than a search of the region within that distance.)
    // (Not when a corner is beyond that distance itself — a corner `skip`
    // rules out, inside a volume: no bound on the piece is below it. Along
    // a crossing of `to`, every mixed piece is such, and the search was most
    // of the measure.)
    // The search is worth it only while it costs less than the bisections
    // it saves: bisected, the piece is done once its halves' edges are
    // within the slack the bound leaves over its nearest corner, after
    // ~2 (edge / slack)^2 pieces of a nearest query each; a surface
    // triangle in the search costs about a tenth of one. (Where the bound
    // is large — a regularized raw offset, whose removed parts are far from
    // the output: the crank's, 451k triangles, searched 7000 triangles a
    // piece and failed 9 times in 10 — few bisections do.)
    if (edge[k] > bound + error_bound &&
        *std::max_element(piece.d.begin(), piece.d.end()) <= (bound + error_bound) * (1 + 1e-6)) {
      const double slack = bound + error_bound - *std::min_element(piece.d.begin(), piece.d.end());
      const double ratio = slack > 0 ? edge[k] / slack : HUGE_VAL;
      const std::size_t most =
          ratio < 1e3 ? std::size_t(256 + 20 * ratio * ratio) : std::numeric_limits<std::size_t>::max();
      if (to.cover_bound(piece.p, piece.best, bound + error_bound, most) <= bound + error_bound) return s;
    }
    const int i = (k + 1) % 3, j = (k + 2) % 3;  // the longest edge runs from corner i to corner j
    Point3d m;
    for (int c = 0; c < 3; ++c) m[c] = 0.5 * (piece.p[i][c] + piece.p[j][c]);
    if (m == piece.p[i] || m == piece.p[j]) return s;  // no double left between them
    const auto [dm2, near] = to.nearest(m, piece.best);
    const double dm = std::sqrt(dm2);
    const bool skip_m = skip && (*skip)(m);
    s.split = true;
    s.raise = skip_m ? 0.0 : dm;
    Piece &a = s.half[0] = piece, &b = s.half[1] = piece;
    a.p[j] = m;
    a.d[j] = dm;
    a.near[j] = near;
    a.skipped[j] = skip_m;
    b.p[i] = m;
    b.d[i] = dm;
    b.near[i] = near;
    b.skipped[i] = skip_m;
    for (Piece& half : s.half) half.longest = longest_edge(half.p);
    return s;
  };
  // Applies a step to `work` and the bound; `splits` counts the budgeted ones.
  auto apply = [&](const Step& s, std::vector<Piece>& work, double& bound, std::size_t& splits) {
    if (s.budgeted && ++splits > kSkippedSplitBudget) {
      bound = std::max(bound, s.counted);
      return;
    }
    if (!s.split) return;
    bound = std::max(bound, s.raise);
    for (const Piece& half : s.half) {
      work.push_back(half);
      if (skip) std::push_heap(work.begin(), work.end(), larger);
    }
  };
  if (skip) {
    // One shared heap (the split budget is global), taken kBatch largest
    // pieces at a time: each batch stepped in parallel against the bound as
    // it stood, then applied in order — the result does not depend on the
    // scheduling (a piece does not see what the others of its batch raise).
    constexpr std::size_t kBatch = 64;
    std::size_t splits = 0;
    std::vector<Piece> batch;
    std::vector<Step> steps;
    while (!stack.empty()) {
      batch.clear();
      while (!stack.empty() && batch.size() < kBatch) {
        std::pop_heap(stack.begin(), stack.end(), larger);
        batch.push_back(stack.back());
        stack.pop_back();
      }
      steps.assign(batch.size(), Step());
      const double bound = lower;
      tbb::parallel_for(std::size_t(0), batch.size(), [&](std::size_t i) { steps[i] = step(batch[i], bound); });
      for (const Step& s : steps) apply(s, stack, lower, splits);
    }
    return lower;
  }
  // Each triangle on its own, from the corners' bound, in parallel: the
  // result does not depend on the scheduling (a triangle never sees a bound
  // another raised, which costs a few more splits than the serial order).
  std::vector<double> found(stack.size(), lower);
  tbb::parallel_for(std::size_t(0), stack.size(), [&](std::size_t i) {
    std::vector<Piece> own{stack[i]};
    std::size_t splits = 0;  // (none counted: nothing is skipped)
    while (!own.empty()) {
      const Piece piece = own.back();
      own.pop_back();
      apply(step(piece, found[i]), own, found[i], splits);
    }
  });
  for (double d : found) lower = std::max(lower, d);
  return lower;
}

struct V3 {
  double x, y, z;
};
V3 v3(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }
V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(const V3& a, const V3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

/// Squared distance from p to segment ab (a point when a = b).
double segment_distance2(const V3& p, const V3& a, const V3& b) {
  const V3 ab = b - a, ap = p - a;
  const double t = dot(ap, ab), len2 = dot(ab, ab);
  if (t <= 0 || len2 <= 0) return dot(ap, ap);
  if (t >= len2) return dot(p - b, p - b);
  const double s = t / len2;
  const V3 d{ap.x - s * ab.x, ap.y - s * ab.y, ap.z - s * ab.z};
  return dot(d, d);
}

/// Squared distance to a triangle; a zero-area one (`degenerate`) counts as
/// its edges. The region of p's nearest point is found as in Ericson, "Real-
/// Time Collision Detection" §5.1.5 (vertex, edge or face region from signs
/// of dot products); a face-region distance is the distance to the plane.
/// Doubles, like CGAL's Epick squared_distance it replaces (a measurement:
/// 37% of degenerate's time on a 380-face fan went to CGAL's version).
double distance2(const K::Point_3& q, const K::Triangle_3& t, bool degenerate) {
  const V3 p = v3(q), a = v3(t[0]), b = v3(t[1]), c = v3(t[2]);
  if (degenerate)
    return std::min({segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
  const V3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return dot(ap, ap);  // vertex a
  const V3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dot(bp, bp);  // vertex b
  if (d1 * d4 - d3 * d2 <= 0 && d1 >= 0 && d3 <= 0) return segment_distance2(p, a, b);
  const V3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dot(cp, cp);  // vertex c
  if (d5 * d2 - d1 * d6 <= 0 && d2 >= 0 && d6 <= 0) return segment_distance2(p, a, c);
  if (d3 * d6 - d5 * d4 <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return segment_distance2(p, b, c);
  const V3 n = cross(ab, ac);
  const double nn = dot(n, n);
  if (!(nn > 0))  // flat in doubles after all: its edges
    return std::min({segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
  const double h = dot(ap, n);
  return h * h / nn;
}

}  // namespace

double squared_distance_to_triangle(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c) {
  // A triangle whose area is clearly non-zero in doubles is not degenerate;
  // only slivers pay for the exact test.
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const K::Triangle_3 t(point(a), point(b), point(c));
  const bool clearly_not_flat = n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 1e-20 * uu * vv;
  return distance2(point(p), t, !clearly_not_flat && t.is_degenerate());
}

namespace {

/// A bounding-volume hierarchy over the triangles for nearest-point and box
/// queries, in doubles (a measurement, like the distances it serves). CGAL's
/// AABB tree answered these with filtered predicates and projected-point
/// constructions: 6 us a query on a smooth mesh and 20-60 us on CAD fans,
/// whose long thin triangles have boxes that overlap over the whole fan.
/// Here a triangle longer than kSplit times the median longest edge is
/// indexed by the boxes of up to 2^kDepth pieces of itself (halved along
/// the longest edge), each leading to the whole triangle: 3.6 / 6.7 / 4.8
/// us on the bunny, ADIS16480 and thingi10k_88566 (same distances).
class Bvh {
 public:
  struct Box {
    double lo[3], hi[3];
  };

  Bvh(const Triangles& triangles, const std::vector<char>& degenerate)
      : triangles_(triangles), degenerate_(degenerate) {
    if (triangles.empty()) return;
    std::vector<double> longest;
    longest.reserve(triangles.size());
    for (const K::Triangle_3& t : triangles) longest.push_back(longest2(v3(t[0]), v3(t[1]), v3(t[2])));
    std::nth_element(longest.begin(), longest.begin() + static_cast<std::ptrdiff_t>(longest.size() / 2), longest.end());
    const double limit2 = kSplit * kSplit * longest[longest.size() / 2];
    for (std::size_t t = 0; t < triangles.size(); ++t)
      add(static_cast<std::uint32_t>(t), v3(triangles[t][0]), v3(triangles[t][1]), v3(triangles[t][2]), limit2, 0);
    cut_.assign(triangles.size(), 0);
    for (std::size_t i = 1; i < entries_.size(); ++i)  // a triangle's pieces are added side by side
      if (entries_[i].triangle == entries_[i - 1].triangle) cut_[entries_[i].triangle] = 1;
    const auto n = static_cast<std::uint32_t>(entries_.size());
    std::map<std::uint32_t, std::uint32_t> counted;
    nodes_.resize(node_count(n, counted));
    build(0, n, 0, counted);
  }

  /// The nearest triangle to p and its squared distance, given a known
  /// candidate (`best`, the squared distance to triangle `index`) to prune
  /// with: the candidate is returned unless a triangle is strictly nearer.
  std::pair<double, std::size_t> nearest(const V3& p, double best, std::size_t index) const {
    nearest_first(p, [&](double box2) { return box2 >= best; },
                  [&](std::uint32_t t) {
                    const double d = distance2(p, t);
                    if (d < best) {
                      best = d;
                      index = t;
                    }
                    return false;
                  });
    return {best, index};
  }

  /// Is a triangle within squared distance r2 of p? Stops at the first;
  /// `found` is set to it. (Boxes are pruned with a relative slack of 1e-12,
  /// so rounding in a box's distance never hides a triangle within r2.)
  bool any_within(const V3& p, double r2, std::size_t& found) const {
    const double prune = r2 * (1 + 1e-12);
    bool hit = false;
    nearest_first(p, [&](double box2) { return box2 > prune; },
                  [&](std::uint32_t t) {
                    if (distance2(p, t) > r2) return false;
                    found = t;
                    return hit = true;
                  });
    return hit;
  }

  /// The triangles with a piece whose box meets [lo, hi], each once, in no
  /// particular order: only a triangle cut into pieces can come up twice,
  /// and only those are sorted to drop repeats.
  std::vector<std::size_t> meeting(const Point3d& lo, const Point3d& hi) const {
    return *meeting(lo, hi, std::numeric_limits<std::size_t>::max());
  }
  /// meeting(), or nullopt once more than `most` boxes meet [lo, hi].
  std::optional<std::vector<std::size_t>> meeting(const Point3d& lo, const Point3d& hi, std::size_t most) const {
    std::vector<std::size_t> out, cut;
    if (nodes_.empty()) return out;
    auto meets = [&](const Box& b) {
      for (int k = 0; k < 3; ++k)
        if (b.hi[k] < lo[k] || b.lo[k] > hi[k]) return false;
      return true;
    };
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {
      const Node& n = nodes_[stack.back()];
      stack.pop_back();
      if (!meets(n.box)) continue;
      if (!n.leaf) {
        stack.push_back(n.a);
        stack.push_back(n.b);
        continue;
      }
      for (std::uint32_t i = n.a; i < n.a + n.b; ++i)
        if (meets(entries_[i].box)) (cut_[entries_[i].triangle] ? cut : out).push_back(entries_[i].triangle);
      if (out.size() + cut.size() > most) return std::nullopt;
    }
    std::sort(cut.begin(), cut.end());
    cut.erase(std::unique(cut.begin(), cut.end()), cut.end());
    out.insert(out.end(), cut.begin(), cut.end());
    return out;
  }

  double distance2(const V3& p, std::size_t t) const;

 private:
  static constexpr double kSplit = 4;  // pieces no longer than 4x the median longest edge...
  static constexpr int kDepth = 6;     // ... or 64 pieces a triangle
  static constexpr std::uint32_t kParallelBuild = 1u << 14;  // entries: below, one thread builds the subtree
  struct Entry {
    Box box;
    std::uint32_t triangle;
  };
  struct Node {
    Box box;
    std::uint32_t a = 0, b = 0;  // leaf: entries [a, a + b); otherwise the children a and b
    bool leaf = false;
  };

  /// Depth first from the root, the nearer child first: skips a node or a
  /// piece when far(squared distance from p to its box) says so, and hands
  /// each triangle of the pieces left to visit(triangle) — once per run of
  /// its pieces, which lie side by side — until visit returns true.
  template <class Far, class Visit>
  void nearest_first(const V3& p, Far far, Visit visit) const {
    if (nodes_.empty()) return;
    std::uint32_t last = std::numeric_limits<std::uint32_t>::max();
    // The median split keeps the tree balanced: depth <= log2(entries) + 1,
    // and the stack holds at most one sibling per level.
    std::array<std::uint32_t, 128> stack;
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (far(box_distance2(n.box, p))) continue;
      if (!n.leaf) {
        const bool left_first = box_distance2(nodes_[n.a].box, p) < box_distance2(nodes_[n.b].box, p);
        stack[top++] = left_first ? n.b : n.a;
        stack[top++] = left_first ? n.a : n.b;
        continue;
      }
      for (std::uint32_t i = n.a; i < n.a + n.b; ++i) {
        const Entry& e = entries_[i];
        if (e.triangle == last || far(box_distance2(e.box, p))) continue;
        last = e.triangle;
        if (visit(e.triangle)) return;
      }
    }
  }
  static double longest2(const V3& a, const V3& b, const V3& c) {
    return std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)});
  }
  static double box_distance2(const Box& b, const V3& p) {
    const double x[3] = {p.x, p.y, p.z};
    double s = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = x[k] < b.lo[k] ? b.lo[k] - x[k] : (x[k] > b.hi[k] ? x[k] - b.hi[k] : 0.0);
      s += d * d;
    }
    return s;
  }
  /// Indexes triangle t by the boxes of pieces no longer than the limit.
  /// Halving points are rounded, so a piece's box is widened by an ulp:
  /// together they still cover the triangle.
  void add(std::uint32_t t, const V3& a, const V3& b, const V3& c, double limit2, int depth) {
    const double ab = dot(b - a, b - a), bc = dot(c - b, c - b), ca = dot(a - c, a - c);
    const double m = std::max({ab, bc, ca});
    if (m <= limit2 || depth == kDepth) {
      Box box;
      const double xa[3] = {a.x, a.y, a.z}, xb[3] = {b.x, b.y, b.z}, xc[3] = {c.x, c.y, c.z};
      for (int k = 0; k < 3; ++k) {
        box.lo[k] = std::min({xa[k], xb[k], xc[k]});
        box.hi[k] = std::max({xa[k], xb[k], xc[k]});
        if (depth > 0) {
          box.lo[k] = std::nextafter(box.lo[k], -std::numeric_limits<double>::infinity());
          box.hi[k] = std::nextafter(box.hi[k], std::numeric_limits<double>::infinity());
        }
      }
      entries_.push_back({box, t});
      return;
    }
    auto mid = [](const V3& u, const V3& v) { return V3{0.5 * (u.x + v.x), 0.5 * (u.y + v.y), 0.5 * (u.z + v.z)}; };
    if (m == ab) {
      add(t, a, mid(a, b), c, limit2, depth + 1);
      add(t, mid(a, b), b, c, limit2, depth + 1);
    } else if (m == bc) {
      add(t, a, b, mid(b, c), limit2, depth + 1);
      add(t, a, mid(b, c), c, limit2, depth + 1);
    } else {
      add(t, a, b, mid(c, a), limit2, depth + 1);
      add(t, mid(c, a), b, c, limit2, depth + 1);
    }
  }
  /// The nodes build() makes for n entries (memoized in `counted`: the
  /// halves of a range have at most two sizes a level).
  static std::uint32_t node_count(std::uint32_t n, std::map<std::uint32_t, std::uint32_t>& counted) {
    if (n <= 4) return 1;
    if (const auto it = counted.find(n); it != counted.end()) return it->second;
    const std::uint32_t c = 1 + node_count(n / 2, counted) + node_count(n - n / 2, counted);
    counted.emplace(n, c);
    return c;
  }

  /// Node over entries [lo, hi): split at the median of the box centres
  /// along the axis where they spread most; leaves of up to four. Built as
  /// node `id` and the nodes after it, in pre-order (left subtree first);
  /// returns how many it made.
  /// Large ranges build their halves in parallel, each into the node ids
  /// it takes in that order: the same tree as one thread builds.
  std::uint32_t build(std::uint32_t lo, std::uint32_t hi, std::uint32_t id,
                      const std::map<std::uint32_t, std::uint32_t>& counted) {
    Box box = entries_[lo].box, centres;
    for (int k = 0; k < 3; ++k) {
      centres.lo[k] = std::numeric_limits<double>::infinity();
      centres.hi[k] = -std::numeric_limits<double>::infinity();
    }
    for (std::uint32_t i = lo; i < hi; ++i)
      for (int k = 0; k < 3; ++k) {
        const Box& e = entries_[i].box;
        box.lo[k] = std::min(box.lo[k], e.lo[k]);
        box.hi[k] = std::max(box.hi[k], e.hi[k]);
        const double c = 0.5 * (e.lo[k] + e.hi[k]);
        centres.lo[k] = std::min(centres.lo[k], c);
        centres.hi[k] = std::max(centres.hi[k], c);
      }
    nodes_[id] = {box, 0, 0, false};
    if (hi - lo <= 4) {
      nodes_[id].leaf = true;
      nodes_[id].a = lo;
      nodes_[id].b = hi - lo;
      return 1;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (centres.hi[k] - centres.lo[k] > centres.hi[axis] - centres.lo[axis]) axis = k;
    const std::uint32_t mid = lo + (hi - lo) / 2;
    std::nth_element(entries_.begin() + lo, entries_.begin() + mid, entries_.begin() + hi,
                     [axis](const Entry& x, const Entry& y) {
                       return x.box.lo[axis] + x.box.hi[axis] < y.box.lo[axis] + y.box.hi[axis];
                     });
    const std::uint32_t left = id + 1;
    std::uint32_t left_count = 0, right_count = 0;
    if (hi - lo >= kParallelBuild) {
      const std::uint32_t right = left + counted.at(mid - lo);
      tbb::parallel_invoke([&] { left_count = build(lo, mid, left, counted); },
                           [&] { right_count = build(mid, hi, right, counted); });
    } else {
      left_count = build(lo, mid, left, counted);
      right_count = build(mid, hi, left + left_count, counted);
    }
    nodes_[id].a = left;
    nodes_[id].b = left + left_count;
    return 1 + left_count + right_count;
  }

  const Triangles& triangles_;
  const std::vector<char>& degenerate_;
  std::vector<Entry> entries_;
  std::vector<char> cut_;  // per triangle: split into several pieces (entries)
  std::vector<Node> nodes_;
};

double Bvh::distance2(const V3& p, std::size_t t) const {
  return polyheal::detail::distance2(K::Point_3(p.x, p.y, p.z), triangles_[t], degenerate_[t] != 0);
}

}  // namespace

struct SurfaceDistance::Impl {
  Triangles triangles;
  std::vector<char> degenerate;  // per triangle, decided once (an exact test, slow on slivers)
  std::unique_ptr<Bvh> bvh;
  // CGAL's tree, for ray queries only (deintersect's local thickness), made on first use
  std::once_flag rays_made;
  std::unique_ptr<Tree> rays;
};

SurfaceDistance::SurfaceDistance(const Soup& soup) : SurfaceDistance(triangles_of(soup)) {}

SurfaceDistance::SurfaceDistance(const std::vector<std::array<Point3d, 3>>& triangles)
    : impl_(std::make_unique<Impl>()) {
  impl_->triangles.resize(triangles.size());
  impl_->degenerate.resize(triangles.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const auto& t = triangles[i];
      impl_->triangles[i] = K::Triangle_3(point(t[0]), point(t[1]), point(t[2]));
      impl_->degenerate[i] = impl_->triangles[i].is_degenerate();
    }
  });
  impl_->bvh = std::make_unique<Bvh>(impl_->triangles, impl_->degenerate);
}

SurfaceDistance::~SurfaceDistance() = default;

double SurfaceDistance::squared_distance(const Point3d& p, const Point3d& hint) const {
  if (impl_->triangles.empty()) return 0.0;
  const V3 q{p[0], p[1], p[2]}, d = q - V3{hint[0], hint[1], hint[2]};
  // the hint lies on the surface: its distance bounds the nearest one
  return impl_->bvh->nearest(q, dot(d, d), 0).first;
}

bool SurfaceDistance::any_within(const Point3d& p, double r2, std::size_t& hint) const {
  const V3 q{p[0], p[1], p[2]};
  if (hint < impl_->triangles.size() && impl_->bvh->distance2(q, hint) <= r2) return true;
  return impl_->bvh->any_within(q, r2, hint);
}

bool SurfaceDistance::any_within(const Point3d& p, double r2, Recent& recent) const {
  const V3 q{p[0], p[1], p[2]};
  auto to_front = [&](std::size_t i, std::size_t t) {  // t goes first; those before i move up one
    for (; i > 0; --i) recent.triangle[i] = recent.triangle[i - 1];
    recent.triangle[0] = t;
  };
  for (std::size_t i = 0; i < recent.count; ++i)
    if (recent.triangle[i] < impl_->triangles.size() && impl_->bvh->distance2(q, recent.triangle[i]) <= r2) {
      to_front(i, recent.triangle[i]);
      return true;
    }
  std::size_t found = 0;
  if (!impl_->bvh->any_within(q, r2, found)) return false;
  if (recent.count < recent.triangle.size()) ++recent.count;
  to_front(recent.count - 1, found);
  return true;
}

std::vector<std::size_t> SurfaceDistance::triangles_near(const Point3d& lo, const Point3d& hi) const {
  return impl_->bvh->meeting(lo, hi);
}

std::optional<std::vector<std::size_t>> SurfaceDistance::triangles_near(const Point3d& lo, const Point3d& hi,
                                                                        std::size_t most) const {
  return impl_->bvh->meeting(lo, hi, most);
}

bool SurfaceDistance::meets(const std::array<Point3d, 3>& piece) const {
  const K::Triangle_3 t(point(piece[0]), point(piece[1]), point(piece[2]));
  if (t.is_degenerate()) return true;  // not decided here: "may meet"
  Point3d lo = piece[0], hi = piece[0];
  for (const Point3d& p : piece)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  for (std::size_t s : triangles_near(lo, hi))
    if (!impl_->degenerate[s] && CGAL::do_intersect(t, impl_->triangles[s])) return true;
  return false;
}

double SurfaceDistance::ray_distance(const Point3d& origin, const Point3d& direction,
                                     const std::vector<std::size_t>& skip) const {
  if (impl_->triangles.empty()) return -1.0;
  std::call_once(impl_->rays_made, [&] {
    impl_->rays = std::make_unique<Tree>(impl_->triangles.cbegin(), impl_->triangles.cend());
  });
  const K::Ray_3 ray(point(origin), K::Vector_3(direction[0], direction[1], direction[2]));
  const auto first = impl_->triangles.cbegin();
  const auto hit = impl_->rays->first_intersection(ray, [&](Triangles::const_iterator t) {
    return std::binary_search(skip.begin(), skip.end(), static_cast<std::size_t>(t - first));
  });
  if (!hit) return -1.0;
  K::Point_3 at;
  if (const auto* p = boost::get<K::Point_3>(&hit->first)) at = *p;
  else if (const auto* s = boost::get<K::Segment_3>(&hit->first)) at = s->source();
  else return -1.0;
  return std::sqrt(CGAL::to_double(CGAL::squared_distance(ray.source(), at)));
}

bool SurfaceDistance::empty() const { return impl_->triangles.empty(); }

namespace {

struct V2 {
  double x, y;
};
double orient2(const V2& a, const V2& b, const V2& c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

/// A plane's frame: a point of it, its unit normal, two unit axes in it.
struct Frame {
  V3 o, n, e1, e2;
  V2 at(const V3& p) const {
    const V3 d = p - o;
    return {dot(d, e1), dot(d, e2)};
  }
  double height(const V3& p) const { return dot(p - o, n); }
};

bool strictly_inside(const V2& p, const std::array<V2, 3>& q) {  // q counter-clockwise
  return orient2(q[0], q[1], p) > 0 && orient2(q[1], q[2], p) > 0 && orient2(q[2], q[0], p) > 0;
}

/// Does segment ab meet the open triangle q (counter-clockwise) other than
/// within `near` of one of its corners? a + s (b - a) clipped against the
/// three open half-planes; a touch at a corner or along a side is no
/// meeting. (A side through a corner of q meets it or not by rounding; a
/// part of q that is left uncovered within `near` of a corner is within
/// 2 near of a covered point, which the caller adds to its bound.)
bool meets_interior(const V2& a, const V2& b, const std::array<V2, 3>& q, double near) {
  double s0 = 0, s1 = 1;
  for (int i = 0; i < 3; ++i) {
    const double fa = orient2(q[i], q[(i + 1) % 3], a), fb = orient2(q[i], q[(i + 1) % 3], b);
    if (fa <= 0 && fb <= 0) return false;
    if (fa > 0 && fb > 0) continue;
    const double s = fa / (fa - fb);
    if (fa <= 0) s0 = std::max(s0, s);  // enters here
    else s1 = std::min(s1, s);          // leaves here
  }
  if (!(s0 < s1)) return false;
  const V2 in{a.x + s0 * (b.x - a.x), a.y + s0 * (b.y - a.y)}, out{a.x + s1 * (b.x - a.x), a.y + s1 * (b.y - a.y)};
  auto within = [&](const V2& x, const V2& c) { return std::hypot(x.x - c.x, x.y - c.y) <= near; };
  for (const V2& c : q)
    if (within(in, c) && within(out, c)) return false;
  return true;
}

}  // namespace

double SurfaceDistance::cover_bound(const Corners& piece, std::size_t t, double limit, std::size_t most) const {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (impl_->degenerate[t] || !(limit < kNone)) return kNone;
  const K::Triangle_3& base = impl_->triangles[t];
  Frame f;
  f.o = v3(base[0]);
  const V3 n = cross(v3(base[1]) - f.o, v3(base[2]) - f.o), u = v3(base[1]) - f.o;
  const double ln = std::sqrt(dot(n, n)), lu = std::sqrt(dot(u, u));
  if (!(ln > 0) || !(lu > 0)) return kNone;
  f.n = {n.x / ln, n.y / ln, n.z / ln};
  f.e1 = {u.x / lu, u.y / lu, u.z / lu};
  f.e2 = cross(f.n, f.e1);
  std::array<V2, 3> q;
  std::array<double, 3> hq;
  for (int k = 0; k < 3; ++k) {
    const V3 c{piece[k][0], piece[k][1], piece[k][2]};
    q[k] = f.at(c);
    hq[k] = f.height(c);
  }
  const double area = orient2(q[0], q[1], q[2]);
  if (area == 0) return kNone;
  if (area < 0) {
    std::swap(q[1], q[2]);
    std::swap(hq[1], hq[2]);
  }
  // How near a corner of the projection a boundary side may cross it
  // (rounding): far below any tolerance or error bound.
  const double near = 1e-9 * std::max({std::hypot(q[1].x - q[0].x, q[1].y - q[0].y),
                                       std::hypot(q[2].x - q[1].x, q[2].y - q[1].y),
                                       std::hypot(q[0].x - q[2].x, q[0].y - q[2].y)});
  // The piece's height over P at a point of its projection (affine).
  const double area_q = std::abs(area);
  auto piece_height = [&](const V2& x) {
    return (orient2(q[1], q[2], x) * hq[0] + orient2(q[2], q[0], x) * hq[1] + orient2(q[0], q[1], x) * hq[2]) / area_q;
  };
  // A surface triangle within `limit` of a point of the piece along P's
  // normal meets the prism the piece sweeps along it, so the prism's box:
  // the piece's box grown by limit |n_d| along each axis d (and a margin
  // for the doubles of the gaps).
  Point3d lo = piece[0], hi = piece[0];
  double scale = 0;
  for (const Point3d& c : piece)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], c[d]);
      hi[d] = std::max(hi[d], c[d]);
      scale = std::max(scale, std::abs(c[d]));
    }
  const double margin = 1e-9 * (scale + limit);
  for (int d = 0; d < 3; ++d) {
    const double grow = limit * std::abs(d == 0 ? f.n.x : d == 1 ? f.n.y : f.n.z) + margin;
    lo[d] -= grow;
    hi[d] += grow;
  }
  struct Side {  // a side of an accepted triangle: its ends (sorted), where its third corner lies
    Point3d a, b;
    V2 a2, b2;
    double third;
  };
  struct Clip {  // a point of the projection and the height gap there (triangle minus piece)
    V2 x;
    double gap;
  };
  std::vector<Side> sides;
  std::vector<Clip> poly, next;
  double bound = 0;
  bool covered = false;
  const V2 centroid{(q[0].x + q[1].x + q[2].x) / 3, (q[0].y + q[1].y + q[2].y) / 3};
  const std::optional<std::vector<std::size_t>> near_piece = triangles_near(lo, hi, most);
  if (!near_piece) return kNone;
  for (std::size_t s : *near_piece) {
    if (impl_->degenerate[s]) continue;
    const K::Triangle_3& tri = impl_->triangles[s];
    std::array<Point3d, 3> p;
    std::array<V2, 3> p2;
    poly.clear();
    for (int k = 0; k < 3; ++k) {
      p[k] = {tri[k].x(), tri[k].y(), tri[k].z()};
      const V3 v = v3(tri[k]);
      p2[k] = f.at(v);
      poly.push_back({p2[k], f.height(v) - piece_height(p2[k])});
    }
    const double a2 = orient2(p2[0], p2[1], p2[2]);
    if (a2 == 0) continue;  // covers nothing
    // The gap is affine over the triangle's projection: over its part
    // inside the piece's projection (Sutherland-Hodgman against the
    // piece's three sides) its largest size is at a corner of that part.
    for (int e = 0; e < 3 && !poly.empty(); ++e) {
      const V2 &qa = q[e], &qb = q[(e + 1) % 3];
      next.clear();
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Clip &c = poly[i], &d = poly[(i + 1) % poly.size()];
        const double fc = orient2(qa, qb, c.x), fd = orient2(qa, qb, d.x);
        if (fc >= 0) next.push_back(c);
        if ((fc > 0 && fd < 0) || (fc < 0 && fd > 0)) {
          const double w = fc / (fc - fd);
          next.push_back({{c.x.x + w * (d.x.x - c.x.x), c.x.y + w * (d.x.y - c.x.y)}, c.gap + w * (d.gap - c.gap)});
        }
      }
      poly.swap(next);
    }
    // Does not meet the piece's projection (a part along its rim only
    // counts: the gap there is a true one, and leaving out a triangle that
    // does meet the open projection would only fail the cover test).
    if (poly.size() < 3) continue;
    double gap = 0;
    for (const Clip& c : poly) gap = std::max(gap, std::abs(c.gap));
    if (gap > limit) continue;  // too far to help
    bound = std::max(bound, gap);
    if (!covered) {
      std::array<V2, 3> ccw = p2;
      if (a2 < 0) std::swap(ccw[1], ccw[2]);
      covered = strictly_inside(centroid, ccw);
    }
    for (int k = 0; k < 3; ++k) {
      int i = k, j = (k + 1) % 3;
      if (p[j] < p[i]) std::swap(i, j);
      sides.push_back({p[i], p[j], p2[i], p2[j], orient2(p2[i], p2[j], p2[3 - i - j])});
    }
  }
  if (!covered) return kNone;
  // The boundary of U: sides with accepted triangles on one side of them only.
  std::sort(sides.begin(), sides.end(),
            [](const Side& x, const Side& y) { return std::tie(x.a, x.b) < std::tie(y.a, y.b); });
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    bool left = false, right = false;
    for (; j < sides.size() && sides[j].a == sides[i].a && sides[j].b == sides[i].b; ++j) {
      left |= sides[j].third > 0;
      right |= sides[j].third < 0;
    }
    if (!(left && right) && meets_interior(sides[i].a2, sides[i].b2, q, near)) return kNone;
    i = j;
  }
  return bound + 2 * near;
}

std::pair<double, std::size_t> SurfaceDistance::nearest(const Point3d& p) const {
  return impl_->bvh->nearest({p[0], p[1], p[2]}, std::numeric_limits<double>::infinity(), 0);
}

std::pair<double, std::size_t> SurfaceDistance::nearest(const Point3d& p, std::size_t hint) const {
  const V3 q{p[0], p[1], p[2]};
  // the hint's own distance prunes the search; only a nearer triangle replaces it
  return impl_->bvh->nearest(q, impl_->bvh->distance2(q, hint), hint);
}

double SurfaceDistance::squared_distance_to(const Point3d& p, std::size_t t) const {
  return distance2(point(p), impl_->triangles[t], impl_->degenerate[t] != 0);
}

double SurfaceDistance::squared_distance(const Point3d& p) const {
  if (impl_->triangles.empty()) return 0.0;
  return nearest(p).first;
}

namespace {
struct Box3 {
  Point3d lo, hi;
};
bool overlap(const Box3& a, const Box3& b) {
  for (int k = 0; k < 3; ++k)
    if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return false;
  return true;
}
/// Triangle t's bounding box, grown by `grow` (and then rounded outward).
Box3 box_of(const Corners& t, double grow) {
  Box3 b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = std::min({t[0][k], t[1][k], t[2][k]});
    b.hi[k] = std::max({t[0][k], t[1][k], t[2][k]});
    if (grow > 0) {
      b.lo[k] = std::nextafter(b.lo[k] - grow, -HUGE_VAL);
      b.hi[k] = std::nextafter(b.hi[k] + grow, HUGE_VAL);
    }
  }
  return b;
}

/// A few boxes in a static tree (median splits): does any meet a box?
class BoxTree {
 public:
  explicit BoxTree(std::vector<Box3> boxes) : boxes_(std::move(boxes)) {
    if (!boxes_.empty()) build(0, boxes_.size());
  }
  bool meets(const Box3& b) const {
    if (nodes_.empty()) return false;
    std::int32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[std::size_t(stack[--top])];
      if (!overlap(n.box, b)) continue;
      if (n.left < 0) {
        for (std::size_t i = n.first; i < n.last; ++i)
          if (overlap(boxes_[i], b)) return true;
        continue;
      }
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
    return false;
  }

 private:
  struct Node {
    Box3 box;
    std::int32_t left = -1, right = -1;  // children; leaves: boxes_[first, last)
    std::size_t first = 0, last = 0;
  };
  std::int32_t build(std::size_t first, std::size_t last) {  // depth about log2(n / 4): far below 64
    const std::int32_t id = static_cast<std::int32_t>(nodes_.size());
    nodes_.emplace_back();
    Box3 all = boxes_[first];
    for (std::size_t i = first; i < last; ++i)
      for (int k = 0; k < 3; ++k) {
        all.lo[k] = std::min(all.lo[k], boxes_[i].lo[k]);
        all.hi[k] = std::max(all.hi[k], boxes_[i].hi[k]);
      }
    nodes_[std::size_t(id)].box = all;
    if (last - first <= 4) {
      nodes_[std::size_t(id)].first = first;
      nodes_[std::size_t(id)].last = last;
      return id;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (all.hi[k] - all.lo[k] > all.hi[axis] - all.lo[axis]) axis = k;
    const std::size_t mid = first + (last - first) / 2;
    std::nth_element(boxes_.begin() + std::ptrdiff_t(first), boxes_.begin() + std::ptrdiff_t(mid),
                     boxes_.begin() + std::ptrdiff_t(last), [axis](const Box3& x, const Box3& y) {
                       return x.lo[axis] + x.hi[axis] < y.lo[axis] + y.hi[axis];
                     });
    const std::int32_t l = build(first, mid), r = build(mid, last);
    nodes_[std::size_t(id)].left = l;
    nodes_[std::size_t(id)].right = r;
    return id;
  }
  std::vector<Box3> boxes_;
  std::vector<Node> nodes_;
};

/// The triangles of `a` that `b` lacks and those of `b` that `a` lacks,
/// counted with multiplicity (k copies in one, j in the other: k - j
/// copies) and sorted: what std::set_difference of the two sorted lists
/// gives, both ways. By one flat hash table over b's triangles (the first
/// copy of each, with how many of its copies a has not matched): sorting
/// both soups for this was 0.8 s of measuring a hole-filled 1M-face scan.
/// (Canonical triangles compare as doubles: -0.0 == 0.0, and hash alike.)
void differences(const std::vector<Corners>& a, const std::vector<Corners>& b, std::vector<Corners>* only_a,
                 std::vector<Corners>* only_b) {
  auto hashes = [](const std::vector<Corners>& t) {
    std::vector<std::uint64_t> h(t.size());
    tbb::parallel_for(std::size_t(0), t.size(), [&](std::size_t i) { h[i] = hash_points(t[i].data(), 3); });
    return h;
  };
  std::vector<Index> table = empty_table(b.size());
  std::vector<Index> unmatched(b.size(), 0);  // by first copy
  {
    const std::vector<std::uint64_t> hb = hashes(b);
    for (std::size_t i = 0; i < b.size(); ++i) {
      const std::size_t slot = probe(table, hb[i], [&](std::size_t s) { return b[table[s]] == b[i]; });
      if (table[slot] == kEmptySlot) table[slot] = static_cast<Index>(i);
      ++unmatched[table[slot]];
    }
  }
  const std::vector<std::uint64_t> ha = hashes(a);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const std::size_t slot = probe(table, ha[i], [&](std::size_t s) { return b[table[s]] == a[i]; });
    if (table[slot] != kEmptySlot && unmatched[table[slot]] > 0) --unmatched[table[slot]];
    else if (only_a) only_a->push_back(a[i]);
  }
  if (only_a) tbb::parallel_sort(only_a->begin(), only_a->end());
  if (!only_b) return;
  for (std::size_t i = 0; i < b.size(); ++i) only_b->insert(only_b->end(), unmatched[i], b[i]);
  tbb::parallel_sort(only_b->begin(), only_b->end());
}

/// The triangles of `to` that can hold the nearest point of `to` to a point
/// of a triangle of `from`, when each triangle of `from` has a corner that
/// is a corner of `to` (hole fills, local moves): a point of such a triangle
/// is within its longest edge of that corner, so its nearest point of `to`
/// lies in the triangle's box grown by that edge, in a triangle of `to`
/// whose box meets that box: those, into `out`. Otherwise false. Distances
/// from `from` to these equal those to `to` (and bounds on them found with
/// fewer triangles still hold): a repair that changed a few faces of a
/// large input is measured without indexing the whole input (0.43 s of a
/// hole-filled 1M-face scan's measure).
bool reachable(const std::vector<Corners>& to, const std::vector<Corners>& from, std::vector<Corners>& out) {
  if (from.empty() || 4 * from.size() > to.size()) return false;  // no gain to speak of
  // from's corners, and which of them are corners of `to`
  std::vector<Point3d> corner;
  for (const Corners& t : from) corner.insert(corner.end(), t.begin(), t.end());
  std::vector<Index> table = empty_table(corner.size());
  for (std::size_t i = 0; i < corner.size(); ++i) {
    const std::size_t slot =
        probe(table, hash_points(&corner[i], 1), [&](std::size_t s) { return corner[table[s]] == corner[i]; });
    if (table[slot] == kEmptySlot) table[slot] = static_cast<Index>(i);
  }
  std::vector<char> on_to(corner.size(), 0);  // by first copy
  for (const Corners& t : to)
    for (const Point3d& p : t) {
      const std::size_t slot = probe(table, hash_points(&p, 1), [&](std::size_t s) { return corner[table[s]] == p; });
      if (table[slot] != kEmptySlot) on_to[table[slot]] = 1;
    }
  std::vector<Box3> grown;
  for (std::size_t f = 0; f < from.size(); ++f) {
    bool cornered = false;
    for (std::size_t k = 3 * f; k < 3 * f + 3; ++k)  // (every corner is in the table)
      cornered = cornered || on_to[table[probe(table, hash_points(&corner[k], 1),
                                               [&](std::size_t s) { return corner[table[s]] == corner[k]; })]];
    if (!cornered) return false;
    const Corners& t = from[f];
    // (the edge in doubles, taken a little longer)
    const double edge = std::max({norm(t[0], t[1]), norm(t[1], t[2]), norm(t[2], t[0])});
    grown.push_back(box_of(t, edge * (1 + 1e-9) + std::numeric_limits<double>::min()));
  }
  const BoxTree tree(std::move(grown));
  std::vector<char> near(to.size(), 0);
  tbb::parallel_for(std::size_t(0), to.size(), [&](std::size_t i) { near[i] = tree.meets(box_of(to[i], 0)); });
  out.clear();
  for (std::size_t i = 0; i < to.size(); ++i)
    if (near[i]) out.push_back(to[i]);
  return true;
}

/// From `from` (triangles of a soup that the other lacks) to the surface `to`.
double measured(const std::vector<Corners>& from, const std::vector<Corners>& to, double error_bound,
                const std::function<bool(const Point3d&)>* skip = nullptr) {
  if (from.empty()) return 0.0;
  std::vector<Corners> near;
  return one_sided(from, SurfaceDistance(reachable(to, from, near) ? near : to), error_bound, skip);
}

/// Two soups' triangles, and those of each that the other lacks. A triangle
/// present in both soups is at distance 0 from the other, so each direction
/// needs only the triangles the other soup lacks: a repair that changed
/// little is measured in time proportional to what it changed.
struct Differing {
  std::vector<Corners> ta, tb, only_a, only_b;
  Differing(const Soup& a, const Soup& b) : ta(triangles_of(a)), tb(triangles_of(b)) {
    differences(ta, tb, &only_a, &only_b);
  }
  /// One soup is empty and the other is not.
  bool unmeasurable() const { return (ta.empty() && !only_b.empty()) || (tb.empty() && !only_a.empty()); }
};
}  // namespace

std::array<double, 2> one_sided_distances(const Soup& a, const Soup& b, double error_bound) {
  const Differing d(a, b);
  if (d.unmeasurable()) return {-1.0, -1.0};
  // The two directions are independent (each builds its own tree): one per
  // core, deterministic whatever the scheduling.
  double ab = 0.0, ba = 0.0;
  tbb::parallel_invoke([&] { ab = measured(d.only_a, d.tb, error_bound); },
                       [&] { ba = measured(d.only_b, d.ta, error_bound); });
  return {ab, ba};
}

double hausdorff_distance(const Soup& a, const Soup& b, double error_bound, double b_to_a_at_most) {
  const Differing d(a, b);
  if (d.unmeasurable()) return -1.0;
  const double ab = measured(d.only_a, d.tb, error_bound);
  // b -> a lies in [0, b_to_a_at_most]: at most ab, it changes nothing
  return b_to_a_at_most <= ab ? ab : std::max(ab, measured(d.only_b, d.ta, error_bound));
}

namespace {
/// From a to b only (points where `skip` holds, if given, do not count).
double one_way(const Soup& a, const Soup& b, double error_bound, const std::function<bool(const Point3d&)>* skip) {
  const std::vector<Corners> ta = triangles_of(a), tb = triangles_of(b);
  std::vector<Corners> only_a;
  differences(ta, tb, &only_a, nullptr);
  if (tb.empty() && !only_a.empty()) return -1.0;
  return measured(only_a, tb, error_bound, skip);
}
}  // namespace

double one_sided_distance(const Soup& a, const Soup& b, double error_bound) {
  return one_way(a, b, error_bound, nullptr);
}

double one_sided_distance_skipping(const Soup& a, const Soup& b, double error_bound,
                                   const std::function<bool(const Point3d&)>& skip) {
  return one_way(a, b, error_bound, &skip);
}

double hausdorff_distance(const Soup& a, const Soup& b, double error_bound) {
  const std::array<double, 2> d = one_sided_distances(a, b, error_bound);
  return std::max(d[0], d[1]);
}

}  // namespace polyheal::detail
