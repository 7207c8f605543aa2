// polyheal compare A B — verify another tool's output B against its input A.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/io/read.h"
#include "polyheal/repair/pipeline.h"
#include "progress.h"
#include "repair_command.h"
#include "report_json.h"

namespace polyheal::cli {
namespace {

struct CompareArgs {
  std::string a, b, max_deviation;
  bool json = false;
  double max_abs = 0, max_ratio = 0;
};

struct Side {
  SurfaceTopology topo;
  long genus = -1;  // manifold surfaces only
  double area = 0, volume = 0;
  bool has_volume = false;
};

Side side(const Report& r, double area) {
  Side s;
  s.topo = topology_of(r);
  if (r.manifold) s.genus = (2 * long(s.topo.components) - s.topo.euler - long(s.topo.boundary_loops)) / 2;
  s.area = area;
  s.has_volume = r.closed && r.oriented;
  s.volume = r.signed_volume;
  return s;
}

nlohmann::json side_json(const Side& s) {
  nlohmann::json j = topology_json(s.topo);
  j["genus"] = s.genus;
  j["area"] = s.area;
  j["volume"] = s.has_volume ? nlohmann::json(s.volume) : nlohmann::json(nullptr);
  return j;
}

}  // namespace

void add_compare(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare a repaired mesh B with its input A: distance, topology, exact check of B");
  cmd->footer(
      "For verifying another tool's output: symmetric Hausdorff distance (absolute and relative\n"
      "to A's bbox diagonal) and both one-sided distances, area and volume change, topology\n"
      "change (components, genus, boundary loops), components of A that B dropped, faces of B\n"
      "that are faces of A exactly, and the exact check of B.\n\n"
      "Exit 0: B is certified clean (and within --max-deviation when given); 1: otherwise; 2: error.");
  cmd->add_option("A", args->a, "the input mesh")->required();
  cmd->add_option("B", args->b, "the output to verify")->required();
  cmd->add_option("--max-deviation", args->max_deviation,
                  "also require the Hausdorff distance within D (model units, or P% of A's diagonal)");
  cmd->add_flag("--json", args->json, "print one JSON document (schema polyheal.compare/1, see README)");
  cmd->callback([args, &exit_code] {
    const auto t0 = std::chrono::steady_clock::now();
    TtyProgress progress;
    parse_length("--max-deviation", args->max_deviation, args->max_abs, args->max_ratio);
    progress.stage("reading");
    const Soup a = read_soup(args->a);
    const Soup b = read_soup(args->b);
    progress.stage("measuring");
    const Report ra = inspect(a);
    const double diag = bbox_diagonal(ra);
    const bool bounded = args->max_abs > 0 || args->max_ratio > 0;
    const double bound = args->max_abs > 0 ? args->max_abs : args->max_ratio * diag;
    // Components count as dropped beyond the bound, or 1% of the diagonal without one.
    const Assessment s = assess(a, ra, b, bounded ? bound : 0.01 * diag, false);
    const Side sa = side(ra, s.area_in), sb = side(s.out, s.area_out);
    const bool ok = s.certified && (!bounded || s.within_deviation);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();
    const double rel = diag > 0 && s.hausdorff >= 0 ? s.hausdorff / diag : -1;
    if (args->json) {
      nlohmann::json j = {
          {"schema", "polyheal.compare/1"},
          {"a", args->a},
          {"b", args->b},
          {"ok", ok},
          {"b_certified_clean", s.certified},
          {"b_checks", checks_json(s.out)},
          {"hausdorff", s.hausdorff},
          {"hausdorff_relative", rel},
          {"a_to_b", s.input_to_output},
          {"b_to_a", s.output_to_input},
          {"error_bound", s.error_bound},
          {"max_deviation", bounded ? nlohmann::json(bound) : nlohmann::json(nullptr)},
          {"within_deviation", bounded ? nlohmann::json(s.within_deviation) : nlohmann::json(nullptr)},
          {"a_mesh", side_json(sa)},
          {"b_mesh", side_json(sb)},
          {"area_ratio", sa.area > 0 ? sb.area / sa.area : 0.0},
          {"volume_ratio", sa.has_volume && sb.has_volume && sa.volume != 0 ? nlohmann::json(sb.volume / sa.volume)
                                                                            : nlohmann::json(nullptr)},
          {"topology_changed", !(sa.topo == sb.topo)},
          {"dropped_components", s.dropped_components},
          {"absorbed_components", s.absorbed_components},
          {"faces_of_a_kept", s.faces_kept},
          {"seconds", secs}};
      std::cout << j.dump(2) << "\n";
    } else {
      std::printf("%s -> %s\n", args->a.c_str(), args->b.c_str());
      std::printf("  Hausdorff %.6g (%.3g%% of A's diagonal %.6g; A->B %.6g, B->A %.6g, error bound %.2g)\n",
                  s.hausdorff, 100 * rel, diag, s.input_to_output, s.output_to_input, s.error_bound);
      auto line = [](const char* name, const Side& x, std::size_t faces) {
        std::printf("  %s: %zu faces, %zu components, genus %ld, %zu boundary loops, area %.6g", name, faces,
                    x.topo.components, x.genus, x.topo.boundary_loops, x.area);
        if (x.has_volume) std::printf(", volume %.6g", x.volume);
        std::printf("\n");
      };
      line("A", sa, ra.faces);
      line("B", sb, s.out.faces);
      std::printf("  topology %s; %zu components of A dropped (%zu inside B); %zu faces of B are faces of A\n",
                  sa.topo == sb.topo ? "unchanged" : "CHANGED", s.dropped_components, s.absorbed_components,
                  s.faces_kept);
      std::string verdict = s.certified ? "B CERTIFIED CLEAN" : "B HAS DEFECTS:";
      for (const std::string& d : defects(s.out)) verdict += " " + d + ";";
      if (bounded && !s.within_deviation) verdict += " and the distance exceeds --max-deviation";
      std::printf("  => %s (%.2f s)\n", verdict.c_str(), secs);
    }
    exit_code = ok ? kClean : kDefects;
  });
}

}  // namespace polyheal::cli
