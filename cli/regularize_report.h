// polyheal CLI — the regularize report (text and JSON), shared by
// `regularize` and `offset` (whose output is a regularized raw offset).
#pragma once

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "polyheal/repair/regularize.h"
#include "progress.h"
#include "report_json.h"
#include "repair_command.h"

namespace polyheal::cli {

inline nlohmann::json regularize_json(const RepairFiles& a, const RegularizeReport& r, double read_s, double write_s) {
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
        {"polygons_fanned", r.polygons_fanned},
        {"walls_left_out", r.walls_left_out},
        {"zero_area_faces", r.zero_area_faces},
        {"intersecting_pairs", r.intersecting_pairs_in},
        {"intersecting_faces", r.intersecting_faces_in}}},
      {"triangles",
       {{"valid", r.valid}, {"partially_valid", r.partially_valid}, {"invalid", r.invalid},
        {"split", r.triangles_split}, {"split_unreached", r.split_unreached}, {"sub_triangles", r.sub_triangles}, {"unclassified", r.unclassified}}},
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
      {"pinches",
       {{"split", r.pinches_split}, {"edges_split", r.pinched_edges_split}, {"max_displacement", r.pinch_displacement}}},
      {"rounding",
       {{"merged_points", r.rounding_merged},
        {"collapsed_faces", r.rounding_collapsed},
        {"intersecting_pairs", r.rounding_pairs},
        {"vertices_moved", r.rounding_moves},
        {"passes", r.rounding_passes},
        {"float_vertices", r.float_rounded},
        {"float_intersecting_pairs", r.float_pairs},
        {"float_vertices_moved", r.float_moves}}},
      {"certificate_faces_searched", r.certificate_searched},
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

inline void print_regularize_text(const RepairFiles& a, const RegularizeReport& r) {
  const double diag = r.bbox_diagonal > 0 ? r.bbox_diagonal : 1.0;
  std::printf("%s -> %s\n", a.input.c_str(), a.output.c_str());
  std::printf("  input: %zu triangles, %zu vertices, %zu components; %zu intersecting pairs (%zu triangles)\n",
              r.faces, r.vertices, r.components_in, r.intersecting_pairs_in, r.intersecting_faces_in);
  std::printf("  triangles: %zu valid, %zu partially valid, %zu invalid; %zu split into %zu sub-triangles (%zu never "
              "reached by a wave)\n",
              r.valid, r.partially_valid, r.invalid, r.triangles_split, r.sub_triangles, r.split_unreached);
  std::printf("  %zu intersection segments; %zu seeds, %zu winding-number lines\n", r.segments, r.seeds,
              r.line_casts);
  if (r.zero_area_faces)
    std::printf("  %zu zero-area faces left out (they bound nothing; T-junctions they closed are split)\n",
                r.zero_area_faces);
  if (r.walls_left_out)
    std::printf("  %zu faces left out first: walls or faces doubled in one direction, without which every edge is "
                "used as often each way (the surface bounds a volume)\n",
                r.walls_left_out);
  if (r.polygons_fanned)
    std::printf("  %zu polygons fanned into triangles (counts below are of triangles)\n",
                r.polygons_fanned);
  if (r.components_removed)
    std::printf("  %zu input components removed entirely (inside the volume, or enclosing none)\n",
                r.components_removed);
  if (r.unclassified) std::printf("  %zu sub-triangles could not be classified (left out)\n", r.unclassified);
  if (r.orientation_conflicts)
    std::printf("  %zu river crossings found no compatible continuation\n", r.orientation_conflicts);
  std::printf("  output: %zu triangles (%zu input faces kept bit for bit), %zu vertices (%zu new)\n", r.faces_out,
              r.faces_kept, r.vertices_out, r.new_vertices);
  if (r.pinches_split)
    std::printf("  the union's boundary pinched at %zu vertices: one copy per cone, moved into it by at most %.3g%s\n",
                r.pinches_split, r.pinch_displacement,
                r.pinched_edges_split ? (" (" + std::to_string(r.pinched_edges_split) +
                                         " of them the midpoints of edges it touched itself along)").c_str()
                                      : "");
  if (r.float_rounded)
    std::printf("  rounding to floats (STL) moved %zu vertices, made %zu pairs intersect; deintersect moved %zu\n",
                r.float_rounded, r.float_pairs, r.float_moves);
  if (r.rounding_merged)
    std::printf("  rounding to %s merged %zu points; %zu faces thinner than its step went\n",
                r.float_rounded ? "doubles, then floats," : "doubles", r.rounding_merged, r.rounding_collapsed);
  if (r.rounding_pairs)
    std::printf("  rounding to doubles made %zu pairs intersect; deintersect moved %zu vertices; %d regularization "
                "passes\n",
                r.rounding_pairs, r.rounding_moves, r.rounding_passes);
  if (r.faces_out == 0)
    std::printf("  no face left: the input encloses no volume (winding number 0 everywhere off it: a surface facing "
                "inwards, or a double-sided sheet, whose opposite faces cancel); `polyheal repair` unites a surface "
                "facing inwards turned outwards, `polyheal rebuild` makes a solid of a sheet\n");
  else
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

/// What `regularize` and `union` share after reading: regularize `soup`,
/// write, read back and certify the file, print the report, set the exit code.
inline void regularize_and_report(const Soup& soup, const RepairFiles& args, TtyProgress& progress, double read_s,
                                  int& exit_code) {
  RegularizeOptions options;
  options.observer = &progress;
  options.certify = false;  // certified below, on the file as written
  options.float_coordinates = float_output(args);
  RegularizeResult result = run_repair(args, [&] { return regularize(soup, options); });
  RegularizeReport& r = result.report;
  finish_repair(
      result.soup, args, progress, r.seconds_certify,
      [&](const Soup& written) {
        certify(soup, written, result.source_face, r, result.scanned);
        return r.certified;
      },
      [&] { return regularize_json(args, r, read_s, r.seconds_certify); },
      [&] { print_regularize_text(args, r); }, exit_code);
}

}  // namespace polyheal::cli
