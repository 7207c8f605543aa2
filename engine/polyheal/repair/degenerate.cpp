#include "polyheal/repair/degenerate.h"

#include <CGAL/boost/graph/Euler_operations.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <deque>
#include <map>
#include <set>

#include "polyheal/inspect/exact_predicates.h"
#include "polyheal/inspect/local_index.h"
#include "polyheal/mesh/convert.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/weld.h"
#include "polyheal/repair/detail/apex_fan.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/detail/plane_slice.h"
#include "polyheal/repair/detail/shape_decimation.h"

namespace polyheal {
namespace {

using Triple = std::array<vertex_descriptor, 3>;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Where c's projection onto line ab falls: 0 at a, 1 at b (NaN when a = b).
double position_along(const Point3d& a, const Point3d& b, const Point3d& c) {
  return dot(sub(c, a), sub(b, a)) / squared_norm(sub(b, a));
}

ShapeCounts shape_counts(const Report& r) { return {r.degenerate_faces.size(), r.caps.size(), r.needles.size()}; }

InspectOptions inspect_options(const DegenerateOptions& o) {
  InspectOptions io;
  io.cap_angle = o.cap_angle;
  io.needle_angle = o.needle_angle;
  return io;
}

/// Stage 1: identical points welded (and points closer than `near`, when
/// positive), faces with a repeated index dropped. `near_welded` and
/// `max_move` tell what the near weld did.
Soup preprocess(const Soup& input, double near, std::size_t& dropped, std::size_t& near_welded, double& max_move) {
  Weld weld = weld_identical_points(input.points);
  near_welded = 0;
  max_move = 0;
  if (near > 0) {
    weld.representative = weld_near_points(input.points, weld.representative, near, near_welded, max_move);
    weld.merged += near_welded;
  }
  const Soup welded = weld.merged ? apply_weld(input, weld) : input;
  Soup out;
  out.points = welded.points;
  dropped = 0;
  for (std::size_t f = 0; f < welded.face_count(); ++f) {
    const FaceView face = welded.face(f);
    std::vector<Index> ids(face.begin(), face.end());
    std::sort(ids.begin(), ids.end());
    if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) {
      ++dropped;
      continue;
    }
    out.add_face(face.begin(), face.end());
  }
  return out;
}
Soup preprocess(const Soup& input, std::size_t& dropped) {
  std::size_t near_welded = 0;
  double max_move = 0;
  return preprocess(input, 0, dropped, near_welded, max_move);
}

/// The working mesh, with all machinery of stages 2-4.
class Pipeline {
 public:
  /// A thin quad split by its diagonal ab into two needles: sides a -> c
  /// and d -> b run from the same end; the sides get `pieces` pieces.
  struct Strip {
    vertex_descriptor a, b, c, d;
    int pieces;
    face_descriptor n, m;  // (a, b, c) and (b, a, d)
  };
  using EdgeKey = std::pair<vertex_descriptor, vertex_descriptor>;  // smaller index first
  static EdgeKey edge_key(vertex_descriptor u, vertex_descriptor w) { return u < w ? EdgeKey{u, w} : EdgeKey{w, u}; }
  /// The points of a side: j/q for 0 < j < q with j's parity. A strip's two
  /// sides share q and take opposite parities, measured from its a/d end.
  struct Grid {
    int pieces, parity;
    std::vector<double> fractions() const {
      std::vector<double> out;
      for (int j = 1; j < pieces; ++j)
        if (j % 2 == parity) out.push_back(double(j) / pieces);
      return out;
    }
    /// The same points measured from the side's other end unless
    /// `same_end`: j/q is (q - j)/q there, of the other parity when q is odd.
    Grid from(bool same_end) const { return same_end ? *this : Grid{pieces, (parity + pieces) % 2}; }
  };

  Pipeline(Mesh& mesh, const detail::SurfaceDistance& input, const DegenerateOptions& o, DegenerateReport& r)
      : mesh_(mesh), o_(o), r_(r), index_(mesh), decimator_(mesh, index_, input, decimation_options(o, r)) {
    cos_cap_ = cos_degrees(o.cap_angle);
    cos_needle_ = cos_degrees(o.needle_angle);
    snap_ = 0.1 * r.tolerance;
    face_limit_ = 3 * mesh.number_of_faces() + 64;
  }

  std::vector<face_descriptor> faces_of(Shape shape) const {
    std::vector<face_descriptor> out;
    for (face_descriptor f : mesh_.faces())
      if (classify_face(mesh_, f, cos_cap_, cos_needle_) == shape) out.push_back(f);
    return out;
  }
  /// One flag per face, in mesh order (the order mesh_to_soup writes).
  std::vector<char> bad_flags() const {
    std::vector<char> out;
    for (face_descriptor f : mesh_.faces()) out.push_back(decimator_.is_bad(f));
    return out;
  }
  std::vector<face_descriptor> bad_faces() const {
    std::vector<face_descriptor> out;
    for (face_descriptor f : mesh_.faces())
      if (decimator_.is_bad(f)) out.push_back(f);
    return out;
  }

  /// From now on the decimation may also remove a vertex and triangulate
  /// its hole anew (ShapeDecimator::set_retriangulate()).
  void retriangulate() { decimator_.set_retriangulate(true); }

  void decimate(const std::vector<face_descriptor>& faces) {
    decimator_.run(faces);
    note_size();
  }

  /// §5 supersampling: three stacks of n evenly spaced axis-aligned planes.
  /// A refused plane is retried at small shifts within its cell.
  void slice_grid(int n) {
    CGAL::Bbox_3 box;
    for (vertex_descriptor v : mesh_.vertices()) box += mesh_.point(v).bbox();
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = box.min(axis), hi = box.max(axis), step = (hi - lo) / (n + 1);
      if (!(step > 0)) continue;
      for (int i = 1; i <= n; ++i) {
        bool done = false;
        for (double shift : {0.0, 0.1, -0.1, 0.2, -0.2, 0.3, -0.3}) {
          const double at = lo + (i + shift) * step;
          std::array<double, 3> normal{0, 0, 0};
          normal[axis] = 1;
          const Kernel::Plane_3 plane{Kernel::FT(normal[0]), Kernel::FT(normal[1]), Kernel::FT(normal[2]),
                                      -Kernel::FT(at)};
          const detail::SliceOptions so = slice_options();
          const detail::SliceResult s = detail::slice_by_plane(mesh_, plane, so);
          if (s.rejected) continue;
          after_slice(s);
          done = true;
          break;
        }
        ++(done ? r_.grid_slices : r_.grid_slices_refused);
      }
    }
    // the supersampled mesh is the new reference for needle supersampling
    face_limit_ = std::max<std::size_t>(face_limit_, 3 * mesh_.number_of_faces() + 64);
  }

  /// §3-4: one slice per cap, until every cap is gone or refused.
  /// Returns the number of caps removed.
  std::size_t slice_caps() {
    refresh_frozen();
    std::size_t removed = 0;
    std::vector<face_descriptor> queue = faces_of(Shape::cap);
    std::vector<char> refused(mesh_.number_of_faces() + 1, 0);
    const std::size_t total = queue.size();
    for (std::size_t k = 0; k < queue.size(); ++k) {
      const face_descriptor cap = queue[k];
      if (o_.observer && total > 0) o_.observer->progress(std::min(1.0, double(k) / double(total)));
      if (mesh_.is_removed(cap) || classify_face(mesh_, cap, cos_cap_, cos_needle_) != Shape::cap) continue;
      if (static_cast<std::size_t>(cap) < refused.size() && refused[static_cast<std::size_t>(cap)]) continue;
      detail::SliceOptions so = slice_options();
      if (!o_.global_slices) so.seed = cap;
      const Kernel::Plane_3 plane = detail::cap_plane(mesh_, cap, so);
      // Local mode cuts short first: across the cap and its neighbours,
      // ended beyond 1.5 long edges (B and C are protected, so the cap's own
      // long edge is always split); if that plan would make a cap, the cut
      // follows its whole connected course.
      detail::SliceResult s;
      if (!o_.global_slices) {
        const Point& b = mesh_.point(so.protected_vertices[0]);
        const Point& c = mesh_.point(so.protected_vertices[1]);
        so.radius = 1.5 * std::sqrt(CGAL::to_double(CGAL::squared_distance(b, c)));
        s = detail::slice_by_plane(mesh_, plane, so);
        so.radius = 0;
      }
      if (o_.global_slices || s.rejected) s = detail::slice_by_plane(mesh_, plane, so);
      if (s.rejected) {
        ++r_.cap_slices_refused;
        if (static_cast<std::size_t>(cap) >= refused.size()) refused.resize(static_cast<std::size_t>(cap) + 1, 0);
        refused[static_cast<std::size_t>(cap)] = 1;
        continue;
      }
      ++r_.cap_slices;
      ++removed;
      after_slice(s);
      for (face_descriptor f : s.faces)  // a cut cap may leave a cap piece (never more caps)
        if (classify_face(mesh_, f, cos_cap_, cos_needle_) == Shape::cap) queue.push_back(f);
      if (o_.interleave) tidy(s);
    }
    return removed;
  }

