#include "polyheal/repair/deintersect.h"

#include <CGAL/boost/graph/Euler_operations.h>
#include <CGAL/boost/graph/helpers.h>
#include <CGAL/Bbox_3.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "polyheal/inspect/exact_predicates.h"
#include "polyheal/inspect/local_index.h"
#include "polyheal/inspect/self_intersections.h"
#include "polyheal/mesh/convert.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/mesh.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/repair/detail/distance.h"

namespace polyheal {
namespace {

using Vector = Kernel::Vector_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// |volume| of tetrahedron abcd (a cost, not a predicate).
double tet_volume(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d) {
  return std::abs(dot(sub(b, a), cross(sub(c, a), sub(d, a)))) / 6.0;
}

enum class OpKind { swap, hammer, lift, group, pair };

/// One operation, in terms that survive other operations: a swap names its
/// edge by its end vertices, a move names vertices and their new positions.
struct Op {
  OpKind kind = OpKind::swap;
  vertex_descriptor a, b;                                    // swap: the edge ab
  std::vector<std::pair<vertex_descriptor, Point>> moves;    // hammer: one, lift: three
  double cost = 0;                                           // swept volume (§4.5, Fig. 9)
  double shift = 0;                                          // the largest vertex move
};

/// The repair of stage 2 on one working mesh.
class Deintersector {
 public:
  /// `original`: every vertex's input position; no move takes a vertex
  /// further than r.max_displacement_allowed from it.
  /// `pairs`: the input's intersecting pairs by input face id (the global
  /// pass of inspect(), same semantics as the local index; the mesh's faces
  /// carry their input ids in kFaceOrigin).
  Deintersector(Mesh& mesh, Mesh::Property_map<vertex_descriptor, Point3d> original, const std::vector<FacePair>& pairs,
                const DeintersectOptions& o, DeintersectReport& r)
      : mesh_(mesh), original_(original), pinned_(vertex_pinned_map(mesh)), identity_(vertex_identity_map(mesh)),
        copies_(pinch_copies(mesh)),
        o_(o), r_(r), index_(mesh),
        partners_(mesh.number_of_faces()) {
    const auto origin = face_origin_map(mesh);
    std::vector<face_descriptor> by_input;
    for (face_descriptor f : mesh.faces()) {
      const std::int64_t i = origin ? (*origin)[f] : static_cast<std::int64_t>(f);
      if (i < 0) continue;
      if (by_input.size() <= std::size_t(i)) by_input.resize(std::size_t(i) + 1, Mesh::null_face());
      by_input[std::size_t(i)] = f;
    }
    for (const FacePair& p : pairs) link(by_input.at(p.first), by_input.at(p.second));
  }

  std::size_t intersecting_faces() const { return intersecting_; }
  /// The work budget (DeintersectOptions::max_trials) is used up.
  bool spent() const { return o_.max_trials > 0 && r_.trials >= o_.max_trials; }
  std::size_t intersecting_pairs() const {
    std::size_t n = 0;
    for (const auto& p : partners_) n += p.size();
    return n / 2;
  }

  /// Rounds of cost phase + implementation phase (§4.5) until nothing
  /// applies (or the work budget is spent).
  void run() {
    while (intersecting_ > 0 && r_.rounds < o_.max_rounds && !spent()) {
      ++r_.rounds;
      if (o_.observer) o_.observer->progress(1.0 - double(intersecting_) / double(std::max<std::size_t>(1, start_)));
      std::vector<Op> ops = cost_phase();
      if (ops.empty()) break;
      std::stable_sort(ops.begin(), ops.end(), [](const Op& x, const Op& y) { return x.cost < y.cost; });
      std::size_t applied = 0;
      for (const Op& op : ops) {
        if (intersecting_ == 0) break;
        if (try_op(op, /*keep=*/true)) {
          ++applied;
          ++(op.kind == OpKind::swap     ? r_.swaps
             : op.kind == OpKind::hammer ? r_.hammers
             : op.kind == OpKind::lift   ? r_.lifts
             : op.kind == OpKind::group  ? r_.group_moves
                                         : r_.pair_moves);
        } else {
          ++r_.stale;
        }
      }
      if (applied == 0) break;
    }
    r_.out_of_trials = intersecting_ > 0 && spent();
  }

 private:
  Mesh& mesh_;
  Mesh::Property_map<vertex_descriptor, Point3d> original_;
  std::optional<Mesh::Property_map<vertex_descriptor, char>> pinned_;  // pinch-point copies: never moved
  std::optional<VertexIdentityMap> identity_;  // pinch-point copies: one vertex
  PinchCopies copies_;                         // ... and their lists
  const DeintersectOptions& o_;
  DeintersectReport& r_;
  LocalIndex index_;
  std::vector<std::vector<face_descriptor>> partners_;  // by face index: the faces it intersects
  std::size_t intersecting_ = 0;                        // faces with a partner
  std::size_t start_ = 0;
  std::unique_ptr<detail::SurfaceDistance> rays_;       // local-thickness mode: this round's surface
  // Rounds after the first skip the sources of operations (an edge, a
  // vertex, a face, a group of vertices) that nothing has changed near (see
  // Sources): their reach in the last cost phase, the boxes of what applied
  // operations changed since, the reach the running trials grow.
  using SourceKey = std::vector<std::uint32_t>;  // kind, then vertex or face ids
  std::map<SourceKey, CGAL::Bbox_3> reach_;
  std::unordered_map<std::size_t, std::optional<Point>> through_;  // per vertex, with its reach (group_ops)
  std::vector<CGAL::Bbox_3> dirty_;
  CGAL::Bbox_3* tracing_ = nullptr;

  static std::size_t id(face_descriptor f) { return static_cast<std::size_t>(f); }

  void link(face_descriptor f, face_descriptor g) {
    for (face_descriptor x : {f, g})
      if (partners_[id(x)].empty()) ++intersecting_;
    partners_[id(f)].push_back(g);
    partners_[id(g)].push_back(f);
    start_ = std::max(start_, intersecting_);
  }

  /// Replaces every pair involving `changed` by the pairs `now`.
  void relink(const std::vector<face_descriptor>& changed,
              const std::vector<std::pair<face_descriptor, face_descriptor>>& now) {
    std::vector<face_descriptor> affected = changed;
    for (face_descriptor f : changed) affected.insert(affected.end(), partners_[id(f)].begin(), partners_[id(f)].end());
    for (const auto& [f, g] : now) affected.insert(affected.end(), {f, g});
    std::sort(affected.begin(), affected.end());
    affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
    for (face_descriptor x : affected) intersecting_ -= partners_[id(x)].empty() ? 0 : 1;
    for (face_descriptor f : changed) {
      for (face_descriptor g : partners_[id(f)]) {
        auto& pg = partners_[id(g)];
        pg.erase(std::remove(pg.begin(), pg.end(), f), pg.end());
      }
      partners_[id(f)].clear();
    }
    for (const auto& [f, g] : now) {
      partners_[id(f)].push_back(g);
      partners_[id(g)].push_back(f);
    }
    for (face_descriptor x : affected) intersecting_ += partners_[id(x)].empty() ? 0 : 1;
    for (face_descriptor x : affected) dirty_.push_back(box({x}));  // their partner lists changed
  }

