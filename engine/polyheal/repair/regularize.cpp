// polyheal — regularization of a self-overlapping closed mesh (Jung, Shin &
// Choi); the stages and the generalisations are described in regularize.h.
#include "polyheal/repair/regularize.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <unordered_map>

#include "polyheal/mesh/convert.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/mesh.h"
#include "polyheal/mesh/weld.h"
#include "polyheal/repair/deintersect.h"
#include "polyheal/repair/detail/distance.h"

namespace polyheal {
namespace {

using K = Kernel;  // Epeck: every construction below is exact
using EPoint = K::Point_3;
using EVector = K::Vector_3;
using IK = InputKernel;  // the input's doubles: exact filtered predicates

// §3.5: the constrained Delaunay triangulation of one triangle, in its plane
// projected along the dominant normal axis (dropping a coordinate is exact).
// Constraints that cross get their crossing point constructed exactly.
struct VertexInfo {
  std::int64_t id = -1;  // global vertex id; -1: a crossing the triangulation constructed
};
using Vb = CGAL::Triangulation_vertex_base_with_info_2<VertexInfo, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_intersections_tag>;

// The winding-number lines: an AABB tree of the input triangles in doubles.
using InputTriangles = std::vector<IK::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<IK, InputTriangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<IK, Primitive>>;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::uint64_t edge_key(Index a, Index b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

struct XyzLess {
  bool operator()(const EPoint& a, const EPoint& b) const { return CGAL::compare_xyz(a, b) == CGAL::SMALLER; }
};

enum State : char { kUnvisited = 0, kValid = 1, kInvalid = 2 };

/// A triangle of the arrangement being classified: an input triangle, or one
/// of the sub-triangles a partially valid triangle is split into (§3.5).
struct Piece {
  std::array<Index, 3> v;  // global vertex ids, oriented like the source triangle
  Index source;            // input face it lies in
  bool alive = true;       // false once the input triangle is split
  State state = kUnvisited;
};

/// The coordinate axes (i, j) that remain when axis k is dropped, in cyclic
/// order: then the 2D orientation of a projected triangle has the sign of
/// its normal's k component.
std::array<int, 2> kept_axes(int k) { return {(k + 1) % 3, (k + 2) % 3}; }

class Regularizer {
 public:
  Regularizer(const Soup& soup, const std::vector<FacePair>& pairs, const Report& report, RegularizeReport& r)
      : soup_(soup), r_(r), partners_(soup.face_count()), split_(soup.face_count(), 0),
        closed_(soup.face_count(), 0), registered_(soup.points.size(), 0), subs_(soup.face_count()) {
    points_.reserve(soup.points.size());
    for (const Point3d& p : soup.points) points_.emplace_back(p[0], p[1], p[2]);
    for (const FacePair& p : pairs) {
      partners_[p.first].push_back(Index(p.second));
      partners_[p.second].push_back(Index(p.first));
    }
    pieces_.reserve(soup.face_count());
    for (std::size_t f = 0; f < soup.face_count(); ++f) {
      const FaceView fv = soup.face(f);
      pieces_.push_back({{fv[0], fv[1], fv[2]}, Index(f)});
      for (int e = 0; e < 3; ++e) {
        edges_[edge_key(fv[e], fv[(e + 1) % 3])].push_back(Index(f));
        face_edges_[edge_key(fv[e], fv[(e + 1) % 3])].push_back(Index(f));
      }
    }
    triangles_.reserve(soup.face_count());
    for (std::size_t f = 0; f < soup.face_count(); ++f) {
      const FaceView fv = soup.face(f);
      auto ip = [&](Index v) { return IK::Point_3(soup.points[v][0], soup.points[v][1], soup.points[v][2]); };
      triangles_.emplace_back(ip(fv[0]), ip(fv[1]), ip(fv[2]));
    }
    tree_.insert(triangles_.begin(), triangles_.end());
    tree_.build();
    for (int k = 0; k < 3; ++k) below_[k] = report.bbox_min[k] - (1.0 + std::abs(report.bbox_min[k]));
  }

  /// §3.3-3.6 with the generalised seeds: every piece ends valid, invalid,
  /// or (reported) unclassified.
  void run(Observer* observer) {
    const std::size_t faces = soup_.face_count();
    // Seeds among the intersection-free triangles first (no sub-triangulation
    // needed to classify them), then among the sub-triangles of what is left.
    for (std::size_t f = 0; f < faces; ++f) {
      if (observer && f % 4096 == 0) observer->progress(0.5 * double(f) / double(faces));
      if (partners_[f].empty() && pieces_[f].state == kUnvisited) seed(Index(f));
    }
    for (std::size_t f = 0; f < faces; ++f) {
      if (observer && f % 4096 == 0) observer->progress(0.5 + 0.5 * double(f) / double(faces));
      if (partners_[f].empty()) continue;
      if (!split_[f]) {
        // A triangle the valid region never reached: classify it only if
        // something of it could still be valid (a sub-triangle not reached).
        split(Index(f));
      }
      for (Index q : subs_[f])
        if (pieces_[q].state == kUnvisited) seed(q);
    }
  }

  /// The valid pieces as a soup: input vertices keep their doubles, new
  /// points are rounded to the nearest double.
  Soup output(std::vector<std::size_t>& source) const {
    Soup out;
    std::vector<std::int64_t> id(points_.size(), -1);
    for (const Piece& p : pieces_) {
      if (!p.alive || p.state != kValid) continue;
      std::array<Index, 3> f;
      for (int k = 0; k < 3; ++k) {
        std::int64_t& i = id[p.v[k]];
        if (i < 0) {
          i = std::int64_t(out.points.size());
          out.points.push_back(p.v[k] < soup_.points.size() ? soup_.points[p.v[k]] : nearest_point3d(points_[p.v[k]]));
        }
        f[k] = Index(i);
      }
      out.add_triangle(f[0], f[1], f[2]);
      source.push_back(p.source);
    }
    return out;
  }

  /// Counts per input triangle (Fig. 2's groups) and the components that
  /// lost every face.
  void tally() {
    const std::size_t faces = soup_.face_count();
    std::vector<char> has_valid(faces, 0);
    for (const Piece& p : pieces_) {
      if (!p.alive) continue;
      if (p.state == kValid) has_valid[p.source] = 1;
      if (p.state == kUnvisited) ++r_.unclassified;
    }
    for (std::size_t f = 0; f < faces; ++f) {
      if (!has_valid[f]) ++r_.invalid;
      else if (split_[f]) ++r_.partially_valid;
      else ++r_.valid;
    }
    // components through shared edges (union-find)
    std::vector<Index> parent(faces);
    std::iota(parent.begin(), parent.end(), Index(0));
    auto find = [&](Index x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (const auto& [key, list] : face_edges_)
      for (std::size_t k = 1; k < list.size(); ++k) parent[find(list[k])] = find(list[0]);
    std::vector<char> root_kept(faces, 0), root_seen(faces, 0);
    for (std::size_t f = 0; f < faces; ++f) {
      const Index root = find(Index(f));
      root_seen[root] = 1;
      if (has_valid[f]) root_kept[root] = 1;
    }
    for (std::size_t f = 0; f < faces; ++f) {
      if (root_seen[f]) ++r_.components_in;
      if (root_seen[f] && !root_kept[f]) ++r_.components_removed;
    }
  }

  std::size_t new_points() const { return points_.size() - soup_.points.size(); }
  double seconds_intersections = 0;

 private:
  // ---- seeds (§3.3, generalised) -----------------------------------------

  void seed(Index q) {
    ++r_.seeds;
    const std::optional<int> w = winding_outside(q);
    if (!w) return;  // left for the growth to reach; unclassified if it never does
    flood(q, *w == 0 ? kValid : kInvalid);
  }

  /// The winding number of the input surface just outside piece q (on the
  /// side its normal points to), decided exactly: a line parallel to the
  /// dominant axis k of q's normal, through a point of q with double
  /// coordinates, crosses the input triangles; those beyond q count +-1 by
  /// the sign of their normal along the line. nullopt when no tried line
  /// avoids every edge and vertex.
  std::optional<int> winding_outside(Index q) {
    const Piece& piece = pieces_[q];
    const FaceView src = soup_.face(piece.source);
    const Point3d& s0 = soup_.points[src[0]];
    const Point3d& s1 = soup_.points[src[1]];
    const Point3d& s2 = soup_.points[src[2]];
    const Point3d u{s1[0] - s0[0], s1[1] - s0[1], s1[2] - s0[2]}, v{s2[0] - s0[0], s2[1] - s0[1], s2[2] - s0[2]};
    const Point3d n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    int k = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(n[a]) > std::abs(n[k])) k = a;
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    auto p2 = [&](const Point3d& p) { return IK::Point_2(p[i], p[j]); };
    // the exact sign of the source's normal along k (nonzero: k is dominant
    // and the triangle is not degenerate; checked anyway)
    const int sign_k = int(CGAL::orientation(p2(s0), p2(s1), p2(s2)));
    if (sign_k == 0) return std::nullopt;
    const std::array<K::Point_2, 3> corners{proj(points_[piece.v[0]], i, j), proj(points_[piece.v[1]], i, j),
                                            proj(points_[piece.v[2]], i, j)};
    static const double weights[][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.25, 0.25}, {0.25, 0.5, 0.25},
                                        {0.25, 0.25, 0.5},         {0.4, 0.35, 0.25},   {0.3, 0.3, 0.4}};
    for (const auto& w : weights) {
      const K::FT ci = corners[0].x() * w[0] + corners[1].x() * w[1] + corners[2].x() * w[2];
      const K::FT cj = corners[0].y() * w[0] + corners[1].y() * w[1] + corners[2].y() * w[2];
      const double s = nearest_double(ci), t = nearest_double(cj);
      const K::Point_2 at(s, t);
      // strictly inside q's projection (q is counter-clockwise there iff sign_k > 0)
      bool inside = true;
      for (int e = 0; e < 3 && inside; ++e)
        inside = int(CGAL::orientation(corners[e], corners[(e + 1) % 3], at)) == sign_k;
      if (!inside) continue;
      ++r_.line_casts;
      const std::optional<int> winding = cast(piece.source, k, s, t, sign_k);
      if (winding) return winding;
    }
    return std::nullopt;
  }

  /// The line {x_i = s, x_j = t} against the input triangles: the signed
  /// crossings beyond face `source` on its outer side (sign_k: the sign of
  /// its normal along k). nullopt when the line meets an edge or a vertex.
  std::optional<int> cast(Index source, int k, double s, double t, int sign_k) {
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    double o[3], d[3] = {0, 0, 0};
    o[i] = s;
    o[j] = t;
    o[k] = below_[k];
    d[k] = 1;
    const IK::Ray_3 ray(IK::Point_3(o[0], o[1], o[2]), IK::Vector_3(d[0], d[1], d[2]));
    std::vector<Primitive::Id> hits;
    tree_.all_intersected_primitives(ray, std::back_inserter(hits));
    const K::FT at_source = plane_coordinate(source, k, s, t);
    const IK::Point_2 at(s, t);
    int winding = 0;
    for (const auto& hit : hits) {
      const Index g = Index(hit - triangles_.begin());
      if (g == source) continue;
      const FaceView gv = soup_.face(g);
      std::array<IK::Point_2, 3> c;
      for (int e = 0; e < 3; ++e) c[e] = IK::Point_2(soup_.points[gv[e]][i], soup_.points[gv[e]][j]);
      const CGAL::Orientation og = CGAL::orientation(c[0], c[1], c[2]);
      if (og == CGAL::COLLINEAR) return std::nullopt;  // the line lies in g's plane
      int same = 0;
      for (int e = 0; e < 3; ++e) {
        const CGAL::Orientation oe = CGAL::orientation(c[e], c[(e + 1) % 3], at);
        if (oe == CGAL::COLLINEAR) return std::nullopt;  // through an edge or a vertex of g
        same += oe == og ? 1 : 0;
      }
      if (same != 3) continue;  // the box was hit, not the triangle
      const CGAL::Comparison_result c_at = CGAL::compare(plane_coordinate(g, k, s, t), at_source);
      if (c_at == CGAL::EQUAL) return std::nullopt;
      const bool beyond = sign_k > 0 ? c_at == CGAL::LARGER : c_at == CGAL::SMALLER;
      if (beyond) winding += sign_k * int(og);  // sign of (direction . normal of g)
    }
    return winding;
  }

  /// The k coordinate where the line {x_i = s, x_j = t} meets face f's plane.
  K::FT plane_coordinate(Index f, int k, double s, double t) const {
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    const FaceView fv = soup_.face(f);
    const EVector n = CGAL::cross_product(points_[fv[1]] - points_[fv[0]], points_[fv[2]] - points_[fv[0]]);
    const EPoint& a = points_[fv[0]];
    return a[k] - (n[i] * (K::FT(s) - a[i]) + n[j] * (K::FT(t) - a[j])) / n[k];
  }

  static K::Point_2 proj(const EPoint& p, int i, int j) { return K::Point_2(p[i], p[j]); }

  // ---- growth (§3.4, §3.6) ------------------------------------------------

  /// Marks q with `state` and spreads it. Valid: to every continuation
  /// (§3.4 through intersection-free neighbours, §3.6 across the river).
  /// Invalid: only across edges with exactly two pieces (the winding numbers
  /// on both sides carry over) and never into a triangle not yet split.
  void flood(Index q, State state) {
    std::vector<Index> front{q};
    pieces_[q].state = state;
    while (!front.empty()) {
      const Index p = front.back();
      front.pop_back();
      if (split_[pieces_[p].source]) close(pieces_[p].source);
      const Piece piece = pieces_[p];
      for (int e = 0; e < 3; ++e) {
        const Index a = piece.v[e], b = piece.v[(e + 1) % 3];
        std::optional<Index> next;
        if (state == kValid) {
          const std::vector<Index> around = pieces_around(a, b, true);
          if (around.size() == 2) {
            const Index other = around[0] == p ? around[1] : around[0];
            if (traverses(other, b, a)) next = other;
          } else if (around.size() > 2) {
            next = continuation(p, a, b, around);
          }
          if (!next) {
            ++r_.orientation_conflicts;
            continue;
          }
        } else {
          const std::vector<Index> around = pieces_around(a, b, false);
          if (around.size() != 2) continue;
          const Index other = around[0] == p ? around[1] : around[0];
          if (!traverses(other, b, a)) continue;
          const Index src = pieces_[other].source;
          if (!partners_[src].empty() && !split_[src]) continue;  // partially valid, perhaps
          next = other;
        }
        Piece& n = pieces_[*next];
        if (n.state == state) continue;
        if (n.state != kUnvisited) {
          ++r_.orientation_conflicts;  // reached as valid and as invalid
          continue;
        }
        n.state = state;
        front.push_back(*next);
      }
    }
  }

  bool traverses(Index p, Index a, Index b) const {
    const auto& v = pieces_[p].v;
    for (int e = 0; e < 3; ++e)
      if (v[e] == a && v[(e + 1) % 3] == b) return true;
    return false;
  }

  /// The live pieces with edge ab. With `complete`, an input triangle among
  /// them that intersects others is split first (its pieces take its place).
  std::vector<Index> pieces_around(Index a, Index b, bool complete) {
    for (;;) {
      std::vector<Index> out;
      const auto it = edges_.find(edge_key(a, b));
      if (it == edges_.end()) return out;
      bool again = false;
      for (Index p : it->second) {
        if (!pieces_[p].alive) continue;
        const Index src = pieces_[p].source;
        if (complete && !partners_[src].empty() && !split_[src]) {
          split(src);
          again = true;
          break;
        }
        out.push_back(p);
      }
      if (!again) return out;
    }
  }

  /// §3.6 crossing the river, generalised: the pieces around edge ab sorted
  /// by angle, starting from p's outer side; the winding number of each
  /// wedge followed from 0 (p is valid); the first piece that bounds a
  /// wedge of winding 0 on its outer side and 1 on its inner side.
  std::optional<Index> continuation(Index p, Index a, Index b, const std::vector<Index>& around) {
    const EPoint& A = points_[a];
    const EVector u = points_[b] - A;
    const EVector n0 = CGAL::cross_product(u, points_[third(p, a, b)] - A);
    struct Item {
      Index piece;
      EVector w;      // third vertex - A
      int half;       // 0: angle in (0, pi) from p, 1: pi, 2: (pi, 2 pi)
      bool entering;  // traverses b -> a: crossing it while rotating enters its inside
    };
    std::vector<Item> items;
    for (Index q : around) {
      if (q == p) continue;
      const EVector w = points_[third(q, a, b)] - A;
      const CGAL::Sign side = CGAL::sign(n0 * w);
      int half = side == CGAL::POSITIVE ? 0 : side == CGAL::NEGATIVE ? 2 : 1;
      if (half == 1 && CGAL::is_positive(n0 * CGAL::cross_product(u, w)))
        throw UnsupportedInput(coplanar_message(pieces_[p].source, pieces_[q].source));
      items.push_back({q, w, half, traverses(q, b, a)});
    }
    auto before = [&](const Item& x, const Item& y) {
      if (x.half != y.half) return x.half < y.half;
      if (x.half == 1) return false;
      return CGAL::is_positive(CGAL::cross_product(u, x.w) * y.w);
    };
    std::sort(items.begin(), items.end(), before);
    for (std::size_t k = 1; k < items.size(); ++k)
      if (!before(items[k - 1], items[k]))  // same half-plane: coincident pieces
        throw UnsupportedInput(coplanar_message(pieces_[items[k - 1].piece].source, pieces_[items[k].piece].source));
    int winding = 0;
    for (const Item& item : items) {
      if (item.entering) {
        if (winding == 0) return item.piece;
        ++winding;
      } else {
        --winding;
      }
    }
    return std::nullopt;
  }

  Index third(Index p, Index a, Index b) const {
    for (Index v : pieces_[p].v)
      if (v != a && v != b) return v;
    return pieces_[p].v[0];
  }

  static std::string coplanar_message(Index f, Index g) {
    return "faces " + std::to_string(f) + " and " + std::to_string(g) +
           " overlap in a common plane; regularize does not resolve coplanar overlaps";
  }

  // ---- sub-triangulation (§3.5) ------------------------------------------

  /// Splits t, every triangle it intersects and every intersecting neighbour
  /// across its edges: then every piece that can share an edge with a piece
  /// of t exists.
  void close(Index t) {
    if (closed_[t]) return;
    closed_[t] = 1;
    split(t);
    for (Index u : partners_[t]) split(u);
    const FaceView fv = soup_.face(t);
    for (int e = 0; e < 3; ++e)
      for (Index n : face_edges_[edge_key(fv[e], fv[(e + 1) % 3])])
        if (!partners_[n].empty()) split(n);
  }

  /// Replaces input triangle t (which intersects others) by its
  /// sub-triangles: §3.5 steps 1-3.
  void split(Index t) {
    if (split_[t] || partners_[t].empty()) return;
    split_[t] = 1;
    ++r_.triangles_split;
    const FaceView fv = soup_.face(t);
    // Corners of t and of what it meets first, so that an intersection
    // point that is an input vertex gets that vertex's id.
    for (Index v : fv) register_vertex(v);
    for (Index u : partners_[t])
      for (Index v : soup_.face(u)) register_vertex(v);
    const EVector n = CGAL::cross_product(points_[fv[1]] - points_[fv[0]], points_[fv[2]] - points_[fv[0]]);
    int k = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(CGAL::to_double(n[a])) > std::abs(CGAL::to_double(n[k]))) k = a;
    if (CGAL::is_zero(n[k])) k = !CGAL::is_zero(n[0]) ? 0 : !CGAL::is_zero(n[1]) ? 1 : 2;
    const int i = kept_axes(k)[0], j = kept_axes(k)[1];
    CDT cdt;
    auto insert = [&](Index id) {
      const CDT::Vertex_handle h = cdt.insert(proj(points_[id], i, j));
      if (h->info().id < 0) h->info().id = id;
      return h;
    };
    for (Index v : fv) insert(v);
    const auto t0 = std::chrono::steady_clock::now();
    for (Index u : partners_[t]) {
      const std::vector<Index>& seg = segment(t, u);
      if (seg.size() == 1) insert(seg[0]);
      if (seg.size() == 2) cdt.insert_constraint(insert(seg[0]), insert(seg[1]));
    }
    seconds_intersections += seconds_since(t0);
    // crossings of segments (§3.5 step 2), lifted back onto t's plane
    const EPoint& A = points_[fv[0]];
    for (auto h = cdt.finite_vertices_begin(); h != cdt.finite_vertices_end(); ++h) {
      if (h->info().id >= 0) continue;
      std::array<K::FT, 3> c;
      c[i] = h->point().x();
      c[j] = h->point().y();
      c[k] = A[k] - (n[i] * (c[i] - A[i]) + n[j] * (c[j] - A[j])) / n[k];
      h->info().id = vertex_id(EPoint(c[0], c[1], c[2]));
    }
    const bool reverse = CGAL::is_negative(n[k]);
    kill(t);
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      std::array<Index, 3> v{Index(f->vertex(0)->info().id), Index(f->vertex(1)->info().id),
                             Index(f->vertex(2)->info().id)};
      if (reverse) std::swap(v[1], v[2]);
      const Index q = Index(pieces_.size());
      pieces_.push_back({v, t});
      subs_[t].push_back(q);
      for (int e = 0; e < 3; ++e) edges_[edge_key(v[e], v[(e + 1) % 3])].push_back(q);
    }
    r_.sub_triangles += subs_[t].size();
  }

