#include "polyheal/inspect/self_intersections.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include <CGAL/box_intersection_d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "polyheal/inspect/detail/parallel.h"
#include "polyheal/mesh/hash.h"
#include "polyheal/inspect/predicates.h"
#include "polyheal/inspect/detail/triangle_pair.h"

namespace polyheal {
namespace {

using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t, CGAL::Box_intersection_d::ID_EXPLICIT>;
// As in PMP::self_intersections: below this many boxes the segment tree scans
// (much faster than the default 10 on surface meshes).
constexpr std::ptrdiff_t kCutoff = 2000;
// The spatial split (box_pairs) stops at this many boxes; they are swept
// without counting the pairs first (at most kLeaf^2 / 2 of them).
constexpr std::size_t kLeaf = 1024;
// A sweep that would test more candidate pairs than this per box (its
// boxes overlap along every axis: a plane of small faces across it) hands
// them to CGAL's box_intersection_d instead.
constexpr std::size_t kSweepBudget = 128;
// Checks of a few flagged faces: up to this many box tests done directly.
constexpr std::size_t kDirectPairs = std::size_t(1) << 21;
// flagged_pairs() splits this many flagged boxes or more, when asked to.
constexpr std::size_t kSplitFlagged = 1024;
using Traits = CGAL::Box_intersection_d::Box_traits_d<const Box*>;
using Tri = detail::Tri<InputKernel>;

/// A triangle of the (fan-triangulated) soup and the face it came from.
struct FanTriangle {
  Index v[3];
  std::uint32_t face;
};

std::vector<FanTriangle> fan_triangles(const Soup& s) {
  std::vector<FanTriangle> t;
  t.reserve(s.indices.size() - 2 * s.face_count());
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    FaceView v = s.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k) t.push_back({{v[0], v[k], v[k + 1]}, static_cast<std::uint32_t>(f)});
  }
  return t;
}

InputKernel::Point_3 point(const Soup& s, Index i) {
  const Point3d& p = s.points[i];
  return {p[0], p[1], p[2]};
}

Tri exact_triangle(const Soup& s, const FanTriangle& t, bool degenerate) {
  return Tri{{point(s, t.v[0]), point(s, t.v[1]), point(s, t.v[2])}, {t.v[0], t.v[1], t.v[2]}, degenerate};
}

/// The box of points[i] for i in `ids`, grown by `grow` on every side and
/// then rounded outward (grow 0: the points' own box, exactly).
Box box_around(const std::vector<Point3d>& points, std::initializer_list<Index> ids, double grow, std::uint32_t id) {
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    lo[c] = std::numeric_limits<double>::infinity();
    hi[c] = -lo[c];
    for (Index i : ids) {
      lo[c] = std::min(lo[c], points[i][c]);
      hi[c] = std::max(hi[c], points[i][c]);
    }
    if (grow > 0) {
      lo[c] = std::nextafter(lo[c] - grow, -std::numeric_limits<double>::infinity());
      hi[c] = std::nextafter(hi[c] + grow, std::numeric_limits<double>::infinity());
    }
  }
  return Box(lo, hi, id);
}

/// Box pointers for the algorithm, which copies and reorders its input.
std::vector<const Box*> pointers_to(const std::vector<Box>& boxes) {
  std::vector<const Box*> pointers(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) pointers[i] = &boxes[i];
  return pointers;
}

/// Degeneracy (exact collinearity) of each triangle, decided when a pair
/// first needs it and kept (from any thread): a check of a few changed faces
/// (`only`) asks it of the faces near them, not of the whole soup.
class DegenerateFlags {
 public:
  DegenerateFlags(const Soup& s, const std::vector<FanTriangle>& tris) : s_(s), tris_(tris), known_(tris.size()) {}
  bool operator()(std::size_t i) const {
    char k = known_[i].load(std::memory_order_relaxed);  // 0: not yet, 1: no, 2: yes
    if (k == 0) {
      const FanTriangle& t = tris_[i];
      k = CGAL::collinear(point(s_, t.v[0]), point(s_, t.v[1]), point(s_, t.v[2])) ? 2 : 1;
      known_[i].store(k, std::memory_order_relaxed);
    }
    return k == 2;
  }

 private:
  const Soup& s_;
  const std::vector<FanTriangle>& tris_;
  mutable std::vector<std::atomic<char>> known_;
};

/// A box seen along a sweep axis: its range there, then its ranges on the
/// other two axes, and the box.
struct Swept {
  double lo, hi, lo1, hi1, lo2, hi2;
  const Box* box;
};