  // ---- geometry helpers -------------------------------------------------

  std::array<vertex_descriptor, 3> corners(face_descriptor f) const {
    const halfedge_descriptor h = mesh_.halfedge(f);
    return {mesh_.source(h), mesh_.target(h), mesh_.target(mesh_.next(h))};
  }
  /// The box of `faces` as they are now (interval boxes of the points).
  CGAL::Bbox_3 box(const std::vector<face_descriptor>& faces) const {
    CGAL::Bbox_3 b;
    for (face_descriptor f : faces)
      for (vertex_descriptor v : corners(f)) b += mesh_.point(v).bbox();
    return b;
  }
  Vector normal_vector(face_descriptor f) const {
    const auto c = corners(f);
    return CGAL::cross_product(mesh_.point(c[1]) - mesh_.point(c[0]), mesh_.point(c[2]) - mesh_.point(c[0]));
  }
  /// A face's corners as they are now, standing for its normal in the
  /// exact sign tests below: normals_agree() decides them on intervals
  /// first (lazy Vector_3 chains built and freed per test were ~15% of a
  /// deintersect run before).
  struct FaceNormal {
    std::array<Point, 3> p;
  };
  FaceNormal normal(face_descriptor f) const {
    const auto c = corners(f);
    return {{mesh_.point(c[0]), mesh_.point(c[1]), mesh_.point(c[2])}};
  }
  static bool is_null(const FaceNormal& n) { return CGAL::collinear(n.p[0], n.p[1], n.p[2]); }
  /// The dot product of the two normals is positive.
  static bool agree(const FaceNormal& x, const FaceNormal& y) {
    return normals_agree(x.p[0], x.p[1], x.p[2], y.p[0], y.p[1], y.p[2]);
  }
  /// ... negative: positive with y turned over.
  static bool opposed(const FaceNormal& x, const FaceNormal& y) {
    return normals_agree(x.p[0], x.p[1], x.p[2], y.p[0], y.p[2], y.p[1]);
  }
  Point3d p3(vertex_descriptor v) const { return approx_point3d(mesh_.point(v)); }

  /// The faces around the vertices `vs` (each once).
  std::vector<face_descriptor> star(const std::vector<vertex_descriptor>& vs) const {
    std::vector<face_descriptor> out;
    for (vertex_descriptor v : vs)
      for (face_descriptor f : CGAL::faces_around_target(mesh_.halfedge(v), mesh_))
        if (f != Mesh::null_face() && std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
    return out;
  }

  /// Exact shape checks on `changed` after an edit: no face becomes
  /// degenerate (exactly collinear), and no edge in `unfolded` (see
  /// unfolded_edges) folds. A face's own normal must not turn around either
  /// (compared with `before`; for a swap each new face with both replaced
  /// faces) — unless the face was folded against a neighbour before the
  /// edit (`folded`): turning an inverted sliver back is a repair.
  bool shapes_ok(const std::vector<face_descriptor>& changed, const std::vector<FaceNormal>& before, bool swap,
                 const std::vector<halfedge_descriptor>& unfolded, const std::vector<char>& folded) const {
    for (std::size_t i = 0; i < changed.size(); ++i) {
      const FaceNormal n = normal(changed[i]);
      if (is_null(n)) return false;
      if (swap) {
        for (const FaceNormal& m : before)
          if (!agree(n, m)) return false;
      } else if (!folded[i] && !agree(n, before[i])) {
        return false;
      }
    }
    for (halfedge_descriptor h : unfolded)
      if (!agree(normal(mesh_.face(h)), normal(mesh_.face(mesh_.opposite(h))))) return false;
    return true;
  }

  /// Per face of `faces`: is it folded against a neighbour now (normals
  /// with a negative dot product across an edge: a dihedral angle below 90
  /// degrees, an inverted sliver; a CAD right angle is not a fold)?
  std::vector<char> folded_faces(const std::vector<face_descriptor>& faces) const {
    std::vector<char> out;
    for (face_descriptor f : faces) {
      const FaceNormal n = normal(f);
      char folded = 0;
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_)) {
        const face_descriptor g = mesh_.face(mesh_.opposite(h));
        if (g != Mesh::null_face() && opposed(n, normal(g))) folded = 1;
      }
      out.push_back(folded);
    }
    return out;
  }

  /// Halfedges `hs` (inner sides of edges an edit may bend) whose two faces
  /// are not folded now: normals with a positive dot product. After the
  /// edit they must still not be (a fold is a spike the oracle does not
  /// count as an intersection).
  std::vector<halfedge_descriptor> unfolded_edges(const std::vector<halfedge_descriptor>& hs) const {
    std::vector<halfedge_descriptor> out;
    for (halfedge_descriptor h : hs) {
      const face_descriptor g = mesh_.face(mesh_.opposite(h));
      if (g != Mesh::null_face() && agree(normal(mesh_.face(h)), normal(g))) out.push_back(h);
    }
    return out;
  }

