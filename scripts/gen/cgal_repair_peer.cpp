// cgal_repair_peer — the CGAL baseline for `polyheal repair` in
// scripts/bench.sh: the repair a CGAL user assembles from Polygon Mesh
// Processing — read as a polygon soup; repair_polygon_soup (merge duplicate
// points and polygons, drop invalid ones); orient_polygon_soup; to a
// Surface_mesh; stitch_borders; triangulate_hole on every border; then
// PMP::experimental::remove_self_intersections — and the result written as OFF.
// Prints: seconds (the repair, without I/O) and faces out. The bench judges
// the written file with `polyheal check` and measures it with the same
// distance code as polyheal's output.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cstdio>
#include <vector>

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Epick;
using Mesh = CGAL::Surface_mesh<K::Point_3>;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: cgal_repair_peer IN OUT.off\n");
    return 2;
  }
  std::vector<K::Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  if (!CGAL::IO::read_polygon_soup(argv[1], points, polygons) || polygons.empty()) {
    std::fprintf(stderr, "cgal_repair_peer: cannot read %s as a polygon soup\n", argv[1]);
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  Mesh mesh;
  try {
    PMP::repair_polygon_soup(points, polygons);
    PMP::orient_polygon_soup(points, polygons);
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
    PMP::triangulate_faces(mesh);
    PMP::stitch_borders(mesh);
    std::vector<Mesh::Halfedge_index> borders;
    PMP::extract_boundary_cycles(mesh, std::back_inserter(borders));
    for (Mesh::Halfedge_index h : borders) {
      std::vector<Mesh::Face_index> added;
      PMP::triangulate_hole(mesh, h, std::back_inserter(added));
    }
    PMP::experimental::remove_self_intersections(mesh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cgal_repair_peer: %s\n", e.what());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  mesh.collect_garbage();
  if (!CGAL::IO::write_polygon_mesh(argv[2], mesh, CGAL::parameters::stream_precision(17))) return 2;
  std::printf("%.4f %zu\n", seconds, static_cast<std::size_t>(mesh.number_of_faces()));
  return 0;
}
