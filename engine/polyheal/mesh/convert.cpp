#include "polyheal/mesh/convert.h"

#include <map>

#include <algorithm>

#include <cstring>
#include <gmpxx.h>
#include <mpfr.h>
#include <type_traits>
#include <unordered_map>

#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/union_find.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

std::string faces_of(const Edge& e) {
  std::string s;
  for (const EdgeUse& u : e.uses) s += (s.empty() ? "" : ", ") + std::to_string(u.face);
  return s;
}
std::string edge_name(const Edge& e) { return "edge (" + std::to_string(e.a) + ", " + std::to_string(e.b) + ")"; }

}  // namespace

namespace {

/// Gives each fan of each listed vertex but the first its own copy.
Soup split_fans(const Soup& soup, const std::vector<Index>& pinched, std::size_t& added) {
  Soup out = soup;
  std::vector<char> is_pinched(soup.points.size(), 0);
  for (Index v : pinched) is_pinched[v] = 1;
  // corners (face, position) at pinched vertices, joined when their faces
  // share an edge at the vertex
  struct Corner {
    std::size_t face, k;
  };
  std::vector<std::vector<Corner>> corners(soup.points.size());
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const FaceView face = soup.face(f);
    for (std::size_t k = 0; k < face.size(); ++k)
      if (is_pinched[face[k]]) corners[face[k]].push_back({f, k});
  }
  added = 0;
  for (Index v : pinched) {
    const std::vector<Corner>& cs = corners[v];
    UnionFind fans(cs.size());
    std::vector<std::pair<Index, std::size_t>> by_neighbour;  // (vertex next to v, corner)
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const FaceView face = soup.face(cs[i].face);
      const std::size_t n = face.size();
      by_neighbour.push_back({face[(cs[i].k + 1) % n], i});
      by_neighbour.push_back({face[(cs[i].k + n - 1) % n], i});
    }
    std::sort(by_neighbour.begin(), by_neighbour.end());
    for (std::size_t j = 1; j < by_neighbour.size(); ++j)
      if (by_neighbour[j].first == by_neighbour[j - 1].first)
        fans.unite(by_neighbour[j].second, by_neighbour[j - 1].second);
    std::vector<Index> copy(cs.size(), v);
    std::vector<char> named(cs.size(), 0);
    bool first = true;
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const std::size_t root = fans.find(i);
      if (!named[root]) {
        named[root] = 1;
        if (first) {
          copy[root] = v;
          first = false;
        } else {
          copy[root] = static_cast<Index>(out.points.size());
          out.points.push_back(soup.points[v]);
          ++added;
        }
      }
      out.indices[out.offsets[cs[i].face] + cs[i].k] = copy[root];
    }
  }
  return out;
}

std::vector<Index> identity(std::size_t n) {
  std::vector<Index> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<Index>(i);
  return v;
}

MeshBuildResult build_mesh(const Soup& input, Mesh& mesh, bool weld_points);

}  // namespace

MeshBuildResult soup_to_mesh_splitting_pinches(const Soup& input, Mesh& mesh, std::size_t* split) {
  const Weld weld = weld_identical_points(input.points);
  const Soup soup = weld.merged ? apply_weld(input, weld) : input;
  const Topology t = analyze_topology(soup);
  std::size_t added = 0;
  MeshBuildResult r;
  if (!t.nonmanifold_vertices.empty() && t.nonmanifold_edges.empty()) {
    const Soup fans = split_fans(soup, t.nonmanifold_vertices, added);
    r = build_mesh(fans, mesh, false);
  } else {
    r = build_mesh(soup, mesh, false);
  }
  if (split) *split = added;
  r.welded = weld.merged;
  return r;
}

MeshBuildResult soup_to_mesh(const Soup& input, Mesh& mesh) { return build_mesh(input, mesh, true); }

void mark_split_pinches(Mesh& mesh) {
  std::map<Point3d, std::vector<vertex_descriptor>> at;  // welded before the split: only copies share a point
  for (vertex_descriptor v : mesh.vertices()) at[approx_point3d(mesh.point(v))].push_back(v);
  bool any = false;
  for (const auto& [p, vs] : at) any = any || vs.size() > 1;
  if (!any) return;
  auto pinned = mesh.add_property_map<vertex_descriptor, char>(kVertexPinned, 0).first;
  auto identity = mesh.add_property_map<vertex_descriptor, std::uint32_t>(kVertexIdentity, kOwnIdentity).first;
  for (const auto& [p, vs] : at)
    if (vs.size() > 1)
      for (vertex_descriptor v : vs) {
        pinned[v] = 1;
        identity[v] = static_cast<std::uint32_t>(vs.front());
      }
}

PinchCopies pinch_copies(const Mesh& mesh) {
  PinchCopies copies;
  const auto identity = vertex_identity_map(mesh);
  const auto pinned = vertex_pinned_map(mesh);
  if (!identity) return copies;
  for (vertex_descriptor v : mesh.vertices())
    if (!mesh.is_isolated(v) && (vertex_identity(identity, v) != static_cast<std::uint32_t>(v) || (pinned && (*pinned)[v])))
      copies[vertex_identity(identity, v)].push_back(v);
  return copies;
}

bool copies_share_edge(const Mesh& mesh, const std::optional<VertexIdentityMap>& identity,
                       const PinchCopies& copies, vertex_descriptor v, vertex_descriptor w) {
  if (!identity) return false;
  const std::uint32_t iv = vertex_identity(identity, v);
  const auto it = copies.find(vertex_identity(identity, w));
  const std::vector<vertex_descriptor> own{w};
  for (vertex_descriptor w2 : it != copies.end() ? it->second : own)
    for (vertex_descriptor x : CGAL::vertices_around_target(mesh.halfedge(w2), mesh))
      if (vertex_identity(identity, x) == iv && !(w2 == w && x == v)) return true;
  return false;
}

