// polyheal deintersect IN -o OUT — Yamakawa & Shimada's self-intersection removal.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/repair/deintersect.h"
#include "progress.h"
#include "repair_command.h"
#include "report_json.h"

namespace polyheal::cli {
namespace {

struct DeintersectArgs : RepairFiles {
  std::string clearance;  // "0.01" (model units) or "local"
  std::string ops = "swap,hammer,lift,group,pair";
  std::string max_displacement;  // "0.5" (model units) or "2%" (of the bbox diagonal)
  double tet_aspect = 0;
  DeintersectOptions options;
};

void parse_ops(const std::string& list, DeintersectOptions& o) {
  o.swap = o.hammer = o.lift = o.group = o.pair = false;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = std::min(list.find(',', start), list.size());
    const std::string op = list.substr(start, end - start);
    if (op == "swap") o.swap = true;
    else if (op == "hammer") o.hammer = true;
    else if (op == "lift") o.lift = true;
    else if (op == "group") o.group = true;
    else if (op == "pair") o.pair = true;
    else
      throw CLI::ValidationError("--ops", "expected a comma-separated list of swap, hammer, lift, group, pair: " + list);
    start = end + 1;
  }
}

void parse_clearance(const DeintersectArgs& a, DeintersectOptions& o) {
  if (!a.clearance.empty() && a.tet_aspect > 0)
    throw CLI::ValidationError("--clearance", "give either --clearance or --tet-aspect, not both");
  if (a.tet_aspect > 0) {
    o.clearance_mode = ClearanceMode::tet_aspect;
    o.clearance = a.tet_aspect;
    return;
  }
  if (a.clearance.empty()) return;
  if (a.clearance == "local") {
    o.clearance_mode = ClearanceMode::local_thickness;
    return;
  }
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(a.clearance, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != a.clearance.size() || !(v > 0))
    throw CLI::ValidationError("--clearance", "expected a positive distance or 'local': " + a.clearance);
  o.clearance_mode = ClearanceMode::absolute;
  o.clearance = v;
}

nlohmann::json to_json(const DeintersectArgs& a, const DeintersectReport& r, double read_s, double write_s) {
  const double diag = r.bbox_diagonal > 0 ? r.bbox_diagonal : 1.0;
  return {
      {"schema", "polyheal.deintersect/1"},
      {"input", a.input},
      {"output", a.output},
      {"certified", r.certified},
      {"parameters",
       {{"clearance_mode", to_string(r.clearance_mode)},
        {"clearance", r.clearance},
        {"bbox_diagonal", r.bbox_diagonal},
        {"operations", a.ops},
        {"max_displacement", r.max_displacement_allowed},
        {"max_trials", a.options.max_trials}}},
      {"faces", r.faces},
      {"vertices", r.vertices},
      {"intersecting_faces", {{"input", r.intersecting_faces_in}, {"output", r.intersecting_faces_out}}},
      {"intersecting_pairs", {{"input", r.intersecting_pairs_in}, {"output", r.intersecting_pairs_out}}},
      {"degenerate_faces", {{"input", r.degenerate_faces_in}, {"output", r.degenerate_faces_out}}},
      {"operations", {{"swaps", r.swaps}, {"hammers", r.hammers}, {"lifts", r.lifts},
                      {"group_moves", r.group_moves},
                      {"pair_moves", r.pair_moves}, {"trials", r.trials},
                      {"stale", r.stale}, {"sources_skipped", r.sources_skipped}}},
      {"rounds", r.rounds},
      {"out_of_trials", r.out_of_trials},
      {"topology", {{"input", topology_json(r.topology_in)}, {"output", topology_json(r.topology_out)}}},
      {"faces_changed", r.faces_changed},
      {"moved_vertices", r.moved_vertices},
      {"max_vertex_displacement", r.max_displacement},
      {"max_vertex_displacement_relative", r.max_displacement / diag},
      {"mean_vertex_displacement", r.mean_displacement},
      {"mean_vertex_displacement_relative", r.mean_displacement / diag},
      {"hausdorff", r.hausdorff},
      {"hausdorff_error_bound", r.hausdorff_error_bound},
      {"hausdorff_relative", r.hausdorff / diag},
      {"unfreed_faces", r.unfreed_faces},
      {"seconds",
       {{"read", read_s},
        {"detect", r.seconds_detect},
        {"repair", r.seconds_repair},
        {"write_and_verify", write_s}}},
  };
}

void print_text(const DeintersectArgs& a, const DeintersectReport& r) {
  const double diag = r.bbox_diagonal > 0 ? r.bbox_diagonal : 1.0;
  std::printf("%s -> %s\n", a.input.c_str(), a.output.c_str());
  std::printf("  %zu faces, %zu vertices; clearance %s", r.faces, r.vertices, to_string(r.clearance_mode));
  if (r.clearance_mode == ClearanceMode::local_thickness) std::printf(" (median ray distance to the next face)\n");
  else std::printf(" %g\n", r.clearance);
  std::printf("  intersecting faces: %zu -> %zu (pairs %zu -> %zu)\n", r.intersecting_faces_in, r.intersecting_faces_out,
              r.intersecting_pairs_in, r.intersecting_pairs_out);
  std::printf("  operations: %zu swaps, %zu hammers, %zu lifts, %zu group moves, %zu pair moves in %d rounds (%zu trials, "
              "%zu stale, %zu sources skipped)\n",
              r.swaps, r.hammers, r.lifts, r.group_moves, r.pair_moves, r.rounds, r.trials, r.stale, r.sources_skipped);
  if (r.out_of_trials) std::printf("  stopped: the work budget (--max-trials %zu) was spent\n", a.options.max_trials);
  std::printf("  moved %zu vertices: max %.6g (%.3g%% of the bbox diagonal), mean %.6g; %zu faces changed\n",
              r.moved_vertices, r.max_displacement, 100.0 * r.max_displacement / diag, r.mean_displacement,
              r.faces_changed);
  std::printf("  Hausdorff distance %.6g +- %.2g (%.3g%% of the bbox diagonal)\n", r.hausdorff, r.hausdorff_error_bound,
              100.0 * r.hausdorff / diag);
  std::printf("  degenerate faces: %zu -> %zu\n", r.degenerate_faces_in, r.degenerate_faces_out);
  std::printf("  topology: euler %ld -> %ld, components %zu -> %zu, boundary loops %zu -> %zu%s\n", r.topology_in.euler,
              r.topology_out.euler, r.topology_in.components, r.topology_out.components, r.topology_in.boundary_loops,
              r.topology_out.boundary_loops, r.topology_in == r.topology_out ? " (unchanged)" : " (CHANGED)");
  const std::size_t shown = a.list ? r.unfreed_faces.size() : std::min<std::size_t>(r.unfreed_faces.size(), 20);
  if (shown) {
    std::printf("  still intersecting (output face ids):");
    for (std::size_t k = 0; k < shown; ++k) std::printf(" %zu", r.unfreed_faces[k]);
    if (shown < r.unfreed_faces.size()) std::printf(" ... and %zu more (--list)", r.unfreed_faces.size() - shown);
    std::printf("\n    (no operation reduces them without making another face intersect)\n");
  }
  std::printf("  time: detect %.3f s, repair %.3f s, certify %.3f s\n", r.seconds_detect, r.seconds_repair,
              r.seconds_certify);
  std::printf("  => %s\n", r.certified ? "CERTIFIED: no self-intersection, no new degenerate face, topology unchanged"
                                       : "NOT CERTIFIED (see above)");
}

}  // namespace

