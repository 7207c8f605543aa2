// polyheal — soup-level cleanup (see clean_soup.h).
#include "polyheal/repair/clean_soup.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Polygon_mesh_processing/merge_border_vertices.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>
#include <unordered_map>

#include "polyheal/inspect/predicates.h"
#include "polyheal/inspect/self_intersections.h"
#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/union_find.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Epick;  // combinatorics only: no coordinate is constructed
using P3 = K::Point_3;
using SMesh = CGAL::Surface_mesh<P3>;
using Tri = std::array<Index, 3>;

/// Sign of the volume a closed triangle set encloses, exactly
/// (enclosed_volume_sign: intervals, then rationals) — over
/// orient_polygon_soup's points, which renumber the input's.
int volume_sign(const std::vector<P3>& pts, const std::vector<std::vector<std::size_t>>& polys,
                const std::vector<std::size_t>& faces) {
  Soup s;
  std::vector<std::size_t> all;
  for (std::size_t f : faces) {
    const Index first = Index(s.points.size());
    for (int k = 0; k < 3; ++k) {
      const P3& p = pts[polys[f][k]];
      s.points.push_back({p.x(), p.y(), p.z()});
    }
    all.push_back(s.face_count());
    s.add_triangle(first, first + 1, first + 2);
  }
  return enclosed_volume_sign(s, all);
}

/// Whether polygon p runs through triangle t's corners in t's order;
/// compared by position, since orient_polygon_soup renumbers the copies it
/// makes of non-manifold points.
bool same_cycle(const std::vector<P3>& pts, const std::vector<std::size_t>& p, const Tri& t) {
  for (int r = 0; r < 3; ++r)
    if (pts[p[0]] == pts[t[r]] && pts[p[1]] == pts[t[(r + 1) % 3]] && pts[p[2]] == pts[t[(r + 2) % 3]]) return true;
  return false;
}

/// Calls f(a, b) for each run [a, b) of sorted `v` whose elements have
/// equal `.first` (pairs sorted by key: the groups the node maps were).
template <class V, class F>
void for_each_run(const V& v, F f) {
  for (std::size_t a = 0, b; a < v.size(); a = b) {
    for (b = a + 1; b < v.size() && v[b].first == v[a].first;) ++b;
    f(a, b);
  }
}

/// A group of copies of one triangle whose orientations cancel: a copy of
/// each orientation, and the group's size.
struct CancelledGroup {
  std::size_t plus, minus, copies;
};

/// Cancelling opposite copies is right where they are two sheets (a
/// double-sided patch, the wall two touching solids share), wrong where one
/// of them is a face of the surface and the other a stray copy: a closed
/// solid given a reversed duplicate would lose the face, and the hole left
/// would be filled anew, away from the input where such holes join. So a
/// group gets one copy back when that copy is what its edges need among the
/// faces kept: no kept face uses any of its edges in the same direction, at
/// most one uses each in the opposite direction, and at least one edge is
/// so used (the copy closes or continues an oriented surface; the other
/// orientation would then be misoriented against it). Repeated to a fixed
/// point, so that adjacent stray copies come back one after the other. On a
/// double-sided sheet every face is a cancelled group, none has a kept
/// neighbour, and all still cancel; at a shared wall the two solids use each
/// wall edge once in each direction, and it still cancels. Returns the
/// number of groups given a copy back (set in `keep`).
std::size_t keep_needed_copies(const std::vector<Tri>& tris, const std::vector<CancelledGroup>& groups,
                               std::vector<char>& keep) {
  if (groups.empty()) return 0;
  std::unordered_map<std::uint64_t, std::uint32_t> directed;  // (from << 32 | to) -> kept faces using it
  auto key = [](Index a, Index b) { return (std::uint64_t(a) << 32) | b; };
  auto uses = [&](Index a, Index b) {
    const auto it = directed.find(key(a, b));
    return it == directed.end() ? 0u : it->second;
  };
  for (std::size_t i = 0; i < tris.size(); ++i)
    if (keep[i])
      for (int k = 0; k < 3; ++k) ++directed[key(tris[i][k], tris[i][(k + 1) % 3])];
  auto needed = [&](const Tri& t) {
    bool used = false;
    for (int k = 0; k < 3; ++k) {
      const Index a = t[k], b = t[(k + 1) % 3];
      const std::uint32_t reverse = uses(b, a);
      if (uses(a, b) != 0 || reverse > 1) return false;
      used = used || reverse == 1;
    }
    return used;
  };
  std::vector<char> done(groups.size(), 0);
  std::size_t restored = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      if (done[g]) continue;
      for (const std::size_t c : {groups[g].plus, groups[g].minus}) {
        if (!needed(tris[c])) continue;
        keep[c] = 1;
        for (int k = 0; k < 3; ++k) ++directed[key(tris[c][k], tris[c][(k + 1) % 3])];
        done[g] = 1;
        ++restored;
        changed = true;
        break;
      }
    }
  }
  return restored;
}

