// polyheal — regularization of a self-overlapping closed mesh (Jung, Shin &
// Choi); the stages and the generalisations are described in regularize.h.
#include "polyheal/repair/regularize.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_group.h>
#include <boost/container/small_vector.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <unordered_map>

#include "polyheal/io/write.h"
#include "polyheal/mesh/convert.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/hash.h"
#include "polyheal/mesh/mesh.h"
#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/union_find.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/weld.h"
#include "polyheal/repair/deintersect.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/detail/exact_meet.h"
#include "polyheal/repair/detail/winding.h"

namespace polyheal {
namespace {

using K = Kernel;  // Epeck: every construction below is exact
using EPoint = K::Point_3;
using EVector = K::Vector_3;
using IK = InputKernel;  // the input's doubles: exact filtered predicates
/// Pieces or faces around one edge: two, or a few at an intersection curve
/// (inline storage: the growth asks this for every edge it crosses).
using Ids = boost::container::small_vector<Index, 6>;
/// Where two triangles meet, as vertex ids: one point or a segment's ends.
using Ends = boost::container::small_vector<Index, 2>;

// §3.5: the constrained Delaunay triangulation of one triangle, in its plane
// projected along the dominant normal axis (dropping a coordinate is exact).
// Constraints that cross get their crossing point constructed exactly.
struct VertexInfo {
  std::int64_t id = -1;  // global vertex id; -1: a crossing the triangulation constructed
};
/// Epeck for the constrained triangulations, with an orientation test that
/// decides as Epeck's does (the doubles' static filter, then intervals)
/// and, where those fail, without a gcd: on the homogeneous coordinates the
/// points were projected from (detail::homogeneous_orientation: the new
/// points are made homogeneous, their rationals only when asked), else on
/// the exact rationals (detail::rational_orientation). The triangulations'
/// exact tests (the points of one segment are exactly collinear) spent most
/// of their time in mpq's gcds, a tenth of regularize's CPU time on a raw
/// offset. Same answers, so the same triangulations.
struct CdtTraits : K {
  struct Orientation_2 {
    using result_type = CGAL::Orientation;
    CGAL::Orientation operator()(const K::Point_2& p, const K::Point_2& q, const K::Point_2& r) const {
      const auto &a = p.approx(), &b = q.approx(), &c = r.approx();
      if (a.x().is_point() && a.y().is_point() && b.x().is_point() && b.y().is_point() && c.x().is_point() &&
          c.y().is_point())
        return CGAL::orientation(IK::Point_2(a.x().inf(), a.y().inf()), IK::Point_2(b.x().inf(), b.y().inf()),
                                 IK::Point_2(c.x().inf(), c.y().inf()));
      {
        CGAL::Protect_FPU_rounding<true> upward;
        const CGAL::Uncertain<CGAL::Orientation> o = CGAL::orientationC2(a.x(), a.y(), b.x(), b.y(), c.x(), c.y());
        if (CGAL::is_certain(o)) return CGAL::get_certain(o);
      }
      if (const auto rp = row(p), rq = row(q), rr = row(r); rp && rq && rr)
        return detail::homogeneous_orientation(*rp, *rq, *rr);
      static_assert(std::is_same_v<K::Exact_kernel::FT, mpq_class>);
      const auto &x = p.exact(), &y = q.exact(), &z = r.exact();
      return detail::rational_orientation({x.x(), x.y()}, {y.x(), y.y()}, {z.x(), z.y()});
    }

   private:
    /// p as homogeneous coordinates: its doubles over 1, or the form it was
    /// projected from (exact_proj); none for other points (constructed by
    /// the triangulation).
    static std::optional<detail::Row2> row(const K::Point_2& p) {
      const auto& a = p.approx();
      if (a.x().is_point() && a.y().is_point())
        return detail::Row2{detail::Z(a.x().inf()), detail::Z(a.y().inf()), detail::Z(1)};
      if (const auto* h = detail::projected_of<K::Point_2, K::Point_3>(p)) return h->row();
      return std::nullopt;
    }
  };
  Orientation_2 orientation_2_object() const { return {}; }
};

}  // namespace
}  // namespace polyheal

/// As Epeck's: point location starts with a walk on the points' doubles.
template <>
struct CGAL::Triangulation_structural_filtering_traits<polyheal::CdtTraits> {
  using Use_structural_filtering_tag = CGAL::Tag_true;
};

namespace polyheal {
namespace {

using Vb = CGAL::Triangulation_vertex_base_with_info_2<VertexInfo, CdtTraits>;
using Fb = CGAL::Triangulation_face_base_with_info_2<Index, CdtTraits,
                                                      CGAL::Constrained_triangulation_face_base_2<CdtTraits>>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<CdtTraits, Tds, CGAL::Exact_intersections_tag>;

// The winding-number lines: an AABB tree of the input triangles in doubles.
using InputTriangles = std::vector<IK::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<IK, InputTriangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<IK, Primitive>>;

/// The axis of v's largest |to_double(v[a])| (the first of equals) and
/// that value — what `if (|to_double(v[a])| > |to_double(v[k])|) k = a`
/// finds, without exact evaluation where intervals decide it. to_double
/// evaluates a lazy number exactly when its interval is wider than 1e-5 of
/// its magnitude (a component exactly zero, as on axis-aligned faces and
/// edges: most of the planning's exact evaluations on a CAD raw offset);
/// such a component cannot be the largest when its interval's magnitude is
/// below a component known, and then nothing needs it.
std::pair<int, double> dominant_axis(const EVector& v) {
  std::array<double, 3> value{};
  std::array<bool, 3> known{};
  double best = -1;
  int k = -1;
  for (int a = 0; a < 3; ++a) {  // to_double's own steps short of the exact one
    const CGAL::Interval_nt<false>& x = v.approx()[a];
    if (CGAL::fit_in_double(x, value[a])) {
      known[a] = true;
    } else if (CGAL::has_smaller_relative_precision(x, K::FT::get_relative_precision_of_to_double())) {
      value[a] = CGAL::to_double(x);
      known[a] = true;
    }
    if (known[a] && std::abs(value[a]) > best) {
      best = std::abs(value[a]);
      k = a;
    }
  }
  bool decided = k >= 0;
  for (int a = 0; a < 3 && decided; ++a)
    decided = known[a] || CGAL::magnitude(v.approx()[a]) < best;
  if (decided) return {k, value[k]};
  k = 0;  // as before: exact where to_double needs it
  for (int a = 1; a < 3; ++a)
    if (std::abs(CGAL::to_double(v[a])) > std::abs(CGAL::to_double(v[k]))) k = a;
  return {k, CGAL::to_double(v[k])};
}

/// num / den as a point known exactly (detail::lazy_point): no lazy tree
/// to evaluate when a filter fails on it (on a raw offset of 125k
/// triangles, evaluating lazy trees of the same points was ~15% of
/// regularize; a point built from three exact coordinates, a node, was a
/// fifth of the triangulations'), and its rationals made only when a test
/// needs them: the triangulations' orientations, the rounding and the
/// hashing take the homogeneous form (the rationals' gcds were a third of
/// constructing the crossing points, Hand1's raw offset).
EPoint exact_point(const detail::Homogeneous& h) { return detail::lazy_point<EPoint>(h); }

/// p's nearest doubles (nearest_point3d), from its homogeneous form where
/// it has one: MPFR divides the unreduced rationals (no gcd).
Point3d nearest(const EPoint& p) {
  const auto* h = detail::homogeneous_of<EPoint, 3>(p);
  if (!h) return nearest_point3d(p);
  const auto& a = p.approx();
  const std::array<mpq_class, 3> u = detail::unreduced(h->num, h->den);
  Point3d out;
  for (int c = 0; c < 3; ++c) out[c] = a[c].is_point() ? a[c].inf() : nearest_double_of(u[c]);
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

enum State : char { kUnvisited = 0, kValid = 1, kInvalid = 2 };

constexpr Index kNoPiece = ~Index(0);

/// A triangle of the arrangement being classified: an input triangle, or one
/// of the sub-triangles a partially valid triangle is split into (§3.5).
struct Piece {
  std::array<Index, 3> v;  // global vertex ids, oriented like the sheets it stands for
  Index source;            // an input face it lies in (and is oriented like)
  int weight = 1;          // coincident sheets it stands for (coplanar overlaps: net count)
  bool alive = true;       // false once the input triangle is split
  State state = kUnvisited;  // its patch's, once the growth is over (zero-area faces: invalid)
  /// Across edge (v[e], v[e + 1]): the other piece, when the edge is inside
  /// one sub-triangulation and unconstrained (no other piece can have it:
  /// an edge another triangle shares lies on their intersection segment, a
  /// constraint, or on the triangle's own side), or joins two input
  /// triangles that touch nothing else (link_untouched_edges()); kNoPiece
  /// otherwise, and the edge is looked up among all pieces (edge_uses_).
  std::array<Index, 3> across{kNoPiece, kNoPiece, kNoPiece};
};

/// The coordinate axes (i, j) that remain when axis k is dropped, in cyclic
/// order: then the 2D orientation of a projected triangle has the sign of
/// its normal's k component.
std::array<int, 2> kept_axes(int k) { return {(k + 1) % 3, (k + 2) % 3}; }

class Regularizer {
 public:
  Regularizer(const Soup& soup, const std::vector<FacePair>& pairs, const Report& report, RegularizeReport& r)
      : soup_(soup), r_(r), partners_(soup.face_count()),
        registered_(soup.points.size(), 0), not_generic_(soup.face_count(), 0) {
    points_.reserve(soup.points.size());
    for (const Point3d& p : soup.points) points_.emplace_back(p[0], p[1], p[2]);
    // Coplanar overlaps (and duplicate faces) join their triangles into one
    // cluster, sub-triangulated together so that coincident pieces are one
    // piece standing for all the sheets there (its weight).
    UnionFind cluster(soup.face_count());
    auto join = [&](Index a, Index b, bool same_plane) {
      partners_[a].push_back(b);
      partners_[b].push_back(a);
      if (same_plane) cluster.unite(a, b);
    };
    // §3.1: zero-area faces (exactly collinear, or a repeated corner) bound
    // nothing; they stay out of every pair, piece and line (their edges
    // still count for the closed-surface check, and a neighbour that meets
    // one's middle corner at a T-junction is split there as an intersection)
    zero_area_.assign(soup.face_count(), 0);
    for (std::size_t f : report.degenerate_faces) zero_area_[f] = 1;
    std::vector<char> same_plane(pairs.size());
    tbb::parallel_for(std::size_t(0), pairs.size(), [&](std::size_t k) {
      same_plane[k] = coplanar(Index(pairs[k].first), Index(pairs[k].second)) ? 1 : 0;
    });
    for (std::size_t k = 0; k < pairs.size(); ++k)
      if (!zero_area_[pairs[k].first] && !zero_area_[pairs[k].second])
        join(Index(pairs[k].first), Index(pairs[k].second), same_plane[k]);
    for (const auto& d : report.duplicate_faces)
      if (!zero_area_[d[0]] && !zero_area_[d[1]]) join(Index(d[0]), Index(d[1]), coplanar(Index(d[0]), Index(d[1])));
    tbb::parallel_for(std::size_t(0), partners_.size(), [&](std::size_t f) {
      std::vector<Index>& list = partners_[f];
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    });
    roots_.resize(soup.face_count());
    for (std::size_t f = 0; f < soup.face_count(); ++f) roots_[f] = Index(cluster.find(f));
    for (std::size_t f = 0; f < soup.face_count(); ++f)
      if (root(Index(f)) != f) members_[root(Index(f))].push_back(Index(f));
    for (auto& [c, list] : members_) list.insert(list.begin(), c);
    pieces_.resize(soup.face_count());
    face_edges_.resize(3 * soup.face_count());
    tbb::parallel_for(std::size_t(0), soup.face_count(), [&](std::size_t f) {
      const FaceView fv = soup.face(f);
      Piece& piece = pieces_[f];
      piece.v = {fv[0], fv[1], fv[2]};
      piece.source = Index(f);
      if (zero_area_[f]) {
        piece.alive = false;
        piece.state = kInvalid;
      }
      for (int e = 0; e < 3; ++e)
        face_edges_[3 * f + std::size_t(e)] = {undirected_edge_key(fv[e], fv[(e + 1) % 3]), Index(3 * f + std::size_t(e))};
    });
    tbb::parallel_sort(face_edges_.begin(), face_edges_.end());
    link_untouched_edges();
  }

  /// §3.3-3.6 with the generalised seeds: every piece ends valid, invalid,
  /// or (reported) unclassified.
  void run(Observer* observer) {
    const std::size_t faces = soup_.face_count();
    presplit();
    commit_all();
    link_patches();
    // The new points' nearest doubles (the output's, most of them), on the
    // other cores while the growth walks the patches on this one.
    rounding_.run([this] {
      const std::size_t first = soup_.points.size();
      rounded_.resize(points_.size() - first);
      tbb::parallel_for(std::size_t(0), rounded_.size(),
                        [&](std::size_t n) { rounded_[n] = nearest(points_[first + n]); });
    });
    cast_isolated();
    // Seeds among the intersection-free triangles first (no sub-triangulation
    // needed to classify them), then among the sub-triangles of what is left.
    for (std::size_t f = 0; f < faces; ++f) {
      if (observer && f % 4096 == 0) observer->progress(0.5 * double(f) / double(faces));
      if (partners_[f].empty() && state(Index(f)) == kUnvisited) seed(Index(f));
    }
    // Triangles no wave reached: their sub-triangles are classified by lines
    // of their own (a component of the output made only of pieces of
    // intersecting triangles has no intersection-free seed).
    for (std::size_t s = 0; s + 1 < base_.size(); ++s) {
      bool reached = false;
      for (Index q = base_[s]; q < base_[s + 1] && !reached; ++q) reached = state(q) != kUnvisited;
      if (!reached) r_.split_unreached += plans_[s].cluster.size();
    }
    // (sub-triangles by slot: their triangles' clusters by least member)
    for (Index q = Index(faces); q < pieces_.size(); ++q) {
      if (observer && q % 4096 == 0) observer->progress(0.5 + 0.5 * double(q - faces) / double(pieces_.size() - faces));
      if (state(q) == kUnvisited) seed(q);
    }
    // each piece's state, its patch's
    tbb::parallel_for(std::size_t(0), pieces_.size(), [&](std::size_t q) {
      if (pieces_[q].alive) pieces_[q].state = State(patch_state_[patch_[q]]);
    });
    for (const Index q : unjoined_)
      if (pieces_[q].state == kValid) ++r_.orientation_conflicts;  // no compatible continuation
  }

  /// The valid pieces as a soup: input vertices keep their doubles, new
  /// points are rounded to the nearest double. Input triangles come first,
  /// then sub-triangles, by triangle.
  Soup output(std::vector<std::size_t>& source, std::vector<char>& made) {
    Soup out;
    std::vector<std::int64_t> id(points_.size(), -1);
    std::vector<std::pair<Index, Index>> fresh;  // (output point, new point) to round
    for (const Piece& p : pieces_) {
      if (!p.alive || p.state != kValid) continue;
      std::array<Index, 3> f;
      for (int k = 0; k < 3; ++k) {
        std::int64_t& i = id[p.v[k]];
        if (i < 0) {
          i = std::int64_t(out.points.size());
          const bool input_vertex = p.v[k] < soup_.points.size();
          out.points.push_back(input_vertex ? soup_.points[p.v[k]] : Point3d{});
          if (!input_vertex) fresh.push_back({Index(i), p.v[k]});
          made.push_back(input_vertex ? 0 : 1);
        }
        f[k] = Index(i);
      }
      out.add_triangle(f[0], f[1], f[2]);
      source.push_back(p.source);
    }
    rounding_.wait();  // (started by run())
    for (const auto& [i, n] : fresh) out.points[i] = rounded_[n - soup_.points.size()];
    return out;
  }

  /// Counts per input triangle (Fig. 2's groups) and the components that
  /// lost every face.
  void tally() {
    const std::size_t faces = soup_.face_count();
    std::vector<char> has_valid(faces, 0);
    for (const Piece& p : pieces_) {
      if (!p.alive) continue;
      if (p.state == kValid) has_valid[p.source] = 1;
      if (p.state == kUnvisited) ++r_.unclassified;
    }
    for (std::size_t f = 0; f < faces; ++f) {
      if (!has_valid[f]) ++r_.invalid;
      else if (!partners_[f].empty()) ++r_.partially_valid;  // (split)
      else ++r_.valid;
    }
    // components through shared edges
    UnionFind components(faces);
    for (std::size_t k = 1; k < face_edges_.size(); ++k)
      if (face_edges_[k].first == face_edges_[k - 1].first)
        components.unite(face_edges_[k].second / 3, face_edges_[k - 1].second / 3);
    std::vector<char> root_kept(faces, 0), root_seen(faces, 0);
    for (std::size_t f = 0; f < faces; ++f) {
      const std::size_t root = components.find(f);
      root_seen[root] = 1;
      if (has_valid[f]) root_kept[root] = 1;
    }
    for (std::size_t f = 0; f < faces; ++f) {
      if (root_seen[f]) ++r_.components_in;
      if (root_seen[f] && !root_kept[f]) ++r_.components_removed;
    }
  }

  std::size_t new_points() const { return points_.size() - soup_.points.size(); }
  ~Regularizer() { rounding_.wait(); }
  double seconds_intersections = 0;

 private:
  // ---- clusters of coplanar overlapping triangles ------------------------

  Index root(Index f) const { return roots_[f]; }

  /// Are input faces a and b in one plane (exactly, on the doubles)?
  bool coplanar(Index a, Index b) const {
    const FaceView fa = soup_.face(a), fb = soup_.face(b);
    auto ip = [&](Index v) { return IK::Point_3(soup_.points[v][0], soup_.points[v][1], soup_.points[v][2]); };
    for (Index v : fb)
      if (CGAL::orientation(ip(fa[0]), ip(fa[1]), ip(fa[2]), ip(v)) != CGAL::COPLANAR) return false;
    return true;
  }

  /// The triangles split together with f: its cluster (f alone, usually).
  Ids cluster_of(Index f) {
    const auto it = members_.find(root(f));
    return it == members_.end() ? Ids{f} : Ids(it->second.begin(), it->second.end());
  }

  /// An edge of exactly two input triangles, neither intersecting another
  /// nor zero-area, is an edge of those two pieces only: a piece joins two
  /// input vertices only where one triangle (or one plane's cluster of
  /// overlapping ones) has both as corners, and a triangle with both has
  /// the edge. Their `across` is set, and the growth crosses such an edge
  /// without looking it up (most of the surface, usually). The input
  /// triangles' uses of every other edge go into the edge lookup (see
  /// edge_uses_).
  void link_untouched_edges() {
    auto untouched = [&](Index f) { return partners_[f].empty() && !zero_area_[f]; };
    for (std::size_t k = 0; k < face_edges_.size();) {
      const std::uint64_t key = face_edges_[k].first;
      std::size_t m = k + 1;
      while (m < face_edges_.size() && face_edges_[m].first == key) ++m;
      const Index u = face_edges_[k].second, w = face_edges_[k + 1 < m ? k + 1 : k].second;
      if (m - k == 2 && u / 3 != w / 3 && untouched(u / 3) && untouched(w / 3)) {
        pieces_[u / 3].across[u % 3] = w / 3;
        pieces_[w / 3].across[w % 3] = u / 3;
      } else {
        for (std::size_t i = k; i < m; ++i) edge_uses_.push_back({key, face_edges_[i].second});
      }
      k = m;
    }
  }

  // ---- seeds (§3.3, generalised) -----------------------------------------

  void seed(Index q) {
    ++r_.seeds;
    std::optional<int> w;
    const auto cast = std::lower_bound(isolated_.begin(), isolated_.end(), q,
                                       [](const Isolated& c, Index i) { return c.piece < i; });
    if (cast != isolated_.end() && cast->piece == q) {
      w = cast->winding;
      r_.line_casts += cast->lines;
    } else {
      w = winding_outside(q, r_.line_casts);
    }
    if (!w) return;  // left for the growth to reach; unclassified if it never does
    flood(q, *w);
  }

  /// A patch that no intersection curve bounds (a whole component crossing
  /// nothing, e.g. each of the pockets that a rounding pass's input has as
  /// surfaces of their own: ~15k on the crank's raw offset) is reached by no
  /// other's flood, so the seed loop will seed it from its least piece
  /// when that is an intersection-free triangle: those pieces' winding
  /// numbers are cast beforehand, side by side (the same lines in the same
  /// order each; seed() takes them from isolated_).
  void cast_isolated() {
    std::vector<char> bounded(pieces_.size(), 0);
    for (const std::uint64_t side : river_sides_) bounded[side >> 32] = 1;
    std::vector<Index> least;
    for (Index f = 0; f < Index(soup_.face_count()); ++f)
      if (patch_[f] == f && !bounded[f] && pieces_[f].alive && partners_[f].empty()) least.push_back(f);
    if (least.empty()) return;
    tree();  // built once, before the threads ask it
    isolated_.resize(least.size());
    tbb::parallel_for(std::size_t(0), least.size(), [&](std::size_t n) {
      Isolated& c = isolated_[n];
      c.piece = least[n];
      c.winding = winding_outside(c.piece, c.lines);
    });
  }

  /// The winding number of the input surface just outside piece q (on the
  /// side its normal points to), decided exactly: a line parallel to the
  /// dominant axis k of q's normal, through a point of q with double
  /// coordinates, crosses the input triangles; those beyond q count +-1 by
  /// the sign of their normal along the line (those through the same point
  /// are the sheets q stands for). nullopt when no tried line avoids every
  /// edge and vertex. Valid: winding <= 0 outside and >= 1 inside.
  std::optional<int> winding_outside(Index q, std::size_t& lines) {
    const Piece& piece = pieces_[q];
    const FaceView src = soup_.face(piece.source);
    const Point3d& s0 = soup_.points[src[0]];
    const Point3d& s1 = soup_.points[src[1]];
    const Point3d& s2 = soup_.points[src[2]];
    const Point3d u{s1[0] - s0[0], s1[1] - s0[1], s1[2] - s0[2]}, v{s2[0] - s0[0], s2[1] - s0[1], s2[2] - s0[2]};
    const Point3d n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    int k = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(n[a]) > std::abs(n[k])) k = a;
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    auto p2 = [&](const Point3d& p) { return IK::Point_2(p[i], p[j]); };
    // the exact sign of the source's normal along k (nonzero: k is dominant
    // and the triangle is not degenerate; checked anyway)
    const int sign_k = int(CGAL::orientation(p2(s0), p2(s1), p2(s2)));
    if (sign_k == 0) return std::nullopt;
    const std::array<K::Point_2, 3> corners{proj(points_[piece.v[0]], i, j), proj(points_[piece.v[1]], i, j),
                                            proj(points_[piece.v[2]], i, j)};
    static const double weights[][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.25, 0.25}, {0.25, 0.5, 0.25},
                                        {0.25, 0.25, 0.5},         {0.4, 0.35, 0.25},   {0.3, 0.3, 0.4}};
    for (const auto& w : weights) {
      const K::FT ci = corners[0].x() * w[0] + corners[1].x() * w[1] + corners[2].x() * w[2];
      const K::FT cj = corners[0].y() * w[0] + corners[1].y() * w[1] + corners[2].y() * w[2];
      const double s = nearest_double(ci), t = nearest_double(cj);
      const K::Point_2 at(s, t);
      // strictly inside q's projection (q is counter-clockwise there iff sign_k > 0)
      bool inside = true;
      for (int e = 0; e < 3 && inside; ++e)
        inside = int(CGAL::orientation(corners[e], corners[(e + 1) % 3], at)) == sign_k;
      if (!inside) continue;
      ++lines;
      const std::optional<int> winding = cast(piece.source, k, s, t, sign_k);
      if (winding) return winding;
    }
    return std::nullopt;
  }

