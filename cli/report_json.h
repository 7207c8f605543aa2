// polyheal CLI — JSON pieces shared by the repair commands' reports.
#pragma once

#include <sys/resource.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "polyheal/inspect/report.h"

namespace polyheal::cli {

inline double peak_memory_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

/// What keeps the written file from being certified, one phrase each.
inline std::vector<std::string> defects(const Report& out) {
  std::vector<std::string> d;
  auto add = [&](std::size_t n, const char* what) {
    if (n) d.push_back(std::to_string(n) + " " + what);
  };
  add(out.boundary_edges.size(), "boundary edges");
  add(out.nonmanifold_edges.size(), "non-manifold edges");
  add(out.nonmanifold_vertices.size(), "non-manifold vertices");
  add(out.misoriented_edges.size(), "misoriented edges");
  add(out.degenerate_faces.size(), "degenerate faces");
  add(out.duplicate_faces.size(), "duplicate faces");
  add(out.self_intersections.size(), "intersecting pairs");
  if (out.faces == 0) d.push_back("no face left");
  return d;
}

inline nlohmann::json topology_json(const SurfaceTopology& t) {
  return {{"euler_characteristic", t.euler}, {"components", t.components}, {"boundary_loops", t.boundary_loops},
          {"manifold", t.manifold}};
}

/// The exact checks of one file, flat: what `repair` reports of its output,
/// what a certificate records and `check --certificate` compares.
inline nlohmann::json checks_json(const Report& r) {
  return {{"faces", r.faces},
          {"components", r.components},
          {"closed", r.closed},
          {"manifold", r.manifold},
          {"oriented", r.oriented},
          {"boundary_edges", r.boundary_edges.size()},
          {"nonmanifold_edges", r.nonmanifold_edges.size()},
          {"nonmanifold_vertices", r.nonmanifold_vertices.size()},
          {"misoriented_edges", r.misoriented_edges.size()},
          {"duplicate_faces", r.duplicate_faces.size()},
          {"degenerate_faces", r.degenerate_faces.size()},
          {"self_intersecting_pairs", r.self_intersections.size()},
          {"tetgen_sharp_folds", r.sharp_folds.size()},
          {"tetgen_nearly_degenerate_faces", r.nearly_degenerate_faces.size()},
          {"certified_clean", r.certified_clean()},
          {"tetgen_ready", r.tetgen_ready()}};
}

}  // namespace polyheal::cli
