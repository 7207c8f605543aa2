#include "polyheal/inspect/report.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <set>

#include "polyheal/inspect/detail/parallel.h"
#include "polyheal/inspect/nesting.h"
#include "polyheal/inspect/predicates.h"
#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

EdgeRef ref(const Edge& e) {
  EdgeRef r{e.a, e.b, {}};
  for (const EdgeUse& u : e.uses) r.faces.push_back(u.face);
  return r;
}

void topology_and_shape(const Soup& soup, const Weld& weld, const InspectOptions& o, Report& r, Topology& topo);
void count_cracks(const Soup& soup, const InspectOptions& o, Report& r);

}  // namespace

bool Report::clean_but_for_crossings() const {
  return faces > 0 && closed && manifold && oriented && degenerate_faces.empty() && duplicate_faces.empty();
}

bool Report::certified_clean() const { return clean_but_for_crossings() && self_intersections.empty(); }

Report inspect(const Soup& input, const InspectOptions& o) {
  Report r;
  auto t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("topology");
  const Weld weld = weld_identical_points(input.points);
  Soup welded;
  if (weld.merged) welded = apply_weld(input, weld);
  const Soup& soup = weld.merged ? welded : input;
  r.vertices = soup.points.size();
  r.faces = soup.face_count();
  r.merged_identical_vertices = weld.merged;
  for (std::size_t f = 0; f < r.faces; ++f) r.non_triangle_faces += soup.face(f).size() != 3;
  r.seconds_topology = seconds_since(t0);  // welding counts as topology

  // The self-intersection pass needs only the welded soup: on two cores it
  // runs beside the topology and shape passes, filling idle time its own
  // parallel phases leave (measured in BENCHMARKS.md).
  auto self_intersection_pass = [&] {
    const auto t = std::chrono::steady_clock::now();
    SelfIntersectionOptions si;
    si.parallel = o.parallel;
    si.observer = o.observer;
    r.self_intersections =
        o.self_intersections && !weld.merged ? *o.self_intersections : find_self_intersections(soup, si);
    r.seconds_self_intersections = seconds_since(t);
  };
  // Nesting (inward components only) needs a certified surface; in
  // parallel it is decided beside the self-intersection pass, before that
  // pass has certified anything, and kept only if it does (its serial
  // tree building was most of a cavity-rich surface's last stretch) — not
  // when the caller's pairs say already that it will not (a rounding pass
  // of regularize: the crank's raw offset, 15k pockets, 1.5 s).
  const bool crossing = o.self_intersections && !weld.merged && !o.self_intersections->empty();
  Topology topo;
  std::optional<Nesting> nested;
  auto topology_and_shape_pass = [&] {
    topology_and_shape(soup, weld, o, r, topo);
    if (o.parallel && !crossing && r.inward_components > 0 && r.clean_but_for_crossings())
      nested = nesting_of_welded(soup, topo);
  };
  if (o.parallel) tbb::parallel_invoke(self_intersection_pass, topology_and_shape_pass);
  else {
    topology_and_shape_pass();
    self_intersection_pass();
  }
  count_cracks(soup, o, r);
  if (r.inward_components > 0 && r.certified_clean()) {
    if (!nested) nested = nesting_of_welded(soup, topo);
    r.nesting_checked = true;
    r.inside_out_components = nested->inside_out_count;
    r.cavities = nested->cavity_count;
  }
  return r;
}

Report inspect_from(const Soup& soup, const Soup& base, const std::vector<FacePair>& base_pairs, InspectOptions o,
                    std::size_t* searched) {
  std::size_t changed = soup.face_count();
  const std::optional<std::vector<FacePair>> pairs =
      find_self_intersections_from(soup, base, base_pairs, 0.125, &changed);
  if (pairs) o.self_intersections = &*pairs;
  Report r = inspect(soup, o);
  // inspect() searches the whole soup where it has identical points (its
  // pairs are the welded soup's)
  if (searched) *searched = !pairs || r.merged_identical_vertices ? soup.face_count() : changed;
  return r;
}