  /// The line {x_i = s, x_j = t} against the input triangles: the signed
  /// crossings beyond face `source` on its outer side (sign_k: the sign of
  /// its normal along k). nullopt when the line meets an edge or a vertex,
  /// or lies in a triangle's plane, beyond the source's nearest corner.
  std::optional<int> cast(Index source, int k, double s, double t, int sign_k) {
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    // A half line, from the source's last corner behind its outer side on:
    // every triangle beyond the source on the line crosses it (exact
    // tests on doubles), and the tree's boxes behind are not visited (the
    // whole line's were: ~0.1 ms a line on 1.5M faces, where a rounding
    // pass of the crank's raw offset casts one for each of ~15k pockets).
    const FaceView sv = soup_.face(source);
    double from = soup_.points[sv[0]][k];
    for (int e = 1; e < 3; ++e)
      from = sign_k > 0 ? std::min(from, soup_.points[sv[e]][k]) : std::max(from, soup_.points[sv[e]][k]);
    double o[3], d[3] = {0, 0, 0};
    o[i] = s;
    o[j] = t;
    o[k] = from;
    d[k] = sign_k;
    const IK::Ray_3 ray(IK::Point_3(o[0], o[1], o[2]), IK::Vector_3(d[0], d[1], d[2]));
    std::vector<Primitive::Id> hits;
    tree().all_intersected_primitives(ray, std::back_inserter(hits));
    const K::FT at_source = plane_coordinate(source, k, s, t);
    const IK::Point_2 at(s, t);
    int winding = 0;
    for (const auto& hit : hits) {
      const Index g = Index(hit - triangles_.begin());
      if (g == source || zero_area_[g]) continue;
      const FaceView gv = soup_.face(g);
      std::array<IK::Point_2, 3> c;
      for (int e = 0; e < 3; ++e) c[e] = IK::Point_2(soup_.points[gv[e]][i], soup_.points[gv[e]][j]);
      const CGAL::Orientation og = CGAL::orientation(c[0], c[1], c[2]);
      if (og == CGAL::COLLINEAR) return std::nullopt;  // the line lies in g's plane
      int same = 0;
      for (int e = 0; e < 3; ++e) {
        const CGAL::Orientation oe = CGAL::orientation(c[e], c[(e + 1) % 3], at);
        if (oe == CGAL::COLLINEAR) return std::nullopt;  // through an edge or a vertex of g
        same += oe == og ? 1 : 0;
      }
      if (same != 3) continue;  // the box was hit, not the triangle
      const CGAL::Comparison_result c_at = CGAL::compare(plane_coordinate(g, k, s, t), at_source);
      if (c_at == CGAL::EQUAL) continue;  // coplanar with the source there: one of the sheets q stands for
      const bool beyond = sign_k > 0 ? c_at == CGAL::LARGER : c_at == CGAL::SMALLER;
      if (beyond) winding += sign_k * int(og);  // sign of (direction . normal of g)
    }
    return winding;
  }

  /// The AABB tree of the input triangles, built on the first call
  /// (presplit() asks for it beside the planning).
  const Tree& tree() {
    if (triangles_.empty()) {
      triangles_.reserve(soup_.face_count());
      for (std::size_t f = 0; f < soup_.face_count(); ++f) {
        const FaceView fv = soup_.face(f);
        auto ip = [&](Index v) { return IK::Point_3(soup_.points[v][0], soup_.points[v][1], soup_.points[v][2]); };
        triangles_.emplace_back(ip(fv[0]), ip(fv[1]), ip(fv[2]));
      }
      tree_.insert(triangles_.begin(), triangles_.end());
      tree_.build();
    }
    return tree_;
  }

  /// The k coordinate where the line {x_i = s, x_j = t} meets face f's plane.
  K::FT plane_coordinate(Index f, int k, double s, double t) const {
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    const FaceView fv = soup_.face(f);
    const EVector n = CGAL::cross_product(points_[fv[1]] - points_[fv[0]], points_[fv[2]] - points_[fv[0]]);
    const EPoint& a = points_[fv[0]];
    return a[k] - (n[i] * (K::FT(s) - a[i]) + n[j] * (K::FT(t) - a[j])) / n[k];
  }

  static K::Point_2 proj(const EPoint& p, int i, int j) { return K::Point_2(p[i], p[j]); }
  /// proj() known exactly, for the triangulations: a leaf, not a lazy tree
  /// over p's own (their exact orientation tests on collinear points, which
  /// no filter decides, evaluated such a tree for every projection).
  /// Its intervals are p's own (tight: an exact value's, as a leaf's are and
  /// a node's become once evaluated), not computed again from the rationals.
  static K::Point_2 exact_proj(const EPoint& p, int i, int j) {
    const auto& a = p.approx();
    if (a[i].is_point() && a[j].is_point()) return K::Point_2(a[i].inf(), a[j].inf());
    if (const auto* h = detail::homogeneous_of<EPoint, 3>(p))  // the projection's homogeneous form: no rationals
      return detail::projected_point<K::Point_2>(p, *h, i, j);
    using Rep = K::Point_2::Rep;
    const auto& e = p.exact();
    return K::Point_2(Rep(new CGAL::Lazy_rep_0<Rep::AT, Rep::ET, K::E2A>(Rep::AT(a[i], a[j]), Rep::ET(e[i], e[j]))));
  }

  // ---- growth (§3.4, §3.6) ------------------------------------------------

  /// Classifies q's patch (outer winding number `winding`) and spreads the
  /// winding numbers: a patch's pieces share theirs (across an edge with
  /// two pieces the neighbour has the same outer winding, link_patches());
  /// across an intersection curve (§3.6, an edge with more than two pieces)
  /// every piece around gets its own from the sorted order (continuation),
  /// valid and invalid alike, so an invalid region cut off by intersection
  /// curves needs no winding-number line of its own. A piece is valid when
  /// winding <= 0 outside and >= 1 inside.
  void flood(Index q, int winding) {
    std::vector<Index> front{patch_[q]};
    classify(patch_[q], winding);
    std::vector<std::pair<Index, int>> next;
    while (!front.empty()) {
      const Index patch = front.back();
      front.pop_back();
      const bool valid = patch_state_[patch] == kValid;
      auto side = std::lower_bound(river_sides_.begin(), river_sides_.end(), std::uint64_t(patch) << 32);
      for (; side != river_sides_.end() && *side >> 32 == patch; ++side) {
        const Index p = Index((*side & 0xffffffffu) / 3);
        const int e = int((*side & 0xffffffffu) % 3);
        char& done = river_done_[edge_group_[3 * std::size_t(p) + std::size_t(e)]];
        if (done) continue;  // every piece around is classified
        const Index a = pieces_[p].v[e], b = pieces_[p].v[(e + 1) % 3];
        next.clear();
        around_windings(p, a, b, pieces_around(p, e), patch_front_[patch], valid, next);
        if (!next.empty()) done = 1;
        if (valid && std::none_of(next.begin(), next.end(), [&](const auto& n) {
              return traverses(n.first, b, a) && n.second <= 0 && n.second + pieces_[n.first].weight >= 1;
            }))
          ++r_.orientation_conflicts;  // no compatible continuation
        for (const auto& [n, w] : next) {
          if (patch_state_[patch_[n]] != kUnvisited) continue;
          classify(patch_[n], w);
          front.push_back(patch_[n]);
        }
      }
    }
  }