  void kill(Index t) {
    pieces_[t].alive = false;
    const auto& v = pieces_[t].v;
    for (int e = 0; e < 3; ++e) {
      auto& list = edges_[edge_key(v[e], v[(e + 1) % 3])];
      list.erase(std::remove(list.begin(), list.end(), t), list.end());
    }
  }

  /// The intersection of input triangles t and u as global vertex ids (one
  /// point or a segment's two ends), constructed once per pair (§3.2).
  const std::vector<Index>& segment(Index t, Index u) {
    const auto [it, inserted] = segments_.try_emplace(edge_key(t, u));
    if (!inserted) return it->second;
    ++r_.segments;
    auto tri = [&](Index f) {
      const FaceView fv = soup_.face(f);
      return K::Triangle_3(points_[fv[0]], points_[fv[1]], points_[fv[2]]);
    };
    const auto result = CGAL::intersection(tri(t), tri(u));
    std::vector<Index>& ids = it->second;
    if (!result) return ids;
    if (const EPoint* p = boost::get<EPoint>(&*result)) {
      ids.push_back(vertex_id(*p));
    } else if (const K::Segment_3* s = boost::get<K::Segment_3>(&*result)) {
      ids.push_back(vertex_id(s->source()));
      ids.push_back(vertex_id(s->target()));
    } else {
      throw UnsupportedInput(coplanar_message(t, u));
    }
    return ids;
  }

