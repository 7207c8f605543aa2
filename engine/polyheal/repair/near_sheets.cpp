// polyheal — pushing apart what TetGen's tolerance would join (near_sheets.h).
#include "polyheal/repair/near_sheets.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "polyheal/inspect/predicates.h"
#include "polyheal/inspect/report.h"
#include "polyheal/inspect/self_intersections.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

Point3d unit(const Point3d& v) {
  const double l = norm(v);
  return l > 0 ? mul(v, 1 / l) : Point3d{0, 0, 0};
}

/// The point of segment ab nearest p (doubles: a direction to move along).
Point3d nearest_on_segment(const Point3d& p, const Point3d& a, const Point3d& b) {
  const Point3d ab = sub(b, a);
  const double l2 = dot(ab, ab);
  const double t = l2 > 0 ? std::clamp(dot(sub(p, a), ab) / l2, 0.0, 1.0) : 0.0;
  return add(a, mul(ab, t));
}

/// The nearest points of segments ab and cd (doubles), by alternating
/// projections from the ends: enough to tell which way they lie apart.
std::pair<Point3d, Point3d> nearest_between(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d) {
  Point3d p = a, q = nearest_on_segment(a, c, d);
  for (int k = 0; k < 8; ++k) {
    p = nearest_on_segment(q, a, b);
    q = nearest_on_segment(p, c, d);
  }
  return {p, q};
}

/// Each vertex's wished direction away from what it is too close to (sums
/// of unit vectors, by welded id), from the report's pairs.
std::vector<Point3d> wishes(const Soup& s, const Report& r) {
  std::vector<Point3d> want(s.points.size(), Point3d{0, 0, 0});
  auto push = [&](Index v, const Point3d& d) { want[v] = add(want[v], d); };
  const auto& P = s.points;
  for (const VertexNearFace& p : r.vertices_near_faces) {
    const FaceView f = s.face(p.face);
    const Point3d n = unit(normal(P[f[0]], P[f[1]], P[f[2]]));
    const int o = orientation_sign(P[f[0]], P[f[1]], P[f[2]], P[p.vertex]);
    if (o == 0) continue;  // on the face's plane (and not on the face: closer to its rim) — the edges say more
    const Point3d d = mul(n, double(o));
    push(p.vertex, d);
    for (Index c : f) push(c, mul(d, -1));
  }
  for (const EdgeNearEdge& p : r.edges_near_edges) {
    const Point3d &a = P[p.e[0]], &b = P[p.e[1]], &c = P[p.f[0]], &d = P[p.f[1]];
    Point3d dir = unit(cross(sub(b, a), sub(d, c)));
    const int o = orientation_sign(a, b, c, d);
    if (o != 0 && norm(dir) > 0) {
      // (c - a) . ((b - a) x (d - c)) = -det[b - a, c - a, d - a]: for o > 0
      // cd lies on the -dir side of ab, which moves along +dir; for o < 0
      // the other way round.
      dir = mul(dir, double(o));
    } else {
      const auto [x, y] = nearest_between(a, b, c, d);
      dir = unit(sub(x, y));
    }
    if (norm(dir) == 0) continue;
    push(p.e[0], dir);
    push(p.e[1], dir);
    push(p.f[0], mul(dir, -1));
    push(p.f[1], mul(dir, -1));
  }
  for (const auto& p : r.close_vertices) {
    const Point3d d = unit(sub(P[p[0]], P[p[1]]));
    push(p[0], d);
    push(p[1], mul(d, -1));
  }
  for (const VertexNearEdge& p : r.vertices_near_edges) {
    const Point3d d = unit(sub(P[p.vertex], nearest_on_segment(P[p.vertex], P[p.a], P[p.b])));
    push(p.vertex, d);
    push(p.a, mul(d, -1));
    push(p.b, mul(d, -1));
  }
  return want;
}

