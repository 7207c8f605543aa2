// polyheal_gen — generators for test fixtures and benchmark inputs.
//
//   polyheal_gen tube --edge 3.0 OUT          Yamakawa & Shimada Fig. 3 thin-walled tube
//   polyheal_gen narrow-clearance OUT         100k clean faces + 5 such tubes (deintersect bench)
//   polyheal_gen cylinder --segments 96 OUT   Botsch & Kobbelt Fig. 1 CAD-like cylinder
//   polyheal_gen cone --segments 100 OUT      CAD-like cone: apex fan, base fanned from a corner
//   polyheal_gen torus-knot --faces 1000000 OUT
//   polyheal_gen torus OUT                    closed torus R=3, r=1
//   polyheal_gen offset --distance D IN OUT   raw offset along area-weighted vertex normals
//   polyheal_gen dirty-box OUT                box of separate patches: gap, overlap, T-junctions, hole
//   polyheal_gen assembly OUT PART...         parts placed into one file (a slicer's or robot's multi-body
//                                             model): PART = FILE@DX,DY,DZ,SCALE[,flip] (flip: inside out)
//   polyheal_gen distance A B                 one-sided distances A->B and B->A (the reports' measure), and
//                                             A->B over the part of A outside B's volume
//
// Output format from the extension; files are overwritten.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/rebuild.h"

using namespace polyheal;

namespace {

constexpr double kPi = 3.14159265358979323846;

Index add(Soup& s, double x, double y, double z) {
  s.points.push_back({x, y, z});
  return static_cast<Index>(s.points.size() - 1);
}

/// A closed thick-walled tube (outer radius ro, inner ri, length L) meshed with
/// target edge length e. The inner ring is rotated half a step, so its
/// vertices face the outer chords' midpoints: with ro = 5, ri = 4.8 the mesh is
/// clean for e = 2.42 (13 segments, outer inradius 4.854) and self-intersecting
/// for e = 3.0 (11 segments, outer inradius 4.797 < 4.8).
Soup tube(double ro, double ri, double length, double e) {
  Soup s;
  const int no = static_cast<int>(std::ceil(2 * kPi * ro / e));
  const int ni = static_cast<int>(std::ceil(2 * kPi * ri / e));
  const int nz = std::max(1, static_cast<int>(std::ceil(length / e)));
  std::vector<std::vector<Index>> outer(nz + 1), inner(nz + 1);
  for (int k = 0; k <= nz; ++k) {
    const double z = length * k / nz;
    for (int j = 0; j < no; ++j) outer[k].push_back(add(s, ro * std::cos(2 * kPi * j / no), ro * std::sin(2 * kPi * j / no), z));
    for (int j = 0; j < ni; ++j) {
      const double a = 2 * kPi * (j + 0.5) / ni;
      inner[k].push_back(add(s, ri * std::cos(a), ri * std::sin(a), z));
    }
  }
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < no; ++j) {  // outer wall, normals away from the axis
      const Index a = outer[k][j], b = outer[k][(j + 1) % no], c = outer[k + 1][(j + 1) % no], d = outer[k + 1][j];
      s.add_triangle(a, b, c);
      s.add_triangle(a, c, d);
    }
    for (int j = 0; j < ni; ++j) {  // inner wall, normals towards the axis
      const Index a = inner[k][j], b = inner[k][(j + 1) % ni], c = inner[k + 1][(j + 1) % ni], d = inner[k + 1][j];
      s.add_triangle(a, c, b);
      s.add_triangle(a, d, c);
    }
  }
  // End annuli: zip the outer and inner rings by angle.
  for (int end = 0; end < 2; ++end) {
    const auto& O = outer[end ? nz : 0];
    const auto& I = inner[end ? nz : 0];
    int i = 0, j = -1;  // inner vertex -1 == ni-1 at angle -pi/ni
    auto alpha = [&](int x) { return 2 * kPi * x / no; };
    auto beta = [&](int x) { return 2 * kPi * (x + 0.5) / ni; };
    auto in = [&](int x) { return I[(x + ni) % ni]; };
    while (i < no || j < ni - 1) {
      const bool outer_step = i < no && (j == ni - 1 || alpha(i + 1) <= beta(j + 1));
      Index a, b, c;
      if (outer_step) {
        a = O[i % no], b = O[(i + 1) % no], c = in(j);
        ++i;
      } else {
        a = O[i % no], b = in(j + 1), c = in(j);
        ++j;
      }
      if (end) s.add_triangle(a, b, c);  // top: +z
      else s.add_triangle(a, c, b);      // bottom: -z
    }
  }
  return s;
}

