#include "polyheal/repair/detail/shape_decimation.h"

#include <CGAL/boost/graph/Euler_operations.h>
#include <CGAL/boost/graph/helpers.h>
#include <boost/container/small_vector.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>
#include <stdexcept>
#include <unordered_map>

#include "polyheal/inspect/exact_predicates.h"
#include "polyheal/inspect/local_index.h"
#include "polyheal/mesh/convert.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/repair/detail/distance.h"

namespace polyheal::detail {
namespace {

using Triple = std::array<vertex_descriptor, 3>;

/// Shape quality of a triangle for ordering (not a predicate): its smallest
/// angle or 180° minus its largest, whichever is smaller, in degrees.
double quality(const Point3d& a, const Point3d& b, const Point3d& c) {
  const auto [lo, hi] = angle_range(a, b, c);
  return std::min(lo, 180.0 - hi);
}

}  // namespace

struct ShapeDecimator::Impl {
  Mesh& mesh;
  LocalIndex& index;
  const SurfaceDistance& input;
  DecimationOptions o;
  double cos_cap, cos_needle, cos_fold, tol2;
  DecimationStats stats;
  std::unordered_map<std::uint32_t, std::vector<Point3d>> attached;  // removed vertices, by nearest face

  /// A candidate operation, fully evaluated.
  struct Plan {
    bool flip = false;
    halfedge_descriptor h;          // collapse: source removed, target kept; flip: the edge
    std::vector<Triple> proposed;   // the new triangles
    std::vector<face_descriptor> replaced;  // faces removed or reshaped
    double worst = -1.0;            // the worst quality among `proposed`
    bool simplify = false;          // removing a vertex only where every new face is fine
    /// Removal of h's source with its hole retriangulated by `diagonals`
    /// (not a collapse: the new faces need not share a corner).
    bool removal = false;
    std::vector<std::pair<vertex_descriptor, vertex_descriptor>> diagonals;
  };

  FaceFlagMap on_input;
  std::optional<Mesh::Property_map<vertex_descriptor, char>> pinned;  // kVertexPinned, if present
  std::optional<VertexIdentityMap> identity;                          // kVertexIdentity, if present
  PinchCopies copies;  // pinch identity -> its copies
  std::vector<char> sticky;  // by vertex index: split points of the slice being tidied
  bool retriangulate = false;  // best_plan() may remove a vertex and triangulate its hole (plan_removal())
  bool is_sticky(vertex_descriptor v) const {
    return static_cast<std::size_t>(v) < sticky.size() && sticky[static_cast<std::size_t>(v)];
  }
  /// near_input() answers, by the corners' doubles in order.
  using NearKey = std::array<Point3d, 3>;
  struct NearKeyHash {
    std::size_t operator()(const NearKey& k) const {
      std::size_t h = 0;
      for (const Point3d& p : k)
        for (double x : p) h = h * 1000003u ^ std::hash<double>{}(x);
      return h;
    }
  };
  mutable std::unordered_map<NearKey, bool, NearKeyHash> near_input_cache;
  mutable SurfaceDistance::Recent recent;  // near_input()'s hints
  /// Double approximations of the vertices, computed once (NaN: not yet).
  Mesh::Property_map<vertex_descriptor, Point3d> approx_point;

  Impl(Mesh& m, LocalIndex& i, const SurfaceDistance& d, const DecimationOptions& opt)
      : mesh(m), index(i), input(d), o(opt), on_input(face_on_input_map(m)),
        pinned(vertex_pinned_map(m)),
        identity(vertex_identity_map(m)),
        copies(pinch_copies(m)),
        approx_point(m.add_property_map<vertex_descriptor, Point3d>(
                          "v:polyheal_approx", Point3d{std::nan(""), 0.0, 0.0}).first) {
    cos_cap = cos_degrees(o.cap_angle);
    cos_needle = cos_degrees(o.needle_angle);
    cos_fold = cos_degrees(o.fold_angle > 0 ? o.fold_angle : o.fold_guard_angle);
    // Sampling can miss the farthest point by a little: decide at 70% of the
    // tolerance; the report states the Hausdorff distance actually measured.
    tol2 = 0.49 * o.tolerance * o.tolerance;
  }

  ~Impl() { mesh.remove_property_map(approx_point); }

  const Point3d& approx(vertex_descriptor v) const {
    Point3d& a = const_cast<Mesh::Property_map<vertex_descriptor, Point3d>&>(approx_point)[v];
    if (std::isnan(a[0])) a = approx_point3d(mesh.point(v));
    return a;
  }

  Triple corners(face_descriptor f) const {
    const halfedge_descriptor h = mesh.halfedge(f);
    return {mesh.source(h), mesh.target(h), mesh.target(mesh.next(h))};
  }
  double quality_of(const Triple& t) const {
    return quality(approx(t[0]), approx(t[1]), approx(t[2]));
  }
  bool is_bad(face_descriptor f) const {
    return classify_face(mesh, f, cos_cap, cos_needle) != Shape::fine || (o.fold_angle > 0 && is_folded(f));
  }