  /// §5 supersampling where it is needed: a needle that no collapse or flip
  /// within the tolerance removes (the side of a thin strip: its long edges
  /// run along the strip, its short one across) is cut by the plane through
  /// the midpoint of its longest edge, perpendicular to it. The cut adds
  /// points on both sides of the strip, halving the triangles' length; the
  /// decimation right after it uses them, and removes the cut's other points
  /// where they are not needed. At most `budget` slices. Returns the number
  /// of slices made.
  ///
  /// With `wedges`, a needle that is the tip of a wedge gets cut_wedge()
  /// instead.
  std::size_t slice_needles(std::size_t budget, bool short_cuts, bool second_longest, bool wedges) {
    refresh_frozen();
    std::size_t made = 0;
    for (face_descriptor needle : faces_of(Shape::needle)) {
      // Supersampling that keeps failing only grows the mesh (typically
      // where the input self-intersects and no operation there is allowed):
      // stop at three times the input's size and report what is left.
      if (made >= budget || mesh_.number_of_faces() > face_limit_) break;
      if (mesh_.is_removed(needle) || classify_face(mesh_, needle, cos_cap_, cos_needle_) != Shape::needle) continue;
      if (wedges) {
        const std::size_t cuts = cut_wedge(needle);
        if (cuts > 0) {
          made += cuts;
          continue;
        }
        if (mesh_.is_removed(needle) || classify_face(mesh_, needle, cos_cap_, cos_needle_) != Shape::needle) continue;
      }
      // The plane is perpendicular to the needle's longest edge, or on
      // alternate rounds to its second longest (the other long side), which
      // cuts the neighbourhood differently when the first cut did not help.
      std::array<halfedge_descriptor, 3> hs;
      std::array<Kernel::FT, 3> len;
      {
        halfedge_descriptor h = mesh_.halfedge(needle);
        for (int k = 0; k < 3; ++k, h = mesh_.next(h)) {
          hs[k] = h;
          len[k] = CGAL::squared_distance(mesh_.point(mesh_.source(h)), mesh_.point(mesh_.target(h)));
        }
      }
      std::array<int, 3> order{0, 1, 2};
      std::sort(order.begin(), order.end(), [&](int a, int b) { return len[a] > len[b]; });
      // The side of a strip (its apex over an end of the longest edge, the
      // strip's diagonal) is cut into needle_pieces() pieces. Across the
      // diagonal, not across the strip's long side: cut so, cad_cylinder
      // came out with 540 faces instead of 436, ADIS16480 5980 for 5706.
      const bool strip = on_strip(hs[order[0]]);
      const int pick = second_longest ? 1 : 0;
      const halfedge_descriptor longest = hs[order[pick]];
      const Kernel::FT best = len[order[pick]];
      // Where exactly the cut runs does not matter, so the planes are put
      // through double approximations: its split points stay one exact
      // construction deep instead of nesting rationals slice after slice.
      const Point p = nearest_double_point(mesh_.point(mesh_.source(longest)));
      const Point q = nearest_double_point(mesh_.point(mesh_.target(longest)));
      if (p == q) continue;
      // Where along pq the planes cut: i / pieces for a strip's side, the
      // midpoint for a needle, and two points for a flat needle (below).
      std::vector<Kernel::FT> at;
      if (strip) {
        const int pieces = needle_pieces(needle, p, q);
        for (int i = 1; i < pieces; ++i) at.push_back(Kernel::FT(i) / Kernel::FT(pieces));
      } else if (const auto t = pick == 0 ? flat_cut(needle, longest) : std::nullopt) {
        at = {Kernel::FT((*t)[0]), Kernel::FT((*t)[1])};
      } else {
        at = {Kernel::FT(0.5)};
      }
      const int pieces = int(at.size()) + 1;
      // the plane perpendicular to pq through p + at[i - 1] (q - p), at its nearest doubles
      auto plane_at = [&](int i) { return Kernel::Plane_3(nearest_double_point(p + (q - p) * at[i - 1]), q - p); };
      detail::SliceResult all;
      face_descriptor seed = needle;
      int cuts = 0;
      for (int i = 1; i < pieces && seed != Mesh::null_face(); ++i) {
        const Kernel::Plane_3 plane = plane_at(i);
        detail::SliceOptions so = slice_options();
        so.seed = seed;
        so.protected_vertices = {mesh_.source(longest), mesh_.target(longest)};
        // A short cut: across the needle and its neighbours, not around the
        // whole part (the verified plan refuses it if ending early would make
        // a cap; then the cut runs its full course).
        so.radius = short_cuts ? 1.5 * std::sqrt(CGAL::to_double(best)) : 0.0;
        detail::SliceResult s = detail::slice_by_plane(mesh_, plane, so);
        if (s.rejected && so.radius > 0) {
          so.radius = 0;
          s = detail::slice_by_plane(mesh_, plane, so);
        }
        if (s.rejected || s.edges_split == 0) break;  // the cuts so far still serve
        ++cuts;
        after_slice(s);
        all.faces.insert(all.faces.end(), s.faces.begin(), s.faces.end());
        all.vertices.insert(all.vertices.end(), s.vertices.begin(), s.vertices.end());
        // the next plane's seed: a piece of this cut that it crosses
        seed = Mesh::null_face();
        if (i + 1 < pieces) {
          const Kernel::Plane_3 next = plane_at(i + 1);
          for (face_descriptor f : s.faces)
            if (!mesh_.is_removed(f) && crosses(f, next)) {
              seed = f;
              break;
            }
        }
      }
      if (cuts == 0) {
        ++r_.needle_slices_refused;
        continue;
      }
      r_.needle_slices += cuts;
      made += cuts;
      if (cuts > 1) {  // once each, in the order the cuts made them
        std::vector<char> seen(mesh_.number_of_faces() + mesh_.number_of_removed_faces(), 0);
        std::vector<face_descriptor> faces;
        for (face_descriptor f : all.faces)
          if (!mesh_.is_removed(f) && !seen[static_cast<std::size_t>(f)]) {
            seen[static_cast<std::size_t>(f)] = 1;
            faces.push_back(f);
          }
        all.faces = std::move(faces);
      }
      tidy(all);
    }
    return made;
  }

