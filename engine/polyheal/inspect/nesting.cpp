#include "polyheal/inspect/nesting.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <unordered_map>

#include "polyheal/inspect/predicates.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using Side = CGAL::Side_of_triangle_mesh<Mesh, K>;

struct Box {
  std::array<double, 3> lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::infinity()};
  std::array<double, 3> hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity()};
  bool within(const Box& o) const {
    for (int k = 0; k < 3; ++k)
      if (lo[k] < o.lo[k] || hi[k] > o.hi[k]) return false;
    return true;
  }
  bool meets(const Box& o) const {
    for (int k = 0; k < 3; ++k)
      if (hi[k] < o.lo[k] || o.hi[k] < lo[k]) return false;
    return true;
  }
};

/// One component as a Surface_mesh with its point-in-volume test, built on
/// first use.
struct Solid {
  Mesh mesh;
  std::unique_ptr<Side> side;
};

}  // namespace

Nesting nesting(const Soup& soup, bool crossing) {
  Nesting n;
  const Soup welded = apply_weld(soup, weld_identical_points(soup.points));
  const Topology t = analyze_topology(welded);
  n.components = t.components;
  n.face_component = t.face_component;
  std::vector<std::vector<std::size_t>> faces(n.components);
  for (std::size_t f = 0; f < welded.face_count(); ++f) faces[t.face_component[f]].push_back(f);
  std::vector<Box> box(n.components);
  std::vector<Index> some_vertex(n.components, 0);
  n.volume_sign.assign(n.components, 0);
  for (std::size_t c = 0; c < n.components; ++c) {
    n.volume_sign[c] = enclosed_volume_sign(welded, faces[c]);
    for (std::size_t f : faces[c])
      for (Index i : welded.face(f))
        for (int k = 0; k < 3; ++k) {
          box[c].lo[k] = std::min(box[c].lo[k], welded.points[i][k]);
          box[c].hi[k] = std::max(box[c].hi[k], welded.points[i][k]);
        }
    some_vertex[c] = welded.face(faces[c].front())[0];
  }
  n.inside_out.assign(n.components, 0);
  n.turned.assign(n.components, 0);
  const bool any_inward = std::any_of(n.volume_sign.begin(), n.volume_sign.end(), [](int s) { return s < 0; });
  if (!any_inward) return n;

  std::vector<Solid> solids(n.components);
  auto solid = [&](std::size_t d) -> const Side& {
    Solid& s = solids[d];
    if (!s.side) {
      std::unordered_map<Index, Mesh::Vertex_index> local;
      for (std::size_t f : faces[d]) {
        std::array<Mesh::Vertex_index, 3> v;
        const FaceView fv = welded.face(f);
        for (int k = 0; k < 3; ++k) {
          auto [it, fresh] = local.try_emplace(fv[k]);
          if (fresh) {
            const Point3d& p = welded.points[fv[k]];
            it->second = s.mesh.add_vertex(K::Point_3(p[0], p[1], p[2]));
          }
          v[k] = it->second;
        }
        s.mesh.add_face(v[0], v[1], v[2]);
      }
      s.side = std::make_unique<Side>(s.mesh);
    }
    return *s.side;
  };
  // c inside d. Disjoint closed surfaces: one vertex of c decides (it is
  // never on d's boundary; were it, c would touch d and not be certified).
  // Crossing ones: the greater part of c's area, sampled (below).
  auto one_vertex_inside = [&](std::size_t c, std::size_t d) {
    if (c == d || !box[c].within(box[d])) return false;
    const Point3d& p = welded.points[some_vertex[c]];
    return solid(d)(K::Point_3(p[0], p[1], p[2])) == CGAL::ON_BOUNDED_SIDE;
  };
  // The share of c's area (kSamples faces spread over its list, each
  // standing for its area at its centroid; every face when fewer) strictly
  // inside a component that `in_one_of` accepts. A centroid is rounded to
  // doubles; the side test on it is exact.
  constexpr std::size_t kSamples = 64;
  auto area_share_inside = [&](std::size_t c, const std::function<bool(std::size_t)>& in_one_of) {
    std::vector<std::size_t> others;
    for (std::size_t d = 0; d < n.components; ++d)
      if (d != c && box[c].meets(box[d]) && in_one_of(d)) others.push_back(d);
    if (others.empty()) return 0.0;
    const std::vector<std::size_t>& fc = faces[c];
    const std::size_t samples = std::min(kSamples, fc.size());
    double inside_area = 0, all_area = 0;
    for (std::size_t k = 0; k < samples; ++k) {
      const FaceView v = welded.face(fc[k * fc.size() / samples]);
      const Point3d &a = welded.points[v[0]], &b = welded.points[v[1]], &e = welded.points[v[2]];
      const double area = norm(normal(a, b, e));
      const Point3d m = mul(add(add(a, b), e), 1.0 / 3);
      const K::Point_3 centroid(m[0], m[1], m[2]);
      all_area += area;
      for (std::size_t d : others)
        if (solid(d)(centroid) == CGAL::ON_BOUNDED_SIDE) {
          inside_area += area;
          break;
        }
    }
    return all_area > 0 ? inside_area / all_area : 0.0;
  };
  auto inside = [&](std::size_t c, std::size_t d) {
    if (!crossing) return one_vertex_inside(c, d);
    return c != d && area_share_inside(c, [d](std::size_t e) { return e == d; }) > 0.5;
  };
  auto enclosed = [&](std::size_t c) {
    if (!crossing) {
      for (std::size_t d = 0; d < n.components; ++d)
        if (inside(c, d)) return true;
      return false;
    }
    return area_share_inside(c, [](std::size_t) { return true; }) > 0.5;
  };
  for (std::size_t c = 0; c < n.components; ++c) {
    if (n.volume_sign[c] >= 0) continue;
    if (enclosed(c)) {
      ++n.cavity_count;
    } else {
      n.inside_out[c] = n.turned[c] = 1;
      ++n.inside_out_count;
    }
  }
  // Inside an inside-out component, each component is turned to face as its
  // depth says once that one faces outwards: outwards at even depth (an
  // island), inwards at odd depth (a cavity). Elsewhere nothing is turned.
  if (!n.inside_out_count) return n;
  for (std::size_t c = 0; c < n.components; ++c) {
    if (n.inside_out[c]) continue;
    bool under = false;
    for (std::size_t d = 0; d < n.components && !under; ++d) under = n.inside_out[d] && inside(c, d);
    if (!under) continue;
    std::size_t depth = 0;
    for (std::size_t d = 0; d < n.components; ++d) depth += inside(c, d);
    n.turned[c] = (n.volume_sign[c] > 0) != (depth % 2 == 0);
  }
  return n;
}

namespace {

Soup reversed_where(const Soup& soup, const std::function<bool(std::size_t)>& turn, std::size_t* faces_turned) {
  Soup out;
  out.points = soup.points;
  out.group_names = soup.group_names;
  out.face_group = soup.face_group;
  std::size_t turned = 0;
  std::vector<Index> face;
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const FaceView v = soup.face(f);
    face.assign(v.begin(), v.end());
    if (turn(f)) {
      std::reverse(face.begin() + 1, face.end());  // same first corner, the other way round
      ++turned;
    }
    out.add_face(face.begin(), face.end());
  }
  if (faces_turned) *faces_turned = turned;
  return out;
}

}  // namespace

Soup reversed(const Soup& soup) {
  return reversed_where(soup, [](std::size_t) { return true; }, nullptr);
}

Soup turned_outward(const Soup& soup, const Nesting& n, std::size_t* faces_turned) {
  return reversed_where(soup, [&](std::size_t f) { return n.turned[n.face_component[f]] != 0; }, faces_turned);
}

}  // namespace polyheal
