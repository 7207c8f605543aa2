// polyheal regularize IN -o OUT — Jung, Shin & Choi's valid-region growing.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/repair/regularize.h"
#include "progress.h"
#include "repair_command.h"
#include "report_json.h"

namespace polyheal::cli {
namespace {

double peak_memory_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

/// What keeps the written file from being certified, one phrase each.
std::vector<std::string> defects(const Report& out) {
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

nlohmann::json to_json(const RepairFiles& a, const RegularizeReport& r, double read_s, double write_s) {
  const double diag = r.bbox_diagonal > 0 ? r.bbox_diagonal : 1.0;
  nlohmann::json intersections = nlohmann::json::array();
  for (const FacePair& p : r.out.self_intersections) intersections.push_back({p.first, p.second});
  return {
      {"schema", "polyheal.regularize/1"},
      {"input", a.input},
      {"output", a.output},
      {"certified", r.certified},
      {"bbox_diagonal", r.bbox_diagonal},
      {"input_mesh",
       {{"faces", r.faces},
        {"vertices", r.vertices},
        {"components", r.components_in},
        {"intersecting_pairs", r.intersecting_pairs_in},
        {"intersecting_faces", r.intersecting_faces_in}}},
      {"triangles",
       {{"valid", r.valid}, {"partially_valid", r.partially_valid}, {"invalid", r.invalid},
        {"split", r.triangles_split}, {"sub_triangles", r.sub_triangles}, {"unclassified", r.unclassified}}},
      {"intersection_segments", r.segments},
      {"seeds", r.seeds},
      {"lines_cast", r.line_casts},
      {"orientation_conflicts", r.orientation_conflicts},
      {"components_removed", r.components_removed},
      {"output_mesh",
       {{"faces", r.faces_out},
        {"vertices", r.vertices_out},
        {"new_vertices", r.new_vertices},
        {"faces_kept", r.faces_kept},
        {"components", r.out.components},
        {"closed", r.out.closed},
        {"manifold", r.out.manifold},
        {"oriented", r.out.oriented},
        {"degenerate_faces", r.out.degenerate_faces.size()},
        {"intersecting_pairs", intersections},
        {"volume", r.out.signed_volume},
        {"defects", defects(r.out)}}},
      {"rounding", {{"intersecting_pairs", r.rounding_pairs}, {"vertices_moved", r.rounding_moves}}},
      {"max_distance_to_input", r.max_distance_to_input},
      {"max_distance_to_input_relative", r.max_distance_to_input / diag},
      {"hausdorff", r.hausdorff},
      {"hausdorff_error_bound", r.hausdorff_error_bound},
      {"hausdorff_relative", r.hausdorff / diag},
      {"seconds",
       {{"read", read_s},
        {"detect", r.seconds_detect},
        {"intersections", r.seconds_intersections},
        {"grow", r.seconds_grow},
        {"stitch", r.seconds_stitch},
        {"write_and_verify", write_s}}},
      {"peak_memory_mb", peak_memory_mb()},
  };
}

void print_text(const RepairFiles& a, const RegularizeReport& r) {
  const double diag = r.bbox_diagonal > 0 ? r.bbox_diagonal : 1.0;
  std::printf("%s -> %s\n", a.input.c_str(), a.output.c_str());
  std::printf("  input: %zu triangles, %zu vertices, %zu components; %zu intersecting pairs (%zu triangles)\n",
              r.faces, r.vertices, r.components_in, r.intersecting_pairs_in, r.intersecting_faces_in);
  std::printf("  triangles: %zu valid, %zu partially valid, %zu invalid; %zu split into %zu sub-triangles\n", r.valid,
              r.partially_valid, r.invalid, r.triangles_split, r.sub_triangles);
  std::printf("  %zu intersection segments; %zu seeds, %zu winding-number lines\n", r.segments, r.seeds,
              r.line_casts);
  if (r.components_removed)
    std::printf("  %zu input components removed entirely (inside the volume, or enclosing none)\n",
                r.components_removed);
  if (r.unclassified) std::printf("  %zu sub-triangles could not be classified (left out)\n", r.unclassified);
  if (r.orientation_conflicts)
    std::printf("  %zu river crossings found no compatible continuation\n", r.orientation_conflicts);
  std::printf("  output: %zu triangles (%zu input faces kept bit for bit), %zu vertices (%zu new)\n", r.faces_out,
              r.faces_kept, r.vertices_out, r.new_vertices);
  if (r.rounding_pairs)
    std::printf("  rounding to doubles made %zu pairs intersect; deintersect moved %zu vertices\n", r.rounding_pairs,
                r.rounding_moves);
  std::printf("  distance to the input: output -> input at most %.3g; Hausdorff %.6g +- %.2g (%.3g%% of the bbox "
              "diagonal)\n",
              r.max_distance_to_input, r.hausdorff, r.hausdorff_error_bound, 100.0 * r.hausdorff / diag);
  std::printf("  volume %.9g, %zu components\n", r.out.signed_volume, r.out.components);
  std::printf("  time: detect %.3f s, intersections %.3f s, grow %.3f s, stitch %.3f s, certify %.3f s; peak memory "
              "%.0f MB\n",
              r.seconds_detect, r.seconds_intersections, r.seconds_grow, r.seconds_stitch, r.seconds_certify,
              peak_memory_mb());
  const std::vector<std::string> d = defects(r.out);
  std::string list;
  for (const std::string& s : d) list += (list.empty() ? "" : ", ") + s;
  std::printf("  => %s%s\n", r.certified ? "CERTIFIED: closed, 2-manifold, oriented, no degenerate face, no "
                                           "self-intersection"
                                         : "NOT CERTIFIED: ",
              r.certified ? "" : list.c_str());
  const std::size_t shown = a.list ? r.out.self_intersections.size()
                                   : std::min<std::size_t>(r.out.self_intersections.size(), 10);
  for (std::size_t k = 0; k < shown; ++k)
    std::printf("    intersecting: faces %zu and %zu\n", r.out.self_intersections[k].first,
                r.out.self_intersections[k].second);
  if (shown < r.out.self_intersections.size())
    std::printf("    ... and %zu more (--list)\n", r.out.self_intersections.size() - shown);
}

}  // namespace

void add_regularize(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RepairFiles>();
  CLI::App* cmd = app.add_subcommand(
      "regularize", "Remove self-overlaps of a closed mesh by valid-region growing (Jung, Shin & Choi)");
  cmd->footer(
      "The output bounds the union of the solids the input encloses (the points of\n"
      "winding number >= 1): it keeps the input triangles on that boundary bit for\n"
      "bit, the parts of intersecting triangles that lie on it (split exactly along\n"
      "the intersection curves), and drops the rest. Components inside another are\n"
      "removed (the report counts them); inward-facing shells (cavities) are kept.\n"
      "The input must be closed and consistently oriented, enclose positive volume,\n"
      "and have no zero-area face (run `polyheal degenerate` first) and no coplanar\n"
      "overlapping faces. Points on intersection curves are rounded to the nearest\n"
      "double; what rounding makes intersect again is repaired by deintersect's\n"
      "vertex moves. The written file is read back and checked exactly.\n\n"
      "Exit 0 when the written file is closed, 2-manifold, oriented, without\n"
      "degenerate faces or self-intersections; 1 otherwise (what is left is\n"
      "listed); 2 on error (bad file, unsupported input, refusing to overwrite).");
  add_repair_files(cmd, *args, "polyheal.regularize/1", "list every intersecting pair left (default: the first 10)");
  cmd->callback([args, &exit_code] {
    TtyProgress progress;
    double read_s = 0;
    const Soup soup = read_repair_input(*args, progress, read_s);
    RegularizeOptions options;
    options.observer = &progress;
    options.certify = false;  // certified below, on the file as written
    RegularizeResult result = run_repair(*args, [&] { return regularize(soup, options); });
    RegularizeReport& r = result.report;
    finish_repair(
        result.soup, *args, progress, r.seconds_certify,
        [&](const Soup& written) {
          certify(soup, written, result.source_face, r);
          return r.certified;
        },
        [&] { return to_json(*args, r, read_s, r.seconds_certify); }, [&] { print_text(*args, r); }, exit_code);
  });
}

}  // namespace polyheal::cli