  /// §5 supersampling where a CAD surface needs it most: a cylinder's or
  /// cone's facet, a thin quad split by its diagonal into two needles (the
  /// paper's Fig. 1). Cuts across such a strip put points on both long
  /// sides at the same places (and on the diagonal), and a strip of aspect
  /// A then needs ceil(A tan(needle angle)) pieces, each two triangles. Here
  /// the sides get staggered points instead: with q pieces of the side,
  /// one side gets the points at odd j/q, the other those at even j/q, and
  /// the zigzag between them has q + 1 triangles whose smallest
  /// angles are about atan(q / A) — q = 3 where cuts needed 3 pieces and
  /// 6 triangles (cgal__joint's 30:1 strips: 4 triangles each). Neighbouring
  /// strips share a side, so its points serve both: strips are visited
  /// across their shared sides, and a strip whose one side has points gets
  /// the mirrored positions on the other (in a ring of an odd number of
  /// strips the last one is left with aligned points, and the needle rounds
  /// after it). The split points lie on the sides exactly and the faces
  /// beside them are fanned (detail::split_edges: nothing moves); a strip
  /// with many points is then retriangulated as its zigzag (zigzag()), one
  /// with few is flipped into it by the decimation after it (tidy()), with
  /// every check of an operation. Returns the points made.
  std::size_t stagger_strips() {
    refresh_frozen();
    const std::vector<Strip> strips = find_strips();
    if (strips.empty()) return 0;
    std::map<EdgeKey, std::vector<std::size_t>> by_side;
    std::set<face_descriptor> in_strip;
    for (std::size_t i = 0; i < strips.size(); ++i) {
      const Strip& s = strips[i];
      by_side[edge_key(s.a, s.c)].push_back(i);
      by_side[edge_key(s.d, s.b)].push_back(i);
      for (halfedge_descriptor h : {CGAL::halfedge(s.a, s.b, mesh_).first, CGAL::halfedge(s.b, s.a, mesh_).first})
        in_strip.insert(mesh_.face(h));
    }
    std::map<EdgeKey, Grid> grids;  // measured from the side's smaller vertex index
    std::set<face_descriptor> fanned;  // faces beside a side with a grid (one such side each)
    auto get = [&](vertex_descriptor from, vertex_descriptor to) -> std::optional<Grid> {
      const auto it = grids.find(edge_key(from, to));
      if (it == grids.end()) return std::nullopt;
      return it->second.from(from == edge_key(from, to).first);
    };
    // Grid g (measured from `from`) for the side, unless a face beside it
    // has another side with a grid, is frozen, or (no strip's) would be
    // fanned into a needle or cap. A grid without points (q = 2, parity 0)
    // takes the same test — refused beside a needle that is no strip's, the
    // side is left to the strip across it: fewer faces so (ADIS16480 5688
    // faces; 5830 when such sides were given their empty grid anyway).
    auto put = [&](vertex_descriptor from, vertex_descriptor to, Grid g) {
      const halfedge_descriptor h = CGAL::halfedge(from, to, mesh_).first;
      std::vector<face_descriptor> beside;
      for (halfedge_descriptor x : {h, mesh_.opposite(h)})
        if (!mesh_.is_border(x)) beside.push_back(mesh_.face(x));
      const std::vector<double> points = g.fractions();
      for (face_descriptor f : beside)
        if (fanned.count(f) || is_frozen(f) || (!in_strip.count(f) && !fans_well(f, from, to, points))) return;
      fanned.insert(beside.begin(), beside.end());
      grids[edge_key(from, to)] = g.from(from == edge_key(from, to).first);
    };
    std::vector<char> visited(strips.size(), 0);
    std::size_t staggered = 0;
    for (std::size_t first = 0; first < strips.size(); ++first) {
      if (visited[first]) continue;
      visited[first] = 1;
      std::deque<std::size_t> queue{first};
      while (!queue.empty()) {
        const Strip& s = strips[queue.front()];
        queue.pop_front();
        const std::optional<Grid> top = get(s.a, s.c), bottom = get(s.d, s.b);
        if (!top && !bottom) {
          put(s.a, s.c, Grid{s.pieces, 1});
          put(s.d, s.b, Grid{s.pieces, 0});
        } else if (top && !bottom) {
          put(s.d, s.b, Grid{top->pieces, 1 - top->parity});
        } else if (!top && bottom) {
          put(s.a, s.c, Grid{bottom->pieces, 1 - bottom->parity});
        }
        staggered += get(s.a, s.c) && get(s.d, s.b);
        for (const EdgeKey& side : {edge_key(s.a, s.c), edge_key(s.d, s.b)})
          for (std::size_t t : by_side[side])
            if (!visited[t]) {
              visited[t] = 1;
              queue.push_back(t);
            }
      }
    }
    std::vector<detail::EdgeSplit> splits;
    std::vector<EdgeKey> split_keys;
    std::size_t points = 0;
    for (const auto& [side, grid] : grids) {
      const auto [u, w] = side;
      detail::EdgeSplit split{CGAL::halfedge(u, w, mesh_).first, {}};
      for (double f : grid.fractions())  // exactly on the side
        split.points.push_back(mesh_.point(u) + (mesh_.point(w) - mesh_.point(u)) * Kernel::FT(f));
      points += split.points.size();
      if (split.points.empty()) continue;
      splits.push_back(std::move(split));
      split_keys.push_back(side);
    }
    detail::SliceResult s = detail::split_edges(mesh_, splits);
    // each side's new points, in order from its smaller vertex index
    std::map<EdgeKey, std::vector<vertex_descriptor>> points_on;
    for (std::size_t i = 0, k = 0; i < splits.size(); ++i)
      for (std::size_t j = 0; j < splits[i].points.size(); ++j) points_on[split_keys[i]].push_back(s.vertices[k++]);
    index_.update(s.faces);
    std::size_t zigzags = 0;
    for (const Strip& strip : strips) zigzags += zigzag(strip, points_on, s);
    r_.strips_staggered += staggered;
    r_.strip_points += points;
    r_.strip_zigzags += zigzags;
    after_slice(s);
    tidy(s);
    return points;
  }