  /// Faces (a, b, c) and (b, a, d) folded onto each other below fold_angle
  /// (exact, on the vertices' doubles: those are what TetGen reads).
  bool folded(const Triple& t, vertex_descriptor d) const {
    return fold_angle_less(approx(t[0]), approx(t[1]), approx(t[2]), approx(d), cos_fold);
  }
  bool is_folded(face_descriptor f) const {
    for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh.halfedge(f), mesh)) {
      const halfedge_descriptor o = mesh.opposite(h);
      if (mesh.is_border(o)) continue;
      if (folded({mesh.source(h), mesh.target(h), mesh.target(mesh.next(h))}, mesh.target(mesh.next(o)))) return true;
    }
    return false;
  }

  /// Would a proposed triangle fold onto its neighbour after the operation
  /// (another proposed triangle, or a face the operation keeps)?
  bool creates_fold(const Plan& plan) const {
    for (const Triple& t : plan.proposed)
      for (int k = 0; k < 3; ++k) {
        const vertex_descriptor a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        std::optional<vertex_descriptor> d;
        for (const Triple& u : plan.proposed)
          for (int j = 0; j < 3 && !d; ++j)
            if (u[j] == b && u[(j + 1) % 3] == a) d = u[(j + 2) % 3];
        if (!d) {
          const auto [h, found] = CGAL::halfedge(b, a, mesh);
          if (!found || mesh.is_border(h)) continue;
          if (std::find(plan.replaced.begin(), plan.replaced.end(), mesh.face(h)) != plan.replaced.end()) continue;
          d = mesh.target(mesh.next(h));
        }
        if (*d != c && folded({a, b, c}, *d)) return true;
      }
    return false;
  }

  bool same_side(const Triple& a, const Triple& b) const {
    return normals_agree(mesh.point(a[0]), mesh.point(a[1]), mesh.point(a[2]), mesh.point(b[0]), mesh.point(b[1]),
                         mesh.point(b[2]));
  }

  // ---- planning (the mesh is not touched) ----

  /// Exact shape checks and the improvement rule; fills plan.worst. The
  /// costlier tolerance and self-intersection tests are left to choose().
  bool acceptable(Plan& plan) const {
    double worst = 180.0;
    std::size_t bad_after = 0, bad_before = 0;
    for (const Triple& t : plan.proposed) {
      const Shape s = classify_triangle(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]), cos_cap, cos_needle);
      if (s == Shape::degenerate || s == Shape::cap) return false;
      bad_after += s != Shape::fine;
      worst = std::min(worst, quality_of(t));
    }
    double before = 180.0;
    for (face_descriptor f : plan.replaced) {
      before = std::min(before, quality_of(corners(f)));
      bad_before += is_bad(f);
    }
    // A flip must raise the worst quality it replaces (so flips cannot
    // cycle); a collapse removes a vertex, so fewer bad faces also count
    // (and for flips when folds count: no flip creates one, so the number
    // of bad faces strictly falls and flips cannot cycle either).
    const bool fewer = bad_after < bad_before && (!plan.flip || o.fold_angle > 0);
    const bool better = plan.simplify ? bad_after == 0 && bad_before == 0 : worst > before || fewer;
    if (!better) return false;
    if ((o.fold_angle > 0 || o.fold_guard_angle > 0) && creates_fold(plan)) return false;
    plan.worst = worst;
    return true;  // the costlier tolerance and intersection tests: choose(), best first
  }

  /// Samples of triangle t near the input surface. "Within the tolerance"
  /// needs one input triangle close enough, not the nearest: the search
  /// stops at the first (the triangles found last, `recent`, are tried
  /// first: neighbouring samples, and the candidates round one face, share
  /// them).
  bool near_input(const Triple& t) const {
    // Every vertex lies on the input surface, so a triangle no longer than
    // the tolerance is within it everywhere; longer ones are sampled.
    const NearKey corner{approx(t[0]), approx(t[1]), approx(t[2])};
    double longest2 = 0;
    for (int k = 0; k < 3; ++k) {
      const Point3d d = sub(corner[k], corner[(k + 1) % 3]);
      longest2 = std::max(longest2, dot(d, d));
    }
    if (longest2 <= tol2) return true;
    // The answer depends only on the corners' doubles, in this order (the
    // samples are computed from them) and the input surface, which stays:
    // on CAD fans the same candidate triangles come up again whenever a
    // neighbour changes (ADIS16480: 157k asked, 70k distinct).
    if (const auto it = near_input_cache.find(corner); it != near_input_cache.end()) return it->second;
    const bool ok = sampled_near_input(t, corner, longest2);
    near_input_cache.emplace(corner, ok);
    return ok;
  }
  bool sampled_near_input(const Triple& t, const NearKey& corner, double longest2) const {
    const int steps = std::min(6, 1 + static_cast<int>(std::sqrt(longest2 / tol2)));
    // The corners lie on the input: a sample within the tolerance of one
    // needs no search. The others are searched farthest from the corners
    // first: a failing triangle (most are: ADIS16480 59k of 71k candidates)
    // usually fails there, after one search instead of several.
    boost::container::small_vector<std::pair<double, Point3d>, 28> far;
    for_each_sample(t, steps, [&](const Point3d& p) {
      double nearest2 = std::numeric_limits<double>::infinity();
      for (const Point3d& c : corner) {
        const Point3d d = sub(p, c);
        nearest2 = std::min(nearest2, dot(d, d));
      }
      if (nearest2 > tol2) far.emplace_back(nearest2, p);
    });
    std::stable_sort(far.begin(), far.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    for (const auto& [d2, p] : far)
      if (!input.any_within(p, tol2, recent)) return false;
    return true;
  }

  /// Output -> input: samples of each new triangle near the input surface.
  /// Input -> output: vertices removed so far, attached to replaced faces,
  /// (and a collapse's own removed vertex) near the new triangles.
  bool within_tolerance(const Plan& plan) const {
    bool ok = true;
    for (const Triple& t : plan.proposed)
      if (!near_input(t)) return false;
    // With folds (fold_angle), a displaced point may be covered by a face
    // the operation keeps: a fold's spike lies on the face it is folded
    // onto. Not otherwise: on the corpus's self-overlapping mpi_and_sphere
    // the plain engine then lost a double layer (Hausdorff 1.0 against a
    // tolerance of 0.035): the input→output check above is sampled, and
    // samples 3.5 apart on its long faces were each near some kept face of
    // the other layer while the surface between them was not. Only fold
    // removal, whose result the repair pipeline measures on the written
    // file, takes it.
    std::optional<std::vector<Triple>> kept;
    for_each_displaced(plan, [&](const Point3d& p) {
      if (!ok || any_near(plan.proposed, p)) return;
      if (o.fold_angle <= 0) {
        ok = false;
        return;
      }
      if (!kept) kept = corners_of(surrounding(plan));
      if (!any_near(*kept, p)) ok = false;
    });
    return ok;
  }
  /// Whether some triangle of `tris` is within the tolerance of p (the
  /// first found: nearest() answers the same, measuring them all).
  bool any_near(const std::vector<Triple>& tris, const Point3d& p) const {
    for (const Triple& t : tris)
      if (squared_distance_to_triangle(p, approx(t[0]), approx(t[1]), approx(t[2])) <= tol2) return true;
    return false;
  }

  /// The faces around an operation that it keeps: those sharing a vertex
  /// with a replaced face.
  std::vector<face_descriptor> surrounding(const Plan& plan) const {
    std::vector<face_descriptor> out;
    for (face_descriptor r : plan.replaced)
      for (vertex_descriptor v : CGAL::vertices_around_face(mesh.halfedge(r), mesh))
        for (face_descriptor f : CGAL::faces_around_target(mesh.halfedge(v), mesh))
          if (f != Mesh::null_face() && std::find(plan.replaced.begin(), plan.replaced.end(), f) == plan.replaced.end())
            out.push_back(f);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  std::vector<Triple> corners_of(const std::vector<face_descriptor>& faces) const {
    std::vector<Triple> out;
    for (face_descriptor f : faces) out.push_back(corners(f));
    return out;
  }

  /// Points of triangle t on a barycentric grid of `steps` (corners included).
  template <class F>
  void for_each_sample(const Triple& t, int steps, F f) const {
    const Point3d a = approx(t[0]), b = approx(t[1]), c = approx(t[2]);
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j) {
        const int k = steps - i - j;
        Point3d p;
        for (int d = 0; d < 3; ++d) p[d] = (i * a[d] + j * b[d] + k * c[d]) / steps;
        f(p);
      }
  }

  /// Points of the input surface the operation takes away from the mesh:
  /// samples of replaced faces that still lay in the input surface, the
  /// points earlier operations attached to replaced faces, and a collapse's
  /// removed vertex.
  template <class F>
  void for_each_displaced(const Plan& plan, F f) const {
    for (face_descriptor r : plan.replaced) {
      if (on_input[r]) for_each_sample(corners(r), 4, f);
      auto it = attached.find(static_cast<std::uint32_t>(r));
      if (it != attached.end())
        for (const Point3d& p : it->second) f(p);
    }
    if (!plan.flip) f(approx(mesh.source(plan.h)));
  }

  /// for_each_displaced()'s points, each once: the replaced faces' samples
  /// share their corners and edges (a third of the points on ADIS16480's
  /// fans were repeats), and a point's copies would go to the same face
  /// (attach()) and answer the same there (within_tolerance()).
  std::vector<Point3d> displaced_points(const Plan& plan) const {
    std::vector<Point3d> out;
    for_each_displaced(plan, [&](const Point3d& p) { out.push_back(p); });
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  std::pair<std::size_t, double> nearest(const std::vector<Triple>& tris, const Point3d& p) const {
    std::pair<std::size_t, double> best{0, std::numeric_limits<double>::infinity()};
    for (std::size_t i = 0; i < tris.size(); ++i) {
      const double d = squared_distance_to_triangle(p, approx(tris[i][0]), approx(tris[i][1]),
                                                    approx(tris[i][2]));
      if (d < best.second) best = {i, d};
    }
    return best;
  }

  /// Would new edges from v to `gained` duplicate an edge of the file
  /// (copies_share_edge: pinch copies are one vertex there)?
  bool joins_copies(vertex_descriptor v, const std::vector<vertex_descriptor>& gained) const {
    for (vertex_descriptor w : gained)
      if (copies_share_edge(mesh, identity, copies, v, w)) return true;
    return false;
  }

  /// Collapse of h: source u goes, target v stays.
  bool plan_collapse(halfedge_descriptor h, Plan& plan, bool simplify = false) const {
    const vertex_descriptor u = mesh.source(h), v = mesh.target(h);
    if (pinned && (*pinned)[u]) return false;  // a pinch point's copy stays where its twins are
    if (identity) {  // v takes over u's edges
      std::vector<vertex_descriptor> gained;
      for (vertex_descriptor w : CGAL::vertices_around_target(mesh.halfedge(u), mesh))
        if (w != v) gained.push_back(w);
      if (joins_copies(v, gained)) return false;
    }
    const auto e = mesh.edge(h);
    if (!CGAL::Euler::does_satisfy_link_condition(e, mesh)) return false;
    const bool border_edge = mesh.is_border(e);
    if (CGAL::is_border(u, mesh) && !border_edge) return false;  // u would leave the boundary
    if (border_edge) {  // a boundary loop of three edges would close
      const halfedge_descriptor b = mesh.is_border(h) ? h : mesh.opposite(h);
      if (mesh.next(mesh.next(mesh.next(b))) == b) return false;
    }
    plan = Plan{};
    plan.h = h;
    // A fresh split point may merge with another one, but collapsing it back
    // into an old vertex must leave only fine faces (or it undoes the slice).
    plan.simplify = simplify || (is_sticky(u) && !is_sticky(v));
    for (halfedge_descriptor g : CGAL::halfedges_around_target(mesh.halfedge(u), mesh)) {
      const face_descriptor f = mesh.face(g);
      if (f == Mesh::null_face()) continue;
      plan.replaced.push_back(f);
      Triple t = corners(f);
      if (std::find(t.begin(), t.end(), v) != t.end()) continue;  // one of the two faces that vanish
      const Triple old = t;
      std::replace(t.begin(), t.end(), u, v);
      if (!same_side(old, t)) return false;
      plan.proposed.push_back(t);
    }
    if (plan.proposed.empty()) return false;
    return acceptable(plan);
  }

  bool plan_flip(halfedge_descriptor h, Plan& plan) const {
    const auto e = mesh.edge(h);
    if (mesh.is_border(e)) return false;
    const halfedge_descriptor o = mesh.opposite(h);
    const vertex_descriptor s = mesh.source(h), t = mesh.target(h), x = mesh.target(mesh.next(h)),
                            y = mesh.target(mesh.next(o));
    if (x == y || CGAL::halfedge(x, y, mesh).second) return false;  // the new edge exists already
    if (joins_copies(x, {y})) return false;
    plan = Plan{};
    plan.flip = true;
    plan.h = h;
    plan.replaced = {mesh.face(h), mesh.face(o)};
    plan.proposed = {Triple{t, x, y}, Triple{x, s, y}};
    const Triple a = corners(mesh.face(h)), b = corners(mesh.face(o));
    for (const Triple& n : plan.proposed)
      if (!same_side(a, n) || !same_side(b, n)) return false;
    return acceptable(plan);
  }

  /// Removal of interior vertex u, its hole (the polygon of its neighbours)
  /// retriangulated for the best worst shape (dynamic programming over the
  /// polygon's triangulations, on double qualities: ordering only; the plan
  /// is then checked exactly like any other). A collapse is the special case
  /// of a fan from one neighbour; the best triangulation may be no fan: a split
  /// point between two others along a CAD cylinder's facet edge is removed
  /// only by joining points across both facets beside it.
  bool plan_removal(vertex_descriptor u, Plan& plan, bool simplify) const {
    if (pinned && (*pinned)[u]) return false;
    if (CGAL::is_border(u, mesh)) return false;
    // the hole's boundary, in the faces' orientation: face (u, a, b) gives a -> b
    const halfedge_descriptor out = mesh.opposite(mesh.halfedge(u));  // u -> ring[0]
    std::vector<vertex_descriptor> ring;
    std::vector<face_descriptor> replaced;
    for (halfedge_descriptor g : CGAL::halfedges_around_source(out, mesh)) {
      replaced.push_back(mesh.face(g));
      ring.push_back(mesh.target(g));
    }
    const std::size_t n = ring.size();
    if (n < 4 || n > 12) return false;
    if (ring[1] != mesh.target(mesh.next(out))) std::reverse(ring.begin() + 1, ring.end());
    std::vector<char> allowed(n * n, 1);  // chord (i, j) may be added
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 2; j < n; ++j) {
        if (i == 0 && j == n - 1) continue;  // a side of the hole
        const bool ok = !CGAL::halfedge(ring[i], ring[j], mesh).second && !joins_copies(ring[i], {ring[j]});
        allowed[i * n + j] = ok;
      }
    // best[i][j]: the best worst quality triangulating ring[i..j] (j > i + 1).
    // A triangle off the input surface (one across a crease, or across a
    // curved part's facets) is forbidden and the triangulation chosen again,
    // up to four times: the best shape is often the one across.
    // Per triangle (i, k, j) of the ring: its quality, computed on first
    // use (the attempts share it), and whether it is forbidden.
    auto at = [n](std::size_t i, std::size_t k, std::size_t j) { return (i * n + k) * n + j; };
    std::vector<double> shape(n * n * n, -1.0);
    std::vector<char> forbidden(n * n * n, 0);
    std::vector<double> best(n * n);
    std::vector<int> cut(n * n);
    std::vector<std::array<std::size_t, 3>> tris;
    for (int attempt = 0;; ++attempt) {
      if (attempt == 4) return false;
      std::fill(best.begin(), best.end(), 180.0);
      std::fill(cut.begin(), cut.end(), -1);
      for (std::size_t len = 2; len < n; ++len)
        for (std::size_t i = 0; i + len < n; ++i) {
          const std::size_t j = i + len;
          best[i * n + j] = -1;
          if (!(i == 0 && j == n - 1) && !allowed[i * n + j]) continue;
          for (std::size_t k = i + 1; k < j; ++k) {
            const double left = k > i + 1 ? best[i * n + k] : 180.0, right = j > k + 1 ? best[k * n + j] : 180.0;
            if (forbidden[at(i, k, j)]) continue;
            double& own = shape[at(i, k, j)];
            if (own < 0) own = quality(approx(ring[i]), approx(ring[k]), approx(ring[j]));
            const double q = std::min({left, right, own});
            if (q > best[i * n + j]) {
              best[i * n + j] = q;
              cut[i * n + j] = static_cast<int>(k);
            }
          }
        }
      if (cut[n - 1] < 0 || best[n - 1] < 0) return false;
      tris.clear();
      std::vector<std::pair<std::size_t, std::size_t>> todo{{0, n - 1}};
      while (!todo.empty()) {
        const auto [i, j] = todo.back();
        todo.pop_back();
        const std::size_t k = static_cast<std::size_t>(cut[i * n + j]);
        tris.push_back({i, k, j});
        if (k > i + 1) todo.emplace_back(i, k);
        if (j > k + 1) todo.emplace_back(k, j);
      }
      bool more = false;
      for (const auto& t : tris)
        if (!near_input({ring[t[0]], ring[t[1]], ring[t[2]]})) {
          forbidden[at(t[0], t[1], t[2])] = 1;
          more = true;
        }
      if (!more) break;
    }
    plan = Plan{};
    plan.removal = true;
    plan.simplify = simplify;
    plan.h = out;  // source: u
    plan.replaced = replaced;
    for (const auto& t : tris) {
      plan.proposed.push_back({ring[t[0]], ring[t[1]], ring[t[2]]});
      if (t[1] > t[0] + 1) plan.diagonals.emplace_back(ring[t[0]], ring[t[1]]);
      if (t[2] > t[1] + 1) plan.diagonals.emplace_back(ring[t[1]], ring[t[2]]);
    }
    // No triangle turns against the surface it replaces: against the face
    // on each side of the hole it spans (the face that side came from), or,
    // spanning none, against every face replaced. (Against every face
    // always refused a point on a crease: its faces in the other plane are
    // perpendicular to the new ones in this.)
    auto side_face = [&](std::size_t i) {  // the replaced face on side ring[i] -> ring[i + 1]
      const vertex_descriptor a = ring[i], b = ring[(i + 1) % n];
      for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, a}}) {
        const auto [h, found] = CGAL::halfedge(x, y, mesh);
        if (found && !mesh.is_border(h) && mesh.target(mesh.next(h)) == u) return mesh.face(h);
      }
      return Mesh::null_face();
    };
    for (std::size_t t = 0; t < tris.size(); ++t) {
      bool spans_side = false;
      for (int e = 0; e < 3; ++e) {
        const std::size_t i = tris[t][e], j = tris[t][(e + 1) % 3];
        if ((i + 1) % n != j) continue;  // a diagonal, not side i of the hole
        const face_descriptor f = side_face(i);
        if (f == Mesh::null_face()) continue;
        spans_side = true;
        if (!same_side(corners(f), plan.proposed[t])) return false;
      }
      if (!spans_side)
        for (face_descriptor f : replaced)
          if (!same_side(corners(f), plan.proposed[t])) return false;
    }
    return acceptable(plan);
  }

  /// The best valid operation removing bad face f, if any.
  bool best_plan(face_descriptor f, Plan& best) const {
    std::array<halfedge_descriptor, 3> hs;
    std::array<Point3d, 3> p;
    {
      halfedge_descriptor h = mesh.halfedge(f);
      for (int k = 0; k < 3; ++k, h = mesh.next(h)) {
        hs[k] = h;
        p[k] = approx(mesh.target(h));
      }
    }
    // edges by length: hs[k] runs from corner k-1 to corner k
    std::array<int, 3> order{0, 1, 2};
    auto len = [&](int k) { const Point3d d = sub(p[k], p[(k + 2) % 3]); return dot(d, d); };
    std::sort(order.begin(), order.end(), [&](int a, int b) { return len(a) < len(b); });
    std::vector<Plan> candidates;
    Plan plan;
    if (o.fold_angle > 0 && is_folded(f)) {  // a fold: every edge, every way
      for (int k = 0; k < 3; ++k) {
        if (plan_collapse(hs[k], plan)) candidates.push_back(plan);
        if (plan_collapse(mesh.opposite(hs[k]), plan)) candidates.push_back(plan);
        if (plan_flip(hs[k], plan)) candidates.push_back(plan);
      }
      return choose(candidates, best);
    }
    for (int k : {order[0], order[1]}) {  // collapse the short edges, either way
      if (plan_collapse(hs[k], plan)) candidates.push_back(plan);
      if (plan_collapse(mesh.opposite(hs[k]), plan)) candidates.push_back(plan);
    }
    if (plan_flip(hs[order[2]], plan)) candidates.push_back(plan);  // flip the longest (caps, collinear faces)
    if (retriangulate)
      for (int k = 0; k < 3; ++k) {
        const vertex_descriptor u = mesh.target(hs[k]);
        if (plan_removal(u, plan, is_sticky(u))) candidates.push_back(plan);
      }
    return choose(candidates, best);
  }

  /// The best-shaped candidate within the tolerance that creates no
  /// self-intersection.
  bool choose(std::vector<Plan>& candidates, Plan& best) const {
    std::sort(candidates.begin(), candidates.end(), [](const Plan& a, const Plan& b) { return a.worst > b.worst; });
    for (Plan& c : candidates)
      if (within_tolerance(c) && !index.would_intersect(c.proposed, c.replaced)) {
        best = std::move(c);
        return true;
      }
    return false;
  }

  // ---- applying ----

  std::vector<face_descriptor> apply(const Plan& plan) {
    const std::vector<Point3d> displaced = displaced_points(plan);
    const std::vector<face_descriptor> around =
        o.fold_angle > 0 ? surrounding(plan) : std::vector<face_descriptor>{};  // kept: descriptors stay valid
    for (face_descriptor f : plan.replaced) {
      attached.erase(static_cast<std::uint32_t>(f));
      index.remove(f);
    }
    std::vector<face_descriptor> changed;
    if (plan.flip) {
      CGAL::Euler::flip_edge(plan.h, mesh);
      changed = plan.replaced;
      for (face_descriptor f : changed) on_input[f] = 0;
      ++stats.flips;
    } else if (plan.removal) {
      // the hole as one face (it keeps the face's properties), then cut by the diagonals
      const halfedge_descriptor hole = CGAL::Euler::remove_center_vertex(mesh.opposite(plan.h), mesh);
      const face_descriptor merged = mesh.face(hole);
      on_input[merged] = 0;
      const std::optional<FaceOriginMap> origin = face_origin_map(mesh);
      for (const auto& [a, b] : plan.diagonals) {
        halfedge_descriptor ha, hb;
        for (halfedge_descriptor g : CGAL::halfedges_around_target(mesh.halfedge(a), mesh)) {
          if (mesh.is_border(g)) continue;
          hb = halfedge_descriptor();
          for (halfedge_descriptor k : CGAL::halfedges_around_face(g, mesh))
            if (mesh.target(k) == b) hb = k;
          if (hb != halfedge_descriptor()) {
            ha = g;
            break;
          }
        }
        const halfedge_descriptor d = CGAL::Euler::split_face(ha, hb, mesh);
        const face_descriptor piece = mesh.face(mesh.opposite(d));
        on_input[piece] = 0;
        if (origin) (*origin)[piece] = (*origin)[mesh.face(d)];
      }
      for (vertex_descriptor w : CGAL::vertices_around_face(hole, mesh))
        for (face_descriptor f : CGAL::faces_around_target(mesh.halfedge(w), mesh))
          if (f != Mesh::null_face()) changed.push_back(f);
      std::sort(changed.begin(), changed.end());
      changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
      ++stats.removals;
    } else {
      for (face_descriptor f : plan.replaced) on_input[f] = 0;  // the two that vanish do not matter
      const Point keep = mesh.point(mesh.target(plan.h));
      const vertex_descriptor v = CGAL::Euler::collapse_edge(mesh.edge(plan.h), mesh);
      mesh.point(v) = keep;
      for (face_descriptor f : CGAL::faces_around_target(mesh.halfedge(v), mesh))
        if (f != Mesh::null_face()) changed.push_back(f);
      ++stats.collapses;
    }
    index.update(changed);
    std::vector<face_descriptor> cover = changed;
    if (o.fold_angle > 0)
      for (face_descriptor f : around)
        if (!mesh.is_removed(f)) cover.push_back(f);
    attach(displaced, cover);
    return changed;
  }

  /// ShapeDecimator::replace_star(): the disc's faces are `replaced`, a
  /// centre vertex is h's source (a displaced point, like a collapse's), and
  /// the new vertices exist, isolated, while the plan is checked.
  std::vector<face_descriptor> replace_star(const StarReplacement& r, std::vector<vertex_descriptor>& made) {
    const std::size_t n = r.link.size();
    if (n < 3 || r.sector_faces.size() != n || r.triangles.size() != r.sectors.size()) return {};
    // the disc: its boundary edges are the link's, inside it; a triangulated
    // disc with I interior vertices has n - 2 + 2I faces
    const std::size_t interior = r.centre_vertex ? 1 : 0;
    if (r.faces.size() != n - 2 + 2 * interior) return {};
    auto in_disc = [&](face_descriptor f) { return std::find(r.faces.begin(), r.faces.end(), f) != r.faces.end(); };
    for (std::size_t i = 0; i < n; ++i) {
      const auto [h, found] = CGAL::halfedge(r.link[i], r.link[(i + 1) % n], mesh);
      if (!found || mesh.is_border(h) || mesh.face(h) != r.sector_faces[i] || !in_disc(mesh.face(h)) ||
          mesh.is_border(mesh.opposite(h)) || in_disc(mesh.face(mesh.opposite(h))))
        return {};
    }
    if (r.centre_vertex) {
      const vertex_descriptor c = *r.centre_vertex;
      if ((pinned && (*pinned)[c]) || CGAL::is_border(c, mesh)) return {};
      for (face_descriptor f : CGAL::faces_around_target(mesh.halfedge(c), mesh))
        if (!in_disc(f)) return {};
    }
    std::vector<vertex_descriptor> id{mesh.add_vertex(r.centre)};
    id.insert(id.end(), r.link.begin(), r.link.end());
    for (const Point& p : r.points) id.push_back(mesh.add_vertex(p));
    auto discard = [&]() {
      for (std::size_t k = 0; k < id.size(); ++k)
        if (k == 0 || k > n) mesh.remove_vertex(id[k]);
      return std::vector<face_descriptor>{};
    };
    Plan plan;
    // for_each_displaced() takes h's source: the centre vertex, or a corner kept
    plan.h = r.centre_vertex ? mesh.opposite(mesh.halfedge(*r.centre_vertex))
                             : CGAL::halfedge(r.link[0], r.link[1], mesh).first;
    plan.replaced = r.faces;
    for (std::size_t t = 0; t < r.triangles.size(); ++t) {
      const Triple tri{id[r.triangles[t][0]], id[r.triangles[t][1]], id[r.triangles[t][2]]};
      if (classify_triangle(mesh.point(tri[0]), mesh.point(tri[1]), mesh.point(tri[2]), cos_cap, cos_needle) !=
          Shape::fine)
        return discard();
      // against the star faces in the middle of its span: across a narrow
      // cone, the faces at the ends of a wide span face away from each other
      const std::size_t first = r.sectors[t][0], span = (r.sectors[t][1] + n - first) % n;
      for (std::size_t i : {(first + span / 2) % n, (first + (span + 1) / 2) % n})
        if (!same_side(corners(r.sector_faces[i]), tri)) return discard();
      plan.proposed.push_back(tri);
    }
    if (!acceptable(plan) || !within_tolerance(plan) || index.would_intersect(plan.proposed, plan.replaced))
      return discard();

    const std::vector<Point3d> displaced = displaced_points(plan);
    const std::optional<FaceOriginMap> origin = face_origin_map(mesh);
    std::vector<std::int64_t> origins;
    for (face_descriptor f : r.sector_faces) origins.push_back(origin ? (*origin)[f] : -1);
    for (face_descriptor f : r.faces) {
      attached.erase(static_cast<std::uint32_t>(f));
      index.remove(f);
    }
    // the disc as one face, then a hole the new faces fill, outermost first
    halfedge_descriptor hole;
    if (r.centre_vertex) {
      hole = CGAL::Euler::remove_center_vertex(mesh.halfedge(*r.centre_vertex), mesh);
    } else {  // no interior vertex: the dual is a tree, each inner edge joins two faces
      std::vector<halfedge_descriptor> inner;
      for (face_descriptor f : r.faces)
        for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh.halfedge(f), mesh))
          if (!mesh.is_border(mesh.opposite(h)) && in_disc(mesh.face(mesh.opposite(h))) && h < mesh.opposite(h))
            inner.push_back(h);
      for (halfedge_descriptor h : inner) {
        if (mesh.face(h) == mesh.face(mesh.opposite(h))) throw std::logic_error("replace_star: the faces are no disc");
        CGAL::Euler::join_face(h, mesh);
      }
      hole = CGAL::halfedge(r.link[0], r.link[1], mesh).first;
    }
    CGAL::Euler::remove_face(hole, mesh);
    std::vector<face_descriptor> faces;
    for (std::size_t t = 0; t < plan.proposed.size(); ++t) {
      const Triple& tri = plan.proposed[t];
      const face_descriptor f = mesh.add_face(tri[0], tri[1], tri[2]);
      if (f == Mesh::null_face()) throw std::logic_error("replace_star: a planned face does not fit its hole");
      on_input[f] = 0;
      if (origin) (*origin)[f] = origins[r.sectors[t][0]];
      faces.push_back(f);
    }
    index.update(faces);
    attach(displaced, faces);
    made.push_back(id[0]);
    made.insert(made.end(), id.begin() + 1 + n, id.end());
    return faces;
  }

  void attach(const std::vector<Point3d>& points, const std::vector<face_descriptor>& faces) {
    if (faces.empty()) return;
    std::vector<Triple> tris;
    for (face_descriptor f : faces) tris.push_back(corners(f));
    for (const Point3d& p : points)
      attached[static_cast<std::uint32_t>(faces[nearest(tris, p).first])].push_back(p);
  }

  void run(const std::vector<face_descriptor>& seeds) {
    using Entry = std::pair<double, std::uint32_t>;  // (quality, face): worst first
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    auto push = [&](face_descriptor f) {
      if (!mesh.is_removed(f) && is_bad(f)) queue.emplace(quality_of(corners(f)), static_cast<std::uint32_t>(f));
    };
    for (face_descriptor f : seeds) push(f);
    while (!queue.empty()) {
      const auto [q, i] = queue.top();
      queue.pop();
      const face_descriptor f(i);
      if (mesh.is_removed(f) || quality_of(corners(f)) != q || !is_bad(f)) continue;  // stale entry
      Plan plan;
      if (!best_plan(f, plan)) continue;  // stuck for now; a neighbour's operation re-queues it
      const std::vector<face_descriptor> changed = apply(plan);
      // the changed faces and their neighbours may be bad, or freed to improve
      std::vector<face_descriptor> around;
      for (face_descriptor g : changed)
        for (vertex_descriptor w : CGAL::vertices_around_face(mesh.halfedge(g), mesh))
          for (face_descriptor n : CGAL::faces_around_target(mesh.halfedge(w), mesh))
            if (n != Mesh::null_face()) around.push_back(n);
      std::sort(around.begin(), around.end());
      around.erase(std::unique(around.begin(), around.end()), around.end());
      for (face_descriptor g : around) push(g);
    }
  }

  /// Removes vertices (a slice's split points) wherever a collapse leaves
  /// only fine faces, within the tolerance — the paper's §7 "decimating along
  /// the intersection curve after each slicing".
  void simplify(const std::vector<vertex_descriptor>& vertices) {
    for (vertex_descriptor x : vertices) {
      if (mesh.is_removed(x) || mesh.is_isolated(x)) continue;
      std::vector<Plan> candidates;
      Plan plan, best;
      for (halfedge_descriptor h : CGAL::halfedges_around_source(x, mesh))
        if (plan_collapse(h, plan, true)) candidates.push_back(plan);
      if (retriangulate && plan_removal(x, plan, true)) candidates.push_back(plan);
      if (choose(candidates, best)) apply(best);
    }
  }

  /// A slice tiles each face it cuts exactly with its pieces, so a point
  /// attached to the face is nearest to one of those pieces: only they are
  /// searched (searching every face of the slice made reattaching quadratic
  /// in the slice's size).
  void reattach(const std::vector<face_descriptor>& faces, const std::vector<face_descriptor>& parents) {
    std::unordered_map<std::uint32_t, std::vector<face_descriptor>> pieces;
    for (std::size_t i = 0; i < faces.size(); ++i) pieces[static_cast<std::uint32_t>(parents[i])].push_back(faces[i]);
    for (const auto& [parent, children] : pieces) {
      auto it = attached.find(parent);
      if (it == attached.end()) continue;
      std::vector<Point3d> points = std::move(it->second);
      attached.erase(it);
      attach(points, children);
    }
  }
};