/// T-junctions: a boundary vertex v within `tol` of the interior of a
/// boundary edge x-y (of face x-y-c) splits that face into x-v-c, v-y-c (in
/// order along the edge when several vertices lie on it). Decided exactly
/// on the input doubles (predicates.h lies_along_segment: v strictly
/// between x and y in projection, farther than tol from both, within tol
/// of the line). The split faces span the original within tol; no
/// coordinate changes. Faces are split one boundary edge per pass; passes
/// repeat until nothing splits.
std::size_t split_t_junctions(const std::vector<Point3d>& pts, std::vector<Tri>& tris,
                              std::vector<std::int64_t>& source, double tol) {
  using Q = CGAL::Exact_rational;
  std::size_t inserted = 0;
  for (int pass = 0; pass < 16; ++pass) {
    // The edges used once, by sorting every (edge, face, corner).
    std::vector<std::pair<std::uint64_t, std::size_t>> sides(3 * tris.size());  // (edge, 3 face + corner)
    for (std::size_t f = 0; f < tris.size(); ++f)
      for (int k = 0; k < 3; ++k) sides[3 * f + k] = {undirected_edge_key(tris[f][k], tris[f][(k + 1) % 3]), 3 * f + k};
    // (Merge sort: on a mesh's face order the keys come in long runs that
    // made std::sort's introsort fall back to heap sort — 3M sides of a
    // 1M-face knot 0.69 s, merge sort 0.15 s. The elements are distinct:
    // the same order either way. So for the sorts by edge and face below.)
    std::stable_sort(sides.begin(), sides.end());
    std::vector<std::pair<std::size_t, int>> border;  // (face, corner): edge corner -> corner+1
    std::vector<Index> border_vertices;
    for_each_run(sides, [&](std::size_t a, std::size_t b) {
      if (b - a != 1) return;
      const std::uint64_t e = sides[a].first;
      border.push_back({sides[a].second / 3, int(sides[a].second % 3)});
      border_vertices.push_back(Index(e >> 32));
      border_vertices.push_back(Index(e & 0xFFFFFFFFu));
    });
    if (border.empty()) break;
    std::sort(border.begin(), border.end());
    std::sort(border_vertices.begin(), border_vertices.end());
    border_vertices.erase(std::unique(border_vertices.begin(), border_vertices.end()), border_vertices.end());

    std::vector<std::array<Index, 2>> edges;
    for (const auto& [f, k] : border) edges.push_back({tris[f][k], tris[f][(k + 1) % 3]});
    std::vector<std::vector<Index>> on_edge(border.size());
    for_each_point_near_edge(
        pts, edges, &border_vertices, [&](std::size_t) { return tol; },
        [&](Index v, std::size_t i) {
          const Index opposite = tris[border[i].first][(border[i].second + 2) % 3];
          if (v != opposite && lies_along_segment(pts[v], pts[edges[i][0]], pts[edges[i][1]], tol))
            on_edge[i].push_back(v);
        });

    std::vector<char> split(tris.size(), 0);
    std::size_t before = inserted;
    for (std::size_t i = 0; i < border.size(); ++i) {
      if (on_edge[i].empty() || split[border[i].first]) continue;
      const std::size_t f = border[i].first;
      split[f] = 1;
      const int k = border[i].second;
      const Tri t = tris[f];
      const Index x = t[k], y = t[(k + 1) % 3], c = t[(k + 2) % 3];
      std::vector<std::pair<Q, Index>> order;
      for (Index v : on_edge[i]) {
        Q along = 0;
        for (int j = 0; j < 3; ++j) along += (Q(pts[v][j]) - Q(pts[x][j])) * (Q(pts[y][j]) - Q(pts[x][j]));
        order.emplace_back(along, v);
      }
      std::sort(order.begin(), order.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
      std::vector<Index> chain{x};
      for (const auto& [q, v] : order)
        if (v != chain.back()) chain.push_back(v);
      chain.push_back(y);
      inserted += chain.size() - 2;
      tris[f] = Tri{chain[0], chain[1], c};
      for (std::size_t j = 1; j + 1 < chain.size(); ++j) {
        tris.push_back(Tri{chain[j], chain[j + 1], c});
        source.push_back(source[f]);
      }
    }
    if (inserted == before) break;
  }
  return inserted;
}

}  // namespace