/// The axis along which the boxes of `boxes` and `more` together overlap
/// least: where their extents are smallest for the range they spread over
/// (a surface of small faces is swept along its longest side; a flat region
/// is never swept across).
int sweep_axis(const std::vector<const Box*>& boxes, const std::vector<const Box*>& more = {}) {
  double lo[3], hi[3], extent[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::infinity();
    hi[a] = -lo[a];
  }
  for (const std::vector<const Box*>* list : {&boxes, &more})
    for (const Box* b : *list)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], b->min_coord(a));
        hi[a] = std::max(hi[a], b->max_coord(a));
        extent[a] += b->max_coord(a) - b->min_coord(a);
      }
  int axis = 0;
  double least = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a)
    if (hi[a] > lo[a] && extent[a] / (hi[a] - lo[a]) < least) {
      least = extent[a] / (hi[a] - lo[a]);
      axis = a;
    }
  return axis;
}

/// `boxes` seen along `axis`, sorted by their lower bound there.
std::vector<Swept> swept(const std::vector<const Box*>& boxes, int axis) {
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  std::vector<Swept> out;
  out.reserve(boxes.size());
  for (const Box* x : boxes)
    out.push_back({x->min_coord(axis), x->max_coord(axis), x->min_coord(b), x->max_coord(b), x->min_coord(c),
                   x->max_coord(c), x});
  std::sort(out.begin(), out.end(), [](const Swept& x, const Swept& y) { return x.lo < y.lo; });
  return out;
}

/// Closed ranges meeting on the two axes other than the sweep's.
inline bool meet_across(const Swept& x, const Swept& y) {
  return x.lo1 <= y.hi1 && y.lo1 <= x.hi1 && x.lo2 <= y.hi2 && y.lo2 <= x.hi2;
}

using SweptIt = std::vector<Swept>::const_iterator;
/// The first of [from, end) (sorted) with lo > t.
inline SweptIt first_above(SweptIt from, SweptIt end, double t) {
  return std::upper_bound(from, end, t, [](double u, const Swept& y) { return u < y.lo; });
}

/// Every overlapping pair of `boxes` (closed boxes, as CGAL's default),
/// each once, by sweep and prune: sorted along the sweep axis, a box is
/// paired with those after it that start before it ends, and kept when its
/// other two ranges meet theirs. Cheap where few boxes overlap along the
/// axis — a part of a surface that the spatial split left (box_pairs). More
/// than kLeaf boxes are counted first: false (nothing called) when the
/// sweep would test more than kSweepBudget pairs a box.
template <class Callback>
bool sweep_self(const std::vector<const Box*>& boxes, const Callback& callback) {
  const std::vector<Swept> w = swept(boxes, sweep_axis(boxes));
  if (w.size() > kLeaf) {
    std::size_t tests = 0;
    for (std::size_t i = 0; i < w.size(); ++i) tests += std::size_t(first_above(w.begin(), w.end(), w[i].hi) - w.begin()) - i - 1;
    if (tests > kSweepBudget * w.size()) return false;
  }
  for (std::size_t i = 0; i < w.size(); ++i)
    for (std::size_t j = i + 1; j < w.size() && w[j].lo <= w[i].hi; ++j)
      if (meet_across(w[i], w[j])) callback(w[i].box, w[j].box);
  return true;
}

/// Every overlapping pair of an `a` box and a `b` box, as callback(a, b),
/// by sweep and prune: a pair whose a box starts first (or with it) is
/// found from that box (b's lower bound within a's range), the others from
/// their b box. False (nothing called) over kSweepBudget pairs a box.
template <class Callback>
bool sweep_cross(const std::vector<const Box*>& a, const std::vector<const Box*>& b, const Callback& callback) {
  const int axis = sweep_axis(a, b);
  const std::vector<Swept> wa = swept(a, axis), wb = swept(b, axis);
  // [first, last) of the other list's boxes that start in x's range:
  // from x's lower bound on (`from_equal`), or strictly after it
  auto ranges = [](const std::vector<Swept>& xs, const std::vector<Swept>& ys, bool from_equal) {
    std::vector<std::array<std::size_t, 2>> r(xs.size());
    for (std::size_t i = 0; i < xs.size(); ++i) {
      const auto first =
          from_equal ? std::lower_bound(ys.begin(), ys.end(), xs[i].lo,
                                        [](const Swept& y, double u) { return y.lo < u; })
                     : first_above(ys.begin(), ys.end(), xs[i].lo);
      const auto last = first_above(first, ys.end(), xs[i].hi);
      r[i] = {std::size_t(first - ys.begin()), std::size_t(last - ys.begin())};
    }
    return r;
  };
  const auto from_a = ranges(wa, wb, true), from_b = ranges(wb, wa, false);
  std::size_t tests = 0;
  for (const auto& r : from_a) tests += r[1] - r[0];
  for (const auto& r : from_b) tests += r[1] - r[0];
  if (tests > kSweepBudget * (wa.size() + wb.size())) return false;
  for (std::size_t i = 0; i < wa.size(); ++i)
    for (std::size_t k = from_a[i][0]; k < from_a[i][1]; ++k)
      if (meet_across(wa[i], wb[k])) callback(wa[i].box, wb[k].box);
  for (std::size_t i = 0; i < wb.size(); ++i)
    for (std::size_t k = from_b[i][0]; k < from_b[i][1]; ++k)
      if (meet_across(wb[i], wa[k])) callback(wa[k].box, wb[i].box);
  return true;
}