  /// Sets a patch's outer winding number and state.
  void classify(Index patch, int winding) {
    patch_front_[patch] = winding;
    patch_state_[patch] = winding <= 0 && winding + pieces_[patch].weight >= 1 ? kValid : kInvalid;
  }

  State state(Index q) const { return pieces_[q].alive ? State(patch_state_[patch_[q]]) : pieces_[q].state; }

  /// Do pieces p and o continue each other across p's edge e: o runs it the
  /// other way (the orientations agree) and stands for as many sheets?
  bool continues(Index p, int e, Index o) const {
    const Piece& piece = pieces_[p];
    return traverses(o, piece.v[(e + 1) % 3], piece.v[e]) && pieces_[o].weight == piece.weight;
  }

  /// The patches: live pieces joined across every edge with exactly two
  /// pieces that continue each other share their outer winding number (the
  /// growth's step across such an edge, §3.4); a patch is named by its
  /// least piece (patch_). Its sides on intersection curves (edges with
  /// more than two pieces, where §3.6 crosses the river) are listed by
  /// patch (river_sides_); an edge with two pieces that do not continue
  /// each other stops the growth (unjoined_: a conflict where valid).
  void link_patches() {
    const std::size_t n = pieces_.size();
    ConcurrentUnionFind joined(n);
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> sides;  // 3 * piece + edge, for now
    tbb::enumerable_thread_specific<std::vector<Index>> unjoined;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
      for (Index p = Index(r.begin()); p != r.end(); ++p) {
        const Piece& piece = pieces_[p];
        if (!piece.alive) continue;
        for (int e = 0; e < 3; ++e) {
          Index other = piece.across[e];
          if (other == kNoPiece) {
            const Ids around = pieces_around(p, e);
            if (around.size() > 2) sides.local().push_back(3 * std::uint64_t(p) + std::uint64_t(e));
            if (around.size() < 2) unjoined.local().push_back(p);  // (not on a closed surface)
            if (around.size() != 2) continue;
            other = around[0] == p ? around[1] : around[0];
          }
          if (!continues(p, e, other)) unjoined.local().push_back(p);
          else if (p < other) joined.unite(p, other);
        }
      }
    });
    patch_.resize(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t p) { patch_[p] = joined.find(Index(p)); });
    for (const auto& list : sides)
      for (const std::uint64_t use : list) river_sides_.push_back(std::uint64_t(patch_[use / 3]) << 32 | use);
    tbb::parallel_sort(river_sides_.begin(), river_sides_.end());
    for (const auto& list : unjoined) unjoined_.insert(unjoined_.end(), list.begin(), list.end());
    patch_state_.assign(n, kUnvisited);
    patch_front_.assign(n, 0);
  }

  bool traverses(Index p, Index a, Index b) const {
    const auto& v = pieces_[p].v;
    for (int e = 0; e < 3; ++e)
      if (v[e] == a && v[(e + 1) % 3] == b) return true;
    return false;
  }

  /// The live pieces with edge e of piece p (an edge no `across` links; p
  /// among them): input triangles first, by index.
  Ids pieces_around(Index p, int e) const {
    Ids out;
    const std::size_t start = edge_group_[3 * std::size_t(p) + std::size_t(e)];
    for (std::size_t k = start; k < edge_uses_.size() && edge_uses_[k].key == edge_uses_[start].key; ++k)
      if (pieces_[edge_uses_[k].use / 3].alive) out.push_back(edge_uses_[k].use / 3);
    return out;
  }

  /// §3.6 crossing the river, generalised: the pieces around edge ab sorted
  /// by angle, starting from p's outer side; the winding number of each
  /// wedge followed from p's outer side (winding `front`), so each piece's
  /// outer winding (appended to `out`). The paper's continuation is the
  /// first piece that faces a wedge of winding <= 0 and backs onto one of
  /// winding >= 1.
  /// Coincident pieces of different planes are an error when p is valid
  /// (they would be on the output); around an invalid p the edge is left
  /// to the seeds (out unchanged).
  void around_windings(Index p, Index a, Index b, const Ids& around, int front, bool strict,
                       std::vector<std::pair<Index, int>>& out) {
    // Exact orientations of the corners (filtered on their intervals, no
    // constructions): n = (B - A) x (C - A), C the third corner of p, and w
    // = D - A for a piece with third corner D; n . w is orientation(A, B,
    // C, D), (B - A) x w1 . w2 is orientation(A, B, D1, D2), and within p's
    // plane n . ((B - A) x w) > 0 says D lies on C's side of AB
    // (coplanar_orientation).
    const EPoint &A = points_[a], &B = points_[b], &C = points_[third(p, a, b)];
    struct Item {
      Index piece;
      Index third;    // its third corner
      int half;       // 0: angle in (0, pi) from p, 1: pi, 2: (pi, 2 pi)
      bool entering;  // traverses b -> a: crossing it while rotating enters its inside
    };
    std::vector<Item> items;
    const Index plane = root(pieces_[p].source);
    for (Index q : around) {
      if (q == p) continue;
      const Index d = third(q, a, b);
      int half = 1;
      // A piece of p's own plane (its triangle or cluster) across the edge
      // lies opposite p (two pieces of one triangulation do not overlap):
      // known without an exact test, which would be degenerate and costly.
      if (root(pieces_[q].source) != plane) {
        const CGAL::Orientation side = CGAL::orientation(A, B, C, points_[d]);
        half = side == CGAL::POSITIVE ? 0 : side == CGAL::NEGATIVE ? 2 : 1;
        if (half == 1 && CGAL::coplanar_orientation(A, B, C, points_[d]) == CGAL::POSITIVE) {
          if (!strict) return;
          throw UnsupportedInput(coplanar_message(pieces_[p].source, pieces_[q].source));
        }
      }
      items.push_back({q, d, half, traverses(q, b, a)});
    }
    auto before = [&](const Item& x, const Item& y) {
      if (x.half != y.half) return x.half < y.half;
      if (x.half == 1) return false;
      return CGAL::orientation(A, B, points_[x.third], points_[y.third]) == CGAL::POSITIVE;
    };
    std::sort(items.begin(), items.end(), before);
    for (std::size_t k = 1; k < items.size(); ++k)
      if (!before(items[k - 1], items[k])) {  // same half-plane: coincident pieces
        if (!strict) return;
        throw UnsupportedInput(coplanar_message(pieces_[items[k - 1].piece].source, pieces_[items[k].piece].source));
      }
    int winding = front;
    for (const Item& item : items) {
      const int weight = pieces_[item.piece].weight;
      if (item.entering) {  // crossing it enters its inside: its outer side is behind
        out.push_back({item.piece, winding});
        winding += weight;
      } else {  // crossing it leaves its inside: its outer side is ahead
        winding -= weight;
        out.push_back({item.piece, winding});
      }
    }
  }

  Index third(Index p, Index a, Index b) const {
    for (Index v : pieces_[p].v)
      if (v != a && v != b) return v;
    return pieces_[p].v[0];
  }

  static std::string coplanar_message(Index f, Index g) {
    return "faces " + std::to_string(f) + " and " + std::to_string(g) +
           " overlap in a common plane; regularize does not resolve coplanar overlaps";
  }

  // ---- sub-triangulation (§3.5) ------------------------------------------

  // §3.5 in three steps. plan() gathers what a triangle's sub-triangulation
  // needs and hands out the ids of new points (segments, their crossings):
  // sequential. triangulate() builds it reading its plan and the points
  // only: run for every intersecting triangle, on the other cores while
  // planning goes on, before the growth (the growth reaches all of them
  // anyway). commit_all() turns every result into pieces, in parallel, and
  // sorts their edges into one lookup; the growth only reads them.

  /// A segment of a triangle alone in its plane (its intersection with a
  /// partner) from a to b through the crossings on it, in order.
  struct Chain {
    Index a, b;
    std::vector<Index> on;
  };
  struct Plan {
    Ids cluster;
    int k = 0, i = 0, j = 0;  // projection along axis k onto (i, j)
    std::vector<Index> lone;  // a triangle alone: single-point intersections, in partner order
    std::vector<Chain> segs;  // a triangle alone: its segments
    std::vector<Ends> meets;  // a cluster: its members' intersections with other planes
    /// A triangle alone: the crossings on its edges (edge e from corner e),
    /// as on_edge_ had them when it was handed to be triangulated.
    std::array<std::vector<Index>, 3> on_edges;
  };
  /// A sub-triangulation's faces that are pieces. A vertex is a global id,
  /// or -1 - k for lifted[k] (a crossing the triangulation constructed);
  /// across[e]: the face across edge (v[e], v[e + 1]) inside the
  /// triangulation when that edge is unconstrained (see Piece::across), -1
  /// otherwise.
  struct SubFace {
    std::array<std::int64_t, 3> v;
    Index source;
    int weight;
    std::array<std::int32_t, 3> across;
  };
  struct Triangulated {
    std::vector<EPoint> lifted;
    std::vector<SubFace> faces;
  };

  /// Every intersecting triangle's sub-triangulation, planned in index order
  /// and built in parallel, beside the planning.
  void presplit() {
    std::vector<Index> roots;
    for (std::size_t f = 0; f < soup_.face_count(); ++f)
      if (!partners_[f].empty() && root(Index(f)) == f) roots.push_back(Index(f));
    slot_.assign(soup_.face_count(), kNoPiece);
    plans_.reserve(roots.size());
    const auto t0 = std::chrono::steady_clock::now();
    precompute_crossings();
    seconds_intersections += seconds_since(t0);
    // each cluster's projection axis, from its root (the front of its
    // members), in parallel: to_double of a lazy normal can need its exact value
    std::vector<int> axis(roots.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, roots.size()), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t s = r.begin(); s != r.end(); ++s) axis[s] = projection_axis(roots[s]);
    });
    // Each plan is triangulated (by the other cores) as soon as what it
    // reads is final: the plan itself and, for a triangle alone in its
    // plane, the crossings on its edges. Those are its own segments' ends,
    // named by its own planning, when every segment of its is generic (an
    // edge of it crosses a face only where it meets that face, a partner,
    // and the same generic test names the crossing for both triangles
    // sharing the edge); after all planning otherwise.
    plans_.resize(roots.size());
    triangulated_.resize(roots.size());
    tbb::task_group triangulations;
    // The seeds' line casts need the input's AABB tree right after this; the
    // other core builds it first (the growth has nothing to do beside it).
    triangulations.run([this] { tree(); });
    auto triangulate_later = [&](std::size_t s) {
      Plan& p = plans_[s];
      if (p.cluster.size() == 1) {
        const FaceView fv = soup_.face(roots[s]);
        for (int e = 0; e < 3; ++e)
          if (const auto it = on_edge_.find(undirected_edge_key(fv[e], fv[(e + 1) % 3])); it != on_edge_.end())
            p.on_edges[std::size_t(e)] = it->second;
      }
      triangulations.run([this, s, t = roots[s]] { triangulated_[s] = triangulate(plans_[s], t); });
    };
    std::vector<std::size_t> last;
    for (std::size_t r = 0; r < roots.size(); ++r) {
      slot_[roots[r]] = Index(r);
      plans_[r] = plan(roots[r], axis[r]);
      if (plans_[r].cluster.size() == 1 && not_generic_[roots[r]]) last.push_back(r);
      else triangulate_later(r);
    }
    for (std::size_t r : last) triangulate_later(r);
    triangulations.wait();
    known_crossings_ = {};
  }

  EVector normal(Index f) const {
    const FaceView fv = soup_.face(f);
    return CGAL::cross_product(points_[fv[1]] - points_[fv[0]], points_[fv[2]] - points_[fv[0]]);
  }

  /// The axis a triangle is projected along: its normal's dominant one.
  int projection_axis(Index t) const {
    const EVector n = normal(t);
    int k = dominant_axis(n).first;
    // (by the sign: CGAL 5.5's is_zero on a lazy number always evaluates it exactly)
    auto zero = [&](int a) { return CGAL::sign(n[a]) == CGAL::ZERO; };
    if (zero(k)) k = !zero(0) ? 0 : !zero(1) ? 1 : 2;
    return k;
  }

  /// `axis`: projection_axis(t) (t: the cluster's root, its front).
  Plan plan(Index t, int axis) {
    Plan plan;
    plan.cluster = cluster_of(t);
    const Ids& cluster = plan.cluster;
    // Corners of the cluster and of what it meets first, so that an
    // intersection point that is an input vertex gets that vertex's id.
    for (Index m : cluster) {
      for (Index v : soup_.face(m)) register_vertex(v);
      for (Index u : partners_[m])
        for (Index v : soup_.face(u)) register_vertex(v);
    }
    const int k = axis;
    plan.k = k;
    plan.i = kept_axes(k)[0];
    plan.j = kept_axes(k)[1];
    const auto t0 = std::chrono::steady_clock::now();
    for (Index m : cluster)
      for (Index u : partners_[m])
        if (root(u) != root(m)) {
          const Ends seg = segment(m, u);
          if (cluster.size() > 1) plan.meets.push_back(seg);  // the cluster's own edges are constraints already
        }
    if (cluster.size() == 1) plan_segments(t, plan);
    seconds_intersections += seconds_since(t0);
    return plan;
  }

  /// §3.5 step 2 for a triangle t alone in its plane: its segments go in as
  /// constraints, split first where two of them cross properly (interiors,
  /// decided exactly in the projection). Such a crossing is the point where
  /// the planes of t and both partners meet, named by the three faces: the
  /// three sub-triangulations through it share one exact point, built once
  /// from the input's doubles, instead of three lifted from the constrained
  /// triangulation's own crossings and proved equal exactly. Anything less
  /// generic (segments touching or overlapping) is left to the triangulation.
  void plan_segments(Index t, Plan& plan) {
    const int i = plan.i, j = plan.j;
    struct Seg {  // projected
      Index a, b, u;
      K::Point_2 pa, pb;
      CGAL::Bbox_2 box;
      std::vector<Index> on;  // crossings, by id
    };
    std::vector<Seg> segs;
    for (Index u : partners_[t]) {
      const Ends seg = segment(t, u);
      if (seg.size() == 1) plan.lone.push_back(seg[0]);
      if (seg.size() != 2 || seg[0] == seg[1]) continue;
      Seg x{seg[0], seg[1], u, exact_proj(points_[seg[0]], i, j), exact_proj(points_[seg[1]], i, j), {}, {}};
      x.box = x.pa.bbox() + x.pb.bbox();
      segs.push_back(std::move(x));
    }
    for (std::size_t x = 0; x < segs.size(); ++x)
      for (std::size_t y = x + 1; y < segs.size(); ++y) {
        Seg &p = segs[x], &q = segs[y];
        if (p.a == q.a || p.a == q.b || p.b == q.a || p.b == q.b) continue;
        if (!CGAL::do_overlap(p.box, q.box)) continue;
        const CdtTraits::Orientation_2 orientation;
        const CGAL::Orientation o1 = orientation(p.pa, p.pb, q.pa), o2 = orientation(p.pa, p.pb, q.pb);
        if (o1 == CGAL::COLLINEAR || o2 == CGAL::COLLINEAR || o1 == o2) continue;
        const CGAL::Orientation o3 = orientation(q.pa, q.pb, p.pa), o4 = orientation(q.pa, q.pb, p.pb);
        if (o3 == CGAL::COLLINEAR || o4 == CGAL::COLLINEAR || o3 == o4) continue;
        const std::optional<Index> id = triple_point(t, p.u, q.u);
        if (!id) continue;
        p.on.push_back(*id);
        q.on.push_back(*id);
      }
    for (Seg& x : segs) {
      // a to b through its crossings, ordered along an axis the segment
      // spans (any such axis gives the one order along a line)
      std::sort(x.on.begin(), x.on.end());
      x.on.erase(std::unique(x.on.begin(), x.on.end()), x.on.end());
      if (x.on.size() > 1) {
        const auto [axis, up] = spanned_axis(x.a, x.b, i, j);
        std::sort(x.on.begin(), x.on.end(), [&](Index m, Index n) { return up ? less_along(m, n, axis) : less_along(n, m, axis); });
      }
      plan.segs.push_back({x.a, x.b, std::move(x.on)});
    }
  }

  /// Whether point m's coordinate `axis` is less than point n's, exactly:
  /// by their intervals (tight: disjoint unless the values are within a
  /// double's step) where they decide, else by their rationals. No lazy
  /// number is made (points_[m][axis] is a construction of its own).
  bool less_along(Index m, Index n, int axis) const {
    const auto &x = points_[m].approx()[axis], &y = points_[n].approx()[axis];
    if (x.sup() < y.inf()) return true;
    if (x.inf() >= y.sup()) return false;
    return points_[m].exact()[axis] < points_[n].exact()[axis];
  }

  /// An axis of (i, j) along which a and b differ (a != b in the plane
  /// projected along the third), and whether b is above a on it: the one
  /// where they are farther apart, as far as their intervals tell.
  std::pair<int, bool> spanned_axis(Index a, Index b, int i, int j) const {
    const auto &pa = points_[a].approx(), &pb = points_[b].approx();
    auto apart = [&](int c) { return pa[c].sup() < pb[c].inf() || pb[c].sup() < pa[c].inf(); };
    auto gap = [&](int c) { return std::abs(0.5 * (pb[c].inf() + pb[c].sup()) - 0.5 * (pa[c].inf() + pa[c].sup())); };
    int axis = -1;
    if (apart(i) && (!apart(j) || gap(i) >= gap(j))) axis = i;
    else if (apart(j)) axis = j;
    if (axis >= 0) return {axis, pa[axis].sup() < pb[axis].inf()};
    // within a double's step on both axes: exactly (at least one differs)
    const auto &ea = points_[a].exact(), &eb = points_[b].exact();
    axis = ea[i] != eb[i] ? i : j;
    return {axis, ea[axis] < eb[axis]};
  }

  /// The constraint a-b. Where a-b is an edge already it is only marked:
  /// CGAL's insert_constraint first asks each of a's other neighbours
  /// whether it lies on a-b, and along a chain of points on one segment the
  /// point before a always does — exactly, which no filter decides (the
  /// triangulations' most frequent exact test). The same triangulation
  /// either way: a Delaunay edge stays one when constrained.
  static void constrain(CDT& cdt, CDT::Vertex_handle a, CDT::Vertex_handle b) {
    CDT::Face_handle f;
    int i = 0;
    if (cdt.dimension() == 2 && cdt.is_edge(a, b, f, i)) {
      f->set_constraint(i, true);
      f->neighbor(i)->set_constraint(cdt.mirror_index(f, i), true);
      return;
    }
    cdt.insert_constraint(a, b);
  }

  /// The constrained triangulation of t's plan; reads the plan and points_
  /// only (elements of which never move), so it runs beside planning.
  Triangulated triangulate(const Plan& plan, Index t) const {
    const Ids& cluster = plan.cluster;
    const int i = plan.i, j = plan.j, k = plan.k;
    CDT cdt;
    std::unordered_map<Index, CDT::Vertex_handle> placed;  // points inserted where they are known to lie
    auto insert = [&](Index id) {
      if (const auto it = placed.find(id); it != placed.end()) return it->second;
      const CDT::Vertex_handle h = cdt.insert(exact_proj(points_[id], i, j));
      if (h->info().id < 0) h->info().id = id;
      // a point inserted again (a segment's end is the next one's start)
      // would be located anew and found equal to its vertex: an exact test
      placed.emplace(id, h);
      return h;
    };
    // each member's corners in the projection and its orientation there
    std::vector<std::array<K::Point_2, 3>> corners;
    std::vector<int> sign;
    for (Index m : cluster) {
      const FaceView mv = soup_.face(m);
      std::array<CDT::Vertex_handle, 3> h;
      for (int e = 0; e < 3; ++e) h[e] = insert(mv[e]);
      if (cluster.size() > 1)
        for (int e = 0; e < 3; ++e) cdt.insert_constraint(h[e], h[(e + 1) % 3]);
      corners.push_back({h[0]->point(), h[1]->point(), h[2]->point()});
      sign.push_back(int(CGAL::orientation(corners.back()[0], corners.back()[1], corners.back()[2])));
    }
    if (cluster.size() == 1) {
      place_edge_points(cdt, t, plan, placed);
      for (Index id : plan.lone) insert(id);
      for (const Chain& x : plan.segs) {
        CDT::Vertex_handle from = insert(x.a);
        for (Index id : x.on) {
          const CDT::Vertex_handle h = insert(id);
          if (h != from) constrain(cdt, from, h);
          from = h;
        }
        const CDT::Vertex_handle end = insert(x.b);
        if (end != from) constrain(cdt, from, end);
      }
    } else {
      for (const Ends& seg : plan.meets) {
        if (seg.size() == 1) insert(seg[0]);
        if (seg.size() == 2) cdt.insert_constraint(insert(seg[0]), insert(seg[1]));
      }
    }
    Triangulated out;
    // crossings of segments (§3.5 step 2), lifted back onto the plane
    const EPoint& A = points_[soup_.face(cluster.front())[0]];
    std::optional<EVector> normal_here;
    for (auto h = cdt.finite_vertices_begin(); h != cdt.finite_vertices_end(); ++h) {
      if (h->info().id >= 0) continue;
      if (!normal_here) normal_here = normal(cluster.front());
      const EVector& n = *normal_here;
      std::array<K::FT, 3> c;
      c[i] = h->point().x();
      c[j] = h->point().y();
      c[k] = A[k] - (n[i] * (c[i] - A[i]) + n[j] * (c[j] - A[j])) / n[k];
      h->info().id = -1 - std::int64_t(out.lifted.size());
      out.lifted.emplace_back(c[0], c[1], c[2]);
    }
    std::vector<std::array<CDT::Vertex_handle, 3>> corner_of;  // per face made, its corners in piece order
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      f->info() = kNoPiece;
      // net count of the members covering this face (counter-clockwise: +1)
      int count = sign[0];
      Index source = cluster.front();
      if (cluster.size() > 1) {
        const K::Point_2 c = CGAL::centroid(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point());
        count = 0;
        std::vector<std::size_t> covering;
        for (std::size_t m = 0; m < cluster.size(); ++m) {
          bool inside = true;
          for (int e = 0; e < 3 && inside; ++e)
            inside = int(CGAL::orientation(corners[m][e], corners[m][(e + 1) % 3], c)) == sign[m];
          if (!inside) continue;
          count += sign[m];
          covering.push_back(m);
        }
        if (count == 0) continue;  // opposite sheets cancel (or no member there)
        for (std::size_t m : covering)  // provenance: a member oriented like the piece
          if (sign[m] * count > 0) {
            source = cluster[m];
            break;
          }
      }
      std::array<CDT::Vertex_handle, 3> h{f->vertex(0), f->vertex(1), f->vertex(2)};
      if (count < 0) std::swap(h[1], h[2]);
      f->info() = Index(out.faces.size());
      out.faces.push_back({{h[0]->info().id, h[1]->info().id, h[2]->info().id}, source, std::abs(count), {-1, -1, -1}});
      corner_of.push_back(h);
    }
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (f->info() == kNoPiece) continue;
      SubFace& face = out.faces[f->info()];
      for (int e = 0; e < 3; ++e) {
        const int opposite = f->index(corner_of[f->info()][(e + 2) % 3]);  // f's vertex opposite edge e
        const CDT::Face_handle g = f->neighbor(opposite);
        if (!f->is_constrained(opposite) && !cdt.is_infinite(g) && g->info() != kNoPiece)
          face.across[e] = std::int32_t(g->info());
      }
    }
    return out;
  }

  /// Replaces every input triangle that intersects others by its
  /// sub-triangles (§3.5 steps 1-3; the triangles it overlaps in its own
  /// plane, its cluster, are split with it in one triangulation: a face of
  /// it covered by several of them is one piece, oriented and weighted by
  /// their net count, zero for no surface there). The pieces are numbered by
  /// slot and made in parallel, with the lookup of every edge that no
  /// `across` links (edge_uses_, edge_group_); the growth reads them only.
  void commit_all() {
    const std::size_t slots = plans_.size(), faces = soup_.face_count();
    // the points triangulations constructed (few), named in slot order
    std::vector<std::vector<Index>> lifted(slots);
    for (std::size_t s = 0; s < slots; ++s)
      for (const EPoint& p : triangulated_[s].lifted) lifted[s].push_back(vertex_id(p));
    std::vector<std::size_t> open(slots + 1, 0);  // per slot: its pieces' edges without `across`
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t s) {
      for (const SubFace& face : triangulated_[s].faces)
        for (int e = 0; e < 3; ++e) open[s + 1] += face.across[e] < 0 ? 1 : 0;
    });
    base_.assign(slots + 1, Index(faces));
    open[0] = edge_uses_.size();  // the input triangles' uses come first
    for (std::size_t s = 0; s < slots; ++s) {
      base_[s + 1] = base_[s] + Index(triangulated_[s].faces.size());
      open[s + 1] += open[s];
    }
    pieces_.resize(base_[slots]);
    edge_uses_.resize(open[slots]);
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t s) {
      std::size_t u = open[s];
      Index q = base_[s];
      for (const SubFace& face : triangulated_[s].faces) {
        Piece& piece = pieces_[q];
        for (int e = 0; e < 3; ++e)
          piece.v[e] = face.v[e] >= 0 ? Index(face.v[e]) : lifted[s][std::size_t(-1 - face.v[e])];
        piece.source = face.source;
        piece.weight = face.weight;
        for (int e = 0; e < 3; ++e) {
          if (face.across[e] >= 0) piece.across[e] = base_[s] + Index(face.across[e]);
          else edge_uses_[u++] = {undirected_edge_key(piece.v[e], piece.v[(e + 1) % 3]), 3 * q + Index(e)};
        }
        ++q;
      }
    });
    for (std::size_t f = 0; f < faces; ++f)
      if (!partners_[f].empty()) pieces_[f].alive = false;  // its pieces take its place
    for (std::size_t s = 0; s < slots; ++s) r_.triangles_split += plans_[s].cluster.size();
    r_.sub_triangles += base_[slots] - faces;
    triangulated_ = {};
    tbb::parallel_sort(edge_uses_.begin(), edge_uses_.end());
    edge_group_.assign(3 * pieces_.size(), kNoPiece);
    river_done_.assign(edge_uses_.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edge_uses_.size()),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        std::size_t start = r.begin();
                        while (start > 0 && edge_uses_[start - 1].key == edge_uses_[r.begin()].key) --start;
                        for (std::size_t k = r.begin(); k != r.end(); ++k) {
                          if (edge_uses_[k].key != edge_uses_[start].key) start = k;
                          edge_group_[edge_uses_[k].use] = Index(start);
                        }
                      });
  }

  /// The point common to the planes of input faces t, u and w (nullopt when
  /// they do not meet in one point), named by the three faces.
  std::optional<Index> triple_point(Index t, Index u, Index w) {
    std::array<Index, 3> key{t, u, w};
    std::sort(key.begin(), key.end());
    if (const auto it = triples_.find(key); it != triples_.end()) return it->second;
    detail::Homogeneous x;
    if (detail::planes_meet_exactly(triangle(t), triangle(u), triangle(w), x) != detail::Meeting::point)
      return std::nullopt;
    const Index id = vertex_id(exact_point(x));
    triples_.emplace(key, id);
    return id;
  }

  detail::Triangle3d triangle(Index f) const {
    const FaceView v = soup_.face(f);
    return {soup_.points[v[0]], soup_.points[v[1]], soup_.points[v[2]]};
  }

  /// The intersection of input triangles t and u as global vertex ids (one
  /// point or a segment's two ends), constructed once per pair (§3.2).
  Ends segment(Index t, Index u) {
    const std::uint64_t key = undirected_edge_key(t, u);
    if (const Ends* known = segments_.find(key)) return *known;
    ++r_.segments;
    Ends ids;
    if (!generic_segment(t, u, ids, [this](Index p, Index q, Index w) { return edge_crossing(p, q, w); })) {
      not_generic_[t] = not_generic_[u] = 1;
      auto tri = [&](Index f) {
        const FaceView fv = soup_.face(f);
        return K::Triangle_3(points_[fv[0]], points_[fv[1]], points_[fv[2]]);
      };
      if (const auto result = CGAL::intersection(tri(t), tri(u))) {
        if (const EPoint* p = boost::get<EPoint>(&*result)) {
          ids.push_back(vertex_id(*p));
        } else if (const K::Segment_3* s = boost::get<K::Segment_3>(&*result)) {
          ids.push_back(vertex_id(s->source()));
          ids.push_back(vertex_id(s->target()));
        } else {
          throw UnsupportedInput(coplanar_message(t, u));
        }
      }
    }
    segments_[key] = ids;
    return segments_[key];
  }

  /// The common case of segment(): triangles t and u in general position
  /// with respect to each other (no corner of either in the other's plane,
  /// no edge through an edge or a corner of the other), decided exactly on
  /// the input's doubles. Then each end of their segment is where an edge of
  /// one crosses the other, and is named by that pair, so the neighbour
  /// sharing the edge gets the same point without comparing exact numbers.
  /// False (ids untouched) when not in general position. `cross(p, q, w)`
  /// names the point where edge pq crosses face w (edge_crossing, or a
  /// pass that only collects the names).
  template <class Cross>
  bool generic_segment(Index t, Index u, Ends& ids, const Cross& cross) const {
    const FaceView tv = soup_.face(t), uv = soup_.face(u);
    auto ip = [&](Index v) { return IK::Point_3(soup_.points[v][0], soup_.points[v][1], soup_.points[v][2]); };
    const std::array<IK::Point_3, 3> a{ip(tv[0]), ip(tv[1]), ip(tv[2])}, b{ip(uv[0]), ip(uv[1]), ip(uv[2])};
    int shared = 0;
    for (Index x : tv) shared += (x == uv[0] || x == uv[1] || x == uv[2]) ? 1 : 0;
    if (shared == 1) return generic_shared_vertex(t, tv, a, u, uv, b, ids, cross);
    if (shared > 1) return false;
    std::array<CGAL::Orientation, 3> oa, ob;
    for (int k = 0; k < 3; ++k) {
      oa[k] = CGAL::orientation(b[0], b[1], b[2], a[k]);
      ob[k] = CGAL::orientation(a[0], a[1], a[2], b[k]);
      if (oa[k] == CGAL::COPLANAR || ob[k] == CGAL::COPLANAR) return false;
    }
    Ends found;
    // edges of x (corners sides ox against y's plane) crossing triangle y
    auto crossings = [&](const FaceView& xv, const std::array<IK::Point_3, 3>& x, const std::array<CGAL::Orientation, 3>& ox,
                         const std::array<IK::Point_3, 3>& y, Index y_face) {
      for (int e = 0; e < 3; ++e) {
        const int f = (e + 1) % 3;
        if (ox[e] == ox[f]) continue;  // the edge stays on one side of y's plane
        std::array<CGAL::Orientation, 3> side;
        for (int k = 0; k < 3; ++k) {
          side[k] = CGAL::orientation(x[e], x[f], y[k], y[(k + 1) % 3]);
          if (side[k] == CGAL::COPLANAR) return false;  // through an edge or a corner of y
        }
        if (side[0] != side[1] || side[1] != side[2]) continue;  // passes beside y
        found.push_back(cross(xv[e], xv[f], y_face));
      }
      return true;
    };
    if (!crossings(tv, a, oa, b, u) || !crossings(uv, b, ob, a, t)) return false;
    if (found.size() != 2 && !found.empty()) return false;  // cannot happen in general position
    ids = found;
    return true;
  }

  /// generic_segment() for triangles sharing one vertex s (a raw offset's
  /// face and the strip beside it): their segment runs from s to where the
  /// edge opposite s in one of them crosses the other.
  template <class Cross>
  bool generic_shared_vertex(Index t, const FaceView& tv, const std::array<IK::Point_3, 3>& a, Index u,
                             const FaceView& uv, const std::array<IK::Point_3, 3>& b, Ends& ids,
                             const Cross& cross) const {
    Index s = 0;
    for (Index x : tv)
      if (x == uv[0] || x == uv[1] || x == uv[2]) s = x;
    Ends found;
    // the edge of x opposite s against triangle y (y_face: its input face)
    auto opposite = [&](const FaceView& xv, const std::array<IK::Point_3, 3>& x, const std::array<IK::Point_3, 3>& y,
                        Index y_face) {
      int k = 0;
      while (xv[k] != s) ++k;
      const int e = (k + 1) % 3, f = (k + 2) % 3;
      const CGAL::Orientation oe = CGAL::orientation(y[0], y[1], y[2], x[e]);
      const CGAL::Orientation of = CGAL::orientation(y[0], y[1], y[2], x[f]);
      if (oe == CGAL::COPLANAR || of == CGAL::COPLANAR) return false;
      if (oe == of) return true;  // the edge stays on one side of y's plane
      std::array<CGAL::Orientation, 3> side;
      for (int j = 0; j < 3; ++j) {
        side[j] = CGAL::orientation(x[e], x[f], y[j], y[(j + 1) % 3]);
        if (side[j] == CGAL::COPLANAR) return false;
      }
      if (side[0] == side[1] && side[1] == side[2]) found.push_back(cross(xv[e], xv[f], y_face));
      return true;
    };
    if (!opposite(tv, a, b, u) || !opposite(uv, b, a, t)) return false;
    if (found.size() != 1) return false;
    ids = {s, found[0]};
    return true;
  }

  /// Inserts the points known to lie on triangle t's edges (the crossings
  /// named by edge_crossing, handed over in its plan) at their place:
  /// sorted along each edge and split into it, so the triangulation never
  /// tests their (exactly zero) orientation against the edge.
  void place_edge_points(CDT& cdt, Index t, const Plan& plan,
                         std::unordered_map<Index, CDT::Vertex_handle>& placed) const {
    const int i = plan.i, j = plan.j;
    const FaceView fv = soup_.face(t);
    std::array<CDT::Vertex_handle, 3> corner;
    for (auto h = cdt.finite_vertices_begin(); h != cdt.finite_vertices_end(); ++h)
      for (int c = 0; c < 3; ++c)
        if (h->info().id == std::int64_t(fv[c])) corner[c] = h;
    for (int e = 0; e < 3; ++e) {
      std::vector<Index> pts = plan.on_edges[std::size_t(e)];
      if (pts.empty()) continue;
      std::sort(pts.begin(), pts.end());
      pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
      // along the edge from corner e: by the coordinate that changes most
      const auto [axis, along] = dominant_axis(points_[fv[(e + 1) % 3]] - points_[fv[e]]);
      const bool up = along > 0;
      std::sort(pts.begin(), pts.end(), [&](Index x, Index y) { return up ? less_along(x, y, axis) : less_along(y, x, axis); });
      CDT::Vertex_handle prev = corner[e];
      const CDT::Vertex_handle end = corner[(e + 1) % 3];
      for (Index id : pts) {
        CDT::Face_handle face;
        int index = 0;
        if (!cdt.is_edge(prev, end, face, index)) return;  // cannot happen; the general insert takes over
        const CDT::Vertex_handle h = cdt.insert(exact_proj(points_[id], i, j), CDT::EDGE, face, index);
        if (h->info().id < 0) h->info().id = id;
        placed.emplace(id, h);
        prev = h;
      }
    }
  }

  EPoint crossing_point(Index p, Index q, Index w) const {
    detail::Homogeneous x;
    detail::line_meets_plane(soup_.points[p], soup_.points[q], triangle(w), x);  // a point: p and q on either side
    return exact_point(x);
  }

  /// The points the generic pairs' segments will end at (edge crossings),
  /// found and constructed in parallel before planning hands out their ids
  /// in its own order (the same ids as constructing them there).
  void precompute_crossings() {
    struct Name {
      std::pair<std::uint64_t, Index> key;  // (edge, face), as in crossings_
      Index p, q;
    };
    std::vector<std::vector<Name>> named(soup_.face_count());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, soup_.face_count()), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t t = r.begin(); t != r.end(); ++t)
        for (Index u : partners_[t]) {
          if (u < t) continue;  // each pair once
          Ends ends;
          generic_segment(Index(t), u, ends, [&](Index p, Index q, Index w) {
            named[t].push_back({{undirected_edge_key(p, q), w}, p, q});
            return Index(0);
          });
        }
    });
    std::vector<Name> names;
    for (auto& list : named) names.insert(names.end(), list.begin(), list.end());
    named = {};
    tbb::parallel_sort(names.begin(), names.end(), [](const Name& x, const Name& y) { return x.key < y.key; });
    names.erase(std::unique(names.begin(), names.end(), [](const Name& x, const Name& y) { return x.key == y.key; }),
                names.end());
    known_crossings_.resize(names.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, names.size()), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        KnownCrossing& c = known_crossings_[k];
        c.name = names[k].key;
        c.point = crossing_point(names[k].p, names[k].q, names[k].key.second);
        c.hash = value_hash(c.point);
      }
    });
  }

  /// The point where edge pq crosses the plane of input face w (exact), by
  /// name: computed once per (edge, face).
  Index edge_crossing(Index p, Index q, Index w) {
    const std::pair<std::uint64_t, Index> name{undirected_edge_key(p, q), w};
    const auto known = std::lower_bound(known_crossings_.begin(), known_crossings_.end(), name,
                                        [](const KnownCrossing& x, const auto& key) { return x.name < key; });
    Index* id = nullptr;
    if (known != known_crossings_.end() && known->name == name) {
      id = &known->id;
      if (*id == kNoPiece) *id = vertex_id(known->point, known->hash);
      else return *id;
    } else {  // (not met by precompute_crossings(): cannot happen)
      const auto [it, inserted] = crossings_.try_emplace(name, Index(0));
      if (!inserted) return it->second;
      id = &it->second;
      *id = vertex_id(crossing_point(p, q, w));
    }
    on_edge_[name.first].push_back(*id);
    return *id;
  }

  void register_vertex(Index v) {
    if (registered_[v]) return;
    registered_[v] = 1;
    const std::uint64_t hash = value_hash(points_[v]);
    if (known_id(points_[v], hash) == kNoPiece) remember(v, hash);
  }

  /// The id of exact point p: an input vertex's (if registered), or a new one.
  Index vertex_id(const EPoint& p) { return vertex_id(p, value_hash(p)); }
  Index vertex_id(const EPoint& p, std::uint64_t hash) {
    if (const Index id = known_id(p, hash); id != kNoPiece) return id;
    points_.push_back(p);
    remember(Index(points_.size() - 1), hash);
    return Index(points_.size() - 1);
  }

  /// A hash of p's exact value (equal points, equal hashes): of its
  /// coordinates where they are doubles, else of their exact values
  /// truncated to doubles, read from tight intervals. The points here are
  /// homogeneous (lazy_point: tight intervals, no rationals made) but for
  /// the few that CGAL's intersection constructed (evaluated here).
  static std::uint64_t value_hash(const EPoint& p) {
    if (const auto& a = p.approx(); !(a.x().is_point() && a.y().is_point() && a.z().is_point()) &&
                                    !detail::homogeneous_of<EPoint, 3>(p))
      (void)p.exact();  // a node's intervals become its exact value's (tight) once evaluated
    // Tight intervals: a double, or the two doubles either side of the
    // value; the end nearer zero is the value truncated (as mpq_get_d).
    const auto& a = p.approx();
    Point3d key;
    for (int c = 0; c < 3; ++c) key[c] = a[c].is_point() || a[c].inf() >= 0 ? a[c].inf() : a[c].sup();
    return hash_points(&key, 1);
  }

  /// The registered point equal to p (of value_hash `hash`), kNoPiece if none.
  Index known_id(const EPoint& p, std::uint64_t hash) const {
    const Head* head = dedup_.find(hash);
    for (Index id = head ? head->id : kNoPiece; id != kNoPiece; id = same_hash_[id])
      if (points_[id] == p) return id;
    return kNoPiece;
  }

  /// Registers point `id` (equal to none registered; of value_hash `hash`).
  void remember(Index id, std::uint64_t hash) {
    if (same_hash_.size() <= id) same_hash_.resize(std::max<std::size_t>(id + 1, 2 * same_hash_.size()), kNoPiece);
    Head& head = dedup_[hash];
    same_hash_[id] = head.id;
    head.id = id;
  }

  const Soup& soup_;
  RegularizeReport& r_;
  /// Input vertices, then points on intersection curves. Elements never
  /// move: planning appends while other threads triangulate earlier plans.
  tbb::concurrent_vector<EPoint> points_;
  /// Registered points by value_hash: the last registered, then each the
  /// one before (same_hash_, by point id); equal points are one.
  struct Head {
    Index id = kNoPiece;
  };
  KeyMap<Head> dedup_;
  std::vector<Index> same_hash_;
  std::vector<std::vector<Index>> partners_;  // per input face: the faces it intersects
  std::vector<char> registered_;
  std::vector<char> not_generic_;  // per input face: a segment of it is not generic_segment()'s
  std::vector<Index> slot_;                // per cluster root: its plan and triangulation
  std::vector<Plan> plans_;
  std::vector<Triangulated> triangulated_;  // until committed
  std::vector<Index> base_;                 // per slot: its first piece (base_[slots]: the end)
  std::vector<Piece> pieces_;               // input faces (ids 0..F-1), then sub-triangles by slot
  std::vector<Index> patch_;                // per piece: its patch (link_patches()), named by its least piece
  std::vector<char> patch_state_;           // per patch: State
  std::vector<int> patch_front_;            // per patch: outer winding number, once classified
  /// Patches' sides on intersection curves: patch << 32 | 3 * piece + edge, sorted.
  std::vector<std::uint64_t> river_sides_;
  std::vector<Index> unjoined_;  // a piece per edge of it where the growth stops (see link_patches())
  struct Isolated {
    Index piece = 0;
    std::optional<int> winding;
    std::size_t lines = 0;  // lines cast for it
  };
  std::vector<Isolated> isolated_;  // by piece: cast_isolated()
  /// A use of an edge by a piece: 3 * piece + e for its edge e (from corner e).
  struct EdgeUse {
    std::uint64_t key;
    Index use;
    bool operator<(const EdgeUse& o) const { return key != o.key ? key < o.key : use < o.use; }
  };
  /// The uses of every edge no `across` links, sorted by edge, then piece:
  /// input faces (but two untouched ones') first, then sub-triangles.
  std::vector<EdgeUse> edge_uses_;
  std::vector<Index> edge_group_;  // per use (an edge without `across`): its edge's first in edge_uses_
  std::vector<std::pair<std::uint64_t, Index>> face_edges_;  // (edge, 3 * input face + e), sorted
  KeyMap<Ends> segments_;                                             // by face pair
  struct PairHash {
    std::size_t operator()(const std::pair<std::uint64_t, Index>& k) const {
      return std::hash<std::uint64_t>()(k.first * 0x9E3779B97F4A7C15ull ^ k.second);
    }
  };
  std::unordered_map<std::pair<std::uint64_t, Index>, Index, PairHash> crossings_;  // (edge, face) -> point
  std::unordered_map<std::uint64_t, std::vector<Index>> on_edge_;                   // input edge -> its crossings
  /// A crossing precompute_crossings() found: its name (edge, face), point,
  /// value_hash, and id once planning handed one out.
  struct KnownCrossing {
    std::pair<std::uint64_t, Index> name;
    EPoint point;
    std::uint64_t hash = 0;
    Index id = kNoPiece;
  };
  std::vector<KnownCrossing> known_crossings_;  // by name, sorted (planning only)
  struct TripleHash {
    std::size_t operator()(const std::array<Index, 3>& k) const {
      return std::hash<std::uint64_t>()((std::uint64_t(k[0]) << 42) ^ (std::uint64_t(k[1]) << 21) ^ k[2]);
    }
  };
  std::unordered_map<std::array<Index, 3>, Index, TripleHash> triples_;  // crossing of two segments on a face
  std::vector<char> river_done_;  // by edge (its first in edge_uses_): an intersection curve's, all classified
  std::vector<char> zero_area_;                                         // per input face (§3.1)
  std::vector<Index> roots_;  // per input face: the root of its cluster (coplanar overlaps, joined)
  tbb::task_group rounding_;        // run() -> output(): the new points rounded
  std::vector<Point3d> rounded_;    // per new point (after the input's): its nearest double
  std::unordered_map<Index, std::vector<Index>> members_;              // cluster root -> its faces (2 or more)

  InputTriangles triangles_;
  Tree tree_;
};

