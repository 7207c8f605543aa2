// polyheal degenerate IN -o OUT — Botsch & Kobbelt's degenerate-face removal.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/repair/degenerate.h"
#include "progress.h"
#include "repair_command.h"
#include "report_json.h"

namespace polyheal::cli {
namespace {

struct DegenerateArgs : RepairFiles {
  bool no_interleave = false;
  std::string tolerance;  // "0.01" (model units) or "0.1%" (of the bbox diagonal)
  std::string weld;       // the same
  DegenerateOptions options;
};

nlohmann::json counts_json(const ShapeCounts& c) {
  return {{"zero_area", c.zero_area}, {"caps", c.caps}, {"needles", c.needles}};
}
nlohmann::json to_json(const DegenerateArgs& a, const DegenerateReport& r, double read_s, double write_s) {
  auto leftovers = nlohmann::json::array();
  for (const Leftover& l : r.leftovers) leftovers.push_back({{"face", l.face}, {"shape", l.shape}, {"reason", l.reason}});
  return {
      {"schema", "polyheal.degenerate/1"},
      {"input", a.input},
      {"output", a.output},
      {"certified", r.certified},
      {"parameters",
       {{"cap_angle", r.cap_angle},
        {"needle_angle", r.needle_angle},
        {"tolerance", r.tolerance},
        {"weld", r.weld_distance},
        {"bbox_diagonal", r.bbox_diagonal},
        {"slice_grid", r.slice_grid},
        {"global_slices", r.global_slices},
        {"interleave", r.interleave}}},
      {"weld",
       {{"near_vertices_welded", r.near_vertices_welded},
        {"max_move", r.max_weld_move},
        {"refused", r.weld_refused},
        {"topology_before", topology_json(r.topology_unwelded)},
        {"self_intersecting_pairs_after", r.self_intersections_welded}}},
      {"before", counts_json(r.before)},
      {"after", counts_json(r.after)},
      {"faces",
       {{"input", r.faces_in},
        {"repeated_index_removed", r.repeated_index_faces},
        {"pinch_vertex_copies", r.pinched_vertices_split},
        {"after_zero_area", r.faces_after_zero_area},
        {"after_slicing", r.faces_after_slicing},
        {"peak", r.peak_faces},
        {"output", r.faces_out}}},
      {"operations",
       {{"grid_slices", r.grid_slices},
        {"grid_slices_refused", r.grid_slices_refused},
        {"cap_slices", r.cap_slices},
        {"cap_slices_refused", r.cap_slices_refused},
        {"needle_slices", r.needle_slices},
        {"needle_slices_refused", r.needle_slices_refused},
        {"apex_fans", r.apex_fans},
        {"apex_fan_points", r.apex_fan_points},
        {"apexes_moved", r.apexes_moved},
        {"planar_fans", r.planar_fans},
        {"wedge_tips", r.wedge_tips},
        {"wedge_cuts", r.wedge_cuts},
        {"strips_staggered", r.strips_staggered},
        {"strip_points", r.strip_points},
        {"strip_zigzags", r.strip_zigzags},
        {"collapses", r.collapses},
        {"flips", r.flips},
        {"removals", r.removals},
        {"split_points_rounded", r.split_points_rounded}}},
      {"topology", {{"input", topology_json(r.topology_in)}, {"output", topology_json(r.topology_out)}}},
      {"self_intersecting_pairs", {{"input", r.self_intersections_in}, {"output", r.self_intersections_out}}},
      {"hausdorff", r.hausdorff},
      {"hausdorff_error_bound", r.hausdorff_error_bound},
      {"hausdorff_relative", r.bbox_diagonal > 0 ? r.hausdorff / r.bbox_diagonal : 0.0},
      {"max_vertex_displacement", r.max_displacement},
      {"leftovers", leftovers},
      {"seconds",
       {{"read", read_s},
        {"preprocess", r.seconds_preprocess},
        {"zero_area", r.seconds_zero_area},
        {"slicing", r.seconds_slicing},
        {"decimation", r.seconds_decimation},
        {"certify", r.seconds_certify},
        {"write_and_verify", write_s}}},
  };
}

void print_text(const DegenerateArgs& a, const DegenerateReport& r) {
  auto counts = [](const ShapeCounts& c) {
    return std::to_string(c.zero_area) + " zero-area, " + std::to_string(c.caps) + " caps, " +
           std::to_string(c.needles) + " needles";
  };
  std::printf("%s -> %s\n", a.input.c_str(), a.output.c_str());
  std::printf("  before: %zu faces; %s (caps > %g deg, needles < %g deg)\n", r.faces_in, counts(r.before).c_str(),
              r.cap_angle, r.needle_angle);
  std::printf("  faces: %zu in, %zu repeated-index removed, %zu after zero-area, %zu after slicing (peak %zu), %zu out\n",
              r.faces_in, r.repeated_index_faces, r.faces_after_zero_area, r.faces_after_slicing, r.peak_faces,
              r.faces_out);
  std::printf("  slices: %zu grid (%zu refused), %zu cap (%zu refused, %s%s), %zu needle (%zu refused), "
              "%zu across %zu wedge tips, %zu points on %zu cone tips, %zu points staggered on %zu strips; %zu collapses, %zu flips, %zu removals; "
              "%zu split points rounded early\n",
              r.grid_slices, r.grid_slices_refused, r.cap_slices, r.cap_slices_refused,
              r.global_slices ? "global" : "local", r.interleave ? ", interleaved" : "", r.needle_slices,
              r.needle_slices_refused, r.wedge_cuts, r.wedge_tips, r.apex_fan_points, r.apex_fans, r.strip_points, r.strips_staggered, r.collapses,
              r.flips, r.removals,
              r.split_points_rounded);
  if (r.near_vertices_welded > 0)
    std::printf("  welded: %zu vertices closer than %.3g to another (moved at most %.3g); the input then: euler %ld, "
                "components %zu, boundary loops %zu (were %ld, %zu, %zu), %zu intersecting pairs (were %zu)\n",
                r.near_vertices_welded, r.weld_distance, r.max_weld_move, r.topology_in.euler, r.topology_in.components,
                r.topology_in.boundary_loops, r.topology_unwelded.euler, r.topology_unwelded.components,
                r.topology_unwelded.boundary_loops, r.self_intersections_welded, r.self_intersections_in);
  else if (r.weld_refused)
    std::printf("  welded: none (welding vertices closer than %.3g would leave a non-manifold surface or more "
                "intersecting pairs)\n",
                r.weld_distance);
  std::printf("  after:  %s\n", counts(r.after).c_str());
  std::printf("  topology: euler %ld -> %ld, components %zu -> %zu, boundary loops %zu -> %zu%s\n", r.topology_in.euler,
              r.topology_out.euler, r.topology_in.components, r.topology_out.components, r.topology_in.boundary_loops,
              r.topology_out.boundary_loops, r.topology_in == r.topology_out ? " (unchanged)" : " (CHANGED)");
  std::printf("  self-intersecting pairs: %zu -> %zu\n", r.self_intersections_in, r.self_intersections_out);
  char moved[128] = "no vertex moved";
  if (r.apexes_moved > 0 || r.near_vertices_welded > 0)
    std::snprintf(moved, sizeof moved, "max vertex displacement %.6g (%zu cone tips moved, %zu vertices welded)",
                  r.max_displacement, r.apexes_moved, r.near_vertices_welded);
  std::printf("  Hausdorff distance %.6g +- %.2g (%.3g%% of the bbox diagonal; tolerance %.6g); %s\n", r.hausdorff,
              r.hausdorff_error_bound, r.bbox_diagonal > 0 ? 100.0 * r.hausdorff / r.bbox_diagonal : 0.0, r.tolerance,
              moved);
  const std::size_t shown = a.list ? r.leftovers.size() : std::min<std::size_t>(r.leftovers.size(), 10);
  for (std::size_t k = 0; k < shown; ++k) {
    const Leftover& l = r.leftovers[k];
    std::printf("  left: face %zu, %s: %s\n", l.face, l.shape.c_str(), l.reason.c_str());
  }
  if (shown < r.leftovers.size())
    std::printf("  ... and %zu more faces left (--list or --json names them all)\n", r.leftovers.size() - shown);
  std::printf("  time: preprocess %.3f s, zero-area %.3f s, slicing %.3f s, decimation %.3f s, certify %.3f s\n",
              r.seconds_preprocess, r.seconds_zero_area, r.seconds_slicing, r.seconds_decimation, r.seconds_certify);
  std::printf("  => %s\n", r.certified ? "CERTIFIED: no degenerate face, cap or needle; topology unchanged; within tolerance"
                                       : "NOT CERTIFIED (see above)");
}

}  // namespace

void add_degenerate(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<DegenerateArgs>();
  CLI::App* cmd = app.add_subcommand("degenerate", "Remove zero-area faces, caps and needles (Botsch & Kobbelt)");
  cmd->footer(
      "Caps are cut by the plane through their obtuse vertex perpendicular to their\n"
      "longest edge (each cut is verified exactly to create no cap); needles and what\n"
      "slicing leaves are removed by edge collapses and flips that keep every vertex\n"
      "at its input position, change no topology, create no cap or self-intersection,\n"
      "and stay within --tolerance of the input surface.\n"
      "Vertices closer than --weld are welded first (a CAD export's rounding leaves\n"
      "cracks whose sides intersect), where that keeps the surface manifold and adds\n"
      "no intersecting pair; the topology kept is then the welded input's.\n"
      "A face that intersects another is never cut: bad faces in and beside the\n"
      "input's intersections are listed (run deintersect or repair first).\n"
      "The written file is read back and checked exactly.\n\n"
      "Exit 0 when the written file has no zero-area face, cap or needle, the same\n"
      "topology as the input, no new self-intersection and a Hausdorff distance\n"
      "within the tolerance; 1 otherwise (the report lists each face left and why);\n"
      "2 on error (bad file, non-manifold input, refusing to overwrite).");
  add_repair_files(cmd, *args, "polyheal.degenerate/1", "name every face left in the text report (default: the first 10)");
  cmd->add_option("--cap-angle", args->options.cap_angle, "a face with an angle above this is a cap (degrees)")
      ->default_val(175.0)->check(CLI::Range(90.0, 179.9));
  cmd->add_option("--needle-angle", args->options.needle_angle,
                  "a face with an angle below this is a needle unless it is a cap (degrees)")
      ->default_val(5.0)->check(CLI::Range(0.0, 30.0));
  cmd->add_option("--tolerance", args->tolerance,
                  "largest allowed distance to the input surface: model units, or a percentage of the bbox "
                  "diagonal (default 0.1%)");
  cmd->add_option("--weld", args->weld,
                  "first weld vertices closer than this: model units, or a percentage of the bbox diagonal "
                  "(default 1e-7%, i.e. 1e-9 of the diagonal; 0: identical points only)");
  cmd->add_option("--slice-grid", args->options.slice_grid,
                  "first cut by three stacks of N evenly spaced axis-aligned planes (more freedom for decimation)")
      ->default_val(0)->check(CLI::Range(0, 1000));
  cmd->add_flag("--global-slices", args->options.global_slices,
                "cut the whole mesh with each cap's plane, as the paper does (default: only the connected cut "
                "through the cap)");
  cmd->add_flag("--no-interleave", args->no_interleave, "do not decimate along each slice right after it");
  cmd->callback([args, &exit_code] {
    parse_length("--tolerance", args->tolerance, args->options.tolerance, args->options.tolerance_ratio);
    parse_length("--weld", args->weld, args->options.weld, args->options.weld_ratio, true);
    args->options.interleave = !args->no_interleave;
    TtyProgress progress;
    double read_s = 0;
    const Soup soup = read_repair_input(*args, progress, read_s);
    args->options.observer = &progress;
    args->options.certify = false;  // certified below, on the file as written
    DegenerateResult result = run_repair(*args, [&] { return remove_degenerate_faces(soup, args->options); });
    DegenerateReport& r = result.report;
    finish_repair(
        result.soup, *args, progress, r.seconds_certify,
        [&](const Soup& written) {
          certify(soup, written, r);
          return r.certified;
        },
        [&] { return to_json(*args, r, read_s, r.seconds_certify); }, [&] { print_text(*args, r); }, exit_code);
  });
}

}  // namespace polyheal::cli