/// All intersecting pairs of `boxes` through `callback`, each once: swept
/// (sweep_self), or by CGAL's sequential box_self_intersection_d where a
/// sweep would test too many. `boxes` may be reordered.
template <class Callback>
void self_pairs(std::vector<const Box*>& boxes, const Callback& callback) {
  if (!sweep_self(boxes, callback))
    CGAL::box_self_intersection_d<CGAL::Sequential_tag>(boxes.begin(), boxes.end(), callback, Traits(), kCutoff);
}

/// All intersecting pairs of `boxes` through `callback`, each once.
///
/// Split at the median box centre along the widest axis into L (boxes
/// entirely below the split value), R (entirely above) and S (straddling
/// it). An L box and an R box cannot overlap, so
///   pairs(X) = pairs(L) + pairs(R) + pairs(S) + S x L + S x R,
/// with pairs(L), pairs(R) split again down to kLeaf boxes (with
/// `parallel`, the halves at every level as tasks: the two cores share the
/// parts to the end), and only the L and R boxes
/// reaching S's range along the axis paired with S. The parts are swept
/// (sweep_self, sweep_cross): on a surface of small faces, a part's boxes
/// overlap few others along its sweep axis (Hand1's raw offset regularized,
/// 168k faces: ~50 candidate pairs a box at 1024, against 300-500 in the
/// four parts of 42k), where CGAL's segment tree over the four parts cost
/// more (check on that output: self-intersections 0.33 -> 0.28 s; on a
/// torus-knot tube of 1M faces 1.02 -> 0.61 s). Unlike CGAL's
/// own Parallel_tag (four input-order chunks, sixteen block pairs, each
/// re-sorted), the parts are disjoint in space, so the work does not grow
/// with the split.
template <class Callback>
void box_pairs(std::vector<const Box*>& boxes, const Callback& callback, bool parallel, bool split = false) {
  // Where no split is made at all (fewer than 20000 boxes, or too many
  // straddling), the pairs are tested in parallel all the same when
  // `parallel`: the boxes are paired first, in batches, and each
  // batch's tests are shared out (a small surface of costly pairs — the
  // large coplanar fans of a coarsened one — is all narrow phase).
  auto unsplit = [&](std::vector<const Box*>& v) {
    if (!parallel || split) return self_pairs(v, callback);
    constexpr std::size_t kBatch = std::size_t(1) << 16;
    std::vector<std::pair<const Box*, const Box*>> batch;
    auto test = [&] {
      tbb::parallel_for(std::size_t(0), batch.size(),
                        [&](std::size_t i) { callback(batch[i].first, batch[i].second); });
      batch.clear();
    };
    self_pairs(v, [&](const Box* x, const Box* y) {
      batch.emplace_back(x, y);
      if (batch.size() == kBatch) test();
    });
    test();
  };
  if (boxes.size() <= kLeaf || (!split && parallel && boxes.size() < 20000)) return unsplit(boxes);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::infinity();
    hi[a] = -lo[a];
  }
  auto centre = [](const Box* b, int a) { return 0.5 * b->min_coord(a) + 0.5 * b->max_coord(a); };
  for (const Box* b : boxes)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], centre(b, a));
      hi[a] = std::max(hi[a], centre(b, a));
    }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  auto mid = boxes.begin() + static_cast<std::ptrdiff_t>(boxes.size() / 2);
  std::nth_element(boxes.begin(), mid, boxes.end(),
                   [&](const Box* p, const Box* q) { return centre(p, axis) < centre(q, axis); });
  const double split_at = centre(*mid, axis);
  std::vector<const Box*> below, above, straddling;
  double reach_lo = std::numeric_limits<double>::infinity(), reach_hi = -reach_lo;  // S's range along the axis
  for (const Box* b : boxes) {
    if (b->max_coord(axis) < split_at) {
      below.push_back(b);
    } else if (b->min_coord(axis) > split_at) {
      above.push_back(b);
    } else {
      straddling.push_back(b);
      reach_lo = std::min(reach_lo, b->min_coord(axis));
      reach_hi = std::max(reach_hi, b->max_coord(axis));
    }
  }
  if (straddling.size() > boxes.size() / 4) return unsplit(boxes);  // no useful split
  std::vector<const Box*>().swap(boxes);
  // box_intersection_d reorders its inputs: each task gets its own copy of S.
  std::vector<const Box*> straddling_copy = straddling;
  auto cross = [&](std::vector<const Box*>& s, const std::vector<const Box*>& side) {
    std::vector<const Box*> near;
    for (const Box* b : side)
      if (b->max_coord(axis) >= reach_lo && b->min_coord(axis) <= reach_hi) near.push_back(b);
    if (!sweep_cross(s, near, callback))
      CGAL::box_intersection_d<CGAL::Sequential_tag>(s.begin(), s.end(), near.begin(), near.end(), callback, Traits(),
                                                     kCutoff);
  };
  auto lower = [&] {
    cross(straddling, below);
    box_pairs(below, callback, parallel, true);
  };
  auto upper = [&] {
    cross(straddling_copy, above);
    self_pairs(straddling_copy, callback);
    box_pairs(above, callback, parallel, true);
  };
  if (parallel) {
    tbb::parallel_invoke(lower, upper);
  } else {
    lower();
    upper();
  }
}