namespace {

/// Report::crack_pairs: only the corners of intersecting faces can close
/// such a pair, so only they are searched (find_close_points, exact).
void count_cracks(const Soup& soup, const InspectOptions& o, Report& r) {
  if (r.self_intersections.empty() || !(o.crack_ratio > 0)) return;
  std::vector<Index> corners;
  for (const FacePair& p : r.self_intersections)
    for (std::size_t f : {p.first, p.second})
      for (Index v : soup.face(f)) corners.push_back(v);
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  Soup near;
  for (Index v : corners) near.points.push_back(soup.points[v]);
  std::set<std::pair<Index, Index>> close;  // soup indices, a < b
  for (const auto& [a, b] : find_close_points(near, o.crack_ratio * bbox_diagonal(r)))
    if (near.points[a] != near.points[b]) close.emplace(corners[a], corners[b]);
  r.crack_vertex_pairs = close.size();
  if (close.empty()) return;
  for (const FacePair& p : r.self_intersections) {
    bool crack = false;
    for (Index a : soup.face(p.first))
      for (Index b : soup.face(p.second))
        crack = crack || (a != b && close.count({std::min(a, b), std::max(a, b)}));
    r.crack_pairs += crack;
  }
}

void topology_and_shape(const Soup& soup, const Weld& weld, const InspectOptions& o, Report& r, Topology& topo) {
  auto t0 = std::chrono::steady_clock::now();
  topo = analyze_topology(soup);
  r.components = topo.components;
  r.isolated_vertices = topo.isolated_vertices - weld.merged;  // welded-away twins are not isolated points
  for (const Edge& e : topo.boundary_edges) r.boundary_edges.push_back(ref(e));
  for (const Edge& e : topo.nonmanifold_edges) r.nonmanifold_edges.push_back(ref(e));
  for (const Edge& e : topo.misoriented_edges) r.misoriented_edges.push_back(ref(e));
  r.boundary_loops = topo.boundary_loops;
  r.nonmanifold_vertices = topo.nonmanifold_vertices;
  r.duplicate_faces = topo.duplicate_faces;
  r.closed = r.boundary_edges.empty() && r.faces > 0;
  r.manifold = r.nonmanifold_edges.empty() && r.nonmanifold_vertices.empty() && topo.repeated_index_faces.empty();
  r.oriented = r.misoriented_edges.empty();
  r.seconds_topology += seconds_since(t0);

  // Shape of each face (fan triangles of polygons), exactly; in parallel.
  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("degenerate faces, caps, needles");
  const double cos_cap = cos_degrees(o.cap_angle);
  const double cos_needle = cos_degrees(o.needle_angle);
  std::vector<Shape> shape(r.faces, Shape::fine);
  std::vector<char> near_degenerate(r.faces, 0);
  auto classify_face = [&](std::size_t f) {
    FaceView v = soup.face(f);
    Shape worst = Shape::fine;
    for (std::size_t k = 1; k + 1 < v.size(); ++k) {
      const Point3d &a = soup.points[v[0]], &b = soup.points[v[k]], &c = soup.points[v[k + 1]];
      const Shape s = classify_triangle(a, b, c, cos_cap, cos_needle);
      if (s != Shape::fine && (worst == Shape::fine || s < worst)) worst = s;
      if (s != Shape::degenerate && is_nearly_degenerate(a, b, c, o.tetgen_epsilon)) near_degenerate[f] = 1;
    }
    shape[f] = worst;
  };
  detail::for_each_index(r.faces, o.parallel, classify_face);
  for (std::size_t f = 0; f < r.faces; ++f) {
    if (shape[f] == Shape::degenerate) r.degenerate_faces.push_back(f);
    if (shape[f] == Shape::cap) r.caps.push_back(f);
    if (shape[f] == Shape::needle) r.needles.push_back(f);
    if (near_degenerate[f]) r.nearly_degenerate_faces.push_back(f);
  }
  for (std::size_t f : topo.repeated_index_faces)
    if (shape[f] != Shape::degenerate) r.degenerate_faces.push_back(f);  // a polygon repeating an index
  std::sort(r.degenerate_faces.begin(), r.degenerate_faces.end());

  // TetGen: adjacent triangles folded onto each other below its angle bound.
  auto opposite = [](FaceView v, const Topology::InteriorEdge& e) {
    for (Index i : v)
      if (i != e.a && i != e.b) return i;
    return v[0];
  };
  // Asked of two non-degenerate triangles only, as the quad (p, q, r, s):
  // faces (p, q, r) and (q, p, s).
  auto quad = [&](const Topology::InteriorEdge& e, EdgeQuad& q) {
    FaceView f0 = soup.face(e.face0), f1 = soup.face(e.face1);
    if (f0.size() != 3 || f1.size() != 3 || shape[e.face0] == Shape::degenerate || shape[e.face1] == Shape::degenerate)
      return false;
    q = {e.a, e.b, opposite(f0, e), opposite(f1, e), e.face0, e.face1};
    return true;
  };
  const double cos_fold = cos_degrees(o.tetgen_fold_angle);
  // TetGen: adjacent triangles it merges into one facet (find_flip_hazards).
  const double cos_merge = cos_degrees(o.tetgen_facet_angle - 1e-3);
  tbb::enumerable_thread_specific<std::vector<FacePair>> folds;
  tbb::enumerable_thread_specific<std::vector<EdgeQuad>> merged;
  detail::for_each_index(topo.interior_edges.size(), o.parallel, [&](std::size_t i) {
    const Topology::InteriorEdge& e = topo.interior_edges[i];
    EdgeQuad q;
    if (!quad(e, q)) return;
    const Point3d &a = soup.points[q.p], &b = soup.points[q.q], &c = soup.points[q.r], &d = soup.points[q.s];
    if (fold_angle_less(a, b, c, d, cos_fold))
      folds.local().push_back({std::min<std::size_t>(e.face0, e.face1), std::max<std::size_t>(e.face0, e.face1)});
    else if (o.tetgen_segments && !fold_angle_less(a, b, c, d, cos_merge))
      merged.local().push_back(q);
  });
  for (const auto& v : folds) r.sharp_folds.insert(r.sharp_folds.end(), v.begin(), v.end());
  std::sort(r.sharp_folds.begin(), r.sharp_folds.end());

  // Bounding box and signed volume (a measurement, not a predicate).
  r.bbox_min = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                std::numeric_limits<double>::infinity()};
  r.bbox_max = {-r.bbox_min[0], -r.bbox_min[1], -r.bbox_min[2]};
  for (const Point3d& p : soup.points)
    for (int a = 0; a < 3; ++a) {
      r.bbox_min[a] = std::min(r.bbox_min[a], p[a]);
      r.bbox_max[a] = std::max(r.bbox_max[a], p[a]);
    }
  if (soup.points.empty()) r.bbox_min = r.bbox_max = {0, 0, 0};