ShapeDecimator::ShapeDecimator(Mesh& mesh, LocalIndex& index, const SurfaceDistance& input,
                               const DecimationOptions& options)
    : impl_(std::make_unique<Impl>(mesh, index, input, options)) {}
ShapeDecimator::~ShapeDecimator() = default;
void ShapeDecimator::run(const std::vector<face_descriptor>& faces, const std::vector<vertex_descriptor>& fresh) {
  for (vertex_descriptor v : fresh) {
    if (static_cast<std::size_t>(v) >= impl_->sticky.size()) impl_->sticky.resize(static_cast<std::size_t>(v) + 1, 0);
    impl_->sticky[static_cast<std::size_t>(v)] = 1;
  }
  impl_->run(faces);
  impl_->sticky.clear();
}
void ShapeDecimator::simplify(const std::vector<vertex_descriptor>& vertices) { impl_->simplify(vertices); }
void ShapeDecimator::reattach(const std::vector<face_descriptor>& faces, const std::vector<face_descriptor>& parents) {
  impl_->reattach(faces, parents);
}
std::vector<face_descriptor> ShapeDecimator::replace_star(const StarReplacement& r,
                                                          std::vector<vertex_descriptor>& made) {
  return impl_->replace_star(r, made);
}
void ShapeDecimator::set_retriangulate(bool on) { impl_->retriangulate = on; }
bool ShapeDecimator::is_bad(face_descriptor f) const { return impl_->is_bad(f); }
const DecimationStats& ShapeDecimator::stats() const { return impl_->stats; }