/// Botsch & Kobbelt Fig. 1: tall side strips, end disks fanned from one rim
/// vertex (caps next to the fan's apex, needles across the disk).
Soup cylinder(int n, double radius, double height) {
  Soup s;
  std::vector<Index> bottom, top;
  for (int j = 0; j < n; ++j) {
    const double a = 2 * kPi * j / n;
    bottom.push_back(add(s, radius * std::cos(a), radius * std::sin(a), 0));
    top.push_back(add(s, radius * std::cos(a), radius * std::sin(a), height));
  }
  for (int j = 0; j < n; ++j) {
    const int k = (j + 1) % n;
    s.add_triangle(bottom[j], bottom[k], top[k]);
    s.add_triangle(bottom[j], top[k], top[j]);
  }
  for (int j = 1; j + 1 < n; ++j) {
    s.add_triangle(top[0], top[j], top[j + 1]);
    s.add_triangle(bottom[0], bottom[j + 1], bottom[j]);
  }
  return s;
}

/// A CAD-like cone (base radius `radius` at z = 0, apex at z = height): its
/// side is one fan of n triangles at the apex (needles when n is large or
/// the cone tall), its base fanned from one corner as the cylinder's caps.
Soup cone(int n, double radius, double height) {
  Soup s;
  std::vector<Index> base;
  for (int j = 0; j < n; ++j) {
    const double a = 2 * kPi * j / n;
    base.push_back(add(s, radius * std::cos(a), radius * std::sin(a), 0));
  }
  const Index apex = add(s, 0, 0, height);
  for (int j = 0; j < n; ++j) s.add_triangle(base[j], base[(j + 1) % n], apex);
  for (int j = 1; j + 1 < n; ++j) s.add_triangle(base[0], base[j + 1], base[j]);
  return s;
}

double signed_volume(const Soup& s) {
  double v = 0;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const Point3d &a = s.points[s.face(f)[0]], &b = s.points[s.face(f)[1]], &c = s.points[s.face(f)[2]];
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return v / 6;
}

void flip_if_inside_out(Soup& s) {
  if (signed_volume(s) >= 0) return;
  for (std::size_t f = 0; f < s.face_count(); ++f) std::swap(s.indices[s.offsets[f] + 1], s.indices[s.offsets[f] + 2]);
}

