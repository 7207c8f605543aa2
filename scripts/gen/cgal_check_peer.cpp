// cgal_check_peer — the CGAL baseline for `polyheal check` in scripts/bench.sh:
// PMP::IO::read_polygon_mesh + PMP::self_intersections (Epick), sequential or
// parallel. Prints: read seconds, check seconds, pair count.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <vector>

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Epick;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using face = boost::graph_traits<Mesh>::face_descriptor;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: cgal_check_peer FILE [--parallel]\n");
    return 2;
  }
  const bool parallel = argc > 2 && std::strcmp(argv[2], "--parallel") == 0;
  auto t0 = std::chrono::steady_clock::now();
  Mesh mesh;
  if (!PMP::IO::read_polygon_mesh(argv[1], mesh)) {
    std::fprintf(stderr, "cgal_check_peer: cannot read %s as a polygon mesh\n", argv[1]);
    return 2;
  }
  auto t1 = std::chrono::steady_clock::now();
  std::vector<std::pair<face, face>> pairs;
  if (parallel)
    PMP::self_intersections<CGAL::Parallel_if_available_tag>(mesh, std::back_inserter(pairs));
  else
    PMP::self_intersections<CGAL::Sequential_tag>(mesh, std::back_inserter(pairs));
  auto t2 = std::chrono::steady_clock::now();
  std::printf("%.3f %.3f %zu\n", std::chrono::duration<double>(t1 - t0).count(),
              std::chrono::duration<double>(t2 - t1).count(), pairs.size());
  return 0;
}
