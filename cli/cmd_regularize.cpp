// polyheal regularize IN -o OUT — Jung, Shin & Choi's valid-region growing.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/repair/regularize.h"
#include "progress.h"
#include "regularize_report.h"
#include "repair_command.h"

namespace polyheal::cli {

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
      "Coplanar overlaps count once per net sheet: faces of two solids touching face\n"
      "to face cancel; zero-area faces are left out (the T-junctions they closed\n"
      "are split); polygons are fanned. The input must be closed and consistently\n"
      "oriented (every edge used as often in each direction); where one-sided\n"
      "walls or faces doubled in one direction are all that stop that (pieces of\n"
      "a convex decomposition glued with a cap left between them), they are left\n"
      "out first and reported. A surface that encloses nothing (facing inwards, a\n"
      "double-sided sheet) gives an empty output, exit 1. Where the union\n"
      "pinches at a vertex or touches itself along an edge, each cone or sheet\n"
      "gets its own vertex, moved 1% of the local edge into it. Points on\n"
      "intersection curves are rounded to the nearest double; what rounding makes\n"
      "intersect again is repaired (deintersect's moves, then regularization of\n"
      "the rounded surface). The written file is read back and checked exactly.\n\n"
      "Exit 0 when the written file is closed, 2-manifold, oriented, without\n"
      "degenerate faces or self-intersections; 1 otherwise (what is left is\n"
      "listed); 2 on error (bad file, unsupported input, refusing to overwrite).");
  add_repair_files(cmd, *args, "polyheal.regularize/1", "list every intersecting pair left (default: the first 10)");
  cmd->callback([args, &exit_code] {
    TtyProgress progress;
    double read_s = 0;
    const Soup soup = read_repair_input(*args, progress, read_s);
    regularize_and_report(soup, *args, progress, read_s, exit_code);
  });
}

}  // namespace polyheal::cli