  std::vector<halfedge_descriptor> halfedges_of(const std::vector<face_descriptor>& faces) const {
    std::vector<halfedge_descriptor> out;
    for (face_descriptor f : faces)
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_)) out.push_back(h);
    return out;
  }

  // ---- the improvement criteria (§4.1) ------------------------------------

  /// With `changed` edited in place and re-indexed: do the pairs `now`
  /// satisfy §4.1 — the number of intersecting faces strictly decreases and
  /// no intersection-free face becomes intersecting? For a swap the two
  /// faces are new triangles, so only their number is compared: no more of
  /// them intersect than of the two they replace. Returns how many fewer
  /// faces intersect; 0 when refused.
  long gain(const std::vector<face_descriptor>& changed,
                const std::vector<std::pair<face_descriptor, face_descriptor>>& now, bool swap) const {
    auto in_changed = [&](face_descriptor f) { return std::find(changed.begin(), changed.end(), f) != changed.end(); };
    std::unordered_map<std::size_t, long> after;  // partners after the edit, per affected face
    for (face_descriptor f : changed) {
      after.emplace(id(f), 0);
      for (face_descriptor g : partners_[id(f)])
        if (!in_changed(g) && !after.count(id(g))) {
          long keep = 0;
          for (face_descriptor x : partners_[id(g)]) keep += in_changed(x) ? 0 : 1;
          after.emplace(id(g), keep);
        }
    }
    for (const auto& [f, g] : now)
      for (face_descriptor x : {f, g}) {
        auto it = after.find(id(x));
        if (it == after.end()) {
          if (partners_[id(x)].empty()) return 0;  // a free face would start intersecting
          it = after.emplace(id(x), long(partners_[id(x)].size())).first;  // not adjacent to `changed` before
        }
        ++it->second;
      }
    long before_count = 0, after_count = 0, before_changed = 0, after_changed = 0;
    for (const auto& [f, n] : after) {
      const bool was = !partners_[f].empty(), is = n > 0;
      before_count += was;
      after_count += is;
      if (in_changed(face_descriptor(static_cast<Mesh::size_type>(f)))) {
        before_changed += was;
        after_changed += is;
        if (!swap && !was && is) return 0;
      } else if (!was && is) {
        return 0;
      }
    }
    if (swap && after_changed > before_changed) return 0;
    return std::max(0L, before_count - after_count);
  }

  // ---- applying and retracting ----------------------------------------------

  /// Applies `op` if it is valid now: shapes, then the criteria. With keep,
  /// a valid op stays and the pair bookkeeping follows; otherwise (or when
  /// invalid) the mesh is restored exactly. Returns the gain (0: invalid).
  long try_op(const Op& op, bool keep) {
    ++r_.trials;
    if (op.kind == OpKind::swap) return try_swap(op, keep);
    return try_moves(op, keep);
  }

  /// The end of every trial, with the edit made: if its shapes are valid,
  /// re-index `changed`, ask the oracle what they intersect now and decide
  /// §4.1; with keep, a valid edit's pairs replace the old ones. Returns the
  /// gain; the caller undoes the edit unless it is kept.
  long decide(const std::vector<face_descriptor>& changed, bool shapes_valid, bool swap, bool keep) {
    if (tracing_) *tracing_ += box(changed);  // where the trial edits and asks the oracle
    if (!shapes_valid) return 0;
    index_.update(changed);
    const auto now = index_.intersections(changed);
    const long g = gain(changed, now, swap);
    if (g > 0 && keep) relink(changed, now);
    return g;
  }

  long try_moves(const Op& op, bool keep) {
    std::vector<vertex_descriptor> vs;
    for (const auto& m : op.moves) vs.push_back(m.first);
    const std::vector<face_descriptor> changed = star(vs);
    std::vector<FaceNormal> before;
    for (face_descriptor f : changed) before.push_back(normal(f));
    const auto unfolded = unfolded_edges(halfedges_of(changed));
    const auto folded = folded_faces(changed);
    const CGAL::Bbox_3 was = keep ? box(changed) : CGAL::Bbox_3();  // dirty if kept
    std::vector<Point> old;
    for (const auto& [v, p] : op.moves) {
      old.push_back(mesh_.point(v));
      mesh_.point(v) = p;
    }
    const long ok = decide(changed, shapes_ok(changed, before, false, unfolded, folded), false, keep);
    if (ok && keep) {
      dirty_.push_back(was);
      return ok;
    }
    for (std::size_t i = 0; i < op.moves.size(); ++i) mesh_.point(op.moves[i].first) = old[i];
    index_.update(changed);
    return ok;
  }

  long try_swap(const Op& op, bool keep) {
    const auto [h, found] = CGAL::halfedge(op.a, op.b, mesh_);
    if (!found || mesh_.is_border(mesh_.edge(h))) return 0;
    const halfedge_descriptor o = mesh_.opposite(h);
    const vertex_descriptor c = mesh_.target(mesh_.next(h)), d = mesh_.target(mesh_.next(o));
    // A swap must not duplicate an edge (also in the file, where pinch copies
    // weld) or leave a vertex with two edges.
    if (c == d || CGAL::halfedge(c, d, mesh_).second || copies_share_edge(mesh_, identity_, copies_, c, d)) return 0;
    for (vertex_descriptor v : {op.a, op.b})  // an interior vertex keeps 3 edges, a border one 2
      if (CGAL::degree(v, mesh_) <= (mesh_.is_border(v, true) ? 2u : 3u)) return 0;
    const std::vector<face_descriptor> changed{mesh_.face(h), mesh_.face(o)};
    const std::vector<FaceNormal> before{normal(changed[0]), normal(changed[1])};
    const halfedge_descriptor start[2] = {mesh_.halfedge(changed[0]), mesh_.halfedge(changed[1])};
    // The quad's four outer edges keep their halfedges through the flip.
    const auto unfolded = unfolded_edges({mesh_.next(h), mesh_.prev(h), mesh_.next(o), mesh_.prev(o)});
    const CGAL::Bbox_3 was = keep ? box(changed) : CGAL::Bbox_3();  // dirty if kept
    const std::array<vertex_descriptor, 4> quad{op.a, op.b, c, d};
    std::array<halfedge_descriptor, 4> around;  // a flip may repoint a vertex's halfedge
    for (int k = 0; k < 4; ++k) around[k] = mesh_.halfedge(quad[k]);
    CGAL::Euler::flip_edge(h, mesh_);
    const long ok = decide(changed, shapes_ok(changed, before, true, unfolded, {}), true, keep);
    if (ok && keep) {
      if (const auto origin = face_origin_map(mesh_)) (*origin)[changed[0]] = (*origin)[changed[1]] = -1;  // new triangles
      dirty_.push_back(was);
      return ok;
    }
    // Each flip turns h one step around the quad (ab, cd, ba, dc): three more
    // bring back ab with every face holding its own triangle again (two
    // would swap the faces' triangles).
    // Each face also gets back the halfedge it started from (a flip points it
    // at h), so its corners come out in the input's order.
    for (int k = 0; k < 3; ++k) CGAL::Euler::flip_edge(h, mesh_);
    mesh_.set_halfedge(changed[0], start[0]);
    mesh_.set_halfedge(changed[1], start[1]);
    for (int k = 0; k < 4; ++k) mesh_.set_halfedge(quad[k], around[k]);  // circulators start where they did
    index_.update(changed);
    return ok;
  }

  // ---- candidates ---------------------------------------------------------

  /// The faces intersecting any face around v.
  std::vector<face_descriptor> partners_around(const std::vector<face_descriptor>& faces) const {
    std::vector<face_descriptor> out;
    for (face_descriptor f : faces)
      for (face_descriptor g : partners_[id(f)])
        if (std::find(out.begin(), out.end(), g) == out.end()) out.push_back(g);
    return out;
  }

  /// Does f have v as a corner — or another copy of v's pinch point (one
  /// vertex for the oracle, kVertexIdentity)?
  bool has_vertex(face_descriptor f, vertex_descriptor v) const {
    const std::uint32_t i = vertex_identity(identity_, v);
    for (vertex_descriptor c : corners(f))
      if (vertex_identity(identity_, c) == i) return true;
    return false;
  }

  Triangle triangle(face_descriptor f) const {
    const auto c = corners(f);
    return {mesh_.point(c[0]), mesh_.point(c[1]), mesh_.point(c[2])};
  }

  /// Exact points where segment (from v to b) crosses the faces `others`
  /// that share no vertex with it; a coplanar overlap gives both ends.
  std::vector<Point> crossings(vertex_descriptor v, vertex_descriptor b, const std::vector<face_descriptor>& others,
                               std::vector<face_descriptor>& crossed) const {
    const Segment s(mesh_.point(v), mesh_.point(b));
    std::vector<Point> xs;
    for (face_descriptor g : others) {
      if (has_vertex(g, v) || has_vertex(g, b)) continue;
      const Triangle t = triangle(g);
      if (t.is_degenerate() || !CGAL::do_intersect(s, t)) continue;
      if (std::find(crossed.begin(), crossed.end(), g) == crossed.end()) crossed.push_back(g);
      const auto x = CGAL::intersection(s, t);
      if (!x) continue;
      if (const Point* p = boost::get<Point>(&*x)) xs.push_back(*p);
      else if (const Segment* q = boost::get<Segment>(&*x)) {
        xs.push_back(q->source());
        xs.push_back(q->target());
      }
    }
    return xs;
  }

  /// Edge hammering (§4.3, Fig. 6). For each edge ab_n at `a` that crosses
  /// other faces: the paper's candidate, (x+b_n)/2 for one crossing x and
  /// (x1+x2)/2 for the two nearest to a; and the near candidate, the point
  /// the clearance ε beyond the first crossing, towards b_n (or x2) — the
  /// paper allows anywhere between x and b_n, and §5.2 suggests a clearance
  /// for hammering too. With several crossings, also the point ε past the
  /// last one: the paper warns that passing x2 re-creates a crossing (Fig.
  /// 6d), which the criteria catch, but when all the crossed faces are one
  /// thin fold, passing them all frees them all. Ops: a to the average of
  /// the paper's candidates (the paper's move), to the average of the near
  /// ones, and to each candidate alone (an average can mix directions that
  /// cancel out). cheapest_valid keeps the best valid one.
  struct HammerCandidates {
    std::vector<Point> paper, near, through, group;
  };
  HammerCandidates hammer_candidates(vertex_descriptor a) const {
    HammerCandidates out;
    auto& [paper, near, through, group] = out;
    const std::vector<face_descriptor> around = star({a});
    const std::vector<face_descriptor> others = partners_around(around);
    const Point& pa = mesh_.point(a);
    std::vector<face_descriptor> crossed;  // the faces a's edges cross
    for (halfedge_descriptor h : CGAL::halfedges_around_target(mesh_.halfedge(a), mesh_)) {
      const vertex_descriptor b = mesh_.source(h);
      std::vector<Point> xs = crossings(a, b, others, crossed);
      if (xs.empty()) continue;
      std::sort(xs.begin(), xs.end(), [&](const Point& x, const Point& y) { return CGAL::has_smaller_distance_to_point(pa, x, y); });
      xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
      const Point& stop = xs.size() == 1 ? mesh_.point(b) : xs[1];  // the move must not pass it
      paper.push_back(CGAL::midpoint(xs[0], stop));
      const Point3d x = approx_point3d(xs[0]), towards = sub(approx_point3d(stop), x);
      const double room = norm(towards), eps = edge_clearance(norm(sub(p3(b), p3(a))));
      if (room > 0 && eps < 0.5 * room) {
        const double t = eps / room;
        near.push_back(Point(x[0] + t * towards[0], x[1] + t * towards[1], x[2] + t * towards[2]));
      }
      if (xs.size() > 1) {
        const Point3d xl = approx_point3d(xs.back()), to_b = sub(p3(b), xl);
        const double room2 = norm(to_b);
        if (room2 > 0 && eps < 0.5 * room2) {
          const double t = eps / room2;
          near.push_back(Point(xl[0] + t * to_b[0], xl[1] + t * to_b[1], xl[2] + t * to_b[2]));
        }
      }
    }
    // Through each crossed face g: a moved along g's normal to ε past g's
    // plane — face lifting (§4.4) with the roles of node and face swapped,
    // so with the lifting clearance of g. Hammering slides a along its
    // edges; where those run almost parallel to g (a ring vertex poking
    // through a wall) that is a long way round. `group` holds the same
    // moves with the hammer's clearance at a's shortest edge, for group_ops.
    const double shortest = shortest_edge(a);
    for (face_descriptor g : crossed) {
      Point3d n;
      if (!unit_normal(g, n)) continue;
      const Point3d p = p3(a);
      const double h = dot(sub(p, p3(corners(g)[0])), n);
      auto past = [&](double eps) {
        const double step = h + (h >= 0 ? eps : -eps);
        return Point(p[0] - step * n[0], p[1] - step * n[1], p[2] - step * n[2]);
      };
      if (const double eps = clearance(g, n); eps >= 0) through.push_back(past(eps));
      group.push_back(past(edge_clearance(shortest)));
    }
    return out;
  }

  /// The single-vertex hammer ops of `a` from its candidates `c`.
  std::vector<Op> hammer_ops(vertex_descriptor a, const HammerCandidates& c) const {
    const Point& pa = mesh_.point(a);
    std::vector<Op> ops;
    auto move_to = [&](const Point& p) {
      Op op;
      op.kind = OpKind::hammer;
      op.moves = {{a, nearest_double_point(p)}};
      if (op.moves[0].second != pa) ops.push_back(op);
    };
    auto average = [](const std::vector<Point>& ps) {
      Vector sum = CGAL::NULL_VECTOR;
      for (const Point& p : ps) sum = sum + (p - CGAL::ORIGIN);
      return CGAL::ORIGIN + sum / static_cast<int>(ps.size());
    };
    for (const std::vector<Point>* set : {&c.paper, &c.near, &c.through}) {
      if (set->empty()) continue;
      move_to(average(*set));
      if (set->size() > 1)
        for (const Point& p : *set) move_to(p);
    }
    return ops;
  }

  /// The hammering clearance for an edge of length `edge` (§5.2 adapted):
  /// the lifting clearance's rule with the edge in place of the face.
  double edge_clearance(double edge) const {
    switch (o_.clearance_mode) {
      case ClearanceMode::absolute: return o_.clearance;
      case ClearanceMode::tet_aspect: return edge / o_.clearance;
      case ClearanceMode::edge_relative: return o_.clearance * edge;
      case ClearanceMode::local_thickness: break;
    }
    return DeintersectOptions{}.clearance * edge;  // no ray for a point on an edge: the default ratio
  }

  /// The face-lifting clearance ε for face f (§4.4, §5.2); negative: do not lift.
  double clearance(face_descriptor f, const Point3d& n) const {
    const auto c = corners(f);
    double longest = 0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, norm(sub(p3(c[k]), p3(c[(k + 1) % 3]))));
    switch (o_.clearance_mode) {
      case ClearanceMode::absolute: return o_.clearance;
      case ClearanceMode::tet_aspect: return longest / o_.clearance;
      case ClearanceMode::edge_relative: return o_.clearance * longest;
      case ClearanceMode::local_thickness: break;
    }
    // §5.2: a ray from each corner along -n to the next face; the median of
    // the non-zero distances, the one if only one, no lift if none.
    std::vector<double> t;
    for (vertex_descriptor v : c) {
      std::vector<std::size_t> skip;
      for (face_descriptor g : star({v})) skip.push_back(id(g));
      std::sort(skip.begin(), skip.end());
      const double d = rays_->ray_distance(p3(v), {-n[0], -n[1], -n[2]}, skip);
      if (d > 0) t.push_back(d);
    }
    if (t.empty()) return -1.0;
    std::sort(t.begin(), t.end());
    return t.size() == 3 ? t[1] : t.size() == 2 ? 0.5 * (t[0] + t[1]) : t[0];
  }

  /// The length of v's shortest edge.
  double shortest_edge(vertex_descriptor v) const {
    double shortest = std::numeric_limits<double>::infinity();
    for (vertex_descriptor b : CGAL::vertices_around_target(mesh_.halfedge(v), mesh_))
      shortest = std::min(shortest, norm(sub(p3(b), p3(v))));
    return shortest;
  }

  /// The nodes p_i of §4.4: the ends of the edges that cross f (edges of
  /// the faces f intersects, sharing no vertex with f).
  std::vector<vertex_descriptor> nodes_crossing(face_descriptor f) const {
    const Triangle t = triangle(f);
    std::vector<vertex_descriptor> nodes;
    for (face_descriptor g : partners_[id(f)])
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(g), mesh_)) {
        const vertex_descriptor p = mesh_.source(h), q = mesh_.target(h);
        if (has_vertex(f, p) || has_vertex(f, q)) continue;
        if (!CGAL::do_intersect(Segment(mesh_.point(p), mesh_.point(q)), t)) continue;
        for (vertex_descriptor x : {p, q})
          if (std::find(nodes.begin(), nodes.end(), x) == nodes.end()) nodes.push_back(x);
      }
    return nodes;
  }

  /// f's unit normal in doubles (a direction to move along, not a
  /// predicate); false for a face too small to have one.
  bool unit_normal(face_descriptor f, Point3d& n) const {
    n = approx_point3d(CGAL::ORIGIN + normal_vector(f));
    const double len = norm(n);
    if (!(len > 0)) return false;
    for (double& x : n) x /= len;
    return true;
  }

  /// Face lifting (§4.4, Fig. 8): the nodes p_i of the edges crossing f give
  /// signed heights d_i = (p_i - t_1).n; f moves by n(d_max + ε) or by
  /// n(d_min - ε). Both are returned; the cost phase keeps the valid one,
  /// the smaller when both are.
  std::vector<Op> lift_ops(face_descriptor f) const {
    std::vector<Op> ops;
    const auto c = corners(f);
    const std::vector<vertex_descriptor> nodes = nodes_crossing(f);
    if (nodes.empty()) return ops;
    Point3d n;
    if (!unit_normal(f, n)) return ops;
    const double eps = clearance(f, n);
    if (eps < 0) return ops;
    double dmin = 0, dmax = 0;
    const Point3d t1 = p3(c[0]);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const double d = dot(sub(p3(nodes[i]), t1), n);
      dmin = i ? std::min(dmin, d) : d;
      dmax = i ? std::max(dmax, d) : d;
    }
    for (double offset : {dmax + eps, dmin - eps}) {
      Op op;
      op.kind = OpKind::lift;
      for (vertex_descriptor v : c) {
        const Point3d p = p3(v);
        op.moves.push_back({v, Point(p[0] + offset * n[0], p[1] + offset * n[1], p[2] + offset * n[2])});
      }
      ops.push_back(op);
    }
    return ops;
  }

  /// Cost of a move (§4.5, Fig. 9b/c): the volume swept by the faces around
  /// the moved vertices, each a prism from its old to its new corners split
  /// into three tetrahedra; plus the cube of the largest vertex move. The
  /// paper's swept volume alone is zero for a vertex sliding in the plane of
  /// its faces, however far — a plate's corner sliding along the plate, say
  /// — which reshapes the mesh as much as any move; the cube is the volume
  /// scale of the move itself and ranks those (op.shift is set first).
  double move_cost(const Op& op) const {
    std::vector<vertex_descriptor> vs;
    for (const auto& m : op.moves) vs.push_back(m.first);
    double cost = 0;
    for (face_descriptor f : star(vs)) {
      const auto c = corners(f);
      std::array<Point3d, 3> from, to;
      for (int k = 0; k < 3; ++k) {
        from[k] = to[k] = p3(c[k]);
        for (const auto& [v, p] : op.moves)
          if (v == c[k]) to[k] = approx_point3d(p);
      }
      cost += tet_volume(from[0], from[1], from[2], to[0]) + tet_volume(to[0], from[1], from[2], to[1]) +
              tet_volume(to[0], to[1], from[2], to[2]);
    }
    return cost + op.shift * op.shift * op.shift;
  }

  /// The cost phase (§4.5): every applicable operation on the intersecting
  /// faces is tried and retracted; the valid ones come back with their cost.
  std::vector<Op> cost_phase() {
    std::vector<face_descriptor> faces;
    for (face_descriptor f : mesh_.faces())
      if (!partners_[id(f)].empty()) faces.push_back(f);
    if (o_.clearance_mode == ClearanceMode::local_thickness) {
      std::vector<std::array<Point3d, 3>> tris(mesh_.number_of_faces());
      for (face_descriptor f : mesh_.faces()) {
        const auto c = corners(f);
        tris[id(f)] = {p3(c[0]), p3(c[1]), p3(c[2])};
      }
      rays_ = std::make_unique<detail::SurfaceDistance>(tris);
    }
    // Collected first: the trials below edit (and restore) the mesh.
    std::vector<std::pair<vertex_descriptor, vertex_descriptor>> edges;
    std::vector<vertex_descriptor> vertices;
    std::unordered_set<std::size_t> seen_edges, seen_vertices;
    for (face_descriptor f : faces)
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_)) {
        if (seen_edges.insert(static_cast<std::size_t>(mesh_.edge(h))).second && !mesh_.is_border(mesh_.edge(h)))
          edges.emplace_back(mesh_.source(h), mesh_.target(h));
        if (seen_vertices.insert(static_cast<std::size_t>(mesh_.target(h))).second) vertices.push_back(mesh_.target(h));
      }
    std::vector<Op> ops;
    const std::vector<face_descriptor> intersecting = faces;
    Sources sources(*this);
    if (!o_.swap) edges.clear();
    if (!o_.hammer && !o_.group) vertices.clear();
    if (!o_.lift) faces.clear();
    for (const auto& [a, b] : edges) {
      if (spent()) break;
      const auto [lo, hi] = std::minmax(std::uint32_t(a), std::uint32_t(b));
      if (!sources.retry({0, lo, hi}, {a, b})) continue;
      Op op;
      op.kind = OpKind::swap;
      op.a = a;
      op.b = b;
      if (!try_op(op, false)) continue;
      // Fig. 9a: the tetrahedron of the two old and the two new triangles.
      const halfedge_descriptor h = CGAL::halfedge(a, b, mesh_).first;
      op.cost = tet_volume(p3(a), p3(b), p3(mesh_.target(mesh_.next(h))),
                           p3(mesh_.target(mesh_.next(mesh_.opposite(h)))));
      ops.push_back(op);
    }
    std::unordered_map<std::size_t, Point> through;  // per vertex: its least through move within the limit
    for (vertex_descriptor v : vertices) {
      if (spent()) break;
      std::optional<Point> to;
      if (!sources.retry({1, std::uint32_t(v)}, {v})) {
        to = sources.through(v);  // as it was: nothing near v changed
      } else {
        const HammerCandidates c = hammer_candidates(v);
        if (o_.hammer) cheapest_valid(hammer_ops(v, c), ops);
        to = least_move(v, c.group);
        sources.set_through(v, to);
      }
      if (to) through.emplace(std::size_t(v), *to);
    }
    if (o_.group) group_ops(vertices, through, ops, sources);
    for (face_descriptor f : faces) {
      if (spent()) break;
      const auto c = corners(f);
      if (sources.retry({2, std::uint32_t(id(f))}, {c[0], c[1], c[2]})) cheapest_valid(lift_ops(f), ops);
    }
    // The last resorts (see push_ops and pair_ops), only when nothing else
    // applies; sources like the others: skipped when the last cost phase
    // tried them too and nothing has changed near them since (a round that
    // had other operations did not come to them, and keeps no reach).
    if (ops.empty() && o_.group)
      for (face_descriptor f : intersecting) {
        if (spent()) break;
        const std::vector<vertex_descriptor> nodes = nodes_crossing(f);
        std::vector<vertex_descriptor> vs = nodes;
        for (vertex_descriptor v : corners(f)) vs.push_back(v);
        if (sources.retry({4, std::uint32_t(id(f))}, vs)) cheapest_valid(push_ops(f, nodes), ops);
      }
    if (ops.empty() && o_.pair) pair_ops(intersecting, ops, sources);
    sources.done();
    return ops;
  }

  /// Which sources of operations a cost phase tries. A source (an edge's
  /// swap, a vertex's hammer moves, a face's lifts, a group move's
  /// vertices, a face's pushes, a crossing pair's pair moves) tried in the last cost phase reads and edits only its reach:
  /// the faces two rings round its vertices (the edited stars, the faces
  /// across their edges that the fold tests read; the faces they intersect
  /// overlap them) and the boxes its trials' edited faces took (where the
  /// oracle looks, whose partner lists gain() reads). If no operation
  /// applied since has touched that reach — no face in it edited, no face
  /// meeting it with a changed partner list (dirty_) — it would try exactly
  /// what it tried then on exactly the same surface, and it had no valid
  /// operation then: one would have been applied (still valid, nothing near
  /// having changed), touching it. So it has none now and is skipped,
  /// keeping its reach (and a vertex its through move). Trials restore the
  /// surface exactly (try_swap), so skipping one changes no other. Not with
  /// local-thickness clearances: the rays see the whole surface.
  class Sources {
   public:
    explicit Sources(Deintersector& d) : d_(d), last_(std::move(d.reach_)), last_through_(std::move(d.through_)) {
      d.reach_.clear();
      d.through_.clear();
      if (d.o_.clearance_mode == ClearanceMode::local_thickness || !d.o_.skip_unchanged) last_.clear();
      if (last_.empty() || d.dirty_.empty()) return;
      using Box =
          CGAL::Box_intersection_d::Box_with_info_d<double, 3, const SourceKey*, CGAL::Box_intersection_d::ID_EXPLICIT>;
      std::vector<Box> reaches, dirty;
      for (const auto& [key, box] : last_) reaches.emplace_back(box, &key);
      for (const CGAL::Bbox_3& b : d.dirty_) dirty.emplace_back(b, nullptr);
      CGAL::box_intersection_d(reaches.begin(), reaches.end(), dirty.begin(), dirty.end(),
                               [&](const Box& r, const Box&) { touched_.insert(r.info()); });
    }
    /// Does the source `key` with vertices `vs` need its trials? If so, the
    /// trials until the next call grow its reach.
    bool retry(const SourceKey& key, std::initializer_list<vertex_descriptor> vs) {
      return retry(key, std::vector<vertex_descriptor>(vs));
    }
    bool retry(const SourceKey& key, const std::vector<vertex_descriptor>& vs) {
      const auto it = last_.find(key);
      if (it != last_.end() && !touched_.count(&it->first)) {
        d_.reach_.emplace(key, it->second);
        d_.tracing_ = nullptr;
        ++d_.r_.sources_skipped;
        return false;
      }
      CGAL::Bbox_3& reach = d_.reach_[key];
      for (vertex_descriptor v : vs)
        for (vertex_descriptor w : CGAL::vertices_around_target(d_.mesh_.halfedge(v), d_.mesh_))
          for (vertex_descriptor x : CGAL::vertices_around_target(d_.mesh_.halfedge(w), d_.mesh_))
            reach += d_.mesh_.point(x).bbox();
      d_.tracing_ = &reach;
      return true;
    }
    std::optional<Point> through(vertex_descriptor v) const {
      const auto it = last_through_.find(std::size_t(v));
      d_.through_[std::size_t(v)] = it->second;
      return it->second;
    }
    void set_through(vertex_descriptor v, const std::optional<Point>& p) { d_.through_[std::size_t(v)] = p; }
    /// The trials after this are no source's; what is applied from here on is new.
    void done() {
      d_.tracing_ = nullptr;
      d_.dirty_.clear();
    }

   private:
    Deintersector& d_;
    std::map<SourceKey, CGAL::Bbox_3> last_;
    std::unordered_map<std::size_t, std::optional<Point>> last_through_;
    std::set<const SourceKey*> touched_;
  };

  /// Of the positions `to` for v (exact constructions), the rounded one
  /// nearest v within the displacement limit; none for a pinned vertex.
  std::optional<Point> least_move(vertex_descriptor v, const std::vector<Point>& to) const {
    if (pinned_ && (*pinned_)[v]) return std::nullopt;
    std::optional<Point> best;
    double best_shift = 0;
    for (const Point& p : to) {
      const Point q = nearest_double_point(p);
      const double shift = norm(sub(approx_point3d(q), p3(v)));
      if (norm(sub(approx_point3d(q), original_[v])) > r_.max_displacement_allowed || q == mesh_.point(v)) continue;
      if (!best || shift < best_shift) best = q, best_shift = shift;
    }
    return best;
  }

  /// Group moves (ours; the paper moves one node or one face at a time).
  /// Where a whole sheet pokes through another — the inner ring of a tube
  /// whose walls cross — every vertex must move back before any face is
  /// freed: moving one leaves its faces crossing through its neighbours, so
  /// no single move meets §4.1 and the sheet stays. Each connected set (by
  /// mesh edges) of vertices that have a through move within the limit
  /// (`through`, see hammer_candidates) is moved at once, each vertex to its
  /// own through position (`HammerCandidates::group`), as one operation
  /// under the same criteria.
  void group_ops(const std::vector<vertex_descriptor>& vertices,
                 const std::unordered_map<std::size_t, Point>& through, std::vector<Op>& ops, Sources& sources) {
    std::unordered_set<std::size_t> done;
    for (vertex_descriptor seed : vertices) {
      if (spent()) break;
      if (!through.count(std::size_t(seed)) || !done.insert(std::size_t(seed)).second) continue;
      Op op;
      op.kind = OpKind::group;
      std::vector<vertex_descriptor> todo{seed};
      while (!todo.empty()) {
        const vertex_descriptor v = todo.back();
        todo.pop_back();
        const Point& to = through.at(std::size_t(v));
        op.moves.push_back({v, to});
        op.shift = std::max(op.shift, norm(sub(approx_point3d(to), p3(v))));
        for (vertex_descriptor w : CGAL::vertices_around_target(mesh_.halfedge(v), mesh_))
          if (through.count(std::size_t(w)) && done.insert(std::size_t(w)).second) todo.push_back(w);
      }
      if (op.moves.size() < 2) continue;  // a single vertex: one of its hammer ops
      std::vector<vertex_descriptor> members;
      for (const auto& m : op.moves) members.push_back(m.first);
      SourceKey key{3};
      for (vertex_descriptor v : members) key.push_back(std::uint32_t(v));
      std::sort(key.begin() + 1, key.end());
      if (!sources.retry(key, members)) continue;
      op.cost = move_cost(op);
      if (try_op(op, false) > 0) ops.push_back(op);
    }
  }

  /// Pushes (ours; a group move, tried only when no other operation
  /// applies): face lifting reversed. Where f is large and the faces
  /// crossing it are a fan of small ones lying almost in its plane (CAD:
  /// two nearly coplanar patches overlapping at a shallow angle), lifting f
  /// past all the nodes moves f far and into its other neighbours, and no
  /// node alone clears f. Instead the nodes on one side of f's plane all
  /// move along f's normal to ε on the other side, ε the hammer's rule at
  /// the shortest edge among them (one ε for the group, so a face whose
  /// corners all move keeps its shape); both sides are candidates.
  /// `nodes`: nodes_crossing(f).
  std::vector<Op> push_ops(face_descriptor f, const std::vector<vertex_descriptor>& nodes) const {
    std::vector<Op> ops;
    Point3d n;
    if (nodes.size() < 2 || !unit_normal(f, n)) return ops;
    const Point3d t1 = p3(corners(f)[0]);
    for (const double side : {1.0, -1.0}) {
      std::vector<vertex_descriptor> moving;
      double shortest = std::numeric_limits<double>::infinity();
      for (vertex_descriptor x : nodes) {
        if (side * dot(sub(p3(x), t1), n) <= 0) continue;
        moving.push_back(x);
        shortest = std::min(shortest, shortest_edge(x));
      }
      if (moving.size() < 2) continue;  // one node: a hammer's through move
      Op op;
      op.kind = OpKind::group;
      for (vertex_descriptor x : moving) {
        const Point3d p = p3(x);
        const double step = dot(sub(p, t1), n) + side * edge_clearance(shortest);
        const auto to = least_move(x, {Point(p[0] - step * n[0], p[1] - step * n[1], p[2] - step * n[2])});
        if (!to) break;
        op.moves.push_back({x, *to});
      }
      if (op.moves.size() == moving.size()) ops.push_back(op);
    }
    return ops;
  }

  /// The centroid of v's neighbours (one step of umbrella smoothing).
  Point umbrella(vertex_descriptor v) const {
    Vector sum = CGAL::NULL_VECTOR;
    int k = 0;
    for (vertex_descriptor b : CGAL::vertices_around_target(mesh_.halfedge(v), mesh_)) {
      sum = sum + (mesh_.point(b) - CGAL::ORIGIN);
      ++k;
    }
    return CGAL::ORIGIN + sum / k;
  }

  /// Pair moves (ours; only when no other operation applies). Two crossing
  /// faces f and g can each be a bump raised off a flat fan — a vertex
  /// inside the triangle of its neighbours, lifted — on two nearly
  /// coincident sheets (CAD and scan meshes with a thin fin): then
  /// flattening either bump alone leaves the other crossing, and moving one
  /// vertex gains nothing, but flattening both frees both. For each corner u
  /// of f and w of g (not shared), u and w move together to the centroids
  /// of their neighbours; among one pair's candidates the smallest valid
  /// move is kept (cheapest_valid), under the same criteria as any move.
  /// A skipped pair still claims its corner pairs in `tried`: the pairs
  /// after it get the candidates they got when it was tried.
  void pair_ops(const std::vector<face_descriptor>& faces, std::vector<Op>& ops, Sources& sources) {
    std::set<std::pair<std::size_t, std::size_t>> tried;
    for (face_descriptor f : faces) {
      if (spent()) break;
      for (face_descriptor g : partners_[id(f)]) {
        if (id(g) < id(f)) continue;  // each pair once
        const auto cf = corners(f), cg = corners(g);
        const bool retry = sources.retry({5, std::uint32_t(id(f)), std::uint32_t(id(g))},
                                         {cf[0], cf[1], cf[2], cg[0], cg[1], cg[2]});
        std::vector<Op> candidates;
        for (vertex_descriptor u : cf)
          for (vertex_descriptor w : cg) {
            if (has_vertex(g, u) || has_vertex(f, w)) continue;
            const std::size_t a = std::size_t(u), b = std::size_t(w);
            if (!tried.insert({std::min(a, b), std::max(a, b)}).second || !retry) continue;
            const auto to_u = least_move(u, {umbrella(u)}), to_w = least_move(w, {umbrella(w)});
            if (!to_u || !to_w) continue;
            Op op;
            op.kind = OpKind::pair;
            op.moves = {{u, *to_u}, {w, *to_w}};
            candidates.push_back(op);
          }
        cheapest_valid(std::move(candidates), ops);
      }
    }
  }

  /// Among the valid candidates of one vertex or face, the one that moves
  /// the mesh least (our choice: minimal repair; the paper takes the
  /// average or the smaller lift), then the least swept volume.
  static bool better(const Op& x, const Op& y) { return x.shift != y.shift ? x.shift < y.shift : x.cost < y.cost; }

  /// Tries each of `candidates` (moves of one vertex or one face) that keep
  /// every vertex within the displacement limit of its input position and
  /// move no pinch-point copy, and
  /// appends the best valid one (better()) to `ops`.
  void cheapest_valid(std::vector<Op> candidates, std::vector<Op>& ops) {
    std::optional<Op> best;
    for (Op& op : candidates) {
      bool within = true;
      for (const auto& [v, p] : op.moves) {
        const Point3d to = approx_point3d(p);
        op.shift = std::max(op.shift, norm(sub(to, p3(v))));
        within = within && norm(sub(to, original_[v])) <= r_.max_displacement_allowed && !(pinned_ && (*pinned_)[v]);
      }
      if (!within) continue;
      op.cost = move_cost(op);
      if ((!best || better(op, *best)) && try_op(op, false) > 0) best = op;
    }
    if (best) ops.push_back(*best);
  }
};

}  // namespace