/// Distinct exact points can round to one double (slivers thinner than the
/// spacing of doubles): those vertices merge, and the faces that lose a
/// corner to it — zero-area at the written precision — go (snap rounding).
void snap_rounded(RegularizeResult& result, std::vector<char>& made, RegularizeReport& r) {
  Soup& s = result.soup;
  const Weld weld = weld_identical_points(s.points);
  if (weld.merged == 0) return;
  r.rounding_merged += weld.merged;
  Soup out;
  std::vector<std::size_t> source;
  std::vector<std::int64_t> id(s.points.size(), -1);
  std::vector<char> out_made;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    std::array<Index, 3> v;
    for (int k = 0; k < 3; ++k) v[k] = weld.representative[s.face(f)[k]];
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
      ++r.rounding_collapsed;
      continue;
    }
    for (Index& x : v) {
      if (id[x] < 0) {
        id[x] = std::int64_t(out.points.size());
        out.points.push_back(s.points[x]);
        out_made.push_back(made[x]);
      }
      x = Index(id[x]);
    }
    out.add_triangle(v[0], v[1], v[2]);
    source.push_back(result.source_face[f]);
  }
  s = std::move(out);
  result.source_face = std::move(source);
  made = std::move(out_made);
}

/// The faces around edge ab (three or more) paired into sheets: sorted by
/// angle around the edge (exact predicates on the doubles), each face
/// running b -> a with the next one, across the wedge inside both (a face
/// running a -> b has its normal towards increasing angle). Empty when the
/// faces do not alternate that way (coincident faces, say).
std::vector<std::pair<Index, Index>> pair_sheets(const Soup& s, Index a, Index b, const std::vector<Index>& faces) {
  auto ip = [&](Index v) { return IK::Point_3(s.points[v][0], s.points[v][1], s.points[v][2]); };
  const IK::Point_3 A = ip(a), B = ip(b);
  struct Item {
    Index face;
    IK::Point_3 c;
    bool forward;  // runs a -> b
    int half;      // -1: the reference; 0: (0, pi); 1: pi; 2: (pi, 2 pi)
  };
  std::vector<Item> items;
  for (Index f : faces) {
    const FaceView v = s.face(f);
    Index third = v[0];
    bool forward = false;
    for (int k = 0; k < 3; ++k) {
      if (v[k] != a && v[k] != b) third = v[k];
      if (v[k] == a && v[(k + 1) % 3] == b) forward = true;
    }
    items.push_back({f, ip(third), forward, 0});
  }
  items[0].half = -1;
  for (std::size_t k = 1; k < items.size(); ++k) {
    const CGAL::Orientation o = CGAL::orientation(A, B, items[0].c, items[k].c);
    if (o == CGAL::POSITIVE) items[k].half = 0;
    else if (o == CGAL::NEGATIVE) items[k].half = 2;
    else if (CGAL::coplanar_orientation(A, B, items[0].c, items[k].c) == CGAL::POSITIVE) return {};  // coincident
    else items[k].half = 1;
  }
  bool tie = false;
  std::sort(items.begin(), items.end(), [&](const Item& x, const Item& y) {
    if (x.half != y.half) return x.half < y.half;
    if (x.half == -1 || x.half == 1) return false;
    const CGAL::Orientation o = CGAL::orientation(A, B, x.c, y.c);
    if (o == CGAL::COPLANAR) tie = true;
    return o == CGAL::POSITIVE;
  });
  if (tie) return {};
  std::vector<std::pair<Index, Index>> sheets;
  const std::size_t n = items.size();
  for (std::size_t k = 0; k < n; ++k) {
    if (items[k].forward) continue;
    const Item& next = items[(k + 1) % n];
    if (!next.forward) return {};
    sheets.push_back({items[k].face, next.face});
  }
  return 2 * sheets.size() == n ? sheets : std::vector<std::pair<Index, Index>>{};
}

