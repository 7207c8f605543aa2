// cgal_degenerate_peer — the CGAL baseline for `polyheal degenerate` in
// scripts/bench.sh: PMP::experimental::remove_almost_degenerate_faces (Epick)
// with the same thresholds (caps above 175 degrees; needles: longest/shortest
// edge above 1/sin(5 degrees), CGAL's needle measure; collapses no longer, and
// cap flips no higher, than 1 per mille of the bbox diagonal — the tolerance
// polyheal uses), then the output written as OFF.
// Prints: seconds, faces out, and the symmetric Hausdorff distance to the
// input (CGAL's bounded-error version, bound 1/4 of that tolerance).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
// The kernel before distance.h: its qualified CGAL::midpoint(Point_3, Point_3)
// must be declared first (CGAL issue #8009, fixed after 5.5).
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/distance.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cmath>
#include <cstdio>

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Epick;
using Mesh = CGAL::Surface_mesh<K::Point_3>;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: cgal_degenerate_peer IN OUT.off\n");
    return 2;
  }
  Mesh mesh;
  if (!PMP::IO::read_polygon_mesh(argv[1], mesh) || mesh.is_empty()) {
    std::fprintf(stderr, "cgal_degenerate_peer: cannot read %s as a polygon mesh\n", argv[1]);
    return 2;
  }
  const Mesh input = mesh;
  const CGAL::Bbox_3 box = PMP::bbox(mesh);
  const double diagonal = std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                                    CGAL::square(box.zmax() - box.zmin()));
  const double pi = 3.14159265358979323846;
  const auto t0 = std::chrono::steady_clock::now();
  PMP::experimental::remove_almost_degenerate_faces(
      mesh, std::cos(175.0 * pi / 180.0), 1.0 / std::sin(5.0 * pi / 180.0), 1e-3 * diagonal,
      CGAL::parameters::flip_triangle_height_threshold(1e-3 * diagonal));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  mesh.collect_garbage();
  if (!CGAL::IO::write_polygon_mesh(argv[2], mesh, CGAL::parameters::stream_precision(17))) return 2;
  const double h = mesh.is_empty() ? -1.0
                                   : PMP::bounded_error_symmetric_Hausdorff_distance<CGAL::Sequential_tag>(
                                         input, mesh, 0.25e-3 * diagonal);
  std::printf("%.4f %zu %.6g %.6g\n", seconds, static_cast<std::size_t>(mesh.number_of_faces()), h, diagonal);
  return 0;
}
