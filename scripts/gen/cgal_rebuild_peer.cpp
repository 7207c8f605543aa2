// cgal_rebuild_peer — the CGAL baseline for `polyheal rebuild` in
// scripts/bench.sh: CGAL::alpha_wrap_3 on the input as a polygon soup, with
// alpha and offset given as fractions of the bounding-box diagonal, written
// as OFF. Prints: seconds (the wrap alone), faces out.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

using K = CGAL::Epick;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: cgal_rebuild_peer IN OUT.off ALPHA OFFSET   (fractions of the bbox diagonal)\n");
    return 2;
  }
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> faces;
  if (!CGAL::IO::read_polygon_soup(argv[1], points, faces) || faces.empty()) {
    std::fprintf(stderr, "cgal_rebuild_peer: cannot read %s as a polygon soup\n", argv[1]);
    return 2;
  }
  const CGAL::Bbox_3 box = CGAL::bbox_3(points.begin(), points.end());
  const double diag = std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                                CGAL::square(box.zmax() - box.zmin()));
  const double alpha = std::atof(argv[3]) * diag, offset = std::atof(argv[4]) * diag;
  // alpha_wrap_3 takes triangles: fan the polygons.
  std::vector<std::array<std::size_t, 3>> tris;
  for (const auto& f : faces)
    for (std::size_t k = 1; k + 1 < f.size(); ++k) tris.push_back({f[0], f[k], f[k + 1]});
  Mesh wrap;
  const auto t0 = std::chrono::steady_clock::now();
  CGAL::alpha_wrap_3(points, tris, alpha, offset, wrap);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!CGAL::IO::write_polygon_mesh(argv[2], wrap, CGAL::parameters::stream_precision(17))) return 2;
  std::printf("%.4f %zu\n", seconds, static_cast<std::size_t>(wrap.number_of_faces()));
  return 0;
}