/// A tube of radius rho around the (2,3) torus knot, about `faces` triangles,
/// with ring spacing close to the segment length (well-shaped triangles).
Soup torus_knot(std::size_t faces, double rho) {
  double length = 0;  // of the centre curve
  for (int i = 0; i < 100000; ++i) {
    const double t = 2 * kPi * i / 100000, r = 2 + std::cos(3 * t), dr = -3 * std::sin(3 * t);
    length += std::sqrt(dr * dr + 4 * r * r + 9 * std::cos(3 * t) * std::cos(3 * t)) * 2 * kPi / 100000;
  }
  const double ratio = length / (2 * kPi * rho);  // rings per segment for square cells
  const int m = std::max(8, static_cast<int>(std::lround(std::sqrt(faces / (2 * ratio)))));
  const int n = std::max<int>(16, static_cast<int>(faces / (2 * m)));
  Soup s;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n;
    const double r = 2 + std::cos(3 * t);
    const double c[3] = {r * std::cos(2 * t), r * std::sin(2 * t), std::sin(3 * t)};
    const double dr = -3 * std::sin(3 * t);
    double T[3] = {dr * std::cos(2 * t) - 2 * r * std::sin(2 * t), dr * std::sin(2 * t) + 2 * r * std::cos(2 * t),
                   3 * std::cos(3 * t)};
    double B[3] = {T[1], -T[0], 0};  // T x z
    const double lb = std::hypot(B[0], B[1]);
    B[0] /= lb, B[1] /= lb;
    const double lt = std::sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
    for (double& x : T) x /= lt;
    const double N[3] = {B[1] * T[2] - B[2] * T[1], B[2] * T[0] - B[0] * T[2], B[0] * T[1] - B[1] * T[0]};
    for (int j = 0; j < m; ++j) {
      const double a = 2 * kPi * j / m;
      add(s, c[0] + rho * (std::cos(a) * N[0] + std::sin(a) * B[0]), c[1] + rho * (std::cos(a) * N[1] + std::sin(a) * B[1]),
          c[2] + rho * (std::cos(a) * N[2] + std::sin(a) * B[2]));
    }
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const Index a = i * m + j, b = i * m + (j + 1) % m, c = ((i + 1) % n) * m + (j + 1) % m, d = ((i + 1) % n) * m + j;
      s.add_triangle(a, b, c);
      s.add_triangle(a, c, d);
    }
  flip_if_inside_out(s);
  return s;
}

Soup torus(double R, double r, int nu, int nv) {
  Soup s;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      add(s, (R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const Index a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                  d = i * nv + (j + 1) % nv;
      s.add_triangle(a, b, c);
      s.add_triangle(a, c, d);
    }
  flip_if_inside_out(s);
  return s;
}

/// Raw offset: every vertex moves by `d` along its area-weighted normal.
Soup offset(const Soup& in, double d) {
  std::vector<std::array<double, 3>> n(in.points.size(), {0, 0, 0});
  for (std::size_t f = 0; f < in.face_count(); ++f) {
    FaceView v = in.face(f);
    const Point3d &a = in.points[v[0]];
    for (std::size_t k = 1; k + 1 < v.size(); ++k) {
      const Point3d &b = in.points[v[k]], &c = in.points[v[k + 1]];
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
      for (Index i : v)
        for (int a3 = 0; a3 < 3; ++a3) n[i][a3] += x[a3];
    }
  }
  Soup out = in;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const double l = std::sqrt(n[i][0] * n[i][0] + n[i][1] * n[i][1] + n[i][2] * n[i][2]);
    if (l > 0)
      for (int a = 0; a < 3; ++a) out.points[i][a] += d * n[i][a] / l;
  }
  return out;
}

/// One face of a box as its own k-by-k grid patch (no shared vertices with the
/// other patches). `origin` + s*u + t*v, s, t in [lo, hi].
void patch(Soup& s, const double origin[3], const double u[3], const double v[3], int k, double lo, double hi,
           int skip_cell = -1) {
  const Index base = static_cast<Index>(s.points.size());
  for (int i = 0; i <= k; ++i)
    for (int j = 0; j <= k; ++j) {
      const double a = lo + (hi - lo) * i / k, b = lo + (hi - lo) * j / k;
      add(s, origin[0] + a * u[0] + b * v[0], origin[1] + a * u[1] + b * v[1], origin[2] + a * u[2] + b * v[2]);
    }
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      if (i * k + j == skip_cell) continue;  // a hole
      const Index a = base + i * (k + 1) + j, b = base + (i + 1) * (k + 1) + j, c = base + (i + 1) * (k + 1) + j + 1,
                  d = base + i * (k + 1) + j + 1;
      s.add_triangle(a, b, c);
      s.add_triangle(a, c, d);
    }
}