/// The union's boundary can pinch: at a vertex where two of its cones touch
/// (two faces sharing the vertex fold through each other, so the valid
/// sectors around it meet only there), or along edges where it touches
/// itself (pair_sheets), the exact result is not a 2-manifold.
/// Each cone gets its own copy of the vertex, moved into its cone by 1% of
/// its shortest edge there: the cones come apart, the surface moves by that
/// much (reported as the distance to the input), and the changed faces are
/// checked again (made[] marks the copies as new points).
void split_pinches(const Soup& input, bool input_manifold, RegularizeResult& result, std::vector<char>& made,
                   RegularizeReport& r) {
  Soup& s = result.soup;
  const std::size_t F = s.face_count();
  // Only vertices of faces that are not input faces kept as they were can
  // pinch (and any vertex, if the input itself is not a manifold).
  std::vector<char> candidate(s.points.size(), input_manifold ? 0 : 1);
  if (input_manifold) {
    std::vector<char> kept(F);
    tbb::parallel_for(std::size_t(0), F,
                      [&](std::size_t f) { kept[f] = kept_as_input(input, s, result.source_face, f) ? 1 : 0; });
    for (std::size_t f = 0; f < F; ++f)
      if (!kept[f])
        for (Index v : s.face(f)) candidate[v] = 1;
  }
  // (vertex, other end of an edge at it) and the face: faces around a
  // vertex that share an edge there belong to one cone
  struct Use {
    std::uint64_t edge;  // vertex << 32 | other end
    Index face;
    Index vertex() const { return Index(edge >> 32); }
    bool operator<(const Use& o) const { return edge != o.edge ? edge < o.edge : face < o.face; }
  };
  std::vector<Use> uses;
  for (std::size_t f = 0; f < F; ++f)
    for (int k = 0; k < 3; ++k) {
      const Index v = s.face(f)[k];
      if (!candidate[v]) continue;
      uses.push_back({std::uint64_t(v) << 32 | s.face(f)[(k + 1) % 3], Index(f)});
      uses.push_back({std::uint64_t(v) << 32 | s.face(f)[(k + 2) % 3], Index(f)});
    }
  tbb::parallel_sort(uses.begin(), uses.end());  // (equal entries are identical: any order is the one order)
  std::vector<std::size_t> starts;  // each vertex's run of uses
  for (std::size_t k = 0; k < uses.size(); ++k)
    if (k == 0 || uses[k].vertex() != uses[k - 1].vertex()) starts.push_back(k);
  starts.push_back(uses.size());
  // Per vertex, in parallel (a vertex's cones are made of its own corners):
  // its corners 3f + k joined into cones; the vertices with more than one.
  struct Pinch {
    Index v;
    std::vector<std::vector<Index>> cones;  // corners, ascending; cones by their least corner
  };
  // face f's corner at vertex v: 3f + its place in f
  auto corner_at = [&](Index f, Index v) {
    const FaceView fv = s.face(f);
    return Index(3 * f + (fv[0] == v ? 0 : fv[1] == v ? 1 : 2));
  };
  tbb::enumerable_thread_specific<std::vector<Pinch>> found;
  tbb::enumerable_thread_specific<std::vector<std::array<Index, 2>>> sheet_edges;  // (v, other end), v < other
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, starts.size() - 1), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Index> corners;
    std::vector<std::size_t> cone_of;
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      const std::size_t k0 = starts[g], k1 = starts[g + 1];
      const Index v = uses[k0].vertex();
      auto corner = [&](Index f) { return corner_at(f, v); };
      corners.clear();
      for (std::size_t k = k0; k < k1; ++k) corners.push_back(corner(uses[k].face));
      std::sort(corners.begin(), corners.end());
      corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
      UnionFind cone(corners.size());  // over the corners' places: a cone's root is its least corner
      auto unite = [&](Index f, Index h) {
        auto place = [&](Index x) {
          return std::size_t(std::lower_bound(corners.begin(), corners.end(), corner(x)) - corners.begin());
        };
        cone.unite(place(f), place(h));
      };
      for (std::size_t k = k0; k < k1;) {
        std::size_t m = k;
        while (m < k1 && uses[m].edge == uses[k].edge) ++m;
        if (m - k > 2) {
          // a non-manifold edge: the union's boundary touches itself along it;
          // each solid's two faces there (around its inside wedge) form one
          // sheet, so the sheets come apart like the cones of a pinch
          std::vector<Index> faces;
          for (std::size_t q = k; q < m; ++q) faces.push_back(uses[q].face);
          const auto sheets = pair_sheets(s, v, Index(uses[k].edge), faces);
          if (!sheets.empty()) {
            for (const auto& [f, h] : sheets) unite(f, h);
            if (v < Index(uses[k].edge)) sheet_edges.local().push_back({v, Index(uses[k].edge)});
            k = m;
            continue;
          }
        }
        for (std::size_t q = k + 1; q < m; ++q) unite(uses[q].face, uses[k].face);
        k = m;
      }
      bool pinched = false;
      for (std::size_t i = 0; i < corners.size() && !pinched; ++i) pinched = cone.find(i) != 0;
      if (!pinched) continue;
      Pinch pinch{v, {}};
      cone_of.assign(corners.size(), 0);
      for (std::size_t i = 0; i < corners.size(); ++i) {
        const std::size_t root = cone.find(i);
        if (root == i) {  // a cone's least corner: cones come in that order
          cone_of[i] = pinch.cones.size();
          pinch.cones.emplace_back();
        }
        cone_of[i] = cone_of[root];
        pinch.cones[cone_of[i]].push_back(corners[i]);
      }
      found.local().push_back(std::move(pinch));
    }
  });
  std::vector<Pinch> pinches;
  for (auto& list : found)
    for (Pinch& pinch : list) pinches.push_back(std::move(pinch));
  std::sort(pinches.begin(), pinches.end(), [](const Pinch& a, const Pinch& b) { return a.v < b.v; });
  auto split = [&](const Pinch& pinch) {
    ++r.pinches_split;
    const Index v = pinch.v;
    const Point3d p = s.points[v];
    bool first = true;
    for (const std::vector<Index>& corners : pinch.cones) {
      Point3d centre{0, 0, 0};
      double shortest = std::numeric_limits<double>::infinity();
      std::size_t n = 0;
      for (Index c : corners) {
        const FaceView fv = s.face(c / 3);
        for (int k = 1; k < 3; ++k) {
          const Point3d& q = s.points[fv[(c % 3 + k) % 3]];
          const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
          shortest = std::min(shortest, std::sqrt(dx * dx + dy * dy + dz * dz));
          for (int a = 0; a < 3; ++a) centre[a] += q[a];
          ++n;
        }
      }
      Point3d dir{centre[0] / double(n) - p[0], centre[1] / double(n) - p[1], centre[2] / double(n) - p[2]};
      const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
      if (!(len > 0)) continue;
      const double step = 0.01 * shortest / len;
      const Point3d moved{p[0] + step * dir[0], p[1] + step * dir[1], p[2] + step * dir[2]};
      Index copy = v;
      if (first) s.points[v] = moved;  // the vertex itself becomes the first cone's apex
      else {
        copy = Index(s.points.size());
        s.points.push_back(moved);
        made.push_back(1);
      }
      if (first) made[v] = 1;
      first = false;
      r.pinch_displacement = std::max(r.pinch_displacement, step * len);
      for (Index c : corners) s.indices[s.offsets[c / 3] + c % 3] = copy;
    }
  };
  for (const Pinch& pinch : pinches) split(pinch);

  // A non-manifold edge whose ends stayed one cone each: the sheets around
  // it are joined through other edges at both ends (a thin cavity whose
  // wall meets the outside along the edge: two parts touching face to face,
  // one face dented by 1e-9 of its size), and no copy of an end parts
  // them. Its midpoint does: the edge's faces split there, the midpoint is a
  // pinch with one cone per sheet (cgal's cycloidal, its faces split at
  // lifted centroids by `polyheal perturb --kind near-coplanar`: 63 such
  // edges, uncertified; the grid then took 31 s).
  std::vector<std::array<Index, 2>> edges;
  for (const auto& list : sheet_edges) edges.insert(edges.end(), list.begin(), list.end());
  if (edges.empty()) return;
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  // the faces at each end, kept up to date as faces split
  std::unordered_map<Index, std::vector<Index>> faces_at;
  for (const auto& e : edges) faces_at.emplace(e[0], std::vector<Index>()), faces_at.emplace(e[1], std::vector<Index>());
  for (std::size_t f = 0; f < s.face_count(); ++f)
    for (Index v : s.face(f))
      if (const auto it = faces_at.find(v); it != faces_at.end()) it->second.push_back(Index(f));
  for (const auto& [a, b] : edges) {
    std::vector<Index> faces;
    for (Index f : faces_at[a]) {
      const FaceView fv = s.face(f);
      if (std::find(fv.begin(), fv.end(), b) != fv.end()) faces.push_back(f);
    }
    if (faces.size() <= 2) continue;  // parted by a copy of an end
    const auto sheets = pair_sheets(s, a, b, faces);
    if (sheets.empty()) continue;
    const Point3d& pa = s.points[a];
    const Point3d& pb = s.points[b];
    const Index m = Index(s.points.size());
    s.points.push_back({0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])});
    made.push_back(1);
    // each face (.., a, b, ..) in its own order becomes (a, m, x) and (m, b, x)
    std::unordered_map<Index, Index> half;  // face -> the new face beside it
    for (Index f : faces) {
      std::array<Index, 3> v{s.face(f)[0], s.face(f)[1], s.face(f)[2]};
      int k = 0;
      while (!((v[k] == a && v[(k + 1) % 3] == b) || (v[k] == b && v[(k + 1) % 3] == a))) ++k;
      const Index from = v[k], to = v[(k + 1) % 3], x = v[(k + 2) % 3];
      s.indices[s.offsets[f] + 0] = from;
      s.indices[s.offsets[f] + 1] = m;
      s.indices[s.offsets[f] + 2] = x;
      const Index g = Index(s.face_count());
      s.add_triangle(m, to, x);
      result.source_face.push_back(result.source_face[f]);
      half[f] = g;
      // the new face holds `to` (a or b) in place of f
      auto& at_to = faces_at[to];
      at_to.erase(std::find(at_to.begin(), at_to.end(), f));
      at_to.push_back(g);
      if (const auto it = faces_at.find(x); it != faces_at.end()) it->second.push_back(g);
    }
    // the midpoint's cones: a sheet's faces and their halves
    Pinch pinch{m, {}};
    for (const auto& [f, h] : sheets) {
      std::vector<Index> corners;
      for (Index g : {f, half[f], h, half[h]}) corners.push_back(corner_at(g, m));
      std::sort(corners.begin(), corners.end());
      pinch.cones.push_back(std::move(corners));
    }
    std::sort(pinch.cones.begin(), pinch.cones.end());
    split(pinch);
    ++r.pinched_edges_split;
  }
}