  /// The strip's faces (the pieces of its two faces after their sides were
  /// split) replaced by the zigzag between its sides' points: vertices in
  /// order of their position along the strip, a triangle per point. Made
  /// only where every new triangle is fine (exactly), the strip is planar
  /// to a tenth of the tolerance (its corner d within that of plane abc, so
  /// the zigzag stays that near the input), and no new triangle meets
  /// another face (the oracle's local query); else the fans stay and the
  /// decimation's flips take over (which, from fans of many points, can
  /// stall: a 24-strip cylinder 150 times longer than wide kept 131
  /// needles). Updates `s` (faces and parents) and the index. Returns
  /// whether it was made.
  bool zigzag(const Strip& strip, const std::map<EdgeKey, std::vector<vertex_descriptor>>& points_on,
              detail::SliceResult& s) {
    auto chain = [&](vertex_descriptor from, vertex_descriptor to) {
      std::vector<vertex_descriptor> out{from};
      const auto it = points_on.find(edge_key(from, to));
      if (it != points_on.end()) {
        if (from == edge_key(from, to).first) out.insert(out.end(), it->second.begin(), it->second.end());
        else out.insert(out.end(), it->second.rbegin(), it->second.rend());
      }
      out.push_back(to);
      return out;
    };
    const std::vector<vertex_descriptor> top = chain(strip.a, strip.c), bottom = chain(strip.d, strip.b);
    // With up to three points the decimation's flips reach the zigzag from
    // the fans (cgal__joint, a 40-strip 29:1 prism), in the order it treats
    // the neighbourhood: ADIS16480 came out with 5688 faces so, 5772 with its
    // one three-point strip zigzagged here, 5818 with its two-point ones too.
    if (top.size() + bottom.size() <= 7) return false;
    const Point3d pa = at(strip.a), pb = at(strip.b), pc = at(strip.c), pd = at(strip.d);
    const Point3d normal = cross(sub(pb, pa), sub(pc, pa));
    const double n2 = squared_norm(normal), off = dot(normal, sub(pd, pa));
    if (!(n2 > 0) || off * off > 0.01 * r_.tolerance * r_.tolerance * n2) return false;
    // the zigzag, by position along each side (top a -> c, bottom d -> b)
    auto along = [&](vertex_descriptor v, const Point3d& from, const Point3d& to) {
      return position_along(from, to, at(v));
    };
    std::vector<Triple> proposed;
    std::vector<char> from_top;
    for (std::size_t i = 0, j = 0; i + 1 < top.size() || j + 1 < bottom.size();) {
      // the side whose next point comes first; at a tie (the far end, or
      // points across from each other) the better-shaped triangle
      bool advance_top = j + 1 == bottom.size();
      if (!advance_top && i + 1 < top.size()) {
        const double t = along(top[i + 1], pa, pc), u = along(bottom[j + 1], pd, pb);
        advance_top = std::abs(t - u) < 1e-9
                          ? angle_range(at(top[i]), at(bottom[j]), at(top[i + 1])).first >
                                angle_range(at(top[i]), at(bottom[j]), at(bottom[j + 1])).first
                          : t < u;
      }
      if (advance_top) {
        proposed.push_back({top[i], bottom[j], top[i + 1]});
        ++i;
      } else {
        proposed.push_back({top[i], bottom[j], bottom[j + 1]});
        ++j;
      }
      from_top.push_back(advance_top);
    }
    for (const Triple& t : proposed)
      if (classify_triangle(mesh_.point(t[0]), mesh_.point(t[1]), mesh_.point(t[2]), cos_cap_, cos_needle_) !=
          Shape::fine)
        return false;
    // the pieces of both faces (each is a piece of itself once its side was split)
    std::vector<face_descriptor> region;
    for (std::size_t k = 0; k < s.faces.size(); ++k)
      if (s.parents[k] == strip.n || s.parents[k] == strip.m) region.push_back(s.faces[k]);
    if (std::find(region.begin(), region.end(), strip.n) == region.end() ||
        std::find(region.begin(), region.end(), strip.m) == region.end())
      return false;
    if (index_.would_intersect(proposed, region)) return false;
    // the region as one face, then cut along the zigzag's diagonals
    for (face_descriptor f : region) index_.remove(f);
    const std::optional<FaceOriginMap> origin = face_origin_map(mesh_);
    const std::int64_t origin_of = origin ? (*origin)[strip.n] : -1;
    std::vector<face_descriptor> left(region);
    for (bool joined = true; joined && left.size() > 1;) {
      joined = false;
      for (face_descriptor f : left) {
        for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(f), mesh_)) {
          const face_descriptor g = mesh_.face(mesh_.opposite(h));
          if (g == f || std::find(left.begin(), left.end(), g) == left.end()) continue;
          CGAL::Euler::join_face(h, mesh_);  // g goes
          left.erase(std::find(left.begin(), left.end(), g));
          joined = true;
          break;
        }
        if (joined) break;
      }
    }
    if (left.size() != 1) return false;  // not reached: the region is a disk
    std::vector<face_descriptor> made;
    face_descriptor rest = left.front();
    for (std::size_t k = 0; k + 1 < proposed.size(); ++k) {
      // the diagonal closing triangle k: from its top corner to its bottom one
      const vertex_descriptor x = from_top[k] ? proposed[k][2] : proposed[k][0];
      const vertex_descriptor y = from_top[k] ? proposed[k][1] : proposed[k][2];
      halfedge_descriptor hx, hy;
      for (halfedge_descriptor h : CGAL::halfedges_around_face(mesh_.halfedge(rest), mesh_)) {
        if (mesh_.target(h) == x) hx = h;
        if (mesh_.target(h) == y) hy = h;
      }
      const halfedge_descriptor d = CGAL::Euler::split_face(hx, hy, mesh_);
      const face_descriptor one = mesh_.face(d), other = mesh_.face(mesh_.opposite(d));
      // the triangle is the piece holding proposed[k]'s third corner
      const vertex_descriptor third = from_top[k] ? proposed[k][0] : proposed[k][1];
      bool one_is_triangle = false;
      for (vertex_descriptor v : CGAL::vertices_around_face(mesh_.halfedge(one), mesh_)) one_is_triangle |= v == third;
      made.push_back(one_is_triangle ? one : other);
      rest = one_is_triangle ? other : one;
    }
    made.push_back(rest);
    FaceFlagMap on_input = face_on_input_map(mesh_);
    for (face_descriptor f : made) {
      if (origin) (*origin)[f] = origin_of;
      on_input[f] = 1;  // on the input to a tenth of the tolerance: replaced later, its samples are checked
    }
    index_.update(made);
    // the slice's record: the region's pieces out, the zigzag in
    std::vector<face_descriptor> faces;
    std::vector<face_descriptor> parents;
    for (std::size_t k = 0; k < s.faces.size(); ++k)
      if (s.parents[k] != strip.n && s.parents[k] != strip.m) {
        faces.push_back(s.faces[k]);
        parents.push_back(s.parents[k]);
      }
    for (std::size_t k = 0; k < made.size(); ++k) {
      faces.push_back(made[k]);
      parents.push_back(from_top[k] ? strip.n : strip.m);
    }
    s.faces = std::move(faces);
    s.parents = std::move(parents);
    return true;
  }

  /// Whether the needle is the side of a thin strip: its apex (the corner
  /// off the longest edge e) stands over an end of e, within a tenth of |e|
  /// (a CAD cylinder's facet split by its diagonal). A sliver whose apex
  /// stands over the middle of e is cut through the apex instead
  /// (tube_edge2.42's end rings: 476 -> 508 faces when cut in pieces).
  bool on_strip(halfedge_descriptor e) const {
    const double t = apex_position(e);
    return std::min(t, 1 - t) < 0.1;
  }

  /// Into how many equal pieces the cuts perpendicular to pq (a strip's
  /// diagonal) divide the needle: the fewest that clear the needle angle. A needle
  /// of height h over pq, cut into k pieces, leaves pieces h wide and |pq| / k
  /// long, split by a diagonal: smallest angle atan(k h / |pq|). So k =
  /// |pq| tan(1.1 needle angle) / h, rounded up, from 2 (the midpoint cut)
  /// to 8 (beyond, the halves of round after round). A strip 29 times longer
  /// than wide (cgal__joint's cylinders) needs 3: halving twice made 4
  /// (cgal__joint: 866 -> 744 faces).
  int needle_pieces(face_descriptor needle, const Point& p, const Point& q) const {
    std::array<Point3d, 3> c;
    halfedge_descriptor h = mesh_.halfedge(needle);
    for (int k = 0; k < 3; ++k, h = mesh_.next(h)) c[k] = approx_point3d(mesh_.point(mesh_.target(h)));
    const double twice_area = norm(cross(sub(c[1], c[0]), sub(c[2], c[0])));
    const double length = std::sqrt(CGAL::to_double(CGAL::squared_distance(p, q)));
    if (!(twice_area > 0) || !(length > 0)) return 2;
    const double k = std::ceil(length * length * std::tan(1.1 * o_.needle_angle * kPi / 180.0) /
                               twice_area);
    return k > 8 || !(k >= 2) ? 2 : static_cast<int>(k);
  }

  /// A flat needle — its apex so near its longest edge that the angles at
  /// both ends of that edge are below the needle angle (a triangle almost a
  /// cap: the paper's cap slice through the apex leaves both halves
  /// needles) — is cut at two points of that edge, one each side of the
  /// apex's foot at the distance that leaves the middle piece's base angles
  /// at 1.2 needle angles: the end pieces keep one tiny angle each, at the
  /// edge's ends, which flips with the faces beyond those ends clear. On
  /// tube_edge2.42's end rings (chords 2.39 long, apexes 0.055 from them)
  /// halving cuts left 476 faces where 416 are possible. Returns the two
  /// edge parameters; nullopt when not flat, or too flat for two cuts (one
  /// would fall within 5% of an end). Placement only, in doubles; the
  /// slices are verified exactly.
  std::optional<std::array<double, 2>> flat_cut(face_descriptor needle, halfedge_descriptor longest) const {
    if (mesh_.face(longest) != needle) return std::nullopt;
    const Point3d a = approx_point3d(mesh_.point(mesh_.source(longest)));
    const Point3d b = approx_point3d(mesh_.point(mesh_.target(longest)));
    const Point3d c = approx_point3d(mesh_.point(mesh_.target(mesh_.next(longest))));
    const Point3d ab = sub(b, a), ac = sub(c, a);
    const double length = norm(ab);
    if (!(length > 0)) return std::nullopt;
    const double foot = dot(ab, ac) / length, height = norm(cross(ab, ac)) / length;
    const double tan_needle = std::tan(o_.needle_angle * kPi / 180.0);
    if (!(foot > 0 && foot < length) || !(height < tan_needle * foot) || !(height < tan_needle * (length - foot)))
      return std::nullopt;
    const double half_middle = height / std::tan(1.2 * o_.needle_angle * kPi / 180.0);
    const std::array<double, 2> t{(foot - half_middle) / length, (foot + half_middle) / length};
    if (!(t[0] >= 0.05 && t[1] <= 0.95)) return std::nullopt;
    return t;
  }

  /// Whether face f has corners strictly on both sides of the plane (exact).
  bool crosses(face_descriptor f, const Kernel::Plane_3& plane) const {
    bool above = false, below = false;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh_.halfedge(f), mesh_)) {
      const CGAL::Oriented_side side = plane.oriented_side(mesh_.point(v));
      above |= side == CGAL::ON_POSITIVE_SIDE;
      below |= side == CGAL::ON_NEGATIVE_SIDE;
    }
    return above && below;
  }

  /// A needle whose short edge is wider than half the tolerance cannot be
  /// collapsed within it. Where it is the tip of a wedge (two long sides
  /// meeting at angle t at apex a: a CAD face's sharp corner, a tapering
  /// strip), halving cuts do not help either: a band between cuts at r/2 and
  /// r from a splits into a triangle whose smallest angle is about t again.
  /// So the tip is cut across by planes perpendicular to its longest side,
  /// at distances r_k from a that fall by a factor q per cut, until it is
  /// narrower than a quarter of the tolerance (a collapse removes it then).
  /// The band between cuts at q r and r, of widths q r tan t and r tan t,
  /// splits into two triangles whose smallest angles are about
  /// atan(q tan t / (1 - q)) and atan(tan t / (1 - q)): at least the needle
  /// angle when 1/q - 1 <= tan t / tan(needle angle); q is set with a margin
  /// (3/4 of that). This is the paper's §5 supersampling, placed where a
  /// wedge needs it. Each cut is a verified local slice, ended about a tip's
  /// width beyond the tip (it circles a where the faces around a allow), and
  /// never snaps a itself; the decimation run after them (tidy()) removes
  /// the tip and whatever split points are not needed. Returns the number
  /// of cuts made (0: not a wedge tip, or the first cut was refused).
  std::size_t cut_wedge(face_descriptor needle) {
    std::array<vertex_descriptor, 3> v;
    std::array<Point3d, 3> p;
    {
      halfedge_descriptor h = mesh_.halfedge(needle);
      for (int k = 0; k < 3; ++k, h = mesh_.next(h)) {
        v[k] = mesh_.target(h);
        p[k] = approx_point3d(mesh_.point(v[k]));
      }
    }
    auto length = [](const Point3d& x, const Point3d& y) { return norm(sub(x, y)); };
    // the apex: the corner opposite the shortest edge
    int k = 0;
    for (int j = 1; j < 3; ++j)
      if (length(p[(j + 1) % 3], p[(j + 2) % 3]) < length(p[(k + 1) % 3], p[(k + 2) % 3])) k = j;
    const vertex_descriptor a = v[k];
    vertex_descriptor b = v[(k + 1) % 3], c = v[(k + 2) % 3];
    double ab = length(p[k], p[(k + 1) % 3]), ac = length(p[k], p[(k + 2) % 3]);
    if (ab < ac) {
      std::swap(b, c);
      std::swap(ab, ac);
    }
    const double width = length(p[(k + 1) % 3], p[(k + 2) % 3]);
    if (!(width > 0.5 * r_.tolerance) || !(ac > 0)) return 0;
    // the angle at a, from the sides (law of cosines)
    const double cos_t = std::clamp((ab * ab + ac * ac - width * width) / (2 * ab * ac), -1.0, 1.0);
    const double tan_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t)) / cos_t;
    if (!(tan_t > 0) || cos_t <= 0) return 0;
    // A tip: its short edge runs across the wedge (both angles at it at
    // least 45 degrees). A needle whose short edge runs along one side of a
    // strip (angles near 0 and 180 at it) is no tip: halving cuts serve it.
    auto cos_at = [&](double adjacent, double other, double opposite) {
      return (adjacent * adjacent + other * other - opposite * opposite) / (2 * adjacent * other);
    };
    const double cos_half = std::sqrt(0.5);
    if (std::abs(cos_at(width, ab, ac)) > cos_half || std::abs(cos_at(width, ac, ab)) > cos_half) return 0;
    const double rate = 1 + 0.75 * tan_t / std::tan(o_.needle_angle * kPi / 180.0);  // 1/q
    const int cuts = static_cast<int>(std::ceil(std::log(width / (0.25 * r_.tolerance)) / std::log(rate)));
    if (cuts < 1 || cuts > 48) return 0;
    // The planes go through double points (as slice_needles' do), keeping
    // split points one exact construction deep.
    const Point pa = nearest_double_point(mesh_.point(a)), pb = nearest_double_point(mesh_.point(b));
    const Kernel::Vector_3 axis = pb - pa;
    const Point3d da = approx_point3d(pa), db = approx_point3d(pb);
    std::vector<face_descriptor> faces;
    std::vector<vertex_descriptor> fresh;
    face_descriptor tip = needle;
    double r = ab;
    std::size_t made = 0;
    for (int i = 0; i < cuts; ++i) {
      r /= rate;
      const double t = r / ab;
      const Point at(da[0] + t * (db[0] - da[0]), da[1] + t * (db[1] - da[1]), da[2] + t * (db[2] - da[2]));
      detail::SliceOptions so = slice_options();
      so.seed = tip;
      so.protected_vertices = {a};
      // ended about a tip's width beyond it: run on for 1.5 r, as needle
      // cuts are, the cuts left needles along the apex's other edges (tried
      // on a knife whose end face has a 3-degree tip: they ran up its side
      // faces along the blade)
      so.radius = 1.5 * r * tan_t;
      const detail::SliceResult s = detail::slice_by_plane(mesh_, Kernel::Plane_3(at, axis), so);
      if (s.rejected || s.edges_split == 0) break;  // the cuts so far still serve (bands of fine faces)
      ++r_.wedge_cuts;
      ++made;
      after_slice(s);
      faces.insert(faces.end(), s.faces.begin(), s.faces.end());
      fresh.insert(fresh.end(), s.vertices.begin(), s.vertices.end());
      // the next seed: the piece at a between its two sides
      tip = Mesh::null_face();
      for (halfedge_descriptor g : CGAL::halfedges_around_target(mesh_.halfedge(a), mesh_)) {
        const face_descriptor f = mesh_.face(g);
        if (f == Mesh::null_face()) continue;
        const vertex_descriptor x = mesh_.source(g), y = mesh_.target(mesh_.next(g));
        // q on side a-end: its split points were rounded to doubles right
        // after their cut (settle()), an ulp off the side's line, so on
        // doubles, to a relative 1e-9 (exact collinearity lost the tip
        // after one cut: a 3-degree blade kept its needle).
        auto on_side = [&](vertex_descriptor q, vertex_descriptor end) {
          if (q == end) return true;
          const Point3d pa = approx_point3d(mesh_.point(a)), u = sub(approx_point3d(mesh_.point(q)), pa),
                        w = sub(approx_point3d(mesh_.point(end)), pa);
          const double uu = squared_norm(u), ww = squared_norm(w);
          return uu > 0 && uu <= ww && dot(u, w) > 0 && squared_norm(cross(u, w)) <= 1e-18 * uu * ww;
        };
        if ((on_side(x, b) && on_side(y, c)) || (on_side(x, c) && on_side(y, b))) {
          tip = f;
          break;
        }
      }
      if (tip == Mesh::null_face()) break;
    }
    if (made == 0) return 0;
    ++r_.wedge_tips;
    detail::SliceResult all;
    for (face_descriptor f : faces)
      if (!mesh_.is_removed(f)) all.faces.push_back(f);
    std::sort(all.faces.begin(), all.faces.end());
    all.faces.erase(std::unique(all.faces.begin(), all.faces.end()), all.faces.end());
    all.vertices = fresh;
    tidy(all);
    return made;
  }

  /// Every split point still there gets the tidy pass again, until it
  /// removes none (at most three passes): removed where every face around
  /// it is fine and stays fine. The neighbourhoods of early slices changed
  /// since their own tidy(): cad_cylinder 538 -> 468 faces, fixed_top
  /// 3804 -> 3020, cgal__joint 1044 -> 890.
  ///
  /// A later pass asks only the points whose ring of neighbours changed in
  /// the pass before: with the same ring a collapse proposes the same faces
  /// over the same attached points (ADIS16480: 8.5k points, each asked
  /// exactly; three full passes took 2 s more for 6 fewer faces of 5844).
  void simplify_split_points() {
    auto ring = [&](vertex_descriptor v) {
      std::vector<std::uint32_t> r;
      for (vertex_descriptor u : CGAL::vertices_around_target(mesh_.halfedge(v), mesh_))
        r.push_back(static_cast<std::uint32_t>(u));
      std::sort(r.begin(), r.end());
      return r;
    };
    // this last pass may also remove a point with its hole triangulated anew
    retriangulate();
    std::vector<vertex_descriptor> todo;  // in the order the slices made them, once each
    std::vector<char> seen(mesh_.number_of_vertices() + mesh_.number_of_removed_vertices(), 0);
    for (vertex_descriptor v : created_)
      if (!mesh_.is_removed(v) && !mesh_.is_isolated(v) && !seen[static_cast<std::size_t>(v)]) {
        seen[static_cast<std::size_t>(v)] = 1;
        todo.push_back(v);
      }
    for (int pass = 0; pass < 3 && !todo.empty(); ++pass) {
      std::vector<std::vector<std::uint32_t>> rings;
      for (vertex_descriptor v : todo) rings.push_back(ring(v));
      const std::size_t before = mesh_.number_of_faces();
      decimator_.simplify(todo);
      if (mesh_.number_of_faces() == before) break;
      std::vector<vertex_descriptor> next;
      for (std::size_t i = 0; i < todo.size(); ++i)
        if (!mesh_.is_removed(todo[i]) && ring(todo[i]) != rings[i]) next.push_back(todo[i]);
      todo = std::move(next);
    }
    note_size();
  }

  /// Certify after rounding, early (ARCHITECTURE.md): each of a slice's
  /// split points takes its written doubles now wherever that changes
  /// nothing the oracle checks around it (detail::round_if_unchanged), so
  /// that the exact tests after it run on doubles instead of the slices'
  /// rationals. A point where it would stays exact (rounded at the end).
  /// All at once first (detail::round_all_if_unchanged: one check, on
  /// doubles; ADIS16480: 500 slices, none refused), one by one when that
  /// is refused. Returns the points moved.
  std::size_t settle(const std::vector<vertex_descriptor>& points) {
    if (const auto all = detail::round_all_if_unchanged(mesh_, index_, points, cos_cap_, cos_needle_)) return *all;
    std::size_t moved = 0;
    for (vertex_descriptor v : points)
      moved += !mesh_.is_removed(v) && detail::round_if_unchanged(mesh_, index_, v, cos_cap_, cos_needle_);
    return moved;
  }

  void finish_stats() {
    r_.collapses = decimator_.stats().collapses;
    r_.flips = decimator_.stats().flips;
    r_.removals = decimator_.stats().removals;
  }

  /// Whether the smallest corner of face (v, b, c) at v is below the needle
  /// angle (doubles: this only picks candidates).
  bool needle_at(vertex_descriptor v, vertex_descriptor b, vertex_descriptor c) const {
    const Point3d u = sub(at(b), at(v)), w = sub(at(c), at(v));
    return angle_between(u, w) < o_.needle_angle * kPi / 180;
  }
  /// v's outgoing halfedges in its faces' order: the face of each h, if
  /// any, is (v, target(h), target(next(h))), and the next h starts there.
  std::vector<halfedge_descriptor> outgoing(vertex_descriptor v) const {
    std::vector<halfedge_descriptor> around;
    const halfedge_descriptor first = mesh_.opposite(mesh_.halfedge(v));
    halfedge_descriptor h = first;
    do {
      around.push_back(h);
      h = mesh_.opposite(mesh_.prev(h));
    } while (h != first);
    return around;
  }

  /// Plans the disc of `star` (link and faces filled in) graded around
  /// `centre` (detail/apex_fan.h) and has the decimation replace it.
  /// `keep` is the vertex whose exact position the centre keeps unless the
  /// plan moves it (a cone's tip), or none (a new centre).
  bool regrade(detail::StarReplacement& star, const Point3d& centre, std::optional<vertex_descriptor> keep) {
    std::vector<Point3d> link;
    for (vertex_descriptor b : star.link) link.push_back(at(b));
    const std::optional<detail::ApexFanPlan> plan =
        detail::plan_apex_fan(centre, link, r_.tolerance, o_.needle_angle, o_.cap_angle);
    if (!plan) return false;
    star.centre = keep && !plan->moved ? mesh_.point(*keep) : Point(plan->apex[0], plan->apex[1], plan->apex[2]);
    for (const Point3d& p : plan->points) star.points.emplace_back(p[0], p[1], p[2]);
    star.triangles = plan->triangles;
    star.sectors = plan->sectors;
    std::vector<vertex_descriptor> made;
    if (decimator_.replace_star(star, made).empty()) return false;
    r_.apex_fan_points += plan->points.size();
    if (keep && plan->moved) {
      ++r_.apexes_moved;
      r_.max_displacement = std::max(r_.max_displacement, norm(sub(plan->apex, centre)));
    }
    created_.insert(created_.end(), made.begin() + (keep ? 1 : 0), made.end());
    note_size();
    return true;
  }

  /// The tips of CAD cones: a vertex at the needle corner of three or more
  /// faces around it, whose star the planner of detail/apex_fan.h grades
  /// into rings (no operation of the paper reaches it: see apex_fan.h), the
  /// new star checked exactly by ShapeDecimator::replace_star(). The tip
  /// keeps its exact coordinates unless the cone is too narrow for any fan
  /// there; the new points lie on its spokes. Returns the stars replaced.
  std::size_t remesh_apex_fans() {
    refresh_frozen();
    std::vector<vertex_descriptor> apexes;
    const std::optional<VertexIdentityMap> identity = vertex_identity_map(mesh_);
    const auto pinned = vertex_pinned_map(mesh_);
    for (vertex_descriptor v : mesh_.vertices()) {
      // a copy of a split pinch point stays where it is
      if (mesh_.is_isolated(v) || (pinned && (*pinned)[v]) || (identity && (*identity)[v] != kOwnIdentity) ||
          CGAL::is_border(v, mesh_))
        continue;
      std::size_t tips = 0;
      for (halfedge_descriptor h : CGAL::halfedges_around_target(mesh_.halfedge(v), mesh_))
        tips += needle_at(v, mesh_.source(h), mesh_.target(mesh_.next(h)));
      if (tips >= 3) apexes.push_back(v);
    }
    std::size_t replaced = 0;
    for (vertex_descriptor v : apexes) {
      if (mesh_.is_removed(v) || CGAL::is_border(v, mesh_)) continue;
      detail::StarReplacement star;
      star.centre_vertex = v;
      bool usable = true;
      for (halfedge_descriptor h : outgoing(v)) {  // face i is (v, link[i], link[i + 1])
        if (is_frozen(mesh_.face(h)) ||
            std::find(star.link.begin(), star.link.end(), mesh_.target(h)) != star.link.end()) {
          usable = false;
          break;
        }
        star.link.push_back(mesh_.target(h));
        star.faces.push_back(mesh_.face(h));
      }
      star.sector_faces = star.faces;
      if (usable && regrade(star, at(v), v)) ++replaced;
    }
    r_.apex_fans += replaced;
    return replaced;
  }

  /// CAD's fan-tessellated planar faces (a cone's or cylinder's base fanned
  /// from one corner of its polygon, needles at that corner): the fan's
  /// polygon, if convex, graded around its centroid instead, as a flat
  /// cone's tip (regrade()). Its corners stay; the new points lie inside it.
  std::size_t remesh_planar_fans() {
    refresh_frozen();
    std::size_t replaced = 0;
    for (vertex_descriptor v : mesh_.vertices()) {
      if (mesh_.is_removed(v) || mesh_.is_isolated(v)) continue;
      const std::vector<halfedge_descriptor> around = outgoing(v);
      const std::size_t m = around.size();
      std::vector<char> needle(m);  // face i has a needle corner at v
      for (std::size_t i = 0; i < m; ++i)
        needle[i] = !mesh_.is_border(around[i]) &&
                    needle_at(v, mesh_.target(around[i]), mesh_.target(mesh_.next(around[i])));
      if (std::count(needle.begin(), needle.end(), 1) < 3) continue;
      auto joined = [&](std::size_t i) {  // face i continues the plane of face i - 1
        const halfedge_descriptor p = around[(i + m - 1) % m], h = around[i];
        return !mesh_.is_border(p) && !mesh_.is_border(h) && coplanar_faces(mesh_.face(p), mesh_.face(h));
      };
      std::size_t start = m;
      for (std::size_t i = 0; i < m && start == m; ++i)
        if (!joined(i)) start = i;
      if (start == m) continue;  // one plane all around v: remesh_apex_fans()' case
      for (std::size_t k = 0; k < m;) {
        std::vector<halfedge_descriptor> run{around[(start + k) % m]};
        std::size_t needles = needle[(start + k) % m];
        for (++k; k < m && joined((start + k) % m); ++k) {
          run.push_back(around[(start + k) % m]);
          needles += needle[(start + k) % m];
        }
        if (needles >= 3 && !mesh_.is_border(run.front()) && regrade_planar_fan(v, run)) {
          ++replaced;
          break;  // v's star changed
        }
      }
    }
    r_.planar_fans += replaced;
    return replaced;
  }

  /// Faces f and g in one plane, exactly (on Epick when every corner is a
  /// double, as on CAD input: coplanarity is the degenerate case, where the
  /// lazy kernel's filter always falls back to rationals).
  bool coplanar_faces(face_descriptor f, face_descriptor g) const {
    std::array<Point, 6> p;
    std::size_t n = 0;
    for (face_descriptor k : {f, g})
      for (vertex_descriptor w : CGAL::vertices_around_face(mesh_.halfedge(k), mesh_)) p[n++] = mesh_.point(w);
    if (std::all_of(p.begin(), p.end(), is_double_point)) {
      std::array<InputKernel::Point_3, 6> q;
      std::transform(p.begin(), p.end(), q.begin(), to_input_point);
      return coplanar_corners(q);
    }
    return coplanar_corners(p);
  }
  template <class P>
  static bool coplanar_corners(const std::array<P, 6>& p) {
    if (CGAL::collinear(p[0], p[1], p[2])) return false;
    for (std::size_t i = 3; i < 6; ++i)
      if (!CGAL::coplanar(p[0], p[1], p[2], p[i])) return false;
    return true;
  }

  /// The fan of `run` (v's consecutive coplanar faces (v, b_j, b_{j+1})):
  /// its polygon (v, b_0, ..., b_k) graded around its centroid, if convex.
  bool regrade_planar_fan(vertex_descriptor v, const std::vector<halfedge_descriptor>& run) {
    detail::StarReplacement star;
    star.link.push_back(v);
    star.sector_faces.push_back(mesh_.face(run.front()));
    for (halfedge_descriptor h : run) {
      if (is_frozen(mesh_.face(h))) return false;
      star.link.push_back(mesh_.target(h));
      star.faces.push_back(mesh_.face(h));
      star.sector_faces.push_back(mesh_.face(h));
    }
    star.link.push_back(mesh_.target(mesh_.next(run.back())));
    star.sector_faces.push_back(mesh_.face(run.back()));
    std::vector<vertex_descriptor> sorted = star.link;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return false;
    // strictly convex (doubles: the exact checks of replace_star() follow)
    const std::size_t n = star.link.size();
    std::vector<Point3d> p;
    Point3d centroid{0, 0, 0};
    for (vertex_descriptor b : star.link) {
      p.push_back(at(b));
      centroid = add(centroid, p.back());
    }
    centroid = mul(centroid, 1.0 / double(n));
    const Point3d normal = cross(sub(p[1], p[0]), sub(p[2], p[0]));
    for (std::size_t i = 0; i < n; ++i)
      if (!(dot(cross(sub(p[(i + 1) % n], p[i]), sub(p[(i + 2) % n], p[(i + 1) % n])), normal) > 0)) return false;
    return regrade(star, centroid, std::nullopt);
  }

  /// Input faces (by id) that intersect another: slices leave them whole
  /// (SliceOptions::frozen) while they still do (refresh_frozen()).
  void freeze(const std::vector<FacePair>& intersecting, std::size_t faces) {
    intersected_.assign(faces, 0);
    for (const FacePair& p : intersecting) intersected_[p.first] = intersected_[p.second] = 1;
    frozen_ = intersected_;
  }

  /// A collapse may reshape a face that intersected, or remove its partner;
  /// once it intersects nothing, slices may cut it again (found on b9_mesh:
  /// its one intersecting pair goes in decimation, and the needles beside
  /// it then need a slice).
  void refresh_frozen() {
    if (std::find(frozen_.begin(), frozen_.end(), 1) == frozen_.end()) return;
    const auto origin = face_origin_map(mesh_);
    if (!origin) return;
    std::fill(frozen_.begin(), frozen_.end(), 0);
    for (face_descriptor f : mesh_.faces()) {
      const std::int64_t i = (*origin)[f];
      if (i >= 0 && static_cast<std::size_t>(i) < intersected_.size() && intersected_[static_cast<std::size_t>(i)] &&
          index_.intersects({f}))
        frozen_[static_cast<std::size_t>(i)] = 1;
    }
  }

  void note_size() { r_.peak_faces = std::max<std::size_t>(r_.peak_faces, mesh_.number_of_faces()); }

 private:
  static detail::DecimationOptions decimation_options(const DegenerateOptions& o, const DegenerateReport& r) {
    detail::DecimationOptions d;
    d.cap_angle = o.cap_angle;
    d.needle_angle = o.needle_angle;
    d.tolerance = r.tolerance;
    d.fold_angle = o.fold_angle;
    d.fold_guard_angle = InspectOptions{}.tetgen_fold_angle;  // split points are rounded early (settle())
    return d;
  }

  /// Snapping, the safeguard's cap angle, and the faces no slice may cut.
  detail::SliceOptions slice_options() const {
    detail::SliceOptions so;
    so.snap_distance = snap_;
    so.cap_angle = o_.cap_angle;
    so.frozen = &frozen_;
    return so;
  }

  void after_slice(const detail::SliceResult& s) {
    created_.insert(created_.end(), s.vertices.begin(), s.vertices.end());
    index_.update(s.faces);
    decimator_.reattach(s.faces, s.parents);
    note_size();
    r_.split_points_rounded += settle(s.vertices);
  }

  /// Decimation along a slice: its bad pieces first, then its split points
  /// wherever removing them leaves only fine faces.
  void tidy(const detail::SliceResult& s) {
    std::vector<face_descriptor> faces;
    for (face_descriptor f : s.faces)
      if (!mesh_.is_removed(f)) faces.push_back(f);
    decimator_.run(faces, s.vertices);
    note_size();
    decimator_.simplify(s.vertices);
  }

  bool is_frozen(face_descriptor f) const {
    const std::optional<FaceOriginMap> origin = face_origin_map(mesh_);
    if (!origin) return false;
    const std::int64_t i = (*origin)[f];
    return i >= 0 && static_cast<std::size_t>(i) < frozen_.size() && frozen_[static_cast<std::size_t>(i)];
  }

  Point3d at(vertex_descriptor v) const { return approx_point3d(mesh_.point(v)); }

  /// The strips among the needles that decimation cannot serve better, with
  /// the pieces their sides need: the fewest q >= 2 whose zigzag's angles,
  /// about atan(q w / |side|), clear 1.1 needle angles, at most 64.
  std::vector<Strip> find_strips() const {
    const double tan_needle = std::tan(1.1 * o_.needle_angle * kPi / 180.0);
    std::vector<Strip> strips;
    for (auto e : mesh_.edges()) {
      if (mesh_.is_border(e)) continue;
      halfedge_descriptor h = mesh_.halfedge(e);
      // the shape on doubles first (cheap, and rarely met), then exactly
      const double tn = apex_along(h), tm = apex_along(mesh_.opposite(h));
      if (tn < 0.1 && tm < 0.1) h = mesh_.opposite(h);  // the apexes over the other ends
      else if (!(tn > 0.9 && tm > 0.9)) continue;
      const face_descriptor n = mesh_.face(h), m = mesh_.face(mesh_.opposite(h));
      if (is_frozen(n) || is_frozen(m) || classify_face(mesh_, n, cos_cap_, cos_needle_) != Shape::needle ||
          classify_face(mesh_, m, cos_cap_, cos_needle_) != Shape::needle)
        continue;
      Strip s{mesh_.source(h), mesh_.target(h), mesh_.target(mesh_.next(h)),
              mesh_.target(mesh_.next(mesh_.opposite(h))), 0, mesh_.face(h), mesh_.face(mesh_.opposite(h))};
      const Point3d pa = at(s.a);
      const double side2 = squared_norm(sub(at(s.c), pa));
      const double width2 = squared_norm(cross(sub(at(s.c), pa), sub(at(s.b), pa))) / side2;  // b's height over ac
      // A strip no wider than the tolerance is collapsed, and one whose
      // neighbour across a side is nearly in its plane is merged with it
      // (the circle of a finely faceted cylinder coarsened): decimation
      // serves those better (trimesh__round: 1030 faces; 2064 staggered).
      if (!(width2 > r_.tolerance * r_.tolerance) || mergeable(s.a, s.c, s.b) || mergeable(s.b, s.d, s.a)) continue;
      const double q = std::ceil(std::sqrt(side2 / width2) * tan_needle);
      if (!(q <= 64)) continue;
      s.pieces = std::max(2, static_cast<int>(q));
      strips.push_back(s);
    }
    return strips;
  }

  /// Where the apex of h's face stands over h: 0 over its source, 1 over
  /// its target (NaN when h has zero length).
  double apex_position(halfedge_descriptor h) const {
    return position_along(at(mesh_.source(h)), at(mesh_.target(h)), at(mesh_.target(mesh_.next(h))));
  }

  /// apex_position(h), or 0.5 unless h is its face's longest edge.
  double apex_along(halfedge_descriptor h) const {
    const Point3d a = at(mesh_.source(h)), b = at(mesh_.target(h)), c = at(mesh_.target(mesh_.next(h)));
    const double ab = squared_norm(sub(b, a));
    if (!(ab > 0) || squared_norm(sub(c, b)) > ab || squared_norm(sub(a, c)) > ab) return 0.5;
    return position_along(a, b, c);
  }

  /// Whether side uw could go, the faces on its two sides (this one's corner
  /// off it: `apex`) made one, within 70% of the tolerance (where the
  /// decimation decides): the side's distance from the chord between the
  /// two corners off it, in the cross-section perpendicular to the side.
  bool mergeable(vertex_descriptor u, vertex_descriptor w, vertex_descriptor apex) const {
    const auto [h, found] = CGAL::halfedge(u, w, mesh_);  // in the face across
    if (!found || mesh_.is_border(h)) return false;
    const Point3d pu = at(u), t = sub(at(w), pu);
    const double t2 = squared_norm(t);
    if (!(t2 > 0)) return false;
    auto across_side = [&](vertex_descriptor x) {  // x - u without its part along the side
      const Point3d d = sub(at(x), pu);
      return sub(d, mul(t, dot(d, t) / t2));
    };
    const Point3d p = across_side(apex), q = across_side(mesh_.target(mesh_.next(h)));
    const double chord2 = squared_norm(sub(q, p));
    return chord2 > 0 && squared_norm(cross(p, q)) <= 0.49 * r_.tolerance * r_.tolerance * chord2;
  }

  /// Whether face f (beside side (from, to), no strip's), fanned from its
  /// corner off the side to the points at `fractions` of it (from `from`),
  /// has no needle or cap piece — on doubles: this only chooses where to cut.
  bool fans_well(face_descriptor f, vertex_descriptor from, vertex_descriptor to,
                 const std::vector<double>& fractions) const {
    vertex_descriptor apex = from;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh_.halfedge(f), mesh_))
      if (v != from && v != to) apex = v;
    const Point3d p = at(from), d = sub(at(to), p), c = at(apex);
    std::vector<double> ts{0.0};
    ts.insert(ts.end(), fractions.begin(), fractions.end());
    ts.push_back(1.0);
    for (std::size_t i = 0; i + 1 < ts.size(); ++i)
      if (!angles_within(add(p, mul(d, ts[i])), add(p, mul(d, ts[i + 1])), c, o_.needle_angle, o_.cap_angle)) return false;
    return true;
  }

  Mesh& mesh_;
  const DegenerateOptions& o_;
  DegenerateReport& r_;
  LocalIndex index_;
  detail::ShapeDecimator decimator_;
  double cos_cap_ = 0, cos_needle_ = 0, snap_ = 0;
  std::size_t face_limit_ = 0;  // needle supersampling stops beyond it
  std::vector<char> intersected_;  // by input face id: intersected another face in the input
  std::vector<char> frozen_;       // ... and still does (refresh_frozen())
  std::vector<vertex_descriptor> created_;  // every slice's split points (some removed since)
};

}  // namespace