namespace {

MeshBuildResult build_mesh(const Soup& input, Mesh& mesh, bool weld_points) {
  mesh.clear();
  MeshBuildResult r;
  const Weld weld = weld_points ? weld_identical_points(input.points) : Weld{identity(input.points.size()), 0};
  const Soup soup = weld.merged ? apply_weld(input, weld) : input;
  r.welded = weld.merged;
  const Topology t = analyze_topology(soup);
  for (std::size_t f : t.repeated_index_faces) r.problems.push_back("face " + std::to_string(f) + " repeats a vertex");
  for (const Edge& e : t.nonmanifold_edges)
    r.problems.push_back(edge_name(e) + " is non-manifold: shared by " + std::to_string(e.uses.size()) +
                         " faces (" + faces_of(e) + ")");
  for (const Edge& e : t.misoriented_edges)
    r.problems.push_back("faces " + faces_of(e) + " disagree in orientation across " + edge_name(e));
  for (Index v : t.nonmanifold_vertices)
    r.problems.push_back("vertex " + std::to_string(v) + " is non-manifold: its faces form more than one fan");
  for (const auto& d : t.duplicate_faces)
    r.problems.push_back("faces " + std::to_string(d[0]) + " and " + std::to_string(d[1]) + " are duplicates");
  if (!r.problems.empty()) return r;

  std::vector<vertex_descriptor> vmap(soup.points.size());
  mesh.reserve(static_cast<Mesh::size_type>(soup.points.size()), 0, static_cast<Mesh::size_type>(soup.face_count()));
  for (std::size_t i = 0; i < soup.points.size(); ++i)
    if (weld.representative[i] == i) {
      const Point3d& p = soup.points[i];
      vmap[i] = mesh.add_vertex(Point(p[0], p[1], p[2]));
    }
  auto origin = mesh.add_property_map<face_descriptor, std::int64_t>(kFaceOrigin, -1).first;
  std::vector<vertex_descriptor> corners;
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    corners.clear();
    for (Index i : soup.face(f)) corners.push_back(vmap[i]);
    const face_descriptor fd = mesh.add_face(corners);
    if (fd == Mesh::null_face()) {  // defensive: the topology pass should have caught it
      r.problems.push_back("face " + std::to_string(f) + " cannot be added to a 2-manifold mesh");
      mesh.clear();
      return r;
    }
    origin[fd] = static_cast<std::int64_t>(f);
  }
  r.ok = true;
  return r;
}

}  // namespace

Soup mesh_to_soup(const Mesh& mesh) {
  Soup s;
  std::unordered_map<std::uint32_t, Index> id;
  for (vertex_descriptor v : mesh.vertices()) {
    id[static_cast<std::uint32_t>(v)] = static_cast<Index>(s.points.size());
    const Point& p = mesh.point(v);
    s.points.push_back(nearest_point3d(p));
  }
  for (face_descriptor f : mesh.faces()) {
    std::vector<Index> face;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) face.push_back(id[static_cast<std::uint32_t>(v)]);
    s.add_face(face.begin(), face.end());
  }
  return s;
}

namespace {

/// An exact rational rounded to the nearest double (ties to even), as
/// IEEE 754 rounds: one correctly rounded MPFR conversion at 53 bits, its
/// subnormal range as a double's (as CGAL's own to_interval for mpq_class
/// does, rounding away from zero there).
double round_exact(const mpq_class& e) {
  const mpfr_exp_t emin = mpfr_get_emin();
  mpfr_set_emin(-1073);
  MPFR_DECL_INIT(y, 53);
  const int inexact = mpfr_set_q(y, e.get_mpq_t(), MPFR_RNDN);
  mpfr_subnormalize(y, inexact, MPFR_RNDN);
  const double d = mpfr_get_d(y, MPFR_RNDN);  // exact: y has a double's precision and range
  mpfr_set_emin(emin);
  return d;
}
static_assert(std::is_same_v<Kernel::Exact_kernel::FT, mpq_class>);

}  // namespace

double nearest_double_of(const mpq_class& q) { return round_exact(q); }

// CGAL::to_double on a lazy number is only guaranteed to a relative
// precision of 1e-5; this is the nearest double.
double nearest_double(const Kernel::FT& x) {
  // A point interval holds the exact value itself (input coordinates): no
  // rational needed, which would otherwise be built and converted per call.
  if (x.approx().is_point()) return x.approx().inf();
  return round_exact(x.exact());
}

// Read from the point's own approximation, or its exact value: p.x() on a
// lazy point is a construction of its own (a new lazy node, and an exact
// evaluation with its once-flag when the interval is not a point) — 15% and
// 16% of a deintersect run on a 150k-face tube before.
Point3d nearest_point3d(const Point& p) {
  const auto& a = p.approx();
  if (a.x().is_point() && a.y().is_point() && a.z().is_point()) return {a.x().inf(), a.y().inf(), a.z().inf()};
  const auto& e = p.exact();
  return {round_exact(e.x()), round_exact(e.y()), round_exact(e.z())};
}

Point nearest_double_point(const Point& p) {
  const Point3d d = nearest_point3d(p);
  return Point(d[0], d[1], d[2]);
}

Point3d approx_point3d(const Point& p) { return nearest_point3d(p); }

}  // namespace polyheal