std::optional<std::size_t> round_all_if_unchanged(Mesh& mesh, LocalIndex& index,
                                                  const std::vector<vertex_descriptor>& points, double cos_cap,
                                                  double cos_needle) {
  struct Move {
    vertex_descriptor v;
    Point from, to;
  };
  std::vector<Move> moves;
  for (vertex_descriptor v : points) {
    if (mesh.is_removed(v) || mesh.is_isolated(v)) continue;
    const Point q = nearest_double_point(mesh.point(v));
    if (q != mesh.point(v)) moves.push_back({v, mesh.point(v), q});
  }
  if (moves.empty()) return std::size_t(0);
  std::vector<face_descriptor> around;
  for (const Move& m : moves)
    for (face_descriptor f : CGAL::faces_around_target(mesh.halfedge(m.v), mesh))
      if (f != Mesh::null_face()) around.push_back(f);
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  std::vector<std::array<vertex_descriptor, 3>> proposed;
  std::vector<std::array<Point, 3>> before;
  for (face_descriptor f : around) {
    const halfedge_descriptor h = mesh.halfedge(f);
    proposed.push_back({mesh.source(h), mesh.target(h), mesh.target(mesh.next(h))});
    before.push_back({mesh.point(proposed.back()[0]), mesh.point(proposed.back()[1]), mesh.point(proposed.back()[2])});
  }
  for (const Move& m : moves) mesh.point(m.v) = m.to;
  bool ok = true;
  for (std::size_t i = 0; ok && i < proposed.size(); ++i) {
    const Point &a = mesh.point(proposed[i][0]), &b = mesh.point(proposed[i][1]), &c = mesh.point(proposed[i][2]);
    const Shape after = classify_triangle(a, b, c, cos_cap, cos_needle);
    ok = (after == Shape::fine || after == classify_triangle(before[i][0], before[i][1], before[i][2], cos_cap,
                                                               cos_needle)) &&
         normals_agree(before[i][0], before[i][1], before[i][2], a, b, c);
  }
  if (ok && !index.would_intersect(proposed, around)) {
    index.update(around);
    return moves.size();
  }
  for (const Move& m : moves) mesh.point(m.v) = m.from;
  return std::nullopt;
}

bool round_if_unchanged(Mesh& mesh, LocalIndex& index, vertex_descriptor v, double cos_cap, double cos_needle) {
  return round_all_if_unchanged(mesh, index, {v}, cos_cap, cos_needle) == std::optional<std::size_t>(1);
}

}  // namespace polyheal::detail