/// The boxes of `boxes` that meet a cell of a grid over `reach` that one of
/// `flagged` meets (all those that meet a flagged box, and some near them).
/// Cells about the size of the flagged boxes' spread over `reach`: eight per
/// flagged box, up to 64 along an axis. A box meeting a flagged one shares a
/// point with it, and the cell of that point (floor is monotone) is marked.
std::vector<const Box*> near_flagged_cells(const std::vector<const Box*>& flagged, const CGAL::Bbox_3& reach,
                                           const std::vector<const Box*>& boxes) {
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, reach.max(a) - reach.min(a));
  const double per_axis = std::min(64.0, std::ceil(std::cbrt(8.0 * double(flagged.size()))));
  if (!(longest > 0) || per_axis < 2) return boxes;
  const double size = longest / per_axis;
  int n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, std::min(64, int(std::ceil((reach.max(a) - reach.min(a)) / size))));
  auto cell = [&](double x, int a) { return std::clamp(int(std::floor((x - reach.min(a)) / size)), 0, n[a] - 1); };
  std::vector<char> marked(std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]), 0);
  // Calls visit(index) for each cell box b meets; stops when it returns true.
  auto cells_of = [&](const Box* b, auto visit) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = cell(b->min_coord(a), a);
      hi[a] = cell(b->max_coord(a), a);
    }
    for (int i = lo[0]; i <= hi[0]; ++i)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int k = lo[2]; k <= hi[2]; ++k)
          if (visit((std::size_t(i) * std::size_t(n[1]) + std::size_t(j)) * std::size_t(n[2]) + std::size_t(k)))
            return true;
    return false;
  };
  for (const Box* b : flagged)
    cells_of(b, [&](std::size_t c) {
      marked[c] = 1;
      return false;
    });
  std::vector<const Box*> out;
  for (const Box* b : boxes)
    if (cells_of(b, [&](std::size_t c) { return marked[c] != 0; })) out.push_back(b);
  return out;
}

/// Every overlapping pair of a `flagged` box with one of `others` through
/// `callback(flagged, other)` (a box in both is paired with itself; a pair of
/// two flagged boxes comes twice). Only boxes meeting the flagged ones' union
/// can pair with one; a few flagged boxes (an edit's) are paired by direct
/// box tests: sorting the whole soup's boxes for them cost more than the tests
/// (rebuild's clean-region rounds: 38 checks of ~10 faces against 100k).
/// Many flagged boxes (rebuild's kept regions: thousands of faces) are split
/// at their median along the widest axis of their union, `depth` levels,
/// and the halves paired in parallel, each with the boxes meeting its own
/// union: every pair still comes once (`callback` is called from any thread).
/// The parts are swept against their near boxes (sweep_cross), or paired by
/// CGAL's segment tree where a sweep would test too many.
template <class Callback>
void flagged_pairs(std::vector<const Box*>& flagged, const std::vector<const Box*>& others, const Callback& callback,
                   int depth) {
  if (flagged.empty()) return;
  CGAL::Bbox_3 reach;
  for (const Box* b : flagged) reach += b->bbox();
  std::vector<const Box*> near;
  for (const Box* b : others)
    if (CGAL::do_overlap(b->bbox(), reach)) near.push_back(b);
  // Flagged boxes spread over the soup (rebuild's kept regions, all over a
  // surface): their union meets most others; only those in cells a flagged
  // box meets are sorted with them.
  if (near.size() > 4 * flagged.size() && flagged.size() * near.size() > kDirectPairs)
    near = near_flagged_cells(flagged, reach, near);
  if (flagged.size() * near.size() <= kDirectPairs) {
    for (const Box* x : flagged)
      for (const Box* y : near)
        if (CGAL::do_overlap(x->bbox(), y->bbox())) callback(x, y);
    return;
  }
  if (depth > 0 && flagged.size() >= kSplitFlagged) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (reach.max(a) - reach.min(a) > reach.max(axis) - reach.min(axis)) axis = a;
    auto centre = [axis](const Box* b) { return 0.5 * b->min_coord(axis) + 0.5 * b->max_coord(axis); };
    const auto mid = flagged.begin() + static_cast<std::ptrdiff_t>(flagged.size() / 2);
    std::nth_element(flagged.begin(), mid, flagged.end(),
                     [&](const Box* p, const Box* q) { return centre(p) < centre(q); });
    std::vector<const Box*> lower(flagged.begin(), mid), upper(mid, flagged.end());
    tbb::parallel_invoke([&] { flagged_pairs(lower, near, callback, depth - 1); },
                         [&] { flagged_pairs(upper, near, callback, depth - 1); });
    return;
  }
  if (!sweep_cross(flagged, near, callback))
    CGAL::box_intersection_d<CGAL::Sequential_tag>(flagged.begin(), flagged.end(), near.begin(), near.end(), callback,
                                                   Traits(), kCutoff);
}

