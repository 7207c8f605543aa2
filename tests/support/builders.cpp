#include "support/builders.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "polyheal/mesh/vec3.h"

namespace polyheal::test {

Soup soup(std::initializer_list<Point3d> points, std::initializer_list<std::array<Index, 3>> faces) {
  Soup s;
  s.points.assign(points.begin(), points.end());
  for (const auto& f : faces) s.add_triangle(f[0], f[1], f[2]);
  return s;
}

Soup tetrahedron(double dx, double dy, double dz) {
  return soup({{dx, dy, dz}, {dx + 1, dy, dz}, {dx, dy + 1, dz}, {dx, dy, dz + 1}},
              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

Soup box(const Point3d& lo, const Point3d& hi, bool inward) {
  Soup s = soup({{lo[0], lo[1], lo[2]}, {hi[0], lo[1], lo[2]}, {hi[0], hi[1], lo[2]}, {lo[0], hi[1], lo[2]},
                 {lo[0], lo[1], hi[2]}, {hi[0], lo[1], hi[2]}, {hi[0], hi[1], hi[2]}, {lo[0], hi[1], hi[2]}},
                {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                 {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}});
  if (inward)
    for (std::size_t f = 0; f < s.face_count(); ++f) std::swap(s.indices[3 * f + 1], s.indices[3 * f + 2]);
  return s;
}

Soup perturbed(const Soup& s, PerturbKind kind, std::uint64_t seed) {
  PerturbOptions o;
  o.kind = kind;
  o.seed = seed;
  return perturb(s, o).soup;
}

Soup concat(const Soup& a, const Soup& b) {
  Soup s = a;
  s.append(b);
  return s;
}

Soup without_faces(const Soup& s, const std::function<bool(std::size_t)>& drop) {
  Soup out;
  out.points = s.points;
  for (std::size_t f = 0; f < s.face_count(); ++f)
    if (!drop(f)) out.add_face(s.face(f).begin(), s.face(f).end());
  return out;
}

/// A sphere of radius r: an icosahedron subdivided `levels` times, its
/// vertices pushed onto the sphere.
Soup icosphere(double r, int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Soup s = soup({{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                       {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}},
                      {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                       {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}});
  auto push = [&](Point3d p) {
    const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return Point3d{r * p[0] / l, r * p[1] / l, r * p[2] / l};
  };
  for (Point3d& p : s.points) p = push(p);
  for (int level = 0; level < levels; ++level) {
    Soup next;
    next.points = s.points;
    std::map<std::pair<Index, Index>, Index> mid;
    auto middle = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Point3d& p = s.points[a];
      const Point3d& q = s.points[b];
      next.points.push_back(push({(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2}));
      return mid[key] = Index(next.points.size() - 1);
    };
    for (std::size_t f = 0; f < s.face_count(); ++f) {
      const Index a = s.face(f)[0], b = s.face(f)[1], c = s.face(f)[2];
      const Index ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      next.add_triangle(a, ab, ca);
      next.add_triangle(ab, b, bc);
      next.add_triangle(ca, bc, c);
      next.add_triangle(ab, bc, ca);
    }
    s = std::move(next);
  }
  return s;
}

std::string fixture(const std::string& name) { return std::string(POLYHEAL_SOURCE_DIR) + "/fixtures/" + name; }

std::string scratch(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(POLYHEAL_BINARY_DIR) / "test-scratch";
  std::filesystem::create_directories(dir);
  const std::filesystem::path p = dir / name;
  std::filesystem::create_directories(p.parent_path());
  std::filesystem::remove_all(p);
  return p.string();
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string run(const std::string& command) {
  std::string out;
  if (FILE* p = ::popen((command + " 2>&1").c_str(), "r")) {
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    ::pclose(p);
  }
  return out;
}

bool tetgen_meshes(const std::string& path, const std::string& name, const std::string& switches) {
  const std::string copy = scratch(name);
  std::filesystem::copy_file(path, copy, std::filesystem::copy_options::overwrite_existing);
  return run("tetgen " + switches + " '" + copy + "' >/dev/null 2>&1; echo \"exit=$?\"").find("exit=0") != std::string::npos;
}

Soup touching_spheres(bool over_face, std::array<Point3d, 2>& touching) {
  const Soup a = icosphere(1, 3);
  const Point3d contact{0, 0, 1};
  Point3d shift{0, 0, 2 + 1e-10};  // a's top vertex (0, 0, 1) under b's bottom one (0, 0, -1)
  if (over_face) {
    std::size_t f = 0;
    while (f < a.face_count() && a.points[a.face(f)[0]] != contact && a.points[a.face(f)[1]] != contact &&
           a.points[a.face(f)[2]] != contact)
      ++f;
    const Point3d &p = a.points[a.face(f)[0]], &q = a.points[a.face(f)[1]], &r = a.points[a.face(f)[2]];
    const Point3d c = mul(add(add(p, q), r), 1.0 / 3);
    const Point3d n = cross(sub(q, p), sub(r, p));
    const double x = c[0] / 2, y = c[1] / 2;  // halfway from the top vertex to the centroid
    const double z = p[2] - (n[0] * (x - p[0]) + n[1] * (y - p[1])) / n[2];  // on the face's plane
    shift = {x, y, z + 1 + 1e-10};
  }
  touching = {contact, add(Point3d{0, 0, -1}, shift)};
  Soup b = a;
  for (Point3d& p : b.points) p = add(p, shift);
  return concat(a, b);
}

double ring_radius(const Soup& s, const Point3d& v) {
  double r = 0;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView t = s.face(f);
    if (std::none_of(t.begin(), t.end(), [&](Index i) { return s.points[i] == v; })) continue;
    for (Index i : t) r = std::max(r, norm(sub(s.points[i], v)));
  }
  return r;
}

std::set<std::array<Point3d, 3>> faces_by_position(const Soup& s) {
  std::set<std::array<Point3d, 3>> out;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView v = s.face(f);
    std::array<Point3d, 3> t{s.points[v[0]], s.points[v[1]], s.points[v[2]]};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    out.insert(t);
  }
  return out;
}

}  // namespace polyheal::test