/// The faces to leave out so that `s` (welded) bounds a volume — every edge
/// used as often in each direction, so that the winding number is defined
/// off the surface — when walls and doubled faces are all that stop it: a
/// one-sided wall between two solids that both lack the face they share (a
/// convex decomposition's pieces glued, one cap left between them), the
/// shared face given twice in one direction (sheets_to_leave_out, without
/// flaps: a wall meets solids along its whole rim). Empty when `s` balances
/// already. Throws UnsupportedInput, naming an edge, when what is left still
/// does not balance.
///
/// A wall lies inside what is kept (winding number 1 around it), a doubled
/// face on it (1/2). A sheet that lies outside the rest is not one: a solid
/// nested in another and sharing faces with it (a part set flush into a
/// block, welded) balances its shared rim either without the part's exposed
/// faces or without the block's faces around them, and only the first
/// leaves the union; the second left the part alone, the block cut away.
/// Such a sheet is kept: the rest's mean winding number over it (at up to
/// 8 of its faces, each its area at its centroid, the two sides averaged so
/// that a kept face through the point counts 1/2) is below 1/4. A
/// measurement (detail/winding.h); the union that follows is exact.
std::vector<std::size_t> walls_to_leave_out(const Soup& s) {
  std::vector<std::array<Index, 3>> tris;
  std::vector<std::size_t> first_tri(s.face_count() + 1, 0);
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView v = s.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k) tris.push_back({v[0], v[k], v[k + 1]});
    first_tri[f + 1] = tris.size();
  }
  std::optional<detail::WindingNumber> field;
  auto lies_inside_rest = [&](const std::vector<std::size_t>& sheet) {
    if (!field) field.emplace(s.points, tris);
    constexpr std::size_t kSamples = 8;
    const std::size_t samples = std::min(kSamples, sheet.size());
    double sum = 0, area = 0;
    for (std::size_t i = 0; i < samples; ++i) {
      const std::size_t f = sheet[i * sheet.size() / samples];
      if (first_tri[f] == first_tri[f + 1]) continue;
      const std::array<Index, 3>& t = tris[first_tri[f]];
      const Point3d &a = s.points[t[0]], &b = s.points[t[1]], &c = s.points[t[2]];
      const Point3d n = normal(a, b, c);
      const double len = norm(n);
      if (!(len > 0)) continue;
      const Point3d g = mul(add(add(a, b), c), 1.0 / 3);
      const double off = 1e-6 * std::max({norm(sub(b, a)), norm(sub(c, b)), norm(sub(a, c))});
      double w = 0;
      for (double side : {off, -off}) {
        const Point3d q = add(g, mul(n, side / len));
        double rest = (*field)(q);
        for (std::size_t u : sheet)
          for (std::size_t r = first_tri[u]; r < first_tri[u + 1]; ++r) rest -= field->share(r, q);
        w += rest / 2;
      }
      sum += w * 0.5 * len;
      area += 0.5 * len;
    }
    return area == 0 || sum / area >= 0.25;
  };
  SheetsLeftOut walls = sheets_to_leave_out(s, false, lies_inside_rest);
  if (walls.imbalance > 0)
    throw UnsupportedInput("edge (" + std::to_string(walls.unbalanced_a) + ", " + std::to_string(walls.unbalanced_b) +
                           ") is used " + std::to_string(walls.unbalanced_by) +
                           " more times in one direction than in the other: the surface is not closed "
                           "and consistently oriented, which regularize needs");
  return std::move(walls.faces);
}