DegenerateResult remove_degenerate_faces(const Soup& input, const DegenerateOptions& o) {
  DegenerateResult result;
  DegenerateReport& r = result.report;
  r.cap_angle = o.cap_angle;
  r.needle_angle = o.needle_angle;
  r.slice_grid = o.slice_grid;
  r.global_slices = o.global_slices;
  r.interleave = o.interleave;
  r.faces_in = input.face_count();

  // 1. preprocess
  auto t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("inspecting input");
  const Report in = inspect(input, inspect_options(o));
  r.before = shape_counts(in);
  r.self_intersections_in = in.self_intersections.size();
  r.topology_unwelded = topology_of(in);
  r.bbox_diagonal = bbox_diagonal(in);
  r.tolerance = o.tolerance >= 0 ? o.tolerance : o.tolerance_ratio * r.bbox_diagonal;
  r.weld_distance = o.weld >= 0 ? o.weld : o.weld_ratio * r.bbox_diagonal;
  // Vertices a hair apart (a CAD STL export's rounding: trimesh's
  // featuretype has 288 pairs 3e-16 apart) leave cracks whose two sides
  // intersect exactly, and no operation may touch an intersection: its
  // needles stayed (863 of 1613). Welded first, they are ordinary edges.
  // The weld is a choice made in doubles; it is kept only where the welded
  // surface builds as a manifold mesh and has no more intersecting pairs.
  Soup clean;
  Report welded_report;
  const Report* in_mesh = &in;  // face ids as in the mesh's kFaceOrigin
  Mesh mesh;
  MeshBuildResult built;
  for (const double near : {r.weld_distance, 0.0}) {
    in_mesh = &in;
    clean = preprocess(input, near, r.repeated_index_faces, r.near_vertices_welded, r.max_weld_move);
    if (!clean.is_triangle_soup()) throw UnsupportedInput("not a triangle mesh (polygons with more than 3 corners)");
    if (r.repeated_index_faces || r.near_vertices_welded) {
      welded_report = inspect(clean, inspect_options(o));
      in_mesh = &welded_report;
    }
    mesh = Mesh();
    // Pinch points (vertices whose faces form several fans, common in CAD
    // STL exports) get one copy per fan; the copies weld again on output.
    built = soup_to_mesh_splitting_pinches(clean, mesh, &r.pinched_vertices_split);
    if (r.near_vertices_welded == 0) break;
    if (built.ok && in_mesh->self_intersections.size() <= in.self_intersections.size()) break;
    r.weld_refused = true;  // try again with identical points only
  }
  r.self_intersections_welded = in_mesh->self_intersections.size();
  r.topology_in = topology_of(*in_mesh);
  r.max_displacement = r.max_weld_move;
  if (!built.ok)
    throw NotManifold(built.problems);
  mark_split_pinches(mesh);  // the copies must stay, and are one vertex to the oracle
  const detail::SurfaceDistance distance(clean);
  Pipeline pipeline(mesh, distance, o, r);
  pipeline.freeze(in_mesh->self_intersections, clean.face_count());
  r.seconds_preprocess = seconds_since(t0);
  pipeline.note_size();

  // 2. zero-area faces
  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("zero-area faces");
  pipeline.decimate(pipeline.faces_of(Shape::degenerate));
  r.faces_after_zero_area = mesh.number_of_faces();
  r.seconds_zero_area = seconds_since(t0);

  // 3. slicing
  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("slicing caps");
  if (o.slice) {
    if (o.slice_grid > 0) pipeline.slice_grid(o.slice_grid);
    pipeline.slice_caps();
  }
  r.faces_after_slicing = mesh.number_of_faces();
  r.seconds_slicing = seconds_since(t0);

  // 4. decimation; caps whose slice was refused may be sliceable once their
  // neighbourhood changed, so alternate while slicing makes progress
  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("decimating needles");
  if (o.slice) {
    pipeline.remesh_planar_fans();
    pipeline.remesh_apex_fans();
    pipeline.stagger_strips();
  }
  pipeline.decimate(pipeline.bad_faces());
  // What decimation could not remove: caps whose slice was refused may be
  // sliceable now that their neighbourhood changed; stuck needles get local
  // supersampling. Bounded: slices per round at most twice the bad faces
  // left (plus a constant), at most 24 rounds, and three without progress.
  // Needle cuts are short (across the needle's neighbourhood) while that
  // makes progress, then run their full course, and wedge tips get their
  // series of cuts (cut_wedge()). Tips come last on purpose: from the first
  // round, on fan-tessellated CAD faces that midpoint cuts clear, they left
  // more faces and more needles (cgal__joint: 68 left, cad_cylinder: 8).
  //
  // Needles still left then are stuck between operations that undo each
  // other (a cut whose points the decimation takes back into a new needle:
  // on trimesh__fixed_top which needles stay depends on ulps of the cut
  // planes). The rounds run again with one more operation for the
  // decimation: a vertex removed with its hole triangulated anew for the
  // best worst shape. It runs only then: from the first round it left more
  // needles elsewhere (cgal__handle 5, cgal__turbine 36).
  auto rounds = [&]() {
    std::size_t bad = pipeline.bad_faces().size(), stalled = 0;
    bool short_cuts = true;
    for (int round = 0; round < 24 && bad > 0 && stalled < 3; ++round) {
      const std::size_t made =
          pipeline.slice_caps() + pipeline.slice_needles(2 * bad + 16, short_cuts, round % 2 == 1, !short_cuts);
      pipeline.decimate(pipeline.bad_faces());
      const std::size_t now = pipeline.bad_faces().size();
      if (now >= bad && short_cuts) {
        short_cuts = false;  // not stalled yet: the full cuts get their rounds
      } else {
        if (made == 0) break;
        stalled = now < bad ? 0 : stalled + 1;  // three rounds without progress end it
      }
      bad = now;
    }
    return bad;
  };
  if (!o.slice || rounds() > 0) {  // without slicing, no rounds: vertex removal at once
    pipeline.retriangulate();
    pipeline.decimate(pipeline.bad_faces());
    if (o.slice) rounds();
  }
  pipeline.simplify_split_points();
  pipeline.finish_stats();
  r.seconds_decimation = seconds_since(t0);

  // 5. round and certify
  t0 = std::chrono::steady_clock::now();
  if (o.observer) o.observer->stage("certifying");
  r.exact_bad = pipeline.bad_flags();
  result.soup = mesh_to_soup(mesh);
  if (o.certify) certify(input, result.soup, r);
  r.seconds_certify = seconds_since(t0);
  return result;
}

