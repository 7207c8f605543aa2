// polyheal — adversarial degenerate tessellations (see perturb.h).
#include "polyheal/mesh/perturb.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

using Tri = std::array<Index, 3>;

/// Deterministic everywhere: mt19937_64 is fully specified; the
/// distributions of <random> are not, so none is used.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : g_(seed) {}
  double unit() { return double(g_() >> 11) * 0x1.0p-53; }  // [0, 1)
  std::size_t below(std::size_t n) { return std::size_t(g_() % n); }
  template <class T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[below(i)]);
  }

 private:
  std::mt19937_64 g_;
};

Point3d along(const Point3d& p, const Point3d& dir, double t) {
  return {p[0] + t * dir[0], p[1] + t * dir[1], p[2] + t * dir[2]};
}

/// A point strictly between a and b at parameter t from a (at least one
/// double step away from a, so the split never repeats a point).
Point3d split_point(const Point3d& a, const Point3d& b, double t) {
  Point3d m = along(a, sub(b, a), t);
  if (m == a)
    for (int k = 0; k < 3; ++k)
      if (a[k] != b[k]) m[k] = std::nextafter(a[k], b[k]);
  return m;
}

double longest_edge(const Point3d& a, const Point3d& b, const Point3d& c) {
  return std::max({norm(sub(b, a)), norm(sub(c, b)), norm(sub(a, c))});
}

}  // namespace

const char* to_string(PerturbKind kind) {
  switch (kind) {
    case PerturbKind::near_coplanar: return "near-coplanar";
    case PerturbKind::near_collinear: return "near-collinear";
    case PerturbKind::duplicates: return "duplicates";
    case PerturbKind::slivers: return "slivers";
  }
  return "?";
}

PerturbKind parse_perturb_kind(const std::string& name) {
  for (PerturbKind k : {PerturbKind::near_coplanar, PerturbKind::near_collinear, PerturbKind::duplicates,
                        PerturbKind::slivers})
    if (name == to_string(k)) return k;
  throw std::invalid_argument("unknown kind '" + name + "' (expected near-coplanar, near-collinear, duplicates or slivers)");
}

