// polyheal union A B [...] -o OUT — the Boolean union of closed meshes, by
// Jung, Shin & Choi's regularization of their concatenation (the paper's §1:
// "the algorithm ... can be applied to Boolean operation between T-meshes").
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/inspect/nesting.h"
#include "polyheal/inspect/predicates.h"
#include "polyheal/repair/regularize.h"
#include "progress.h"
#include "regularize_report.h"
#include "repair_command.h"

namespace polyheal::cli {

void add_union(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RepairFiles>();
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto keep_orientation = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("union", "The Boolean union of closed meshes (regularization of all of them)");
  cmd->footer(
      "Each input must be a closed, consistently oriented triangle mesh. Their\n"
      "union is the boundary of the points some input encloses (winding number\n"
      ">= 1 over all of them), computed exactly as `polyheal regularize` does on\n"
      "their concatenation: faces outside the others kept bit for bit, crossing\n"
      "faces split exactly along the intersection curves, coplanar contacts\n"
      "resolved (faces of solids touching face to face cancel). Output, report\n"
      "(schema polyheal.regularize/1, with \"input\" naming all inputs) and exit\n"
      "codes as `regularize`. An input that encloses negative volume as a whole\n"
      "(exact sign) is inside out — taken as it is, it would cut its solid out\n"
      "of the others — and is turned outwards first, with a note on stderr\n"
      "(--keep-orientation takes it as given).");
  cmd->add_option("IN", *inputs, "input meshes (two or more)")->required()->expected(2, 1 << 20);
  cmd->add_option("-o,--output", args->output, "output mesh; format from the extension")->required();
  cmd->add_flag("--json", args->json, "print one JSON document (schema polyheal.regularize/1, see README)");
  cmd->add_flag("--list", args->list, "list every intersecting pair left (default: the first 10)");
  cmd->add_flag("--ascii", args->ascii, "STL/PLY output in ASCII");
  cmd->add_flag("--overwrite", args->overwrite, "replace an existing output file (never an input)");
  cmd->add_flag("--keep-orientation", *keep_orientation,
                "take an input that is inside out as given (it then subtracts its solid from the others)");
  cmd->callback([args, inputs, keep_orientation, &exit_code] {
    TtyProgress progress;
    const auto t0 = std::chrono::steady_clock::now();
    Soup all;
    for (const std::string& in : *inputs) {
      RepairFiles one = *args;
      one.input = in;
      double s = 0;
      Soup part = read_repair_input(one, progress, s);
      if (!*keep_orientation && enclosed_volume_sign(part) < 0) {
        part = reversed(part);
        std::fprintf(stderr, "polyheal: note: %s encloses negative volume (inside out): turned outwards for the union\n",
                     in.c_str());
      }
      all.append(part);
      args->input += (args->input.empty() ? "" : " + ") + in;
    }
    const double read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    regularize_and_report(all, *args, progress, read_s, exit_code);
  });
}

}  // namespace polyheal::cli