void add_deintersect(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<DeintersectArgs>();
  CLI::App* cmd =
      app.add_subcommand("deintersect", "Remove self-intersections by edge swapping, hammering and face lifting "
                                        "(Yamakawa & Shimada)");
  cmd->footer(
      "Each operation is kept only if, decided exactly, the number of intersecting\n"
      "faces drops and no intersection-free face starts intersecting; it must also\n"
      "leave no degenerate, turned or folded face and move no vertex further than\n"
      "--max-displacement. Operations are tried, costed by the volume they sweep,\n"
      "and applied cheapest first, in rounds. A group move (ours, not the paper's)\n"
      "moves a connected set of vertices that poke through a face back past it at\n"
      "once, for a sheet no single move can free (a tube's inner wall through its\n"
      "outer one). When nothing else applies, a group move may also push the nodes\n"
      "on one side of a face past it (face lifting reversed), and a pair move\n"
      "smooths a corner of each of two crossing faces at once (two bumps on nearly\n"
      "coincident sheets).\n"
      "Faces away from the intersections keep their exact input coordinates; every\n"
      "face is kept (swaps re-connect, moves move).\n"
      "Clearance (how far a lifted face clears the nodes it was crossing): by default\n"
      "2% of the lifted face's longest edge; --clearance D in model units;\n"
      "--clearance local from the local thickness (rays along the face normal);\n"
      "--tet-aspect G for a tetrahedral mesh of aspect ratio G (longest edge / G).\n"
      "The written file is read back and checked exactly.\n\n"
      "Exit 0 when the written file has no self-intersection, no more degenerate\n"
      "faces than the input and the same topology; 1 otherwise (the faces still\n"
      "intersecting are listed); 2 on error (bad file, non-manifold input,\n"
      "refusing to overwrite).");
  add_repair_files(cmd, *args, "polyheal.deintersect/1", "name every face still intersecting (default: the first 20)");
  cmd->add_option("--clearance", args->clearance,
                  "face-lifting clearance: a distance in model units, or 'local' (default: 2% of the lifted "
                  "face's longest edge)");
  cmd->add_option("--tet-aspect", args->tet_aspect, "clearance = longest edge of the lifted face / G")
      ->check(CLI::Range(1.0, 1e9));
  cmd->add_option("--max-rounds", args->options.max_rounds, "stop after this many rounds")
      ->default_val(100)->check(CLI::Range(1, 100000));
  cmd->add_option("--max-trials", args->options.max_trials,
                  "stop trying operations after N trials (0: no limit); what is left is reported")
      ->default_val(0)
      ->check(count_check());
  cmd->add_option("--max-displacement", args->max_displacement,
                  "no vertex moves further than this from its input position: model units, or a percentage "
                  "of the bbox diagonal (default 2%); faces that would need more are left and reported");
  cmd->add_option("--ops", args->ops, "operations to use, comma-separated (default swap,hammer,lift,group,pair)");
  cmd->callback([args, &exit_code] {
    parse_clearance(*args, args->options);
    parse_ops(args->ops, args->options);
    parse_length("--max-displacement", args->max_displacement, args->options.max_displacement,
                 args->options.max_displacement_ratio);
    TtyProgress progress;
    double read_s = 0;
    const Soup soup = read_repair_input(*args, progress, read_s);
    args->options.observer = &progress;
    args->options.certify = false;  // certified below, on the file as written
    DeintersectResult result = run_repair(*args, [&] { return remove_self_intersections(soup, args->options); });
    // If the written coordinates intersect more than the exact mesh did
    // (rounding broke something), repair the written mesh and write again.
    const auto t1 = std::chrono::steady_clock::now();
    progress.stage("writing and verifying");
    DeintersectReport& r = result.report;
    for (int pass = 0;; ++pass) {
      const Soup written = write_and_read_back(result.soup, *args, pass > 0);
      certify(soup, written, r);
      if (r.intersecting_faces_out <= r.intersecting_faces_exact || pass == 2) break;
      DeintersectResult again = remove_self_intersections(written, args->options);
      r.swaps += again.report.swaps;
      r.hammers += again.report.hammers;
      r.lifts += again.report.lifts;
      r.group_moves += again.report.group_moves;
      r.pair_moves += again.report.pair_moves;
      r.rounds += again.report.rounds;
      r.trials += again.report.trials;
      r.out_of_trials = r.out_of_trials || again.report.out_of_trials;
      r.max_displacement += again.report.max_displacement;  // an upper bound
      r.intersecting_faces_exact = again.report.intersecting_faces_exact;
      result.soup = std::move(again.soup);
    }
    r.seconds_certify = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    progress.finish();
    if (args->json)
      std::cout << to_json(*args, r, read_s, r.seconds_certify).dump(2) << "\n";
    else
      print_text(*args, r);
    exit_code = r.certified ? kClean : kDefects;
  });
}

}  // namespace polyheal::cli