void certify(const Soup& input, const Soup& written, DegenerateReport& r) {
  std::size_t dropped = 0;
  const Soup clean = preprocess(input, dropped);
  InspectOptions io;
  io.cap_angle = r.cap_angle;
  io.needle_angle = r.needle_angle;
  const Report out = inspect(written, io);
  r.faces_out = out.faces;
  r.after = shape_counts(out);
  r.self_intersections_out = out.self_intersections.size();
  r.topology_out = topology_of(out);
  r.leftovers.clear();
  // Corners by welded point: pinch copies are written as separate points.
  const Weld weld = weld_identical_points(written.points);
  std::vector<char> intersecting(out.faces, 0), beside(written.points.size(), 0);
  for (const FacePair& p : out.self_intersections)
    for (std::size_t f : {p.first, p.second}) {
      intersecting[f] = 1;
      for (Index v : written.face(f)) beside[weld.representative[v]] = 1;
    }
  auto is_beside = [&](std::size_t f) {
    return std::any_of(written.face(f).begin(), written.face(f).end(),
                       [&](Index v) { return beside[weld.representative[v]] != 0; });
  };
  auto why = [&](std::size_t f, const char* unfixable) {
    const bool rounding = f < r.exact_bad.size() && !r.exact_bad[f];
    if (rounding) return std::string("made by rounding exact coordinates to doubles");
    if (intersecting[f])  // no operation may touch an intersection, no slice cut it
      return std::string("it intersects another face, as in the input: run deintersect or repair first");
    if (is_beside(f))
      return std::string("beside faces that intersect, as in the input (no slice may cut them): run deintersect "
                         "or repair first");
    return std::string(unfixable);
  };
  for (std::size_t f : out.degenerate_faces)
    r.leftovers.push_back({f, "zero-area", why(f, "no flip or collapse within the tolerance is valid")});
  for (std::size_t f : out.caps)
    r.leftovers.push_back({f, "cap", why(f, "its slice would create a cap, and no flip or collapse within the "
                                            "tolerance is valid")});
  for (std::size_t f : out.needles)
    r.leftovers.push_back({f, "needle", why(f, "no collapse or flip within the tolerance keeps the surface "
                                               "manifold, cap-free and intersection-free")});
  std::sort(r.leftovers.begin(), r.leftovers.end(), [](const Leftover& a, const Leftover& b) { return a.face < b.face; });
  // Bounded-error Hausdorff distance: the true value lies in [h, h + bound].
  // A coarse bound first; where h + bound straddles the tolerance, tighten
  // the bound just enough to decide (the cost grows as the bound shrinks).
  double error_bound = 0.25 * r.tolerance;
  r.hausdorff = detail::hausdorff_distance(clean, written, error_bound);
  for (int k = 0; k < 2 && r.hausdorff >= 0 && r.hausdorff < r.tolerance &&
                  r.hausdorff + error_bound > r.tolerance;
       ++k) {
    error_bound = 0.9 * (r.tolerance - r.hausdorff);
    r.hausdorff = detail::hausdorff_distance(clean, written, error_bound);
  }
  r.hausdorff_error_bound = error_bound;
  r.certified = r.after.total() == 0 && r.topology_out == r.topology_in &&
                r.self_intersections_out <= r.self_intersections_welded && r.hausdorff >= 0 &&
                r.hausdorff + error_bound <= r.tolerance;
}

}  // namespace polyheal
