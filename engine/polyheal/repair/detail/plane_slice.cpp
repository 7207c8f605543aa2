#include "polyheal/repair/detail/plane_slice.h"

#include <CGAL/boost/graph/Euler_operations.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "polyheal/inspect/exact_predicates.h"
#include "polyheal/repair/detail/exact_meet.h"

namespace polyheal::detail {
namespace {

/// A piece cut from `parent` takes its provenance and on-input flag.
void inherit(const std::optional<FaceOriginMap>& origin, FaceFlagMap& on_input, face_descriptor child,
             face_descriptor parent) {
  if (origin) (*origin)[child] = (*origin)[parent];
  on_input[child] = on_input[parent];
}

class Slicer {
 public:
  Slicer(Mesh& mesh, const Kernel::Plane_3& plane, const SliceOptions& o)
      : mesh_(mesh), plane_(plane), o_(o), origin_(face_origin_map(mesh)), on_input_(face_on_input_map(mesh)) {}

  SliceResult run() {
    classify_vertices();
    apply_safeguard();
    const std::vector<face_descriptor> faces = faces_to_cut();
    if (cuts_frozen(faces) || (o_.verify && !plan_is_safe(faces))) {
      result_.rejected = true;
      return std::move(result_);
    }
    split_crossed_edges(faces);
    for (face_descriptor f : faces) cut_face(f);
    return std::move(result_);
  }

 private:
  /// -1 / 0 / +1, classified on first use (a local slice looks only at the
  /// vertices its search reaches: classifying every vertex of a 500k-face
  /// mesh for each of 2450 cap slices took 67 s).
  int side(vertex_descriptor v) const {
    signed char& s = side_[static_cast<std::size_t>(v)];
    if (s == kUnknown) s = classify(v);
    return s;
  }
  bool crossing(halfedge_descriptor h) const { return side(mesh_.source(h)) * side(mesh_.target(h)) < 0; }
  bool is_cut(face_descriptor f) const {
    bool above = false, below = false;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh_.halfedge(f), mesh_)) {
      above |= side(v) > 0;
      below |= side(v) < 0;
    }
    return above && below;
  }
  // §4, first pass: above / below / on, exactly; epsilon snapping. Global
  // slices classify every vertex here; local ones as their search goes.
  void classify_vertices() {
    side_.assign(mesh_.num_vertices(), kUnknown);
    protected_.assign(mesh_.num_vertices(), 0);
    for (vertex_descriptor v : o_.protected_vertices) protected_[static_cast<std::size_t>(v)] = 1;
    eps2_ = Kernel::FT(o_.snap_distance) * Kernel::FT(o_.snap_distance);
    if (o_.seed == Mesh::null_face())
      for (vertex_descriptor v : mesh_.vertices()) side(v);
  }

  signed char classify(vertex_descriptor v) const {
    const Point& p = mesh_.point(v);
    const int s = static_cast<int>(plane_.oriented_side(p));
    if (s != 0 && o_.snap_distance > 0 && !protected_[static_cast<std::size_t>(v)] &&
        CGAL::squared_distance(p, plane_) <= eps2_) {
      ++result_.vertices_snapped;
      return 0;
    }
    return static_cast<signed char>(s);
  }

  // §4 safeguard: a crossing edge nearly parallel to the plane gets one
  // endpoint (the nearer, never a protected one) snapped onto the plane.
  // Snapping only removes crossings, so one pass over the edges suffices:
  // every edge for a global slice, before the search; each edge the search
  // meets for a local one, as it meets it (guard()).
  void apply_safeguard() {
    sin_bound_ = sin_degrees(180.0 - o_.cap_angle);
    normal_ = plane_.orthogonal_vector();
    if (o_.seed != Mesh::null_face()) return;
    for (auto e : mesh_.edges()) guard(mesh_.halfedge(e));
  }