/// Repairs the pairs that rounding made intersect (every intersecting pair
/// of `soup`, sorted) with deintersect's vertex moves on the region around
/// them only: the faces whose boxes meet a pair's box grown by its
/// diagonal, with every corner they share with the rest of the surface
/// fixed (so the faces outside stay as they are). Building and indexing the
/// whole surface for a few pairs was most of the repair (Hand1's raw
/// offset: 168k faces for 29 pairs). Faces changed are flagged in
/// `recheck`: a move may meet a face outside the region, which the caller's
/// check of the changed faces finds. False, `soup` unchanged, when the
/// region is not worth cutting out (over a quarter of the surface), cannot
/// be repaired alone (points to weld), or an edge swap in it joined two of
/// its fixed corners that a face outside joins already; the caller repairs
/// the whole surface then.
bool deintersect_locally(Soup& soup, const std::vector<FacePair>& pairs, std::vector<char>& recheck,
                         std::size_t& moved) {
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;
  const std::size_t n = soup.face_count();
  auto box_of = [&](std::size_t f) {
    CGAL::Bbox_3 b;
    for (Index v : soup.face(f)) b += CGAL::Bbox_3(soup.points[v][0], soup.points[v][1], soup.points[v][2],
                                                   soup.points[v][0], soup.points[v][1], soup.points[v][2]);
    return b;
  };
  std::vector<Box> faces, reach;
  faces.reserve(n);
  for (std::size_t f = 0; f < n; ++f) faces.emplace_back(box_of(f), f);
  for (const FacePair& p : pairs) {
    const CGAL::Bbox_3 b = box_of(p.first) + box_of(p.second);
    const double d = std::sqrt(CGAL::square(b.xmax() - b.xmin()) + CGAL::square(b.ymax() - b.ymin()) +
                               CGAL::square(b.zmax() - b.zmin()));
    reach.emplace_back(CGAL::Bbox_3(b.xmin() - d, b.ymin() - d, b.zmin() - d, b.xmax() + d, b.ymax() + d, b.zmax() + d),
                       reach.size());
  }
  std::vector<char> in_region(n, 0);
  // A few pairs (Hand1's raw offset: 29 against 168k faces): each face's box
  // against every reach directly, in parallel; sorting the whole soup's
  // boxes for them cost more than the tests.
  constexpr std::size_t kDirectTests = std::size_t(1) << 24;
  if (reach.size() * n <= kDirectTests) {
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t f) {
      for (const Box& b : reach)
        if (CGAL::do_overlap(faces[f].bbox(), b.bbox())) {
          in_region[f] = 1;
          break;
        }
    });
  } else {
    CGAL::box_intersection_d(faces.begin(), faces.end(), reach.begin(), reach.end(),
                             [&](const Box& f, const Box&) { in_region[f.info()] = 1; });
  }
  const std::size_t region = std::size_t(std::count(in_region.begin(), in_region.end(), char(1)));
  if (region > n / 4) return false;
  // the region as a soup of its own, faces in their order; corners used
  // outside it fixed
  std::vector<char> outside(soup.points.size(), 0);
  for (std::size_t f = 0; f < n; ++f)
    if (!in_region[f])
      for (Index v : soup.face(f)) outside[v] = 1;
  Soup sub;
  constexpr Index kNone = ~Index(0);
  std::vector<Index> sub_id(soup.points.size(), kNone), full_id;
  std::vector<std::size_t> full_face;
  std::vector<char> fixed;
  for (std::size_t f = 0; f < n; ++f) {
    if (!in_region[f]) continue;
    std::array<Index, 3> t;
    for (int k = 0; k < 3; ++k) {
      const Index v = soup.face(f)[k];
      if (sub_id[v] == kNone) {
        sub_id[v] = Index(sub.points.size());
        sub.points.push_back(soup.points[v]);
        full_id.push_back(v);
        fixed.push_back(outside[v]);
      }
      t[k] = sub_id[v];
    }
    sub.add_triangle(t[0], t[1], t[2]);
    full_face.push_back(f);
  }
  std::vector<std::size_t> sub_face(n, 0);
  for (std::size_t i = 0; i < full_face.size(); ++i) sub_face[full_face[i]] = i;
  std::vector<FacePair> sub_pairs;  // still sorted: the faces keep their order
  for (const FacePair& p : pairs) sub_pairs.push_back({sub_face[p.first], sub_face[p.second]});
  double diagonal2 = 0;  // the whole surface's: the displacement limit is relative to it
  {
    CGAL::Bbox_3 all;
    for (const Point3d& p : soup.points) all += CGAL::Bbox_3(p[0], p[1], p[2], p[0], p[1], p[2]);
    if (!soup.points.empty())
      diagonal2 = CGAL::square(all.xmax() - all.xmin()) + CGAL::square(all.ymax() - all.ymin()) +
                  CGAL::square(all.zmax() - all.zmin());
  }
  DeintersectOptions d;
  d.certify = false;
  d.known_pairs = &sub_pairs;
  d.fixed_points = &fixed;
  d.max_displacement = d.max_displacement_ratio * std::sqrt(diagonal2);
  DeintersectResult fixed_region;
  try {
    fixed_region = remove_self_intersections(sub, d);
  } catch (const UnsupportedInput&) {
    return false;
  }
  const Soup& out = fixed_region.soup;
  if (out.face_count() != sub.face_count() || out.points.size() < sub.points.size()) return false;
  // out's point j < |sub| is sub's point j; after them come copies of the
  // region's pinch points (a corner whose faces in the region form two
  // fans), unmoved: each is the point at its position
  std::map<Point3d, Index> at;
  if (out.points.size() > sub.points.size())
    for (std::size_t j = 0; j < sub.points.size(); ++j) at.emplace(sub.points[j], Index(j));
  std::vector<Index> to_full(out.points.size());
  for (std::size_t j = 0; j < out.points.size(); ++j) {
    if (j < sub.points.size()) {
      to_full[j] = full_id[j];
      continue;
    }
    const auto it = at.find(out.points[j]);
    if (it == at.end()) return false;  // cannot happen: copies are pinned
    to_full[j] = full_id[it->second];
  }
  // An edge swap inside the region must not join two of its border corners
  // that a face outside joins already: every edge stays used exactly twice.
  std::unordered_map<std::uint64_t, int> uses;
  auto use = [&](Index a, Index b) { ++uses[undirected_edge_key(a, b)]; };
  for (std::size_t i = 0; i < full_face.size(); ++i)
    for (int k = 0; k < 3; ++k) use(to_full[out.face(i)[k]], to_full[out.face(i)[(k + 1) % 3]]);
  for (std::size_t f = 0; f < n; ++f)
    if (!in_region[f])
      for (int k = 0; k < 3; ++k) {
        const Index a = soup.face(f)[k], b = soup.face(f)[(k + 1) % 3];
        if (sub_id[a] != kNone && sub_id[b] != kNone) use(a, b);
      }
  for (const auto& [edge, count] : uses)
    if (count != 2) return false;
  for (std::size_t j = 0; j < sub.points.size(); ++j) soup.points[full_id[j]] = out.points[j];
  for (std::size_t i = 0; i < full_face.size(); ++i) {
    const std::size_t f = full_face[i];
    for (int k = 0; k < 3; ++k) {
      const Index j = out.face(i)[k];
      if (to_full[j] != soup.indices[3 * f + k] || out.points[j] != sub.points[sub.face(i)[k]]) recheck[f] = 1;
      soup.indices[3 * f + k] = to_full[j];
    }
  }
  moved = fixed_region.report.moved_vertices;
  return true;
}

/// The corner polygon f is fanned from: the first whose fan has no exactly
/// zero-area triangle (0 if none has).
std::size_t fan_apex(const Soup& soup, std::size_t f) {
  const FaceView v = soup.face(f);
  const std::size_t n = v.size();
  auto ip = [&](Index i) { return IK::Point_3(soup.points[i][0], soup.points[i][1], soup.points[i][2]); };
  for (std::size_t a = 0; a < n; ++a) {
    bool flat = false;
    for (std::size_t k = 1; k + 1 < n && !flat; ++k)
      flat = CGAL::collinear(ip(v[a]), ip(v[(a + k) % n]), ip(v[(a + k + 1) % n]));
    if (!flat) return a;
  }
  return 0;
}

}  // namespace

bool kept_as_input(const Soup& input, const Soup& output, const std::vector<std::size_t>& source_face, std::size_t f) {
  const FaceView a = input.face(source_face[f]), b = output.face(f);
  if (a.size() != 3) return false;
  for (int k = 0; k < 3; ++k)
    if (input.points[a[k]] != output.points[b[k]]) return false;
  return true;
}

namespace {

/// The intersecting pairs with a face that has a corner flagged in `at`
/// (rounded): only those faces can differ from the surface certified before.
/// Where they are more than a quarter of the faces, the whole surface is
/// searched instead — the same sweep (find_self_intersections pairs all the
/// boxes then too), with the pairs of two unflagged faces tested as well —
/// and kept with its pairs in `scanned` (when it has no identical points):
/// the certificate then searches only the faces of the written file that
/// differ from it (Hand1's raw offset at 0.6% chord tolerance, 250k faces
/// out: the certificate's search 0.34 s -> ~0.03 s).
std::vector<FacePair> pairs_at(const Soup& soup, const std::vector<char>& at, std::optional<ScannedSurface>& scanned) {
  std::vector<char> face(soup.face_count(), 0);
  for (std::size_t f = 0; f < soup.face_count(); ++f)
    for (Index v : soup.face(f)) face[f] |= at[v];
  if (4 * std::size_t(std::count(face.begin(), face.end(), char(1))) > soup.face_count()) {
    std::vector<FacePair> pairs = find_self_intersections(soup);
    if (weld_identical_points(soup.points).merged == 0) scanned = ScannedSurface{soup, pairs};
    return pairs;
  }
  SelfIntersectionOptions only;
  only.only = &face;
  return find_self_intersections(soup, only);
}

/// Moves apart the faces of `pairs` (intersecting since rounding) with
/// deintersect's vertex moves: on the region around them
/// (deintersect_locally), else on the whole surface, taken when it keeps
/// every face (the provenance depends on their order). Faces changed are
/// flagged in `recheck`. Returns the vertices moved.
std::size_t moved_apart(Soup& soup, const std::vector<FacePair>& pairs, std::vector<char>& recheck) {
  for (const FacePair& p : pairs) recheck[p.first] = recheck[p.second] = 1;
  std::size_t moved = 0;
  if (deintersect_locally(soup, pairs, recheck, moved)) return moved;
  try {
    DeintersectOptions d;
    d.certify = false;
    d.known_pairs = &pairs;  // every pair: faces without a rounded corner are the exact result's
    DeintersectResult fixed = remove_self_intersections(soup, d);
    if (fixed.soup.face_count() == soup.face_count()) {
      for (std::size_t f = 0; f < fixed.soup.face_count(); ++f)
        for (int k = 0; k < 3; ++k)
          if (fixed.soup.points[fixed.soup.face(f)[k]] != soup.points[soup.face(f)[k]]) recheck[f] = 1;
      soup = std::move(fixed.soup);
      return fixed.report.moved_vertices;
    }
  } catch (const UnsupportedInput&) {
    // not a manifold mesh: the caller's next pass or the certificate deals with it
  }
  return 0;
}

}  // namespace