  void register_vertex(Index v) {
    if (registered_[v]) return;
    registered_[v] = 1;
    dedup_.emplace(points_[v], v);
  }

  /// The id of exact point p: an input vertex's (if registered), or a new one.
  Index vertex_id(const EPoint& p) {
    const auto [it, inserted] = dedup_.try_emplace(p, Index(points_.size()));
    if (inserted) points_.push_back(p);
    return it->second;
  }

  const Soup& soup_;
  RegularizeReport& r_;
  std::vector<EPoint> points_;  // input vertices, then points on intersection curves
  std::map<EPoint, Index, XyzLess> dedup_;
  std::vector<std::vector<Index>> partners_;  // per input face: the faces it intersects
  std::vector<char> split_, closed_, registered_;
  std::vector<std::vector<Index>> subs_;  // per input face: its sub-triangles
  std::vector<Piece> pieces_;             // input faces (ids 0..F-1), then sub-triangles
  std::unordered_map<std::uint64_t, std::vector<Index>> edges_;       // pieces by edge
  std::unordered_map<std::uint64_t, std::vector<Index>> face_edges_;  // input faces by edge
  std::unordered_map<std::uint64_t, std::vector<Index>> segments_;    // by face pair
  InputTriangles triangles_;
  Tree tree_;
  double below_[3];
};

}  // namespace