  /// The safeguard on every edge at f's corners, once per corner: what the
  /// global pass would decide there (a corner's classification depends on
  /// all its edges, not only f's).
  void guard_corners(face_descriptor f) {
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh_.halfedge(f), mesh_))
      if (guarded_.insert(v).second)
        for (halfedge_descriptor h : CGAL::halfedges_around_target(mesh_.halfedge(v), mesh_)) guard(h);
  }

  void guard(halfedge_descriptor h) {
    if (!crossing(h)) return;
    const vertex_descriptor u = mesh_.source(h), v = mesh_.target(h);
    if (angle_to_plane_less(mesh_.point(v) - mesh_.point(u), normal_, sin_bound_)) snap_one_end(u, v);
  }

  /// Classifies one endpoint of edge uv as on the plane: the nearer one,
  /// never a protected one. Both protected: nothing (the plan verifies).
  void snap_one_end(vertex_descriptor u, vertex_descriptor v) {
    const bool pu = protected_[static_cast<std::size_t>(u)], pv = protected_[static_cast<std::size_t>(v)];
    if (pu && pv) return;
    const vertex_descriptor w =
        pu ? v
        : pv ? u
             : CGAL::compare(CGAL::squared_distance(mesh_.point(u), plane_),
                             CGAL::squared_distance(mesh_.point(v), plane_)) != CGAL::LARGER ? u : v;
    side_[static_cast<std::size_t>(w)] = 0;
    ++result_.vertices_snapped;
  }

  // Global: every cut face. Local: the connected cut curve through the seed,
  // followed across crossed edges and around on-plane vertices.
  std::vector<face_descriptor> faces_to_cut() {
    std::vector<face_descriptor> out;
    if (o_.seed == Mesh::null_face()) {
      for (face_descriptor f : mesh_.faces())
        if (is_cut(f)) out.push_back(f);
      return out;
    }
    guard_corners(o_.seed);
    if (!is_cut(o_.seed)) return out;
    std::vector<char> seen(mesh_.num_faces(), 0);
    std::deque<face_descriptor> queue{o_.seed};
    seen[static_cast<std::size_t>(o_.seed)] = 1;
    auto visit = [&](face_descriptor g) {
      if (g != Mesh::null_face() && !seen[static_cast<std::size_t>(g)] && is_cut(g)) {
        seen[static_cast<std::size_t>(g)] = 1;
        queue.push_back(g);
      }
    };
    // Beyond the radius the cut ends at the next vertex. Snapping only
    // removes crossings, so every edge still crossed at the end was crossed
    // when the search passed it, and both its faces are in the set.
    std::vector<Point3d> centre;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh_.halfedge(o_.seed), mesh_))
      centre.push_back(approx_point3d(mesh_.point(v)));
    auto far = [&](vertex_descriptor v) {
      if (o_.radius <= 0) return false;
      const Point3d p = approx_point3d(mesh_.point(v));
      for (const Point3d& c : centre) {
        const double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
        if (dx * dx + dy * dy + dz * dz <= o_.radius * o_.radius) return false;
      }
      return true;
    };
    while (!queue.empty()) {
      const face_descriptor f = queue.front();
      queue.pop_front();
      out.push_back(f);
      guard_corners(f);
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_)) {
        if (crossing(h) && far(mesh_.source(h)) && far(mesh_.target(h))) snap_one_end(mesh_.source(h), mesh_.target(h));
        if (crossing(h)) visit(mesh_.face(mesh_.opposite(h)));
        if (side(mesh_.target(h)) == 0 && !far(mesh_.target(h)))
          for (face_descriptor g : CGAL::faces_around_target(h, mesh_)) visit(g);
      }
    }
    // Faces the search took in that snapping has since left uncut are
    // skipped by the plan and by cut_face (they have no two cut corners).
    return out;
  }

  bool cuts_frozen(const std::vector<face_descriptor>& faces) const {
    if (!o_.frozen || !origin_) return false;
    for (face_descriptor f : faces) {
      const std::int64_t i = (*origin_)[f];
      if (i >= 0 && static_cast<std::size_t>(i) < o_.frozen->size() && (*o_.frozen)[static_cast<std::size_t>(i)] &&
          is_cut(f))
        return true;
    }
    return false;
  }

  // The pieces cut_face() will make, computed without touching the mesh, each
  // classified exactly: a slice whose snapped vertices lie off the plane can
  // make a cap (or a zero-area piece) after all, and is then refused whole.
  bool plan_is_safe(const std::vector<face_descriptor>& faces) const {
    const double cos_cap = cos_degrees(o_.cap_angle);
    std::vector<Point> poly;
    std::vector<char> on;
    for (face_descriptor f : faces) {
      poly.clear();
      on.clear();
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_)) {
        if (crossing(h)) {
          poly.push_back(split_point(h));
          on.push_back(1);
        }
        poly.push_back(mesh_.point(mesh_.target(h)));
        on.push_back(side(mesh_.target(h)) == 0);
      }
      std::vector<std::size_t> cut;
      for (std::size_t k = 0; k < poly.size(); ++k)
        if (on[k]) cut.push_back(k);
      const std::size_t n = poly.size();
      // A piece of a cap may stay a cap (the face was one already; another
      // slice removes it); a cap piece of a face that was not a cap is new.
      const int parent_caps = classify_face(mesh_, f, cos_cap, 1.0) == Shape::cap ? 1 : 0;
      int caps = 0;
      if (cut.size() != 2 || (cut[0] + 1) % n == cut[1] || (cut[1] + 1) % n == cut[0]) continue;
      for (auto [from, to] : {std::pair{cut[0], cut[1]}, std::pair{cut[1], cut[0]}}) {
        std::vector<Point> piece;
        for (std::size_t k = from;; k = (k + 1) % n) {
          piece.push_back(poly[k]);
          if (k == to) break;
        }
        for (const auto& t : triangulation(piece)) {
          const Shape s = classify_triangle(t[0], t[1], t[2], cos_cap, 1.0);
          if (s == Shape::degenerate) return false;
          if (s == Shape::cap && ++caps > parent_caps) return false;
        }
      }
    }
    return true;
  }

  /// A piece (triangle or quad) as triangles, the quad split by the diagonal
  /// through its largest angle — the rule triangulate_quad() applies.
  static std::vector<std::array<Point, 3>> triangulation(const std::vector<Point>& piece) {
    if (piece.size() == 3) return {{piece[0], piece[1], piece[2]}};
    const std::size_t k = largest_angle_corner(piece);
    return {{piece[k], piece[(k + 1) % 4], piece[(k + 2) % 4]}, {piece[(k + 2) % 4], piece[(k + 3) % 4], piece[k]}};
  }

  /// Where crossed edge h meets the plane, exactly: with hp, hq the (scaled)
  /// heights of its ends P = Pn / Pd and Q = Qn / Qd,
  /// (hp Qn - hq Pn) / (hp Qd - hq Pd), on integers (Mpzf, exact_meet.h),
  /// then one division per coordinate: a point known exactly, not a lazy
  /// tree of rationals that the plan's exact tests and the rounding would
  /// each evaluate (ADIS16480: a fifth of the run). Computed once per edge:
  /// the plan and the cut ask for the same points.
  Point split_point(halfedge_descriptor h) const {
    const auto key = static_cast<std::uint32_t>(mesh_.edge(h));
    if (const auto it = split_points_.find(key); it != split_points_.end()) return it->second;
    if (!plane_z_) {
      plane_z_.emplace();
      integer_plane(plane_, plane_z_->first, plane_z_->second);
    }
    const auto& [n, d] = *plane_z_;
    const Homogeneous p = homogeneous(mesh_.point(mesh_.source(h))), q = homogeneous(mesh_.point(mesh_.target(h)));
    const Z hp = n * p.num + d * p.den, hq = n * q.num + d * q.den;
    const Point x = leaf_point<Point>({hp * q.num - hq * p.num, hp * q.den - hq * p.den});
    split_points_.emplace(key, x);
    return x;
  }

  // §4, second pass: split each crossed edge at its exact intersection point.
  void split_crossed_edges(const std::vector<face_descriptor>& faces) {
    std::vector<Mesh::Edge_index> crossed;  // an edge between two cut faces is seen twice
    for (face_descriptor f : faces)
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_))
        if (crossing(h)) crossed.push_back(mesh_.edge(h));
    std::sort(crossed.begin(), crossed.end());
    crossed.erase(std::unique(crossed.begin(), crossed.end()), crossed.end());
    for (Mesh::Edge_index e : crossed) {
      const halfedge_descriptor h = mesh_.halfedge(e);
      const Point x = split_point(h);
      const halfedge_descriptor hn = CGAL::Euler::split_edge(h, mesh_);
      const vertex_descriptor vx = mesh_.target(hn);
      mesh_.point(vx) = x;
      if (static_cast<std::size_t>(vx) >= side_.size()) {
        side_.resize(static_cast<std::size_t>(vx) + 1, kUnknown);
        protected_.resize(static_cast<std::size_t>(vx) + 1, 0);
      }
      side_[static_cast<std::size_t>(vx)] = 0;
      result_.vertices.push_back(vx);
      ++result_.edges_split;
    }
  }

  // Splits a cut face (now a 4- or 5-gon) between its two on-plane corners,
  // then each quad by the diagonal through its largest angle.
  void cut_face(face_descriptor f) {
    std::vector<halfedge_descriptor> on;
    for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_))
      if (side(mesh_.target(h)) == 0) on.push_back(h);
    if (on.size() != 2 || mesh_.next(on[0]) == on[1] || mesh_.next(on[1]) == on[0]) return;  // not a cut triangle
    const halfedge_descriptor h = CGAL::Euler::split_face(on[0], on[1], mesh_);
    ++result_.faces_cut;
    const face_descriptor g = mesh_.face(mesh_.opposite(h));
    inherit(origin_, on_input_, g, f);
    for (face_descriptor piece : {f, g}) triangulate_quad(piece, f);
  }

  void triangulate_quad(face_descriptor piece, face_descriptor parent) {
    std::vector<halfedge_descriptor> hs;
    std::vector<Point> corners;
    for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(piece), mesh_)) {
      hs.push_back(h);
      corners.push_back(mesh_.point(mesh_.target(h)));
    }
    if (hs.size() == 4) {
      const std::size_t k = largest_angle_corner(corners);
      const halfedge_descriptor d = CGAL::Euler::split_face(hs[k], hs[(k + 2) % 4], mesh_);
      const face_descriptor other = mesh_.face(mesh_.opposite(d));
      inherit(origin_, on_input_, other, parent);
      result_.faces.push_back(other);
      result_.parents.push_back(parent);
    }
    result_.faces.push_back(piece);
    result_.parents.push_back(parent);
  }

  Mesh& mesh_;
  const Kernel::Plane_3& plane_;
  const SliceOptions& o_;
  std::optional<FaceOriginMap> origin_;
  FaceFlagMap on_input_;
  static constexpr signed char kUnknown = 2;  // side_: not classified yet
  mutable std::vector<signed char> side_;
  std::vector<char> protected_;
  Kernel::FT eps2_;        // snap distance, squared
  double sin_bound_ = 0;    // the safeguard's angle bound
  Kernel::Vector_3 normal_;  // the plane's normal
  mutable SliceResult result_;  // classify() counts the vertices it snaps
  std::unordered_set<vertex_descriptor> guarded_;  // local slices: corners whose edges are guarded
  mutable std::optional<std::pair<Z3, Z>> plane_z_;   // the plane as integers, for split_point()
  mutable std::unordered_map<std::uint32_t, Point> split_points_;  // by edge
};

}  // namespace