/// Runs the broad phase and calls `found(a, b)` for each intersecting pair of
/// fan triangles (from any thread). `stop` ends the search early.
template <class Found>
void scan(const Soup& s, const SelfIntersectionOptions& o, Found found, const std::atomic<bool>& stop) {
  const std::vector<FanTriangle> tris = fan_triangles(s);
  const DegenerateFlags degenerate(s, tris);
  std::vector<Box> boxes;
  boxes.reserve(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i)
    boxes.push_back(box_around(s.points, {tris[i].v[0], tris[i].v[1], tris[i].v[2]}, 0, static_cast<std::uint32_t>(i)));
  if (o.observer) o.observer->stage("self-intersections");
  std::vector<const Box*> pointers = pointers_to(boxes);
  auto callback = [&](const Box* px, const Box* py) {
    const Box &x = *px, &y = *py;
    if (stop.load(std::memory_order_relaxed)) return;
    const FanTriangle &a = tris[x.info()], &b = tris[y.info()];
    if (a.face == b.face) return;  // two fan triangles of one polygon
    if (detail::faces_intersect<InputKernel>(exact_triangle(s, a, degenerate(x.info())),
                                             exact_triangle(s, b, degenerate(y.info()))))
      found(a.face, b.face);
  };
  if (o.only) {
    std::vector<const Box*> flagged;
    for (const Box* b : pointers)
      if ((*o.only)[tris[b->info()].face]) flagged.push_back(b);
    // Flagged faces a large part of the soup (regularize's rounding check:
    // every face with a corner on an intersection curve, half the output):
    // one self scan of all the boxes, the pairs without a flagged face
    // dropped before the exact test, costs less than pairing the flagged
    // boxes with the rest (Hand1's raw offset: 91k of 168k faces, 0.23 ->
    // 0.17 s). The same pairs either way.
    if (4 * flagged.size() > pointers.size()) {
      auto flagged_face = [&](const Box* b) { return (*o.only)[tris[b->info()].face] != 0; };
      box_pairs(
          pointers,
          [&](const Box* x, const Box* y) {
            if (flagged_face(x) || flagged_face(y)) callback(x, y);
          },
          o.parallel);
      return;
    }
    flagged_pairs(
        flagged, pointers,
        [&](const Box* x, const Box* y) {
          if (x != y) callback(x, y);
        },
        o.parallel ? 2 : 0);
    return;
  }
  box_pairs(pointers, callback, o.parallel);
}

}  // namespace