namespace {

/// regularize(), and in `unsettled` the output faces that may still cross
/// another after rounding (every intersecting pair of the output has one;
/// empty when rounding made no pair). Not with float_coordinates.
RegularizeResult regularized(const Soup& raw, const RegularizeOptions& o, std::vector<char>& unsettled) {
  RegularizeResult result;
  RegularizeReport& r = result.report;
  auto t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("detecting");
  if (!raw.is_triangle_soup()) {
    // Polygons are fanned, from the first corner whose fan has no zero-area
    // triangle (decided exactly; a polygon with collinear corners along a
    // side has one); the output's provenance names the polygon.
    Soup fanned;
    fanned.points = raw.points;
    std::vector<std::size_t> polygon;
    for (std::size_t f = 0; f < raw.face_count(); ++f) {
      const FaceView v = raw.face(f);
      const std::size_t n = v.size();
      if (n < 3) throw UnsupportedInput("face " + std::to_string(f) + " has fewer than 3 corners");
      const std::size_t apex = fan_apex(raw, f);
      for (std::size_t k = 1; k + 1 < n; ++k) {
        fanned.add_triangle(v[apex], v[(apex + k) % n], v[(apex + k + 1) % n]);
        polygon.push_back(f);
      }
    }
    RegularizeOptions inner = o;
    inner.known_pairs = nullptr;  // the fan's faces are not the input's
    RegularizeResult result = regularized(fanned, inner, unsettled);
    for (std::size_t& f : result.source_face) f = polygon[f];
    result.report.faces = raw.face_count();
    for (std::size_t f = 0; f < raw.face_count(); ++f) result.report.polygons_fanned += raw.face(f).size() > 3 ? 1 : 0;
    if (o.certify) certify(raw, result.soup, result.source_face, result.report, result.scanned);
    return result;
  }
  const Soup input = apply_weld(raw, weld_identical_points(raw.points));
  if (input.face_count() == 0) throw UnsupportedInput("no faces");
  InspectOptions io;
  io.observer = o.observer;
  io.self_intersections = o.known_pairs;
  io.crack_ratio = 0;  // cracks are not reported here (the search is serial)
  const Report in = inspect(input, io);
  // A closed, consistently oriented surface (non-manifold edges allowed):
  // every edge used as often in each direction. Then the winding number is
  // defined everywhere off the surface. Walls and doubled faces that stop
  // that are left out first (reported); the rest is regularized, and the
  // output is certified against the whole input. (A surface whose every
  // edge is used once each way — closed, oriented, no edge of three or more
  // faces, as the inspection found — balances: nothing to look for.)
  const bool balanced = in.closed && in.oriented && in.nonmanifold_edges.empty();
  if (const std::vector<std::size_t> walls = balanced ? std::vector<std::size_t>{} : walls_to_leave_out(input);
      !walls.empty()) {
    Soup rest;
    rest.points = raw.points;
    std::vector<std::size_t> kept;
    for (std::size_t f = 0, w = 0; f < raw.face_count(); ++f) {
      if (w < walls.size() && walls[w] == f) {
        ++w;
        continue;
      }
      const FaceView v = raw.face(f);
      rest.add_triangle(v[0], v[1], v[2]);
      kept.push_back(f);
    }
    if (rest.face_count() == 0) throw UnsupportedInput("no faces are left once the walls are left out");
    RegularizeOptions inner = o;
    inner.certify = false;
    inner.known_pairs = nullptr;  // fewer faces: other indices
    RegularizeResult result = regularized(rest, inner, unsettled);
    for (std::size_t& f : result.source_face) f = kept[f];
    result.report.faces = raw.face_count();
    result.report.walls_left_out = walls.size();
    if (o.certify) certify(raw, result.soup, result.source_face, result.report, result.scanned);
    return result;
  }
  r.zero_area_faces = in.degenerate_faces.size();
  r.faces = in.faces;
  r.vertices = raw.points.size();
  r.intersecting_pairs_in = in.self_intersections.size();
  {
    std::vector<char> intersecting(input.face_count(), 0);
    for (const FacePair& p : in.self_intersections) intersecting[p.first] = intersecting[p.second] = 1;
    r.intersecting_faces_in = std::size_t(std::count(intersecting.begin(), intersecting.end(), char(1)));
  }
  r.bbox_diagonal = bbox_diagonal(in);
  r.seconds_detect = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("growing the valid region");
  auto grow = std::make_unique<Regularizer>(input, in.self_intersections, in, r);
  grow->run(o.observer);
  grow->tally();
  r.seconds_intersections = grow->seconds_intersections;
  r.seconds_grow = seconds_since(t0) - r.seconds_intersections;

  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("stitching");
  std::vector<char> made;  // per output vertex: a point on an intersection curve (rounded)
  result.soup = grow->output(result.source_face, made);
  // The growth's data (its exact points, pieces, plans and maps) is freed on
  // another core while the stitching goes on (Hand1's raw offset: 0.03 s).
  tbb::task_group freeing;
  freeing.run([&grow] { grow.reset(); });
  snap_rounded(result, made, r);
  split_pinches(input, in.nonmanifold_vertices.empty(), result, made, r);
  r.new_vertices = std::size_t(std::count(made.begin(), made.end(), char(1)));
  r.faces_out = result.soup.face_count();
  r.vertices_out = result.soup.points.size();
  for (std::size_t f = 0; f < result.soup.face_count(); ++f)
    r.faces_kept += kept_as_input(input, result.soup, result.source_face, f) ? 1 : 0;
  // Certify after rounding: a point on an intersection curve rounded to
  // doubles can make faces intersect again; deintersect's vertex moves (in
  // doubles) repair that where they can.
  if (o.observer) o.observer->stage("checking the rounded surface");
  const std::vector<FacePair> rounded = pairs_at(result.soup, made, result.scanned);
  // Where it searched only the faces at rounded points, most faces are the
  // input's own, and the input, searched whole above, is the certificate's
  // base (knot1000k: 22k of 504k faces out are not input triangles). Not
  // when the caller gave the input's pairs: this run did not search for them.
  if (!result.scanned && !o.known_pairs) result.scanned = ScannedSurface{input, in.self_intersections};
  r.rounding_pairs = rounded.size();
  unsettled.clear();
  if (!rounded.empty()) {
    // After the moves a pair can meet only where a face changed, or where a
    // pair found above was left as it was: only those faces are checked again.
    unsettled.assign(result.soup.face_count(), 0);
    r.rounding_moves = moved_apart(result.soup, rounded, unsettled);
    // What is still intersecting is regularized again, exactly, on the
    // rounded coordinates: each pass leaves fewer and smaller crossings to
    // round (iterated snap rounding). The pairs found are all the pairs
    // (see above), so the pass does not search the whole surface for them,
    // and it says which of its faces to check after it (the crank's raw
    // offset +2%, 1.5M faces after the first pass: two whole-surface scans
    // of ~3 s each fewer).
    for (int pass = 1; pass < o.max_passes; ++pass) {
      SelfIntersectionOptions changed;
      changed.only = &unsettled;
      const std::vector<FacePair> left = find_self_intersections(result.soup, changed);
      if (left.empty()) break;
      RegularizeOptions again;
      again.certify = false;
      again.max_passes = 1;
      again.known_pairs = &left;
      try {
        std::vector<char> next_unsettled;
        RegularizeResult next = regularized(result.soup, again, next_unsettled);
        for (std::size_t& f : next.source_face) f = result.source_face[f];
        result.soup = std::move(next.soup);
        result.source_face = std::move(next.source_face);
        if (next.scanned) result.scanned = std::move(next.scanned);  // the later, nearer base
        unsettled = std::move(next_unsettled);
        r.rounding_passes = pass + 1;
        r.pinches_split += next.report.pinches_split;
        r.pinched_edges_split += next.report.pinched_edges_split;
        r.pinch_displacement = std::max(r.pinch_displacement, next.report.pinch_displacement);
      } catch (const UnsupportedInput&) {
        break;  // e.g. rounding made a face zero-area: the certificate reports it
      }
      if (unsettled.empty()) break;  // the pass's rounding made no pair
    }
  }
  // Floats (the output is STL): every point rounded as the file will hold
  // it, the points that become one merged; what that makes intersect is
  // moved apart (deintersect's moves clear a face by a fraction of its
  // edge, far above a float step) and rounded again, three times at most.
  // The result is floats; what is left the certificate reports.
  for (int round = 0; o.float_coordinates; ++round) {
    std::vector<char> moved(result.soup.points.size(), 0);
    for (std::size_t v = 0; v < result.soup.points.size(); ++v) {
      Point3d& p = result.soup.points[v];
      const Point3d q = nearest_float(p);
      moved[v] = q != p;
      p = q;
    }
    const std::size_t n = std::size_t(std::count(moved.begin(), moved.end(), char(1)));
    if (n == 0) break;
    r.float_rounded += n;
    snap_rounded(result, moved, r);
    const std::vector<FacePair> pairs = pairs_at(result.soup, moved, result.scanned);
    r.float_pairs += pairs.size();
    if (pairs.empty() || round == 3) break;
    std::vector<char> recheck(result.soup.face_count(), 0);
    r.float_moves += moved_apart(result.soup, pairs, recheck);
  }
  r.faces_out = result.soup.face_count();
  r.vertices_out = result.soup.points.size();
  freeing.wait();
  r.seconds_stitch = seconds_since(t0);

  if (o.certify) {
    t0 = std::chrono::steady_clock::now();
    if (o.observer) o.observer->stage("certifying");
    certify(raw, result.soup, result.source_face, r, result.scanned);
    r.seconds_certify = seconds_since(t0);
  }
  return result;
}

}  // namespace

RegularizeResult regularize(const Soup& raw, const RegularizeOptions& o) {
  std::vector<char> unsettled;
  return regularized(raw, o, unsettled);
}

namespace {

/// The point of triangle abc nearest to p, in doubles, as (v, w) with
/// q = a + v (b - a) + w (c - a) (Ericson, Real-Time Collision Detection
/// §5.1.5), then made a point of the triangle exactly: v, w >= 0 and
/// v + w <= 1 in real arithmetic on the returned doubles.
std::array<double, 2> nearest_parameters(const Point3d& p, const std::array<Point3d, 3>& c) {
  const Point3d ab = sub(c[1], c[0]), ac = sub(c[2], c[0]), ap = sub(p, c[0]);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  std::array<double, 2> vw{0, 0};
  if (d1 <= 0 && d2 <= 0) return vw;  // vertex a
  const Point3d bp = sub(p, c[1]);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  const Point3d cp = sub(p, c[2]);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  const double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
  if (d3 >= 0 && d4 <= d3) vw = {1, 0};                                      // vertex b
  else if (d6 >= 0 && d5 <= d6) vw = {0, 1};                                 // vertex c
  else if (vc <= 0 && d1 >= 0 && d3 <= 0) vw = {d1 / (d1 - d3), 0};          // edge ab
  else if (vb <= 0 && d2 >= 0 && d6 <= 0) vw = {0, d2 / (d2 - d6)};          // edge ac
  else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {                        // edge bc
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    vw = {1 - t, t};
  } else {
    const double denom = 1 / (va + vb + vc);
    vw = {vb * denom, vc * denom};
  }
  double& v = vw[0];
  double& w = vw[1];
  if (!(v >= 0)) v = 0;  // also NaN, from a degenerate triangle
  if (!(w >= 0)) w = 0;
  if (v >= 1) return {1, 0};
  // fl(1 - v) is within half a spacing of 1 - v: the double below it is not above
  if (w > 0 && !(w < std::nextafter(1 - v, 0.0))) w = std::nextafter(1 - v, 0.0);
  if (w < 0) w = 0;
  return vw;
}

/// An upper bound on the squared distance from p to triangle c, tight to
/// the double: interval arithmetic (no rounding error can hide in it) on
/// CGAL's distance; where one of its comparisons cannot be decided (p on an
/// edge's line, say), the distance to a point of the triangle — the one
/// nearest_parameters() picks, enclosed in intervals — which bounds it.
double squared_distance_upper(const Point3d& p, const std::array<Point3d, 3>& c) {
  using IA = CGAL::Simple_cartesian<CGAL::Interval_nt<false>>;
  CGAL::Protect_FPU_rounding<true> protect;
  auto ia = [](const Point3d& q) { return IA::Point_3(q[0], q[1], q[2]); };
  try {
    return CGAL::squared_distance(ia(p), IA::Triangle_3(ia(c[0]), ia(c[1]), ia(c[2]))).sup();
  } catch (const CGAL::Uncertain_conversion_exception&) {
  }
  using I = CGAL::Interval_nt<false>;
  // |p - q|^2 enclosed, q = c[i] + v (c[j] - c[i]) + w (c[k] - c[i])
  auto bound = [&](int i, int j, int k, double v, double w) {
    I d2 = 0;
    for (int x = 0; x < 3; ++x) {
      const I a = c[i][x];
      const I d = I(p[x]) - (a + I(v) * (I(c[j][x]) - a) + I(w) * (I(c[k][x]) - a));
      d2 += d * d;
    }
    return d2.sup();
  };
  const std::array<double, 2> vw = nearest_parameters(p, c);
  double best = bound(0, 1, 2, vw[0], vw[1]);
  // On a sliver the plane's parameters are ill-conditioned; an edge's are
  // not: the nearest point of each edge is a witness too.
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const Point3d e = sub(c[j], c[i]);
    const double t = dot(sub(p, c[i]), e) / squared_norm(e);
    best = std::min(best, bound(i, j, j, t > 0 ? (t < 1 ? t : 1.0) : 0.0, 0.0));
  }
  return best;
}

/// Output -> input: each output triangle lies in the input triangle it came
/// from up to rounding; the distance to one triangle is convex, so its
/// corners bound it. Bounded in interval arithmetic (doubles lose the
/// rounding error in cancellation on slivers far from the origin;
/// squared_distance_upper), for the corners that are not the source
/// triangle's own. 0 without a source for every face.
double max_distance_to_sources(const Soup& input, const Soup& written, const std::vector<std::size_t>& source_face,
                               double bbox_diagonal) {
  if (source_face.size() == written.face_count()) {
    // Candidate sources of a face: its own and its edge neighbours' (a swap
    // in the rounding repair re-connects two faces across their sources).
    std::vector<std::pair<std::uint64_t, Index>> edges;
    for (std::size_t f = 0; f < written.face_count(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Index a = written.face(f)[k], b = written.face(f)[(k + 1) % 3];
        edges.push_back({(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), Index(f)});
      }
    tbb::parallel_sort(edges.begin(), edges.end());
    auto bound_by = [&](std::size_t f, std::size_t src) {
      // the source polygon's fan triangle that bounds face f best (one
      // triangle for a triangle)
      const FaceView s = input.face(src);
      const std::size_t n = s.size(), a = n > 3 ? fan_apex(input, src) : 0;
      std::optional<double> best;
      for (std::size_t k = 1; k + 1 < n; ++k) {
        const std::array<Point3d, 3> c{input.points[s[a]], input.points[s[(a + k) % n]],
                                       input.points[s[(a + k + 1) % n]]};
        double m = 0;
        for (Index v : written.face(f)) {
          const Point3d& p = written.points[v];
          if (p == c[0] || p == c[1] || p == c[2]) continue;
          m = std::max(m, squared_distance_upper(p, c));
        }
        if (!best || m < *best) best = m;
      }
      return best ? *best : 0.0;
    };
    // neighbours are tried only when the own source does not bound the face
    // at rounding level (a swapped face, in practice)
    const double rounding_level = std::pow(1e-9 * bbox_diagonal, 2);
    const double worst = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, written.face_count()), 0.0,
        [&](const tbb::blocked_range<std::size_t>& range, double worst) {
          for (std::size_t f = range.begin(); f < range.end(); ++f) {
            double best = bound_by(f, source_face[f]);
            for (int k = 0; k < 3 && best > rounding_level; ++k) {
              const Index a = written.face(f)[k], b = written.face(f)[(k + 1) % 3];
              const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
              for (auto it = std::lower_bound(edges.begin(), edges.end(), std::make_pair(key, Index(0)));
                   it != edges.end() && it->first == key && best > 0; ++it)
                if (it->second != f) best = std::min(best, bound_by(f, source_face[it->second]));
            }
            worst = std::max(worst, best);
          }
          return worst;
        },
        [](double x, double y) { return std::max(x, y); });
    return std::sqrt(worst);
  }
  return 0.0;
}

}  // namespace

void certify(const Soup& input, const Soup& written, const std::vector<std::size_t>& source_face,
             RegularizeReport& r, const std::optional<ScannedSurface>& scanned) {
  // The oracle on the written file beside the distances (each is parallel
  // inside but has serial parts: tree building, sorting).
  const double bound = 1e-3 * r.bbox_diagonal;
  auto oracle = [&] {
    r.certificate_searched = written.face_count();
    r.out = scanned ? inspect_from(written, scanned->soup, scanned->pairs, {}, &r.certificate_searched)
                    : inspect(written);
  };
  tbb::parallel_invoke(oracle,
                       [&] {
                         r.max_distance_to_input =
                             max_distance_to_sources(input, written, source_face, r.bbox_diagonal);
                         // That bounds output -> input (its square is an
                         // interval bound; the root may round down): where
                         // the input's removed walls lie farther from the
                         // output, that direction need not be measured.
                         const double at_most = source_face.size() == written.face_count()
                                                    ? std::nextafter(r.max_distance_to_input, HUGE_VAL)
                                                    : HUGE_VAL;
                         r.hausdorff = detail::hausdorff_distance(input, written, bound, at_most);
                       });
  r.hausdorff_error_bound = bound;
  r.certified = r.out.certified_clean();
}

}  // namespace polyheal