  if (o.tetgen_segments) {
    std::vector<EdgeQuad> quads;
    for (const auto& v : merged) quads.insert(quads.end(), v.begin(), v.end());
    r.vertices_near_edges_checked = true;
    std::vector<std::array<Index, 2>> edges;
    edges.reserve(topo.interior_edges.size() + topo.boundary_edges.size());
    for (const Topology::InteriorEdge& e : topo.interior_edges) edges.push_back({e.a, e.b});
    for (const Edge& e : topo.boundary_edges) edges.push_back({e.a, e.b});
    const double shortest = o.tetgen_epsilon * bbox_diagonal(r);
    // Independent searches, as tasks: most of them are sequential inside,
    // and the self-intersection pass beside this one ends first
    // (torus_knot_1M: 3.9 s of them one after another).
    const std::function<void()> searches[] = {
        [&] { r.flip_hazards = find_flip_hazards(soup, quads, o.tetgen_epsilon, o.parallel); },
        // a vertex within its tolerance of an edge it is not on
        [&] { r.vertices_near_edges = find_vertices_near_edges(soup, edges, o.tetgen_epsilon); },
        // two points closer than its shortest edge (-T times the bbox
        // diagonal, its 'minedgelength') become one
        [&] { r.close_vertices = find_close_points(soup, shortest); },
        // two edges closer than that, sharing no vertex, or a vertex and a
        // face: its Steiner points on them would be
        [&] { r.edges_near_edges = find_edges_near_edges(soup, edges, shortest, o.parallel); },
        [&] { r.vertices_near_faces = find_vertices_near_faces(soup, shortest); },
    };
    if (o.parallel) tbb::parallel_invoke(searches[0], searches[1], searches[2], searches[3], searches[4]);
    else
      for (const auto& search : searches) search();
  }
  // About the bbox centre: the same sum for a closed surface, without the
  // cancellation of determinants ~|p|^3 far from the origin (a millimetre
  // box 1e8 away summed to 97756 about the origin).
  long double volume = 0;
  const long double centre[3] = {0.5L * ((long double)r.bbox_min[0] + r.bbox_max[0]),
                                 0.5L * ((long double)r.bbox_min[1] + r.bbox_max[1]),
                                 0.5L * ((long double)r.bbox_min[2] + r.bbox_max[2])};
  auto at = [&](Index i, int c) { return (long double)soup.points[i][c] - centre[c]; };
  for (std::size_t f = 0; f < r.faces; ++f) {
    FaceView v = soup.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k) {
      const Index a = v[0], b = v[k], c = v[k + 1];
      volume += at(a, 0) * (at(b, 1) * at(c, 2) - at(b, 2) * at(c, 1)) -
                at(a, 1) * (at(b, 0) * at(c, 2) - at(b, 2) * at(c, 0)) +
                at(a, 2) * (at(b, 0) * at(c, 1) - at(b, 1) * at(c, 0));
    }
  }
  r.signed_volume = static_cast<double>(volume / 6);
  if (r.closed && r.oriented) {
    std::vector<std::vector<std::size_t>> by_component(r.components);
    for (std::size_t f = 0; f < r.faces; ++f) by_component[topo.face_component[f]].push_back(f);
    int sign = 0;  // of the last component
    for (const std::vector<std::size_t>& faces : by_component)
      if (!faces.empty() && (sign = enclosed_volume_sign(soup, faces)) < 0) ++r.inward_components;
    if (by_component.size() == 1) {  // the whole is its one component
      r.volume_sign = sign;
    } else {
      r.volume_sign = enclosed_volume_sign(soup);
    }
  }
  r.seconds_shape = seconds_since(t0);
}

}  // namespace

SurfaceTopology topology_of(const Report& r) {
  SurfaceTopology t;
  const long used = long(r.vertices) - long(r.isolated_vertices) - long(r.merged_identical_vertices);
  // Triangles only here (polygons are refused): each interior edge has two
  // face sides, each boundary edge one.
  const long edges = (3 * long(r.faces) + long(r.boundary_edges.size())) / 2;
  t.euler = used - edges + long(r.faces);
  t.components = r.components;
  t.boundary_loops = r.boundary_loops;
  t.manifold = r.manifold && r.oriented;
  return t;
}

double bbox_diagonal(const Report& r) {
  const double dx = r.bbox_max[0] - r.bbox_min[0], dy = r.bbox_max[1] - r.bbox_min[1],
               dz = r.bbox_max[2] - r.bbox_min[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace polyheal
