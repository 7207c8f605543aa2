// polyheal — raw offset of a closed mesh, then regularization; see offset.h.
#include "polyheal/repair/offset.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <limits>
#include <cstdio>
#include <map>
#include <numeric>
#include <utility>

#include "polyheal/inspect/predicates.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/union_find.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/repair/detail/distance.h"

namespace polyheal {
namespace {

using Vec = std::array<double, 3>;

Vec unit(const Vec& a) {
  const double l = norm(a);
  return l > 0 ? mul(a, 1.0 / l) : a;
}

/// The unit vector a fraction t of the way from unit a to unit b along the
/// great circle (a straight blend where they are too close or opposite).
Vec slerp(const Vec& a, const Vec& b, double t) {
  const double th = angle_between(a, b), s = std::sin(th);
  if (s < 1e-12) return unit(add(mul(a, 1 - t), mul(b, t)));
  return add(mul(a, std::sin((1 - t) * th) / s), mul(b, std::sin(t * th) / s));
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class RawOffset {
 public:
  RawOffset(const Soup& in, double d, double step, OffsetReport& r) : in_(in), d_(d), step_(step), r_(r) {
    const std::size_t F = in.face_count();
    normal_.resize(F);
    for (std::size_t f = 0; f < F; ++f) {
      const FaceView v = in.face(f);
      const Point3d &a = in.points[v[0]], &b = in.points[v[1]], &c = in.points[v[2]];
      // the edges scaled by a power of two (exactly) to about unit length,
      // so that the cross product neither underflows nor overflows
      Vec u = sub(b, a), w = sub(c, a);
      const double m = std::max({std::fabs(u[0]), std::fabs(u[1]), std::fabs(u[2]), std::fabs(w[0]), std::fabs(w[1]),
                                 std::fabs(w[2])});
      if (m > 0 && std::isfinite(m)) {
        const int scale = -std::ilogb(m);
        for (int k = 0; k < 3; ++k) {
          u[k] = std::ldexp(u[k], scale);
          w[k] = std::ldexp(w[k], scale);
        }
      }
      const Vec n = cross(u, w);
      if (!(norm(n) > 0) || !std::isfinite(norm(n)))
        throw UnsupportedInput("face " + std::to_string(f) +
                               (is_collinear(a, b, c) ? " has zero area (collinear corners, exactly); remove it first"
                                                      : " is too thin for its normal to have a direction in doubles; "
                                                        "remove it first (polyheal degenerate)"));
      normal_[f] = unit(n);
    }
    // half-edge twins: half-edge 3f+e runs corner e -> corner e+1 of face f
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
    keyed.reserve(3 * F);
    for (std::size_t f = 0; f < F; ++f)
      for (int e = 0; e < 3; ++e) {
        const Index a = in.face(f)[e], b = in.face(f)[(e + 1) % 3];
        keyed.push_back({(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), std::uint32_t(3 * f + e)});
      }
    std::sort(keyed.begin(), keyed.end());
    twin_.assign(3 * F, ~0u);
    for (std::size_t k = 0; k < keyed.size();) {
      std::size_t m = k;
      while (m < keyed.size() && keyed[m].first == keyed[k].first) ++m;
      if (m - k != 2 || tail(keyed[k].second) == tail(keyed[k + 1].second))
        throw NotManifold({"edge (" + std::to_string(keyed[k].first >> 32) + ", " +
                           std::to_string(keyed[k].first & 0xFFFFFFFFu) +
                           ") is not shared by exactly two faces in opposite directions"},
                          "offset needs a closed, oriented 2-manifold");
      twin_[keyed[k].second] = keyed[k + 1].second;
      twin_[keyed[k + 1].second] = keyed[k].second;
      k = m;
    }
    sharp_.resize(3 * F);
    for (std::size_t h = 0; h < 3 * F; ++h) sharp_[h] = angle_between(normal_[h / 3], normal_[twin_[h] / 3]) > step_;
    for (std::size_t h = 0; h < 3 * F; ++h)
      if (sharp_[h] && h < twin_[h]) ++r_.sharp_edges;
  }

  Soup build() {
    const std::size_t F = in_.face_count();
    corner_point_.assign(3 * F, ~0u);
    sector_.assign(3 * F, ~0u);
    // fans: around each vertex, from a corner, rotate to the face across the
    // half-edge leaving the vertex
    std::vector<char> seen(3 * F, 0);
    std::vector<std::size_t> uses(in_.points.size(), 0);
    for (std::size_t f = 0; f < F; ++f)
      for (Index v : in_.face(f)) ++uses[v];
    for (std::size_t c0 = 0; c0 < 3 * F; ++c0) {
      if (seen[c0]) continue;
      std::vector<std::uint32_t> fan;  // corners around the vertex, in rotation order
      for (std::uint32_t c = std::uint32_t(c0);;) {
        seen[c] = 1;
        fan.push_back(c);
        const std::uint32_t across = twin_[c];  // half-edge c leaves the vertex; its twin enters it
        c = 3 * (across / 3) + (across % 3 + 1) % 3;  // the twin's head corner: the same vertex
        if (c == c0) break;
      }
      const Index v = in_.face(c0 / 3)[c0 % 3];
      if (fan.size() != uses[v])
        throw UnsupportedInput("vertex " + std::to_string(v) +
                               " is a pinch point (its faces form several fans): offset needs a 2-manifold");
      vertex(v, fan);
    }
    for (std::size_t f = 0; f < F; ++f) {
      out_.add_triangle(corner_point_[3 * f], corner_point_[3 * f + 1], corner_point_[3 * f + 2]);
      ++r_.face_triangles;
    }
    // strips: half-edge h (tail a, head b) in face f, twin in face g
    for (std::size_t h = 0; h < 3 * F; ++h) {
      if (!sharp_[h] || h > twin_[h]) continue;
      const std::size_t g = twin_[h];
      const std::size_t a_f = h, b_f = 3 * (h / 3) + (h % 3 + 1) % 3;  // corners of a and b in f
      const std::size_t b_g = g, a_g = 3 * (g / 3) + (g % 3 + 1) % 3;  // in g
      const std::vector<Index> A = arc(a_f, a_g), B = arc(b_f, b_g);
      // zipper between the arcs: triangles (b_j, a_i, a_i+1) and (b_j, a_i, b_j+1)
      std::size_t i = 0, j = 0;
      const std::size_t ma = A.size() - 1, mb = B.size() - 1;
      while (i < ma || j < mb) {
        const bool advance_a = j == mb || (i < ma && double(i + 1) / ma <= double(j + 1) / mb);
        if (advance_a) {
          out_.add_triangle(B[j], A[i], A[i + 1]);
          ++i;
        } else {
          out_.add_triangle(B[j], A[i], B[j + 1]);
          ++j;
        }
        ++r_.strip_triangles;
      }
    }
    return std::move(out_);
  }

 private:
  Index tail(std::uint32_t h) const { return in_.face(h / 3)[h % 3]; }

  Index add_point(const Vec& p) {
    out_.points.push_back(p);
    return Index(out_.points.size() - 1);
  }

  /// The sectors of vertex v's fan (cut at sharp edges), their points, and,
  /// with three or more sectors, the spherical patch.
  void vertex(Index v, const std::vector<std::uint32_t>& fan) {
    const Vec& p = in_.points[v];
    const std::size_t k = fan.size();
    // fan[i] and fan[i+1] are separated by half-edge fan[i] (leaving v)
    std::size_t start = k;
    for (std::size_t i = 0; i < k && start == k; ++i)
      if (sharp_[fan[i]]) start = (i + 1) % k;
    std::vector<Vec> sector_normal;
    if (start == k) start = 0;
    std::size_t sharp_count = 0;
    for (std::size_t i = 0; i < k; ++i) sharp_count += sharp_[fan[i]] ? 1 : 0;
    // fewer than two sharp edges: one sector, the whole fan (closed at `last`)
    std::uint32_t s = 0;
    Vec acc{0, 0, 0};
    for (std::size_t n = 0; n < k; ++n) {
      const std::uint32_t c = fan[(start + n) % k];
      const FaceView fv = in_.face(c / 3);
      const Vec e1 = sub(in_.points[fv[(c % 3 + 1) % 3]], p), e2 = sub(in_.points[fv[(c % 3 + 2) % 3]], p);
      acc = add(acc, mul(normal_[c / 3], angle_between(e1, e2)));
      sector_[c] = s;
      const bool last = n + 1 == k;
      if ((sharp_count >= 2 && sharp_[c]) || last) {
        sector_normal.push_back(unit(acc));
        acc = {0, 0, 0};
        if (!last) ++s;
      }
    }
    std::vector<Index> sector_point;
    for (const Vec& n : sector_normal) sector_point.push_back(add_point(add(p, mul(n, d_))));
    for (std::uint32_t c : fan) corner_point_[c] = sector_point[sector_[c]];
    normals_[v] = sector_normal;
    points_[v] = sector_point;
    if (sector_normal.size() < 3) return;
    // the patch: the loop of arcs, each traversed opposite to its strip (a
    // strip runs from the sector of the face the edge leaves v in to the other)
    ++r_.corner_vertices;
    std::map<std::uint32_t, std::uint32_t> next;  // sector -> sector, along the loop
    for (std::uint32_t c : fan)
      if (sharp_[c]) {
        const std::uint32_t across = twin_[c];
        const std::uint32_t c_in = 3 * (across / 3) + (across % 3 + 1) % 3;  // v's corner in the other face
        next[sector_[c_in]] = sector_[c];
      }
    std::vector<Index> loop;
    std::vector<Vec> dirs;
    std::uint32_t from = 0;
    for (std::size_t n = 0; n < sector_normal.size(); ++n) {
      const std::uint32_t to = next.at(from);
      const std::vector<Index> a = arc_points(v, from, to);
      for (std::size_t q = 0; q + 1 < a.size(); ++q) loop.push_back(a[q]);
      from = to;
    }
    Vec centre{0, 0, 0};
    for (const Vec& n : sector_normal) centre = add(centre, n);
    centre = unit(centre);
    for (Index q : loop) dirs.push_back(unit(sub(out_.points[q], p)));
    if (d_ < 0)
      for (Vec& u : dirs) u = mul(u, -1.0);
    double widest = 0;
    for (const Vec& u : dirs) widest = std::max(widest, angle_between(centre, u));
    const std::size_t rings = std::max<std::size_t>(1, std::size_t(std::ceil(widest / step_)));
    std::vector<Index> inner{add_point(add(p, mul(centre, d_)))};  // ring 0: the apex
    for (std::size_t ring = 1; ring <= rings; ++ring) {
      std::vector<Index> outer;
      if (ring == rings) outer = loop;
      else
        for (const Vec& u : dirs) outer.push_back(add_point(add(p, mul(slerp(centre, u, double(ring) / rings), d_))));
      const std::size_t m = loop.size();
      for (std::size_t j = 0; j < m; ++j) {
        const std::size_t j1 = (j + 1) % m;
        if (inner.size() == 1) {
          out_.add_triangle(inner[0], outer[j], outer[j1]);
          ++r_.patch_triangles;
        } else {
          out_.add_triangle(inner[j], outer[j], outer[j1]);
          out_.add_triangle(inner[j], outer[j1], inner[j1]);
          r_.patch_triangles += 2;
        }
      }
      inner = outer;
    }
  }

  /// The arc at corner c's vertex from c's sector to corner c2's sector.
  std::vector<Index> arc(std::size_t c, std::size_t c2) {
    const Index v = in_.face(c / 3)[c % 3];
    return arc_points(v, sector_[c], sector_[c2]);
  }

  /// The points of vertex v's arc from sector a to sector b, refined to the
  /// chord angle; made once per sector pair (shared by strips and patch).
  std::vector<Index> arc_points(Index v, std::uint32_t a, std::uint32_t b) {
    if (a == b) return {points_[v][a]};
    const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
    const auto key = std::make_pair(v, (std::uint64_t(lo) << 32) | hi);
    auto it = arcs_.find(key);
    if (it == arcs_.end()) {
      const Vec &n0 = normals_[v][lo], &n1 = normals_[v][hi];
      const std::size_t m = std::max<std::size_t>(1, std::size_t(std::ceil(angle_between(n0, n1) / step_)));
      std::vector<Index> pts{points_[v][lo]};
      for (std::size_t q = 1; q < m; ++q)
        pts.push_back(add_point(add(in_.points[v], mul(slerp(n0, n1, double(q) / m), d_))));
      pts.push_back(points_[v][hi]);
      it = arcs_.emplace(key, std::move(pts)).first;
    }
    std::vector<Index> out = it->second;
    if (a > b) std::reverse(out.begin(), out.end());
    return out;
  }

  const Soup& in_;
  double d_, step_;
  OffsetReport& r_;
  std::vector<Vec> normal_;
  std::vector<std::uint32_t> twin_;
  std::vector<char> sharp_;
  std::vector<std::uint32_t> corner_point_, sector_;
  std::map<Index, std::vector<Vec>> normals_;     // per vertex: its sectors' normals
  std::map<Index, std::vector<Index>> points_;    // per vertex: its sectors' points
  std::map<std::pair<Index, std::uint64_t>, std::vector<Index>> arcs_;
  Soup out_;
};

/// Removes the regularized components that are not part of the offset's
/// boundary: at a vertex where the surface folds (concave outwards, convex
/// inwards), the raw offset's inverted strips and patch enclose small pockets
/// the winding number counts (solid ones inwards, cavities outwards). Every
/// point of the true offset's boundary is at distance |d| from the input, and
/// the raw offset's chords at least |d| - tol; a component whose median vertex
/// is nearer than `inside` lies inside the offset and is dropped.
void drop_pockets(const Soup& input, const Soup& raw, double inside, RegularizeResult& reg, OffsetReport& r) {
  Soup& s = reg.soup;
  const std::size_t F = s.face_count();
  if (F == 0) return;
  const detail::SurfaceDistance distance(input);
  std::vector<double> vertex_distance(s.points.size(), -1);
  for (std::size_t f = 0; f < F; ++f)
    for (Index v : s.face(f))
      if (vertex_distance[v] < 0) vertex_distance[v] = std::sqrt(distance.squared_distance(s.points[v]));
  // Two groupings: faces sharing a vertex (a cluster of pockets touching each
  // other goes as one), then faces sharing an edge (a pocket touching the
  // rest of the surface at a vertex goes alone).
  std::vector<char> drop(F, 0);
  const std::size_t before = r.pockets_removed;
  for (const bool by_vertex : {true, false}) {
    UnionFind components(F);
    std::vector<std::pair<std::uint64_t, Index>> keys;  // (vertex or edge, face)
    for (std::size_t f = 0; f < F; ++f) {
      if (drop[f]) continue;
      for (int e = 0; e < 3; ++e) {
        const Index a = s.face(f)[e], b = s.face(f)[(e + 1) % 3];
        keys.push_back({by_vertex ? std::uint64_t(a) : (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b),
                        Index(f)});
      }
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t k = 1; k < keys.size(); ++k)
      if (keys[k].first == keys[k - 1].first) components.unite(keys[k].second, keys[k - 1].second);
    std::map<std::size_t, std::vector<double>> by_component;
    for (std::size_t f = 0; f < F; ++f)
      if (!drop[f])
        for (Index v : s.face(f)) by_component[components.find(f)].push_back(vertex_distance[v]);
    std::vector<char> drop_root(F, 0);
    for (auto& [root, d] : by_component) {
      std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
      if (d[d.size() / 2] < inside) {
        drop_root[root] = 1;
        ++r.pockets_removed;
      }
    }
    for (std::size_t f = 0; f < F; ++f)
      if (!drop[f] && drop_root[components.find(f)]) drop[f] = 1;
  }
  if (r.pockets_removed == before) return;
  Soup kept;
  std::vector<std::size_t> source;
  std::vector<std::int64_t> id(s.points.size(), -1);
  std::size_t kept_faces = 0;
  for (std::size_t f = 0; f < F; ++f) {
    const FaceView v = s.face(f);
    if (drop[f]) {
      ++r.pocket_faces;
      continue;
    }
    std::array<Index, 3> t;
    for (int k = 0; k < 3; ++k) {
      if (id[v[k]] < 0) {
        id[v[k]] = std::int64_t(kept.points.size());
        kept.points.push_back(s.points[v[k]]);
      }
      t[k] = Index(id[v[k]]);
    }
    kept.add_triangle(t[0], t[1], t[2]);
    source.push_back(reg.source_face[f]);
  }
  for (std::size_t f = 0; f < kept.face_count(); ++f) kept_faces += kept_as_input(raw, kept, source, f) ? 1 : 0;
  std::vector<Point3d> raw_points = raw.points;
  std::sort(raw_points.begin(), raw_points.end());
  std::size_t made = 0;
  for (const Point3d& p : kept.points) made += std::binary_search(raw_points.begin(), raw_points.end(), p) ? 0 : 1;
  s = std::move(kept);
  reg.source_face = std::move(source);
  reg.report.faces_out = s.face_count();
  reg.report.vertices_out = s.points.size();
  reg.report.new_vertices = made;
  reg.report.faces_kept = kept_faces;
}

}  // namespace

OffsetResult offset(const Soup& input, const OffsetOptions& o) {
  OffsetResult result;
  OffsetReport& r = result.report;
  if (!(o.distance != 0) || !std::isfinite(o.distance)) throw UnsupportedInput("the offset distance must be non-zero");
  if (!input.is_triangle_soup()) throw UnsupportedInput("not a triangle mesh (polygons with more than 3 corners)");
  {
    // The raw offset is built in doubles (normals, strip and patch points),
    // whose squared lengths underflow on a mesh far below unit scale (a cube
    // of side 1e-100 lost every face), and a distance below the coordinates'
    // resolution moves nothing (every face then looks like a fold).
    double extent = 0;
    for (int a = 0; a < 3; ++a) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (Index v : input.indices) {
        lo = std::min(lo, input.points[v][a]);
        hi = std::max(hi, input.points[v][a]);
      }
      if (hi >= lo) extent = std::max(extent, hi - lo);
    }
    auto g = [](double x) {
      char t[32];
      std::snprintf(t, sizeof t, "%g", x);
      return std::string(t);
    };
    if (extent > 0 && (extent < 1e-50 || extent > 1e100))
      throw UnsupportedInput("the mesh spans " + g(extent) +
                             ": offset builds its raw surface in doubles and needs an extent within [1e-50, 1e100] "
                             "(scale the mesh first)");
    if (std::abs(o.distance) < 1e-12 * extent)
      throw UnsupportedInput("the offset distance " + g(o.distance) + " is below 1e-12 of the mesh's extent " +
                             g(extent) + ": its coordinates cannot resolve it");
  }
  r.distance = o.distance;
  r.tolerance = o.tolerance > 0 ? o.tolerance : 0.01 * std::abs(o.distance);
  const double ratio = std::min(1.0, r.tolerance / std::abs(o.distance));
  const double step = 2 * std::acos(1 - ratio);
  r.chord_angle_degrees = step * 180.0 / 3.14159265358979323846;
  r.faces = input.face_count();
  const auto t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("raw offset");
  RawOffset raw(input, o.distance, step, r);
  result.raw = raw.build();
  r.raw_faces = result.raw.face_count();
  r.raw_vertices = result.raw.points.size();
  r.seconds_raw = seconds_since(t0);
  if (!o.regularize) {
    result.soup = result.raw;
    result.source_face.resize(result.raw.face_count());
    std::iota(result.source_face.begin(), result.source_face.end(), std::size_t(0));
    return result;
  }
  RegularizeOptions ro;
  ro.certify = false;
  ro.observer = o.observer;
  ro.float_coordinates = o.float_coordinates;
  RegularizeResult reg = regularize(result.raw, ro);
  r.regularized = true;
  drop_pockets(input, result.raw, std::abs(o.distance) - 2 * r.tolerance, reg, r);
  if (o.certify) certify(result.raw, reg.soup, reg.source_face, reg.report, reg.scanned);
  r.regularize = reg.report;
  result.soup = std::move(reg.soup);
  result.source_face = std::move(reg.source_face);
  result.scanned = std::move(reg.scanned);
  return result;
}

}  // namespace polyheal