DuplicateFaces resolve_duplicate_faces(const std::vector<std::array<Index, 3>>& tris, bool keep_sheets) {
  // Opposite copies cancel in pairs (their winding-number contributions
  // do); of what remains, one copy of the prevailing orientation is kept. A
  // cancelled group is given back one copy where the surface around it
  // needs exactly that copy (keep_needed_copies()).
  // Copies found by sorting the faces by their sorted vertex triple (a
  // node-based map from triple to faces allocated a list per face: 1.4 s
  // of a 1M-face scan's repair). A group's copies come in face order and
  // the groups in the order of their first face.
  DuplicateFaces d;
  auto sorted = [](Tri t) {
    std::sort(t.begin(), t.end());
    return t;
  };
  std::vector<std::pair<Tri, std::size_t>> by_set(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) by_set[i] = {sorted(tris[i]), i};
  std::stable_sort(by_set.begin(), by_set.end());
  std::vector<std::array<std::size_t, 3>> runs;  // (first face, [a, b) in by_set) of each group of copies
  for_each_run(by_set, [&](std::size_t a, std::size_t b) {
    if (b - a >= 2) runs.push_back({by_set[a].second, a, b});
  });
  std::sort(runs.begin(), runs.end());
  d.keep.assign(tris.size(), 1);
  std::vector<CancelledGroup> cancelled_groups;
  std::vector<std::array<std::size_t, 2>> cancelled_runs;  // [a, b) in by_set, beside cancelled_groups
  std::vector<std::size_t> copies;
  for (const auto& [first, a, b] : runs) {
    const Tri& s = by_set[a].first;
    copies.clear();
    for (std::size_t k = a; k < b; ++k) copies.push_back(by_set[k].second);
    auto parity = [&](std::size_t i) {  // +1 when the cycle is (s0 s1 s2), -1 when reversed
      const Tri& t = tris[i];
      const int r0 = int(std::find(t.begin(), t.end(), s[0]) - t.begin());
      return t[(r0 + 1) % 3] == s[1] ? 1 : -1;
    };
    int net = 0;
    for (std::size_t i : copies) net += parity(i);
    bool kept = false;
    for (std::size_t i : copies) {
      if (net != 0 && !kept && parity(i) == (net > 0 ? 1 : -1)) {
        kept = true;
        continue;
      }
      d.keep[i] = 0;
    }
    const std::size_t removed = copies.size() - (net != 0 ? 1 : 0);
    const std::size_t cancelled = copies.size() - std::size_t(std::abs(net));
    d.cancelled += cancelled;
    d.dropped += removed - cancelled;
    if (net == 0) {
      const auto plus = std::find_if(copies.begin(), copies.end(), [&](std::size_t i) { return parity(i) > 0; });
      const auto minus = std::find_if(copies.begin(), copies.end(), [&](std::size_t i) { return parity(i) < 0; });
      cancelled_groups.push_back({*plus, *minus, copies.size()});
      cancelled_runs.push_back({a, b});
    }
  }
  d.opposite_kept = keep_needed_copies(tris, cancelled_groups, d.keep);
  for (std::size_t g = 0; g < cancelled_groups.size(); ++g) {
    const CancelledGroup& c = cancelled_groups[g];
    if (d.keep[c.plus] || d.keep[c.minus]) {  // one copy kept, the others dropped as duplicates
      d.cancelled -= c.copies;
      d.dropped += c.copies - 1;
    } else if (keep_sheets) {  // every copy stays
      d.cancelled -= c.copies;
      for (std::size_t k = cancelled_runs[g][0]; k < cancelled_runs[g][1]; ++k) d.keep[by_set[k].second] = 1;
    }
  }
  return d;
}