std::vector<FacePair> find_self_intersections(const Soup& soup, const SelfIntersectionOptions& options) {
  tbb::enumerable_thread_specific<std::vector<FacePair>> local;
  std::atomic<bool> stop{false};
  scan(soup, options,
       [&](std::size_t f, std::size_t g) { local.local().push_back({std::min(f, g), std::max(f, g)}); }, stop);
  std::vector<FacePair> pairs;
  for (auto& v : local) pairs.insert(pairs.end(), v.begin(), v.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // polygons: several fan pairs
  return pairs;
}

std::optional<std::vector<FacePair>> find_self_intersections_from(const Soup& soup, const Soup& base,
                                                                  const std::vector<FacePair>& base_pairs,
                                                                  double most, std::size_t* changed_faces) {
  using Key = std::array<Point3d, 3>;
  auto key = [](const Soup& s, std::size_t f) {
    const FaceView v = s.face(f);
    return sorted_corners(s.points[v[0]], s.points[v[1]], s.points[v[2]]);
  };
  // base's triangles by their corners: the first of each (copies meet the
  // same faces, but for each other)
  std::vector<Key> base_key(base.face_count());
  std::vector<std::uint64_t> base_hash(base.face_count());
  tbb::parallel_for(std::size_t(0), base.face_count(), [&](std::size_t f) {
    if (base.face(f).size() != 3) return;
    base_key[f] = key(base, f);
    base_hash[f] = hash_points(base_key[f].data(), 3);
  });
  std::vector<Index> first(base.face_count(), kEmptySlot);
  std::vector<Index> table = empty_table(base.face_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    if (base.face(f).size() != 3) continue;
    const std::size_t slot = probe(table, base_hash[f], [&](std::size_t s) {
      return base_hash[table[s]] == base_hash[f] && base_key[table[s]] == base_key[f];
    });
    if (table[slot] == kEmptySlot) table[slot] = static_cast<Index>(f);
    first[f] = table[slot];
  }
  // soup's faces that are base's triangles, each taken once
  std::vector<Index> image(soup.face_count(), kEmptySlot);  // the base triangle (first copy) each face is
  tbb::parallel_for(std::size_t(0), soup.face_count(), [&](std::size_t g) {
    if (soup.face(g).size() != 3) return;
    const Key k = key(soup, g);
    const std::uint64_t h = hash_points(k.data(), 3);
    image[g] = table[probe(table, h, [&](std::size_t s) { return base_hash[table[s]] == h && base_key[table[s]] == k; })];
  });
  std::vector<char> changed(soup.face_count(), 1);
  std::vector<Index> taken(base.face_count(), kEmptySlot);  // by first copy: the soup face that is it
  std::size_t n_changed = 0;
  for (std::size_t g = 0; g < soup.face_count(); ++g) {
    const Index f = image[g];
    if (f == kEmptySlot) {
      ++n_changed;
    } else if (taken[f] == kEmptySlot) {
      taken[f] = static_cast<Index>(g);
      changed[g] = 0;
    } else {  // a copy in soup: it meets its twin
      n_changed += 1 + (changed[taken[f]] == 0);
      changed[taken[f]] = 1;
    }
    if (double(n_changed) > most * double(soup.face_count())) return std::nullopt;
  }
  if (changed_faces) *changed_faces = n_changed;
  std::vector<FacePair> pairs;
  for (const FacePair& p : base_pairs) {
    if (first[p.first] == kEmptySlot || first[p.second] == kEmptySlot) continue;  // polygons
    const Index a = taken[first[p.first]], b = taken[first[p.second]];
    if (a == kEmptySlot || b == kEmptySlot || a == b || changed[a] || changed[b]) continue;
    pairs.push_back({std::min<std::size_t>(a, b), std::max<std::size_t>(a, b)});
  }
  SelfIntersectionOptions o;
  o.only = &changed;
  const std::vector<FacePair> found = find_self_intersections(soup, o);
  pairs.insert(pairs.end(), found.begin(), found.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // base's copies pair alike
  return pairs;
}

bool does_self_intersect(const Soup& soup, const SelfIntersectionOptions& options) {
  std::atomic<bool> stop{false};
  scan(soup, options, [&](std::size_t, std::size_t) { stop = true; }, stop);
  return stop.load();
}

void for_each_point_near_edge(const std::vector<Point3d>& points, const std::vector<std::array<Index, 2>>& edges,
                              const std::vector<Index>* candidates, const std::function<double(std::size_t)>& grow,
                              const std::function<void(Index, std::size_t)>& near) {
  std::vector<Box> edge_boxes, point_boxes;
  edge_boxes.reserve(edges.size());
  for (std::size_t i = 0; i < edges.size(); ++i)
    edge_boxes.push_back(box_around(points, {edges[i][0], edges[i][1]}, grow(i), static_cast<std::uint32_t>(i)));
  auto add_point = [&](Index v) { point_boxes.push_back(box_around(points, {v}, 0, static_cast<std::uint32_t>(v))); };
  if (candidates) {
    point_boxes.reserve(candidates->size());
    for (Index v : *candidates) add_point(v);
  } else {
    point_boxes.reserve(points.size());
    for (std::size_t v = 0; v < points.size(); ++v) add_point(static_cast<Index>(v));
  }
  CGAL::box_intersection_d(edge_boxes.begin(), edge_boxes.end(), point_boxes.begin(), point_boxes.end(),
                           [&](const Box& e, const Box& p) {
                             const Index v = static_cast<Index>(p.info());
                             if (v != edges[e.info()][0] && v != edges[e.info()][1]) near(v, e.info());
                           },
                           CGAL::Box_intersection_d::Box_traits_d<Box>(), kCutoff);
}

std::vector<std::array<Index, 2>> find_close_points(const Soup& soup, double tol) {
  std::vector<std::array<Index, 2>> out;
  if (!(tol > 0)) return out;
  std::vector<Box> boxes;
  boxes.reserve(soup.points.size());
  const double half = 0.5 * tol * (1 + 1e-9);  // two boxes meet when their points are within tol on every axis
  for (std::size_t v = 0; v < soup.points.size(); ++v)
    boxes.push_back(box_around(soup.points, {static_cast<Index>(v)}, half, static_cast<std::uint32_t>(v)));
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      boxes.begin(), boxes.end(),
      [&](const Box& p, const Box& q) {
        const Index a = static_cast<Index>(std::min(p.info(), q.info())), b = static_cast<Index>(std::max(p.info(), q.info()));
        if (is_closer_than(soup.points[a], soup.points[b], tol)) out.push_back({a, b});
      },
      CGAL::Box_intersection_d::Box_traits_d<Box>(), kCutoff);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<EdgeNearEdge> find_edges_near_edges(const Soup& soup, const std::vector<std::array<Index, 2>>& edges,
                                                double tol, bool parallel, const std::vector<char>* only) {
  std::vector<EdgeNearEdge> out;
  if (!(tol > 0)) return out;
  std::vector<Box> boxes;
  boxes.reserve(edges.size());
  const double half = 0.5 * tol * (1 + 1e-9);  // two boxes meet when their segments are within tol on every axis
  for (std::size_t i = 0; i < edges.size(); ++i)
    boxes.push_back(box_around(soup.points, {edges[i][0], edges[i][1]}, half, static_cast<std::uint32_t>(i)));
  std::vector<const Box*> pointers = pointers_to(boxes);
  tbb::enumerable_thread_specific<std::vector<EdgeNearEdge>> local;
  auto near = [&](const Box* x, const Box* y) {
    std::array<Index, 2> e = edges[x->info()], f = edges[y->info()];
    if (e[0] == f[0] || e[0] == f[1] || e[1] == f[0] || e[1] == f[1]) return;
    const Point3d* p = soup.points.data();
    if (!segments_closer_than(p[e[0]], p[e[1]], p[f[0]], p[f[1]], tol)) return;
    if (e[0] > e[1]) std::swap(e[0], e[1]);
    if (f[0] > f[1]) std::swap(f[0], f[1]);
    local.local().push_back(e < f ? EdgeNearEdge{e, f} : EdgeNearEdge{f, e});
  };
  if (only) {
    std::vector<const Box*> flagged;
    for (const Box* b : pointers)
      if ((*only)[b->info()]) flagged.push_back(b);
    flagged_pairs(flagged, pointers, near, parallel ? 2 : 0);
  } else {
    // Most meeting boxes are of edges sharing a vertex (always meeting): the
    // broad phase is the cost, so it runs in parallel as scan()'s does.
    box_pairs(pointers, near, parallel);
  }
  for (const auto& v : local) out.insert(out.end(), v.begin(), v.end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());  // two flagged edges: found both ways
  return out;
}

std::vector<VertexNearFace> find_vertices_near_faces(const Soup& soup, double tol, const std::vector<char>* only) {
  std::vector<VertexNearFace> out;
  if (!(tol > 0)) return out;
  const std::vector<FanTriangle> tris = fan_triangles(soup);
  std::vector<Box> face_boxes, point_boxes;
  face_boxes.reserve(tris.size());
  const double grow = tol * (1 + 1e-9);
  for (std::size_t t = 0; t < tris.size(); ++t)
    face_boxes.push_back(
        box_around(soup.points, {tris[t].v[0], tris[t].v[1], tris[t].v[2]}, grow, static_cast<std::uint32_t>(t)));
  point_boxes.reserve(soup.points.size());
  for (std::size_t v = 0; v < soup.points.size(); ++v)
    point_boxes.push_back(
        box_around(soup.points, {static_cast<Index>(v)}, 0, static_cast<std::uint32_t>(tris.size() + v)));
  DegenerateFlags degenerate(soup, tris);
  tbb::enumerable_thread_specific<std::vector<VertexNearFace>> local;
  auto near = [&](const Box* f, const Box* p) {
    const FanTriangle& t = tris[f->info()];
    const Index v = static_cast<Index>(p->info() - tris.size());
    if (v == t.v[0] || v == t.v[1] || v == t.v[2] || degenerate(f->info())) return;
    const Point3d* x = soup.points.data();
    if (point_closer_than_to_triangle(x[v], x[t.v[0]], x[t.v[1]], x[t.v[2]], tol))
      local.local().push_back({v, t.face});
  };
  if (only) {
    // A flagged face against every point, every face against a flagged
    // face's corners.
    std::vector<const Box*> faces = pointers_to(face_boxes), points = pointers_to(point_boxes), flagged_faces,
                            flagged_points;
    std::vector<char> corner(soup.points.size(), 0);
    for (const Box* b : faces)
      if ((*only)[tris[b->info()].face]) {
        flagged_faces.push_back(b);
        for (Index v : tris[b->info()].v) corner[v] = 1;
      }
    for (const Box* b : points)
      if (corner[b->info() - tris.size()]) flagged_points.push_back(b);
    flagged_pairs(flagged_faces, points, near, 2);
    flagged_pairs(flagged_points, faces, [&](const Box* p, const Box* f) { near(f, p); }, 2);
  } else {
    CGAL::box_intersection_d(face_boxes.begin(), face_boxes.end(), point_boxes.begin(), point_boxes.end(),
                             [&](const Box& f, const Box& p) { near(&f, &p); },
                             CGAL::Box_intersection_d::Box_traits_d<Box>(), kCutoff);
  }
  for (const auto& v : local) out.insert(out.end(), v.begin(), v.end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end(),
                        [](const VertexNearFace& a, const VertexNearFace& b) {
                          return a.vertex == b.vertex && a.face == b.face;
                        }),
            out.end());
  return out;
}

std::vector<FacePair> find_flip_hazards(const Soup& soup, const std::vector<EdgeQuad>& quads, double eps,
                                        bool parallel) {
  std::vector<char> flips(quads.size(), 0);  // not coplanar (a flip changes the surface) and maybe flipped
  detail::for_each_index(quads.size(), parallel, [&](std::size_t i) {
    const EdgeQuad& e = quads[i];
    const Point3d &p = soup.points[e.p], &q = soup.points[e.q], &r = soup.points[e.r], &s = soup.points[e.s];
    flips[i] = CGAL::orientation(point(soup, e.p), point(soup, e.q), point(soup, e.r), point(soup, e.s)) !=
                   CGAL::COPLANAR &&
               !tetgen_keeps_edge(p, q, r, s, eps);
  });
  std::vector<EdgeQuad> bent;
  for (std::size_t i = 0; i < quads.size(); ++i)
    if (flips[i]) bent.push_back(quads[i]);
  std::vector<FacePair> out;
  if (bent.empty()) return out;
  const std::vector<FanTriangle> tris = fan_triangles(soup);
  std::vector<Box> face_boxes, flip_boxes;
  face_boxes.reserve(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t)
    face_boxes.push_back(
        box_around(soup.points, {tris[t].v[0], tris[t].v[1], tris[t].v[2]}, 0, static_cast<std::uint32_t>(t)));
  // The flipped triangles: (r, s, p) and (s, r, q) of quad k are 2k, 2k + 1.
  std::vector<Tri> flipped;
  flipped.reserve(2 * bent.size());
  for (const EdgeQuad& e : bent) {
    for (const auto& v : {std::array<Index, 3>{e.r, e.s, e.p}, std::array<Index, 3>{e.s, e.r, e.q}}) {
      flip_boxes.push_back(
          box_around(soup.points, {v[0], v[1], v[2]}, 0, static_cast<std::uint32_t>(tris.size() + flipped.size())));
      flipped.push_back(detail::make_tri<InputKernel>(point(soup, v[0]), point(soup, v[1]), point(soup, v[2]), v[0],
                                                      v[1], v[2]));
    }
  }
  DegenerateFlags degenerate(soup, tris);
  std::vector<char> hazard(bent.size(), 0);
  auto found = [&](const Box* f, const Box* g) {
    const std::size_t i = f->info() - tris.size(), k = i / 2;
    const FanTriangle& t = tris[g->info()];
    if (hazard[k] || t.face == bent[k].face0 || t.face == bent[k].face1) return;
    if (detail::faces_intersect(flipped[i], exact_triangle(soup, t, degenerate(g->info())))) hazard[k] = 1;
  };
  // Each half of the flipped triangles against all faces (each task its own
  // copy of the face pointers: box_intersection_d reorders them); a quad's
  // two triangles stay in one half, so hazard[k] has one writer.
  std::vector<const Box*> faces_a = pointers_to(face_boxes), flips_a = pointers_to(flip_boxes);
  auto against_faces = [&](std::vector<const Box*>& flips, std::vector<const Box*>& faces) {
    CGAL::box_intersection_d<CGAL::Sequential_tag>(flips.begin(), flips.end(), faces.begin(), faces.end(), found,
                                                   Traits(), kCutoff);
  };
  if (parallel && flips_a.size() >= 2000) {
    const auto half = flips_a.begin() + static_cast<std::ptrdiff_t>(2 * (bent.size() / 2));
    std::vector<const Box*> flips_b(half, flips_a.end()), faces_b = faces_a;
    flips_a.erase(half, flips_a.end());
    tbb::parallel_invoke([&] { against_faces(flips_a, faces_a); }, [&] { against_faces(flips_b, faces_b); });
  } else {
    against_faces(flips_a, faces_a);
  }
  for (std::size_t k = 0; k < bent.size(); ++k)
    if (hazard[k])
      out.push_back({std::min(bent[k].face0, bent[k].face1), std::max(bent[k].face0, bent[k].face1)});
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<VertexNearEdge> find_vertices_near_edges(const Soup& soup, const std::vector<std::array<Index, 2>>& edges,
                                                     double eps) {
  std::vector<VertexNearEdge> out;
  for_each_point_near_edge(
      soup.points, edges, nullptr,
      [&](std::size_t i) {  // within eps |ab| of the segment, and a little more for the rounding of |ab|
        const Point3d &a = soup.points[edges[i][0]], &b = soup.points[edges[i][1]];
        double d2 = 0;
        for (int c = 0; c < 3; ++c) d2 += (a[c] - b[c]) * (a[c] - b[c]);
        return eps * std::sqrt(d2) * (1 + 1e-9);
      },
      [&](Index v, std::size_t i) {
        const std::array<Index, 2>& ab = edges[i];
        if (is_nearly_on_segment(soup.points[v], soup.points[ab[0]], soup.points[ab[1]], eps))
          out.push_back({v, std::min(ab[0], ab[1]), std::max(ab[0], ab[1])});
      });
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace polyheal
