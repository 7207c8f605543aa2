#include "polyheal/repair/short_edges.h"

#include <algorithm>
#include <array>
#include <iterator>
#include <vector>

#include "polyheal/inspect/predicates.h"
#include "polyheal/inspect/report.h"
#include "polyheal/mesh/union_find.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

/// The soup with only the points its faces use, in their order.
Soup without_unused_points(const Soup& soup) {
  std::vector<Index> renumber(soup.points.size(), Index(-1));
  for (Index i : soup.indices) renumber[i] = 0;
  Soup out;
  for (std::size_t v = 0; v < soup.points.size(); ++v)
    if (renumber[v] == 0) {
      renumber[v] = static_cast<Index>(out.points.size());
      out.points.push_back(soup.points[v]);
    }
  out.indices.reserve(soup.indices.size());
  for (Index i : soup.indices) out.indices.push_back(renumber[i]);
  out.offsets = soup.offsets;
  out.face_group = soup.face_group;
  out.group_names = soup.group_names;
  return out;
}

/// The vertices the report's exact defects involve (welded ids).
std::vector<Index> defect_vertices(const Soup& soup, const Report& r) {
  std::vector<Index> v;
  auto face = [&](std::size_t f) {
    for (Index i : soup.face(f)) v.push_back(i);
  };
  for (const auto* edges : {&r.boundary_edges, &r.nonmanifold_edges, &r.misoriented_edges})
    for (const EdgeRef& e : *edges) {
      v.push_back(e.a);
      v.push_back(e.b);
    }
  v.insert(v.end(), r.nonmanifold_vertices.begin(), r.nonmanifold_vertices.end());
  for (std::size_t f : r.degenerate_faces) face(f);
  for (const auto& d : r.duplicate_faces) {
    face(d[0]);
    face(d[1]);
  }
  for (const FacePair& p : r.self_intersections) {
    face(p.first);
    face(p.second);
  }
  return v;
}

/// Triangles on which edges collapse one after another (the soup's points
/// never move: a collapse u -> v sends u's corners to v).
struct Collapser {
  std::vector<std::array<Index, 3>> tris;
  std::vector<char> alive;
  std::vector<std::vector<std::size_t>> faces_of;  // by vertex: its triangles (alive or not)

  explicit Collapser(const Soup& soup) : faces_of(soup.points.size()) {
    for (std::size_t f = 0; f < soup.face_count(); ++f) {
      const FaceView v = soup.face(f);
      tris.push_back({v[0], v[1], v[2]});
      for (Index i : v) faces_of[i].push_back(f);
    }
    alive.assign(tris.size(), 1);
  }
  static bool has(const std::array<Index, 3>& t, Index v) { return t[0] == v || t[1] == v || t[2] == v; }
  std::vector<Index> neighbours(Index u) const {
    std::vector<Index> n;
    for (std::size_t f : faces_of[u])
      if (alive[f])
        for (Index w : tris[f])
          if (w != u) n.push_back(w);
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    return n;
  }
  /// Collapses u -> v if uv is an edge of exactly two triangles and the
  /// link condition holds (the vertices adjacent to both are those two
  /// triangles' third corners): a closed 2-manifold stays one, with the
  /// same topology. Returns whether it did.
  bool collapse(Index u, Index v) {
    std::vector<std::size_t> shared;
    std::vector<Index> apexes;
    for (std::size_t f : faces_of[u])
      if (alive[f] && has(tris[f], v)) {
        shared.push_back(f);
        for (Index w : tris[f])
          if (w != u && w != v) apexes.push_back(w);
      }
    if (shared.size() != 2 || apexes[0] == apexes[1]) return false;
    const std::vector<Index> nu = neighbours(u), nv = neighbours(v);
    std::vector<Index> common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    std::sort(apexes.begin(), apexes.end());
    if (common != apexes) return false;
    if (nu.size() + nv.size() - common.size() <= 4) return false;  // a tetrahedron would flatten
    for (std::size_t f : shared) alive[f] = 0;
    for (std::size_t f : faces_of[u])
      if (alive[f]) {
        for (Index& w : tris[f])
          if (w == u) w = v;
        faces_of[v].push_back(f);
      }
    faces_of[u].clear();
    return true;
  }
  Soup soup(const Soup& from) const {
    Soup out;
    out.points = from.points;
    out.group_names = from.group_names;
    for (std::size_t f = 0; f < tris.size(); ++f)
      if (alive[f]) {
        out.add_triangle(tris[f][0], tris[f][1], tris[f][2]);
        if (!from.face_group.empty()) out.face_group.push_back(from.face_group[f]);
      }
    return out;
  }
};

}  // namespace

Soup collapse_short_edges(const Soup& clean, const ShortEdgeOptions& o, ShortEdgeReport& r) {
  r = ShortEdgeReport{};
  const Soup base = apply_weld(clean, weld_identical_points(clean.points));
  if (!base.is_triangle_soup()) return without_unused_points(base);
  InspectOptions exact;  // the exact defects; TetGen's tolerances are the caller's to weigh
  const Report before = inspect(base, exact);
  const double tol = o.epsilon * bbox_diagonal(before);
  // The short edges, shortest first (lengths in doubles: an order, not a decision).
  std::vector<std::pair<double, std::array<Index, 2>>> edges;
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const FaceView t = base.face(f);
    for (int k = 0; k < 3; ++k) {
      const Index a = t[k], b = t[(k + 1) % 3];
      if (a < b && is_closer_than(base.points[a], base.points[b], tol))
        edges.push_back({squared_norm(sub(base.points[a], base.points[b])), {a, b}});
    }
  }
  if (edges.empty()) return without_unused_points(base);
  std::sort(edges.begin(), edges.end());

  std::vector<char> refused(edges.size(), 0);
  for (int round = 0; round < o.max_rounds; ++round) {
    Collapser mesh(base);
    UnionFind into(base.points.size());  // where each point went: its set's smallest index, as a collapse keeps
    std::vector<std::vector<std::size_t>> made_into(base.points.size());  // collapses by survivor
    std::size_t collapses = 0;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (refused[e]) continue;
      const Index a = Index(into.find(edges[e].second[0])), b = Index(into.find(edges[e].second[1]));
      if (a == b) continue;
      const Index keep = std::min(a, b), gone = std::max(a, b);
      if (!is_closer_than(base.points[keep], base.points[gone], tol) || !mesh.collapse(gone, keep)) continue;
      into.unite(keep, gone);
      made_into[keep].push_back(e);
      ++collapses;
    }
    const Soup collapsed = mesh.soup(base);
    const Report after = inspect(collapsed, exact);
    const std::vector<Index> involved = defect_vertices(collapsed, after);
    if (involved.empty() && after.certified_clean()) {
      // The link condition keeps the topology; checked all the same.
      if (!(topology_of(after) == topology_of(before))) break;
      r.collapses = collapses;
      r.faces_removed = base.face_count() - collapsed.face_count();
      for (std::size_t v = 0; v < base.points.size(); ++v)
        r.max_displacement = std::max(r.max_displacement, norm(sub(base.points[v], base.points[into.find(v)])));
      return without_unused_points(collapsed);
    }
    // Refuse the collapses into each vertex a defect involves.
    std::size_t now = 0;
    for (Index v : involved)
      for (std::size_t e : made_into[v]) {
        now += !refused[e];
        refused[e] = 1;
      }
    r.collapses_undone += now;
    if (now == 0) break;  // a defect no collapse explains (or one the input had): give up
  }
  r = ShortEdgeReport{};
  r.gave_up = true;
  return without_unused_points(base);
}

}  // namespace polyheal