CleanSoupResult clean_soup(const Soup& input, const CleanSoupOptions& o) {
  CleanSoupResult result;
  CleanSoupReport& r = result.report;
  r.faces_in = input.face_count();

  // Weld: identical points always, near points on request.
  const Weld weld = weld_identical_points(input.points);
  r.identical_vertices_welded = weld.merged;
  std::vector<Index> rep = weld.representative;
  // Points closer than the T-junction tolerance are one point: the crack
  // edge between them has zero length.
  const double near = std::max(o.weld, o.t_junction);
  if (near > 0) rep = weld_near_points(input.points, weld.representative, near, r.near_vertices_welded, r.max_weld_move);

  // Fan polygons; drop faces that repeat an index.
  std::vector<Tri> tris;
  std::vector<std::int64_t> source;
  for (std::size_t f = 0; f < input.face_count(); ++f) {
    const FaceView v = input.face(f);
    if (v.size() > 3) ++r.polygons_fanned;
    for (std::size_t k = 1; k + 1 < v.size(); ++k) {
      const Tri t{rep[v[0]], rep[v[k]], rep[v[k + 1]]};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        ++r.repeated_index_faces;
        continue;
      }
      tris.push_back(t);
      source.push_back(std::int64_t(f));
    }
  }

  // Duplicates: copies of one vertex set (resolve_duplicate_faces()).
  {
    const DuplicateFaces d = resolve_duplicate_faces(tris, false);
    r.duplicate_faces_dropped = d.dropped;
    r.cancelled_faces = d.cancelled;
    r.opposite_copies_kept = d.opposite_kept;
    std::size_t w = 0;
    for (std::size_t i = 0; i < tris.size(); ++i)
      if (d.keep[i]) {
        tris[w] = tris[i];
        source[w++] = source[i];
      }
    tris.resize(w);
    source.resize(w);
  }

  r.t_junctions = split_t_junctions(input.points, tris, source, o.t_junction);

  // Compact the points to those faces use.
  std::vector<P3> pts;
  std::vector<std::vector<std::size_t>> polys;
  {
    std::vector<std::size_t> map(input.points.size(), std::size_t(-1));
    for (Tri& t : tris) {
      std::vector<std::size_t> p(3);
      for (int k = 0; k < 3; ++k) {
        if (map[t[k]] == std::size_t(-1)) {
          map[t[k]] = pts.size();
          const Point3d& q = input.points[t[k]];
          pts.emplace_back(q[0], q[1], q[2]);
        }
        p[k] = map[t[k]];
        t[k] = Index(p[k]);
      }
      polys.push_back(std::move(p));
    }
  }

  // The topology of the faces as they stand (by index alone), computed
  // when first asked and again after orientation changes them.
  std::optional<Topology> topo;
  auto topology = [&]() -> const Topology& {
    if (!topo) {
      Soup faces;
      faces.points.resize(pts.size());
      for (const std::vector<std::size_t>& p : polys) faces.add_triangle(Index(p[0]), Index(p[1]), Index(p[2]));
      topo = analyze_topology(faces);
    }
    return *topo;
  };

  // A caller that wants only a closed 2-manifold stops here when the faces,
  // whatever their orientation, cannot make one (orientation changes no
  // edge's use count; orient_polygon_soup, costly on large non-manifold
  // soups, would only split more).
  if (o.only_if_closed) {
    const Topology& t = topology();
    if (tris.empty() || !t.boundary_edges.empty() || !t.nonmanifold_edges.empty() || !t.nonmanifold_vertices.empty())
      return result;
  }

  // Orientation. orient_polygon_soup makes each component consistent (and
  // duplicates non-manifold points); it may turn a component the input had
  // consistent, so each component is then turned back to agree with the
  // input when all its faces did, else to enclose positive volume (closed)
  // or to agree with most input faces (open). Faces that make a polygon
  // mesh as they are already are one: orient_polygon_soup would turn
  // nothing and split nothing (1.3 s on a 1M-face scan), and each
  // component agrees with the input.
  if (o.orient && !polys.empty() && !is_polygon_mesh(topology())) {
    const std::size_t points_before = pts.size();
    PMP::orient_polygon_soup(pts, polys);
    topo.reset();
    r.split_vertices = pts.size() - points_before;
    // Faces joined across edges used twice, by sorting every (edge, face).
    std::vector<std::pair<std::uint64_t, std::size_t>> uses(3 * polys.size());
    for (std::size_t f = 0; f < polys.size(); ++f)
      for (int k = 0; k < 3; ++k)
        uses[3 * f + k] = {undirected_edge_key(Index(polys[f][k]), Index(polys[f][(k + 1) % 3])), f};
    std::stable_sort(uses.begin(), uses.end());
    UnionFind uf(polys.size());
    std::vector<char> open_component_face(polys.size(), 0);
    for_each_run(uses, [&](std::size_t a, std::size_t b) {
      if (b - a == 2) uf.unite(uses[a].second, uses[a + 1].second);
      if (b - a == 1) open_component_face[uses[a].second] = 1;
    });
    // each component's faces, in face order
    std::vector<std::pair<std::size_t, std::size_t>> by_component(polys.size());  // (root, face)
    for (std::size_t f = 0; f < polys.size(); ++f) by_component[f] = {uf.find(f), f};
    std::stable_sort(by_component.begin(), by_component.end());
    std::vector<std::size_t> faces;
    for_each_run(by_component, [&](std::size_t a, std::size_t b) {
      faces.clear();
      for (std::size_t k = a; k < b; ++k) faces.push_back(by_component[k].second);
      std::size_t agree = 0;
      bool open = false;
      for (std::size_t f : faces) {
        agree += same_cycle(pts, polys[f], tris[f]);  // tris: the compacted input triangles
        open = open || open_component_face[f];
      }
      bool flip;
      if (agree == faces.size() || agree == 0) flip = agree == 0;
      else if (!open) flip = volume_sign(pts, polys, faces) < 0;
      else flip = 2 * agree < faces.size();
      if (flip)
        for (std::size_t f : faces) std::reverse(polys[f].begin(), polys[f].end());
      for (std::size_t f : faces) r.reoriented_faces += !same_cycle(pts, polys[f], tris[f]);
    });
  }

  // Stitch and fill, on a halfedge mesh.
  SMesh mesh;
  if (!polys.empty() && is_polygon_mesh(topology())) {
    PMP::polygon_soup_to_polygon_mesh(pts, polys, mesh);
    r.stitched_edges = PMP::stitch_borders(mesh);
    if (o.fill_holes) {
      // Two holes that touch at a vertex: orient_polygon_soup gives each fan
      // there its own copy of the point, and that joins the two holes into
      // one border cycle through both copies (a figure eight). Filled as one
      // polygon it would bridge the holes with faces far from the input and
      // edges used four times; the copies within a cycle are merged back, so
      // that each hole is a cycle of its own and is filled alone.
      PMP::merge_duplicated_vertices_in_boundary_cycles(mesh);
      std::vector<SMesh::Halfedge_index> loops;
      std::vector<char> seen(mesh.number_of_halfedges() + mesh.number_of_removed_halfedges(), 0);  // stitching leaves removed slots
      for (SMesh::Halfedge_index h : mesh.halfedges()) {
        if (!mesh.is_border(h) || seen[h.idx()]) continue;
        std::size_t n = 0;
        for (SMesh::Halfedge_index g : CGAL::halfedges_around_face(h, mesh)) {
          seen[g.idx()] = 1;
          ++n;
        }
        ++r.holes;
        if (o.max_hole_edges && n > o.max_hole_edges) {
          ++r.holes_left;
          continue;
        }
        loops.push_back(h);
      }
      for (SMesh::Halfedge_index h : loops) {
        // Large loops skip the cubic fallback (O(n^3)); a loop it cannot
        // fill is left open and counted.
        const std::size_t n = CGAL::halfedges_around_face(h, mesh).size();
        std::vector<SMesh::Face_index> added;
        PMP::triangulate_hole(mesh, h, std::back_inserter(added),
                              CGAL::parameters::use_delaunay_triangulation(true).do_not_use_cubic_algorithm(n > 100));
        if (added.empty()) {
          ++r.holes_left;
        } else {
          ++r.holes_filled;
          r.hole_faces += added.size();
        }
      }
    }
  } else if (!polys.empty()) {
    // Not a polygon mesh (orientation off, non-manifold): the triangles as they are.
    for (const P3& p : pts) result.soup.points.push_back({p.x(), p.y(), p.z()});
    for (std::size_t f = 0; f < polys.size(); ++f) {
      result.soup.add_triangle(Index(polys[f][0]), Index(polys[f][1]), Index(polys[f][2]));
      result.source.push_back(source[f]);
    }
  }

  // Export: faces in mesh order (the soup's polygons first, then fills).
  Soup& out = result.soup;
  if (out.face_count() == 0) {
  std::vector<Index> vmap(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), Index(-1));
  for (SMesh::Vertex_index v : mesh.vertices()) {
    vmap[v.idx()] = Index(out.points.size());
    const P3& p = mesh.point(v);
    out.points.push_back({p.x(), p.y(), p.z()});
  }
  for (SMesh::Face_index f : mesh.faces()) {
    std::array<Index, 3> t{};
    int k = 0;
    for (SMesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      if (k < 3) t[k] = vmap[v.idx()];
      ++k;
    }
    if (k != 3) continue;
    out.add_triangle(t[0], t[1], t[2]);
    result.source.push_back(f.idx() < source.size() ? source[f.idx()] : -1);
  }
  }
  if (!input.face_group.empty()) {
    out.face_group.reserve(out.face_count());
    for (std::int64_t s : result.source) out.face_group.push_back(s >= 0 ? input.face_group[std::size_t(s)] : -1);
    out.group_names = input.group_names;
  }
  r.faces_out = out.face_count();
  return result;
}

}  // namespace polyheal
