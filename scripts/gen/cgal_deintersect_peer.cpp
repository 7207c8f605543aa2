// cgal_deintersect_peer — the CGAL baseline for `polyheal deintersect` in
// scripts/bench.sh: PMP::experimental::remove_self_intersections (Epick,
// default parameters: local smoothing, then hole filling), then the output
// written as OFF.
// Prints: seconds, faces out, whether CGAL's own check still finds a
// self-intersection (1/0), the symmetric Hausdorff distance to the input
// (CGAL's bounded-error version, bound 1e-4 of the bbox diagonal; -1 when
// the output is empty), and the bbox diagonal.
// The bench certifies the written file with `polyheal check` as well: the
// peer's verdict is its own, in doubles.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
// The kernel before distance.h (CGAL issue #8009, fixed after 5.5).
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/distance.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cmath>
#include <cstdio>

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Epick;
using Mesh = CGAL::Surface_mesh<K::Point_3>;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: cgal_deintersect_peer IN OUT.off\n");
    return 2;
  }
  Mesh mesh;
  if (!PMP::IO::read_polygon_mesh(argv[1], mesh) || mesh.is_empty()) {
    std::fprintf(stderr, "cgal_deintersect_peer: cannot read %s as a polygon mesh\n", argv[1]);
    return 2;
  }
  const Mesh input = mesh;
  const CGAL::Bbox_3 box = PMP::bbox(mesh);
  const double diagonal = std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                                    CGAL::square(box.zmax() - box.zmin()));
  const auto t0 = std::chrono::steady_clock::now();
  bool ok = false;
  try {
    ok = PMP::experimental::remove_self_intersections(mesh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cgal_deintersect_peer: %s\n", e.what());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  mesh.collect_garbage();
  if (!CGAL::IO::write_polygon_mesh(argv[2], mesh, CGAL::parameters::stream_precision(17))) return 2;
  const bool still = !mesh.is_empty() && PMP::does_self_intersect(mesh);
  const double h = mesh.is_empty() ? -1.0
                                   : PMP::bounded_error_symmetric_Hausdorff_distance<CGAL::Sequential_tag>(
                                         input, mesh, 1e-4 * diagonal);
  std::printf("%.4f %zu %d %.6g %.6g %d\n", seconds, static_cast<std::size_t>(mesh.number_of_faces()), still ? 1 : 0, h,
              diagonal, ok ? 1 : 0);
  return 0;
}