/// A 10-unit box whose six faces are separate patches: +x shrunk (gaps), +y
/// enlarged (overlaps), +z at another resolution (T-junctions, duplicated
/// edges), -z missing one cell (a hole).
Soup dirty_box() {
  Soup s;
  const double L = 10;
  struct Side {
    double o[3], u[3], v[3];
  };
  // u x v points outwards.
  const Side sides[6] = {
      {{L, 0, 0}, {0, 1, 0}, {0, 0, 1}},  // +x
      {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},  // -x
      {{0, L, 0}, {0, 0, 1}, {1, 0, 0}},  // +y
      {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}},  // -y
      {{0, 0, L}, {1, 0, 0}, {0, 1, 0}},  // +z
      {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}},  // -z
  };
  patch(s, sides[0].o, sides[0].u, sides[0].v, 4, 0.05, L - 0.05);
  patch(s, sides[1].o, sides[1].u, sides[1].v, 4, 0, L);
  patch(s, sides[2].o, sides[2].u, sides[2].v, 4, -0.05, L + 0.05);
  patch(s, sides[3].o, sides[3].u, sides[3].v, 4, 0, L);
  patch(s, sides[4].o, sides[4].u, sides[4].v, 3, 0, L);
  patch(s, sides[5].o, sides[5].u, sides[5].v, 4, 0, L, 5);
  return s;
}

/// A large clean mesh with a few small narrow-clearance defects: a torus-knot
/// tube of `faces` faces and `tubes` copies of the coarse thin-walled tube
/// (edge 3.0, 220 faces, every face intersecting) in a row beside it — the
/// benchmark for "work grows with the intersecting region, not the mesh".
Soup narrow_clearance(std::size_t faces, int tubes) {
  Soup s = torus_knot(faces, 0.2);
  double xmax = 0;
  for (const Point3d& p : s.points) xmax = std::max(xmax, p[0]);
  for (int k = 0; k < tubes; ++k) {
    const Soup t = tube(5.0, 4.8, 12.0, 3.0);
    const Index base = static_cast<Index>(s.points.size());
    for (const Point3d& p : t.points) s.points.push_back({p[0] + xmax + 6.0 + 11.0 * k, p[1], p[2]});
    for (std::size_t f = 0; f < t.face_count(); ++f) {
      const FaceView v = t.face(f);
      s.add_triangle(base + v[0], base + v[1], base + v[2]);
    }
  }
  return s;
}

/// One part of `assembly`: FILE@DX,DY,DZ,SCALE[,flip] — its points scaled
/// about the origin, then moved; `flip` turns its faces inside out.
void add_part(Soup& s, const std::string& spec) {
  const std::size_t at = spec.rfind('@');
  if (at == std::string::npos) throw std::runtime_error("part '" + spec + "': expected FILE@DX,DY,DZ,SCALE[,flip]");
  const Soup part = read_soup(spec.substr(0, at));
  double t[4] = {0, 0, 0, 1};
  bool flip = false;
  std::size_t from = at + 1;
  for (int k = 0; from <= spec.size(); ++k) {
    const std::size_t comma = std::min(spec.find(',', from), spec.size());
    const std::string field = spec.substr(from, comma - from);
    if (k < 4) t[k] = std::atof(field.c_str());
    else if (field == "flip") flip = true;
    else throw std::runtime_error("part '" + spec + "': unknown field '" + field + "'");
    from = comma + 1;
  }
  const Index base = Index(s.points.size());
  for (const Point3d& p : part.points) s.points.push_back({p[0] * t[3] + t[0], p[1] * t[3] + t[1], p[2] * t[3] + t[2]});
  for (std::size_t f = 0; f < part.face_count(); ++f) {
    const FaceView v = part.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k)
      flip ? s.add_triangle(base + v[0], base + v[k + 1], base + v[k]) : s.add_triangle(base + v[0], base + v[k], base + v[k + 1]);
  }
}