/// The corners of the faces of `next` that moves from `cur` made intersect
/// another face or degenerate (exactly; the other faces are as they were in
/// the clean `cur`, and moves change no connectivity).
std::vector<Index> defect_corners(const Soup& cur, const Soup& next) {
  const std::size_t F = next.face_count();
  std::vector<char> changed(F, 0);
  for (std::size_t f = 0; f < F; ++f)
    for (Index i : next.face(f)) changed[f] |= next.points[i] != cur.points[i];
  std::vector<Index> v;
  auto face = [&](std::size_t f) {
    for (Index i : next.face(f)) v.push_back(i);
  };
  for (std::size_t f = 0; f < F; ++f) {
    const FaceView t = next.face(f);
    if (changed[f] && is_collinear(next.points[t[0]], next.points[t[1]], next.points[t[2]])) face(f);
  }
  SelfIntersectionOptions only;
  only.only = &changed;
  for (const FacePair& p : find_self_intersections(next, only)) {
    face(p.first);
    face(p.second);
  }
  return v;
}

}  // namespace

std::size_t close_pair_count(const Report& r) {
  return r.vertices_near_faces.size() + r.edges_near_edges.size() + r.close_vertices.size() +
         r.vertices_near_edges.size();
}

Soup separate_near_sheets(const Soup& clean, const SeparateOptions& o, SeparateReport& r, const Report* known) {
  r = SeparateReport{};
  Soup cur = apply_weld(clean, weld_identical_points(clean.points));
  if (!cur.is_triangle_soup()) return cur;
  const std::vector<Point3d> start = cur.points;
  InspectOptions tetgen;
  tetgen.tetgen_segments = true;
  tetgen.tetgen_epsilon = o.epsilon;
  // The caller's report names vertices by the same ids when welding changed nothing.
  Report rep = known && known->vertices_near_edges_checked && cur.points == clean.points ? *known : inspect(cur, tetgen);
  if (!rep.certified_clean()) return cur;
  r.pairs_before = r.pairs_after = close_pair_count(rep);
  const double step = o.step * o.epsilon * bbox_diagonal(rep);
  std::vector<char> frozen(cur.points.size(), 0);
  for (; r.rounds < o.max_rounds && close_pair_count(rep) > 0; ++r.rounds) {
    const std::vector<Point3d> want = wishes(cur, rep);
    std::vector<Index> moving;
    for (std::size_t v = 0; v < want.size(); ++v)
      if (!frozen[v] && norm(want[v]) > 0.5) moving.push_back(Index(v));  // opposite wishes cancel: stays
    if (moving.empty()) break;
    Soup next = cur;
    for (Index v : moving) next.points[v] = add(cur.points[v], mul(unit(want[v]), step));
    // Undo, and freeze, the moves of the corners of faces that now
    // intersect or degenerate, until none do.
    for (;;) {
      std::size_t undone = 0;
      const std::vector<Index> bad = defect_corners(cur, next);
      if (bad.empty()) break;
      for (Index v : bad)
        if (next.points[v] != cur.points[v]) {
          next.points[v] = cur.points[v];
          frozen[v] = 1;
          ++undone;
        }
      r.refused += undone;
      if (undone == 0) {  // a defect no move explains: the last clean surface
        next = cur;
        break;
      }
    }
    if (next.points == cur.points) break;
    Report next_rep = inspect(next, tetgen);
    if (close_pair_count(next_rep) >= close_pair_count(rep)) break;  // no better: the moves only shuffle what is close
    cur = std::move(next);
    rep = std::move(next_rep);
    r.pairs_after = close_pair_count(rep);
  }
  for (std::size_t v = 0; v < cur.points.size(); ++v)
    if (cur.points[v] != start[v]) {
      ++r.moved_vertices;
      r.max_displacement = std::max(r.max_displacement, norm(sub(cur.points[v], start[v])));
    }
  return cur;
}

}  // namespace polyheal