const char* to_string(ClearanceMode mode) {
  switch (mode) {
    case ClearanceMode::edge_relative: return "edge-relative";
    case ClearanceMode::absolute: return "absolute";
    case ClearanceMode::local_thickness: return "local";
    case ClearanceMode::tet_aspect: return "tet-aspect";
  }
  return "?";
}

DeintersectResult remove_self_intersections(const Soup& input, const DeintersectOptions& o) {
  DeintersectResult result;
  DeintersectReport& r = result.report;
  r.clearance_mode = o.clearance_mode;
  r.clearance = o.clearance;
  auto t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("detecting");
  if (!input.is_triangle_soup()) throw UnsupportedInput("not a triangle mesh (polygons with more than 3 corners)");
  Mesh mesh;
  // Pinch points (vertices whose faces form several fans, common in CAD STL
  // exports) get one copy per fan, pinned in place; the copies weld again on
  // output, and the oracle treats them as the one vertex they are.
  std::size_t pinches = 0;
  const MeshBuildResult built = soup_to_mesh_splitting_pinches(input, mesh, &pinches);
  if (!built.ok)
    throw NotManifold(built.problems, "deintersect needs a manifold mesh (pinch vertices are fine)");
  mark_split_pinches(mesh);
  if (o.fixed_points) {
    // with no point welded, vertex i is point i (pinch copies, pinned, come after)
    if (o.fixed_points->size() != input.points.size() || built.welded > 0)
      throw UnsupportedInput("fixed points need the soup's points distinct (none welded)");
    auto pinned = mesh.add_property_map<vertex_descriptor, char>(kVertexPinned, 0).first;
    for (vertex_descriptor v : mesh.vertices())
      if (static_cast<std::size_t>(v) < input.points.size() && (*o.fixed_points)[static_cast<std::size_t>(v)])
        pinned[v] = 1;
  }
  InspectOptions io;
  io.self_intersections = o.known_pairs;
  const Report in = inspect(input, io);
  r.faces = in.faces;
  r.vertices = mesh.number_of_vertices();
  r.degenerate_faces_in = in.degenerate_faces.size();
  r.topology_in = topology_of(in);
  r.bbox_diagonal = bbox_diagonal(in);
  auto original = mesh.add_property_map<vertex_descriptor, Point3d>("v:polyheal_original").first;
  for (vertex_descriptor v : mesh.vertices()) original[v] = approx_point3d(mesh.point(v));

  r.max_displacement_allowed =
      o.max_displacement >= 0 ? o.max_displacement : o.max_displacement_ratio * r.bbox_diagonal;
  Deintersector repair(mesh, original, in.self_intersections, o, r);
  r.intersecting_faces_in = repair.intersecting_faces();
  r.intersecting_pairs_in = repair.intersecting_pairs();
  r.seconds_detect = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("repairing");
  repair.run();
  r.intersecting_faces_exact = repair.intersecting_faces();
  for (vertex_descriptor v : mesh.vertices()) {
    const Point3d p = approx_point3d(mesh.point(v));
    const double d = norm(sub(p, original[v]));
    if (d == 0) continue;
    ++r.moved_vertices;
    r.max_displacement = std::max(r.max_displacement, d);
    r.mean_displacement += d;
  }
  if (r.moved_vertices) r.mean_displacement /= double(r.moved_vertices);
  r.seconds_repair = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("certifying");
  result.soup = mesh_to_soup(mesh);
  if (o.certify) certify(input, result.soup, r);
  r.seconds_certify = seconds_since(t0);
  return result;
}