[[noreturn]] void usage() {
  std::fprintf(stderr,
               "usage: polyheal_gen tube [--edge E] [--outer R] [--inner R] [--length L] OUT\n"
               "       polyheal_gen cylinder [--segments N] [--radius R] [--height H] OUT\n"
               "       polyheal_gen torus-knot [--faces N] OUT\n"
               "       polyheal_gen torus OUT\n"
               "       polyheal_gen offset --distance D IN OUT\n"
               "       polyheal_gen dirty-box OUT\n"
               "       polyheal_gen assembly OUT FILE@DX,DY,DZ,SCALE[,flip]...\n"
               "       polyheal_gen narrow-clearance [--faces N] [--tubes K] OUT\n"
               "       polyheal_gen distance A B   (prints: A->B B->A diagonal-of-A A->B-outside-B, bounded error 1e-4 diagonal)\n");
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) usage();
  const std::string cmd = argv[1];
  std::vector<std::string> pos;
  auto opt = [&](const char* name, double def) {
    for (int i = 2; i + 1 < argc; ++i)
      if (std::strcmp(argv[i], name) == 0) return std::atof(argv[i + 1]);
    return def;
  };
  for (int i = 2; i < argc; ++i) {
    if (argv[i][0] == '-' && argv[i][1] == '-') {
      ++i;
      continue;
    }
    pos.push_back(argv[i]);
  }
  try {
    if (cmd == "distance" && pos.size() == 2) {
      const Soup a = read_soup(pos[0]), b = read_soup(pos[1]);
      double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      for (const Point3d& p : a.points)
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], p[k]);
          hi[k] = std::max(hi[k], p[k]);
        }
      const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                    (hi[2] - lo[2]) * (hi[2] - lo[2]));
      const std::array<double, 2> d = detail::one_sided_distances(a, b, 1e-4 * diag);
      // A to B over the part of A outside B's volume (B's generalised winding
      // number at most 1/2): what B loses of A, its removed interiors aside.
      const double outside = measure_loss(a, b, 2e-3 * diag, true).outside_distance;
      std::printf("%.6g %.6g %.6g %.6g\n", d[0], d[1], diag, outside);
      return 0;
    }
    Soup s;
    if (cmd == "assembly" && pos.size() >= 2) {
      for (std::size_t k = 1; k < pos.size(); ++k) add_part(s, pos[k]);
      pos = {pos.front()};
    } else if (cmd == "tube" && pos.size() == 1) s = tube(opt("--outer", 5.0), opt("--inner", 4.8), opt("--length", 12.0), opt("--edge", 3.0));
    else if (cmd == "cylinder" && pos.size() == 1) s = cylinder(int(opt("--segments", 96)), opt("--radius", 10), opt("--height", 40));
    else if (cmd == "torus-knot" && pos.size() == 1) s = torus_knot(std::size_t(opt("--faces", 100000)), opt("--radius", 0.2));
    else if (cmd == "cone" && pos.size() == 1) s = cone(int(opt("--segments", 100)), opt("--radius", 10), opt("--height", 10));
    else if (cmd == "torus" && pos.size() == 1) s = torus(3, 1, 48, 24);
    else if (cmd == "offset" && pos.size() == 2) s = offset(read_soup(pos[0]), opt("--distance", 0.1));
    else if (cmd == "dirty-box" && pos.size() == 1) s = dirty_box();
    else if (cmd == "narrow-clearance" && pos.size() == 1) s = narrow_clearance(std::size_t(opt("--faces", 100000)), int(opt("--tubes", 5)));
    else usage();
    WriteOptions w;
    w.allow_overwrite = true;
    write_soup(s, pos.back(), w);
    std::printf("%s: %zu vertices, %zu faces\n", pos.back().c_str(), s.points.size(), s.face_count());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "polyheal_gen: %s\n", e.what());
    return 2;
  }
  return 0;
}
