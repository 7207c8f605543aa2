// polyheal CLI — JSON pieces shared by the repair commands' reports.
#pragma once

#include <sys/resource.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/repair/pipeline.h"

namespace polyheal::cli {

inline double peak_memory_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

/// A note on a closed, oriented surface whose faces point inwards, or ""
/// (not a defect: a consistently oriented surface may mean a cavity, but a
/// solid the wrong way out is wrong for most tools). Exact signs and, on a
/// certified surface, exact nesting (Report::volume_sign, inward_components,
/// inside_out_components, cavities).
inline std::string inward_note(const Report& r) {
  if (!r.closed || !r.oriented || r.inward_components == 0) return "";
  auto count = [](std::size_t n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
  if (r.nesting_checked) {
    std::string note;
    if (r.inside_out_components)
      note = (r.components == 1 ? std::string("the surface is inside out")
                                : count(r.inside_out_components, "component", "components") + " of " +
                                      std::to_string(r.components) + " inside out") +
             " (negative volume, exact sign, inside no other component): " +
             (r.inside_out_components == 1 ? "its faces point inwards; `polyheal repair` turns it outwards"
                                           : "their faces point inwards; `polyheal repair` turns them outwards");
    if (r.cavities)
      note += (note.empty() ? "" : "; ") + count(r.cavities, "component faces", "components face") +
              " inwards inside another: cavities";
    return note;
  }
  if (r.volume_sign < 0) return "the surface encloses negative volume (exact sign): its faces point inwards, inside out";
  return std::to_string(r.inward_components) + " of " + std::to_string(r.components) + " components enclose" +
         (r.inward_components == 1 ? "s" : "") +
         " negative volume (exact sign): a cavity if inside another component, else inside out";
}

/// defect_kinds() as phrases: "3 boundary edges", ..., "no face left".
inline std::vector<std::string> defect_phrases(const std::vector<std::pair<std::string, std::size_t>>& kinds) {
  std::vector<std::string> d;
  for (const auto& [what, n] : kinds) d.push_back(what == "no face left" ? what : std::to_string(n) + " " + what);
  return d;
}

/// What keeps the written file from being certified (with `for_tetgen`:
/// TetGen-ready), one phrase each.
inline std::vector<std::string> defects(const Report& out, bool for_tetgen = false) {
  return defect_phrases(defect_kinds(out, for_tetgen));
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
          // null: not looked for (InspectOptions::tetgen_segments), so TetGen-readiness is not decided
          {"tetgen_vertices_near_edges",
           r.vertices_near_edges_checked ? nlohmann::json(r.vertices_near_edges.size()) : nlohmann::json(nullptr)},
          {"tetgen_close_vertices",
           r.vertices_near_edges_checked ? nlohmann::json(r.close_vertices.size()) : nlohmann::json(nullptr)},
          {"tetgen_edges_near_edges",
           r.vertices_near_edges_checked ? nlohmann::json(r.edges_near_edges.size()) : nlohmann::json(nullptr)},
          {"tetgen_vertices_near_faces",
           r.vertices_near_edges_checked ? nlohmann::json(r.vertices_near_faces.size()) : nlohmann::json(nullptr)},
          {"tetgen_flip_hazards",
           r.vertices_near_edges_checked ? nlohmann::json(r.flip_hazards.size()) : nlohmann::json(nullptr)},
          {"certified_clean", r.certified_clean()},
          {"tetgen_ready", r.vertices_near_edges_checked || !r.certified_clean() ? nlohmann::json(r.tetgen_ready())
                                                                                 : nlohmann::json(nullptr)}};
}

}  // namespace polyheal::cli