void certify(const Soup& input, const Soup& written, DeintersectReport& r) {
  const Report out = inspect(written);
  r.intersecting_pairs_out = out.self_intersections.size();
  r.unfreed_faces.clear();
  for (const FacePair& p : out.self_intersections) {
    r.unfreed_faces.push_back(p.first);
    r.unfreed_faces.push_back(p.second);
  }
  std::sort(r.unfreed_faces.begin(), r.unfreed_faces.end());
  r.unfreed_faces.erase(std::unique(r.unfreed_faces.begin(), r.unfreed_faces.end()), r.unfreed_faces.end());
  r.intersecting_faces_out = r.unfreed_faces.size();
  r.degenerate_faces_out = out.degenerate_faces.size();
  r.topology_out = topology_of(out);
  r.faces_changed = 0;
  if (written.face_count() == input.face_count())
    for (std::size_t f = 0; f < written.face_count(); ++f) {
      const FaceView a = input.face(f), b = written.face(f);
      bool same = a.size() == b.size();
      for (std::size_t k = 0; same && k < a.size(); ++k) same = input.points[a[k]] == written.points[b[k]];
      r.faces_changed += same ? 0 : 1;
    }
  // Measured to within a tenth of the largest displacement, and never finer
  // than 1e-4 of the bbox diagonal (swaps move no vertex but do move the
  // surface; the cost of the measure grows as the bound shrinks). Zero when
  // no face changed.
  const double bound = std::max(0.1 * r.max_displacement, 1e-4 * r.bbox_diagonal);
  r.hausdorff = r.faces_changed ? detail::hausdorff_distance(input, written, bound) : 0.0;
  r.hausdorff_error_bound = r.faces_changed ? bound : 0.0;
  r.certified = r.intersecting_pairs_out == 0 && r.degenerate_faces_out <= r.degenerate_faces_in &&
                r.topology_out == r.topology_in;
}

}  // namespace polyheal
