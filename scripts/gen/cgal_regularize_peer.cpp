// cgal_regularize_peer — the CGAL baseline for `polyheal regularize` in
// scripts/bench.sh: PMP::experimental::autorefine_and_remove_self_intersections
// (Epeck, as its documentation requires exact constructions), the result
// rounded to doubles and written as OFF.
// Prints: seconds, faces out, whether the function reported success (1/0),
// whether CGAL's own check still finds a self-intersection in the rounded
// mesh (1/0).
// The bench certifies the written file with `polyheal check` as well: the
// peer's verdict is its own.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cstdio>

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Epeck;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using KD = CGAL::Epick;
using MeshD = CGAL::Surface_mesh<KD::Point_3>;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: cgal_regularize_peer IN OUT.off\n");
    return 2;
  }
  Mesh mesh;
  if (!PMP::IO::read_polygon_mesh(argv[1], mesh) || mesh.is_empty()) {
    std::fprintf(stderr, "cgal_regularize_peer: cannot read %s as a polygon mesh\n", argv[1]);
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  bool ok = false;
  try {
    ok = PMP::experimental::autorefine_and_remove_self_intersections(mesh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cgal_regularize_peer: %s\n", e.what());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  mesh.collect_garbage();
  MeshD out;
  CGAL::copy_face_graph(mesh, out, CGAL::parameters::vertex_to_vertex_output_iterator(CGAL::Emptyset_iterator()),
                        CGAL::parameters::default_values());
  if (!CGAL::IO::write_polygon_mesh(argv[2], out, CGAL::parameters::stream_precision(17))) return 2;
  const bool still = !out.is_empty() && PMP::does_self_intersect(out);
  std::printf("%.4f %zu %d %d\n", seconds, static_cast<std::size_t>(out.number_of_faces()), ok ? 1 : 0, still ? 1 : 0);
  return 0;
}