PerturbResult perturb(const Soup& input, const PerturbOptions& o) {
  PerturbResult r;
  r.faces_in = input.face_count();
  const Weld weld = weld_identical_points(input.points);
  std::vector<Point3d> pts = input.points;
  std::vector<Tri> tris;
  for (std::size_t f = 0; f < input.face_count(); ++f) {
    const FaceView v = input.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k)
      tris.push_back({weld.representative[v[0]], weld.representative[v[k]], weld.representative[v[k + 1]]});
  }
  Rng rng(o.seed);
  std::vector<Tri> out;
  std::vector<char> used(tris.size(), 0);
  auto add_point = [&](const Point3d& p) {
    pts.push_back(p);
    return Index(pts.size() - 1);
  };

  if (o.kind == PerturbKind::near_coplanar || o.kind == PerturbKind::duplicates) {
    std::vector<std::size_t> order(tris.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    rng.shuffle(order);
    const std::size_t n = std::size_t(std::llround(o.fraction * double(tris.size())));
    for (std::size_t i = 0; i < n && i < order.size(); ++i) used[order[i]] = 1;
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const Tri& f = tris[t];
      if (!used[t]) {
        out.push_back(f);
        continue;
      }
      ++r.operations;
      const Point3d &a = pts[f[0]], &b = pts[f[1]], &c = pts[f[2]];
      if (o.kind == PerturbKind::near_coplanar) {
        // Centroid lifted off the plane: three faces within epsilon of coplanar.
        const Point3d n = normal(a, b, c);
        const double len = norm(n);
        Point3d g{(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
        if (len > 0) g = along(g, n, (rng.unit() < 0.5 ? -1 : 1) * o.epsilon * longest_edge(a, b, c) / len);
        const Index p = add_point(g);
        out.push_back({f[0], f[1], p});
        out.push_back({f[1], f[2], p});
        out.push_back({f[2], f[0], p});
      } else if (rng.unit() < 0.5) {
        // A repeated face, in either orientation.
        out.push_back(f);
        out.push_back(rng.unit() < 0.5 ? f : Tri{f[0], f[2], f[1]});
      } else {
        // A corner replaced by an unwelded copy of its point.
        Tri g = f;
        const std::size_t k = rng.below(3);
        g[k] = add_point(pts[f[k]]);
        out.push_back(g);
      }
    }
  } else {
    // Edge operations: interior edges with two consistently oriented faces,
    // each face touched at most once.
    std::unordered_map<std::uint64_t, std::vector<std::pair<std::size_t, int>>> uses;  // (face, corner of edge start)
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        Index a = tris[t][k], b = tris[t][(k + 1) % 3];
        uses[undirected_edge_key(a, b)].push_back({t, k});
      }
    std::vector<std::array<std::pair<std::size_t, int>, 2>> edges;
    for (const auto& [key, u] : uses)
      if (u.size() == 2 && tris[u[0].first][u[0].second] == tris[u[1].first][(u[1].second + 1) % 3])
        edges.push_back({u[0], u[1]});
    std::sort(edges.begin(), edges.end());  // unordered_map order is not portable
    rng.shuffle(edges);
    const std::size_t n = std::size_t(std::llround(o.fraction * double(tris.size())));
    std::vector<std::vector<Tri>> replaced(tris.size());
    for (const auto& e : edges) {
      if (r.operations >= n) break;
      const auto [f1, k1] = e[0];
      const auto [f2, k2] = e[1];
      if (used[f1] || used[f2]) continue;
      used[f1] = used[f2] = 1;
      ++r.operations;
      // f1 = (a, b, c) with the edge a->b; f2 = (b, a, d).
      const Index a = tris[f1][k1], b = tris[f1][(k1 + 1) % 3], c = tris[f1][(k1 + 2) % 3];
      const Index d = tris[f2][(k2 + 2) % 3];
      const Point3d &pa = pts[a], &pb = pts[b], &pc = pts[c];
      const double len = norm(sub(pb, pa));
      if (o.kind == PerturbKind::slivers) {
        // Split epsilon from a: needles (a, m, c) and (m, a, d).
        const Index m = add_point(split_point(pa, pb, o.epsilon));
        replaced[f1] = {{a, m, c}, {m, b, c}};
        replaced[f2] = {{b, m, d}, {m, a, d}};
      } else {
        // near-collinear: m just inside f1, epsilon x |ab| off the edge;
        // f1 becomes (a, m, c), (m, b, c) and the cap (a, b, m), which
        // tile it exactly; f2 is left as it is.
        const Point3d ab = sub(pb, pa), ac = sub(pc, pa);
        const Point3d inward = cross(cross(ab, ac), ab);  // in f1's plane, perpendicular to ab, toward c
        const double il = norm(inward);
        Point3d m = split_point(pa, pb, 0.25 + 0.5 * rng.unit());
        if (il > 0) m = along(m, inward, o.epsilon * len / il);
        const Index mi = add_point(m);
        replaced[f1] = {{a, mi, c}, {mi, b, c}, {a, b, mi}};
        replaced[f2] = {tris[f2]};
      }
    }
    for (std::size_t t = 0; t < tris.size(); ++t) {
      if (!used[t]) out.push_back(tris[t]);
      else out.insert(out.end(), replaced[t].begin(), replaced[t].end());
    }
  }

  // Compact the points to those the faces use (in first-use order).
  std::vector<Index> map(pts.size(), Index(-1));
  for (Tri& t : out) {
    for (Index& i : t) {
      if (map[i] == Index(-1)) {
        map[i] = Index(r.soup.points.size());
        r.soup.points.push_back(pts[i]);
      }
      i = map[i];
    }
    r.soup.add_triangle(t[0], t[1], t[2]);
  }
  r.faces_out = r.soup.face_count();
  return r;
}

}  // namespace polyheal
