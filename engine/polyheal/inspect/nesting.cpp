#include "polyheal/inspect/nesting.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>
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

/// The components of a welded soup (faces joined through shared edges),
/// their boxes, and each one's Surface_mesh with its point-in-volume test
/// and distance index, built on first use.
class Components {
 public:
  explicit Components(const Soup& soup)
      : own_soup_(apply_weld(soup, weld_identical_points(soup.points))), own_topology_(analyze_topology(*own_soup_)),
        welded_(*own_soup_), topology_(*own_topology_) {
    index();
  }
  /// `welded` has no two identical points; `topology` is its analysis.
  Components(const Soup& welded, const Topology& topology) : welded_(welded), topology_(topology) { index(); }
  std::size_t count() const { return topology_.components; }
  const Soup& welded() const { return welded_; }
  const Topology& topology() const { return topology_; }
  const std::vector<std::size_t>& faces(std::size_t c) const { return faces_[c]; }
  const Box& box(std::size_t c) const { return box_[c]; }
  /// Whether p lies strictly inside component d (exact on p's doubles).
  bool inside(std::size_t d, const Point3d& p) {
    return solid(d).side->operator()(K::Point_3(p[0], p[1], p[2])) == CGAL::ON_BOUNDED_SIDE;
  }
  /// The squared distance from p to component d's surface (doubles; a measurement).
  double squared_distance(std::size_t d, const Point3d& p) {
    Solid& s = solid(d);
    if (!s.tree) {
      s.tree = std::make_unique<Tree>(s.mesh.faces().begin(), s.mesh.faces().end(), s.mesh);
      s.tree->accelerate_distance_queries();
    }
    return s.tree->squared_distance(K::Point_3(p[0], p[1], p[2]));
  }

 private:
  using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  struct Solid {
    Mesh mesh;
    std::unique_ptr<Side> side;
    std::unique_ptr<Tree> tree;
  };
  Solid& solid(std::size_t d) {
    Solid& s = solids_[d];
    if (!s.side) {
      std::unordered_map<Index, Mesh::Vertex_index> local;
      for (std::size_t f : faces_[d]) {
        std::array<Mesh::Vertex_index, 3> v;
        const FaceView fv = welded_.face(f);
        for (int k = 0; k < 3; ++k) {
          auto [it, fresh] = local.try_emplace(fv[k]);
          if (fresh) {
            const Point3d& p = welded_.points[fv[k]];
            it->second = s.mesh.add_vertex(K::Point_3(p[0], p[1], p[2]));
          }
          v[k] = it->second;
        }
        s.mesh.add_face(v[0], v[1], v[2]);
      }
      s.side = std::make_unique<Side>(s.mesh);
    }
    return s;
  }

  void index() {
    faces_.resize(count());
    for (std::size_t f = 0; f < welded_.face_count(); ++f) faces_[topology_.face_component[f]].push_back(f);
    box_.resize(count());
    for (std::size_t c = 0; c < count(); ++c)
      for (std::size_t f : faces_[c])
        for (Index i : welded_.face(f))
          for (int k = 0; k < 3; ++k) {
            box_[c].lo[k] = std::min(box_[c].lo[k], welded_.points[i][k]);
            box_[c].hi[k] = std::max(box_[c].hi[k], welded_.points[i][k]);
          }
    solids_.resize(count());
  }

  std::optional<Soup> own_soup_;
  std::optional<Topology> own_topology_;
  const Soup& welded_;
  const Topology& topology_;
  std::vector<std::vector<std::size_t>> faces_;
  std::vector<Box> box_;
  std::vector<Solid> solids_;
};