RegularizeResult regularize(const Soup& raw, const RegularizeOptions& o) {
  RegularizeResult result;
  RegularizeReport& r = result.report;
  auto t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("detecting");
  if (!raw.is_triangle_soup()) throw UnsupportedInput("not a triangle mesh (polygons with more than 3 corners)");
  const Soup input = apply_weld(raw, weld_identical_points(raw.points));
  InspectOptions io;
  io.observer = o.observer;
  const Report in = inspect(input, io);
  if (in.faces == 0) throw UnsupportedInput("no faces");
  if (!in.boundary_edges.empty())
    throw UnsupportedInput("not closed (" + std::to_string(in.boundary_edges.size()) +
                           " boundary edges, first at face " + std::to_string(in.boundary_edges.front().faces.front()) +
                           "); regularize needs a closed surface");
  if (!in.misoriented_edges.empty())
    throw UnsupportedInput("not consistently oriented (first at face " +
                           std::to_string(in.misoriented_edges.front().faces.front()) + ")");
  if (!in.degenerate_faces.empty())
    throw UnsupportedInput(std::to_string(in.degenerate_faces.size()) + " zero-area faces (first: face " +
                           std::to_string(in.degenerate_faces.front()) +
                           "); remove them first (polyheal degenerate), §3.1");
  if (!in.duplicate_faces.empty())
    throw UnsupportedInput("duplicate faces " + std::to_string(in.duplicate_faces.front()[0]) + " and " +
                           std::to_string(in.duplicate_faces.front()[1]));
  if (in.signed_volume < 0)
    throw UnsupportedInput("the surface encloses a negative volume (its faces point inwards); reverse it first");
  r.faces = in.faces;
  r.vertices = raw.points.size();
  r.intersecting_pairs_in = in.self_intersections.size();
  {
    std::vector<std::size_t> fs;
    for (const FacePair& p : in.self_intersections) {
      fs.push_back(p.first);
      fs.push_back(p.second);
    }
    std::sort(fs.begin(), fs.end());
    r.intersecting_faces_in = std::size_t(std::unique(fs.begin(), fs.end()) - fs.begin());
  }
  r.bbox_diagonal = std::sqrt(std::pow(in.bbox_max[0] - in.bbox_min[0], 2) + std::pow(in.bbox_max[1] - in.bbox_min[1], 2) +
                              std::pow(in.bbox_max[2] - in.bbox_min[2], 2));
  r.seconds_detect = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("growing the valid region");
  Regularizer grow(input, in.self_intersections, in, r);
  grow.run(o.observer);
  grow.tally();
  r.seconds_intersections = grow.seconds_intersections;
  r.seconds_grow = seconds_since(t0) - r.seconds_intersections;

  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("stitching");
  result.soup = grow.output(result.source_face);
  r.new_vertices = grow.new_points();
  r.faces_out = result.soup.face_count();
  r.vertices_out = result.soup.points.size();
  for (std::size_t f = 0; f < result.soup.face_count(); ++f) {
    const FaceView a = input.face(result.source_face[f]), b = result.soup.face(f);
    bool same = true;
    for (int k = 0; k < 3 && same; ++k) same = input.points[a[k]] == result.soup.points[b[k]];
    r.faces_kept += same ? 1 : 0;
  }
  // Certify after rounding: a point on an intersection curve rounded to
  // doubles can make faces intersect again; deintersect's vertex moves (in
  // doubles) repair that where they can.
  if (o.observer) o.observer->stage("checking the rounded surface");
  const std::vector<FacePair> rounded = find_self_intersections(result.soup);
  r.rounding_pairs = rounded.size();
  if (!rounded.empty()) {
    DeintersectOptions d;
    d.certify = false;
    try {
      DeintersectResult fixed = remove_self_intersections(result.soup, d);
      r.rounding_moves = fixed.report.moved_vertices;
      result.soup = std::move(fixed.soup);
    } catch (const UnsupportedInput&) {
      // not a manifold mesh: the certificate reports what is left
    }
  }
  r.seconds_stitch = seconds_since(t0);

  if (o.certify) {
    t0 = std::chrono::steady_clock::now();
    if (o.observer) o.observer->stage("certifying");
    certify(raw, result.soup, result.source_face, r);
    r.seconds_certify = seconds_since(t0);
  }
  return result;
}

void certify(const Soup& input, const Soup& written, const std::vector<std::size_t>& source_face,
             RegularizeReport& r) {
  r.out = inspect(written);
  // Output -> input: each output triangle lies in the input triangle it came
  // from up to rounding; the distance to one triangle is convex, so its
  // corners bound it.
  r.max_distance_to_input = 0;
  if (source_face.size() == written.face_count())
    for (std::size_t f = 0; f < written.face_count(); ++f) {
      const FaceView s = input.face(source_face[f]);
      for (Index v : written.face(f))
        r.max_distance_to_input = std::max(
            r.max_distance_to_input,
            std::sqrt(detail::squared_distance_to_triangle(written.points[v], input.points[s[0]], input.points[s[1]],
                                                           input.points[s[2]])));
    }
  const double bound = 1e-3 * r.bbox_diagonal;
  r.hausdorff = detail::hausdorff_distance(input, written, bound);
  r.hausdorff_error_bound = bound;
  r.certified = r.out.certified_clean();
}

}  // namespace polyheal