SliceResult slice_by_plane(Mesh& mesh, const Kernel::Plane_3& plane, const SliceOptions& options) {
  return Slicer(mesh, plane, options).run();
}

SliceResult split_edges(Mesh& mesh, const std::vector<EdgeSplit>& splits) {
  SliceResult result;
  const std::optional<FaceOriginMap> origin = face_origin_map(mesh);
  FaceFlagMap on_input = face_on_input_map(mesh);
  for (const EdgeSplit& split : splits) {
    if (split.points.empty()) continue;
    // the faces beside the edge, each with its corner opposite it
    std::vector<std::pair<face_descriptor, vertex_descriptor>> beside;
    for (halfedge_descriptor h : {split.edge, mesh.opposite(split.edge)})
      if (!mesh.is_border(h)) beside.emplace_back(mesh.face(h), mesh.target(mesh.next(h)));
    halfedge_descriptor rest = split.edge;  // from the last split point on to the edge's target
    std::vector<vertex_descriptor> points;
    for (const Point& x : split.points) {
      const halfedge_descriptor hn = CGAL::Euler::split_edge(rest, mesh);  // next(hn) == rest
      const vertex_descriptor vx = mesh.target(hn);
      mesh.point(vx) = x;
      points.push_back(vx);
      result.vertices.push_back(vx);
      ++result.edges_split;
    }
    for (const auto& [f, apex] : beside) {
      ++result.faces_cut;
      std::vector<face_descriptor> pieces{f};
      for (vertex_descriptor vx : points)
        for (face_descriptor g : pieces) {  // the piece that still has vx beside its edge
          halfedge_descriptor to_apex, to_point;
          std::size_t corners = 0;
          for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh.halfedge(g), mesh)) {
            ++corners;
            if (mesh.target(h) == apex) to_apex = h;
            if (mesh.target(h) == vx) to_point = h;
          }
          if (corners == 3 || to_apex == halfedge_descriptor() || to_point == halfedge_descriptor()) continue;
          const face_descriptor piece = mesh.face(mesh.opposite(CGAL::Euler::split_face(to_apex, to_point, mesh)));
          inherit(origin, on_input, piece, f);
          pieces.push_back(piece);
          break;
        }
      for (face_descriptor g : pieces) {
        result.faces.push_back(g);
        result.parents.push_back(f);
      }
    }
  }
  return result;
}

Kernel::Plane_3 cap_plane(const Mesh& mesh, face_descriptor cap, SliceOptions& options) {
  std::vector<vertex_descriptor> v;
  std::vector<Point> p;
  for (vertex_descriptor w : CGAL::vertices_around_face(mesh.halfedge(cap), mesh)) {
    v.push_back(w);
    p.push_back(mesh.point(w));
  }
  const std::size_t a = largest_angle_corner(p), b = (a + 1) % 3, c = (a + 2) % 3;
  options.protected_vertices.push_back(v[b]);
  options.protected_vertices.push_back(v[c]);
  return Kernel::Plane_3(p[a], p[c] - p[b]);
}

}  // namespace polyheal::detail