Nesting nesting_of(Components& parts, bool crossing) {
  Nesting n;
  const Soup& welded = parts.welded();
  n.components = parts.count();
  n.face_component = parts.topology().face_component;
  std::vector<Index> some_vertex(n.components, 0);
  n.volume_sign.assign(n.components, 0);
  for (std::size_t c = 0; c < n.components; ++c) {
    n.volume_sign[c] = enclosed_volume_sign(welded, parts.faces(c));
    some_vertex[c] = welded.face(parts.faces(c).front())[0];
  }
  n.inside_out.assign(n.components, 0);
  n.turned.assign(n.components, 0);
  const bool any_inward = std::any_of(n.volume_sign.begin(), n.volume_sign.end(), [](int s) { return s < 0; });
  if (!any_inward) return n;

  // c inside d. Disjoint closed surfaces: one vertex of c decides (it is
  // never on d's boundary; were it, c would touch d and not be certified).
  // Crossing ones: the greater part of c's area, sampled (below).
  auto one_vertex_inside = [&](std::size_t c, std::size_t d) {
    if (c == d || !parts.box(c).within(parts.box(d))) return false;
    return parts.inside(d, welded.points[some_vertex[c]]);
  };
  // The share of c's area (kSamples faces spread over its list, each
  // standing for its area at its centroid; every face when fewer) strictly
  // inside a component that `in_one_of` accepts. A centroid is rounded to
  // doubles; the side test on it is exact.
  constexpr std::size_t kSamples = 64;
  auto area_share_inside = [&](std::size_t c, const std::function<bool(std::size_t)>& in_one_of) {
    std::vector<std::size_t> others;
    for (std::size_t d = 0; d < n.components; ++d)
      if (d != c && parts.box(c).meets(parts.box(d)) && in_one_of(d)) others.push_back(d);
    if (others.empty()) return 0.0;
    const std::vector<std::size_t>& fc = parts.faces(c);
    const std::size_t samples = std::min(kSamples, fc.size());
    double inside_area = 0, all_area = 0;
    for (std::size_t k = 0; k < samples; ++k) {
      const FaceView v = welded.face(fc[k * fc.size() / samples]);
      const Point3d &a = welded.points[v[0]], &b = welded.points[v[1]], &e = welded.points[v[2]];
      const double area = norm(normal(a, b, e));
      const Point3d m = mul(add(add(a, b), e), 1.0 / 3);
      all_area += area;
      for (std::size_t d : others)
        if (parts.inside(d, m)) {
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

}  // namespace

Nesting nesting(const Soup& soup, bool crossing) {
  Components parts(soup);
  return nesting_of(parts, crossing);
}

Nesting nesting_of_welded(const Soup& welded, const Topology& topology) {
  Components parts(welded, topology);
  return nesting_of(parts, false);
}

std::vector<Interpenetration> interpenetrations(const Soup& soup, const std::vector<FacePair>& pairs) {
  if (pairs.empty()) return {};
  Components parts(soup);
  const std::vector<std::size_t>& component = parts.topology().face_component;
  std::set<std::pair<std::size_t, std::size_t>> crossing;
  for (const FacePair& p : pairs) {
    const std::size_t c = component[p.first], d = component[p.second];
    if (c == d) return {};  // a part crossing itself: local moves' work
    crossing.emplace(std::min(c, d), std::max(c, d));
  }
  // Up to kSamples of c's vertices spread over them; with `in`, only those
  // strictly inside d's box.
  constexpr std::size_t kSamples = 256;
  const Soup& welded = parts.welded();
  auto sampled = [&](std::size_t c, const Box* in) {
    std::vector<Index> all;
    for (std::size_t f : parts.faces(c))
      for (Index i : welded.face(f)) {
        const Point3d& p = welded.points[i];
        bool within = true;
        for (int k = 0; k < 3 && in; ++k) within = within && p[k] > in->lo[k] && p[k] < in->hi[k];
        if (within) all.push_back(i);
      }
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    const std::size_t samples = std::min(kSamples, all.size());
    std::vector<Index> out(samples);
    for (std::size_t k = 0; k < samples; ++k) out[k] = all[k * all.size() / samples];
    return out;
  };
  // How deep a vertex of c (sampled in d's box) lies inside d.
  auto depth_in = [&](std::size_t c, std::size_t d) {
    double deepest = 0;
    for (Index i : sampled(c, &parts.box(d))) {
      const Point3d& p = welded.points[i];
      if (parts.inside(d, p)) deepest = std::max(deepest, std::sqrt(parts.squared_distance(d, p)));
    }
    return deepest;
  };
  // How far c strays from d's surface: the farthest of c's sampled vertices.
  auto strays = [&](std::size_t c, std::size_t d) {
    double farthest = 0;
    for (Index i : sampled(c, nullptr)) farthest = std::max(farthest, parts.squared_distance(d, welded.points[i]));
    return std::sqrt(farthest);
  };
  auto diagonal = [&](std::size_t c) { return norm(sub(parts.box(c).hi, parts.box(c).lo)); };
  auto outward = [&](std::size_t c) { return enclosed_volume_sign(welded, parts.faces(c)) > 0; };
  std::vector<Interpenetration> out;
  for (const auto& [c, d] : crossing) {
    Interpenetration x{std::max(depth_in(c, d), depth_in(d, c)), std::min(diagonal(c), diagonal(d))};
    if (outward(c) && outward(d)) x.apart = diagonal(c) <= diagonal(d) ? strays(c, d) : strays(d, c);
    out.push_back(x);
  }
  return out;
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
