// polyheal perturb IN -o OUT --kind K --seed S — adversarial degenerate
// tessellations, reproducibly, for testing downstream tools.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/perturb.h"

namespace polyheal::cli {

void add_perturb(CLI::App& app, int& exit_code) {
  struct Args {
    std::string input, output, kind;
    PerturbOptions options;
    bool json = false, ascii = false, overwrite = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("perturb", "Make adversarial degenerate tessellations from a mesh, reproducibly");
  cmd->footer(
      "Kinds (each applied to --fraction of the faces, positions relative to the local edge length):\n"
      "  near-coplanar   a face split in three at its centroid lifted epsilon off its plane\n"
      "  near-collinear  an edge's face split by a point epsilon inside it: a cap (nearly collinear\n"
      "                  triangle) tiling the face with two others\n"
      "  duplicates      faces repeated (either orientation) and corners given unwelded copies\n"
      "  slivers         an edge split epsilon from one end: needles on both sides\n"
      "The same input, kind, seed, fraction and epsilon give the same file, bit for bit.\n"
      "Untouched vertices keep their exact coordinates. Exit 0 on success, 2 on error.");
  cmd->add_option("IN", a->input, "input mesh (.off, .obj, .stl, .ply)")->required();
  cmd->add_option("-o,--output", a->output, "output mesh; format from the extension")->required();
  cmd->add_option("--kind", a->kind, "near-coplanar, near-collinear, duplicates or slivers")
      ->required()
      ->check(CLI::IsMember({"near-coplanar", "near-collinear", "duplicates", "slivers"}));
  cmd->add_option("--seed", a->options.seed, "random seed")->default_val(1);
  cmd->add_option("--fraction", a->options.fraction, "fraction of the faces to perturb, 0..1")
      ->default_val(0.1)->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--epsilon", a->options.epsilon, "offset or split distance relative to the local edge length")
      ->default_val(1e-9)->check(CLI::Range(0.0, 0.5));
  cmd->add_flag("--json", a->json, "print a JSON summary (schema polyheal.perturb/1)");
  cmd->add_flag("--ascii", a->ascii, "STL/PLY output in ASCII");
  cmd->add_flag("--overwrite", a->overwrite, "replace an existing output file (never the input)");
  cmd->callback([a, &exit_code] {
    refuse_to_clobber(a->input, a->output, false);
    check_output_path(a->output, a->overwrite, true);
    a->options.kind = parse_perturb_kind(a->kind);
    const Soup in = read_soup(a->input);
    const PerturbResult r = perturb(in, a->options);
    WriteOptions wo;
    wo.ascii = a->ascii;
    wo.allow_overwrite = a->overwrite;
    const WriteInfo info = write_soup(r.soup, a->output, wo);
    if (a->json) {
      std::cout << nlohmann::json{{"schema", "polyheal.perturb/1"},
                                  {"input", a->input},
                                  {"output", a->output},
                                  {"kind", a->kind},
                                  {"seed", a->options.seed},
                                  {"fraction", a->options.fraction},
                                  {"epsilon", a->options.epsilon},
                                  {"operations", r.operations},
                                  {"faces_in", r.faces_in},
                                  {"faces_out", r.faces_out},
                                  {"coordinates_rounded", info.coordinates_rounded}}
                       .dump(2)
                << "\n";
    } else {
      std::printf("%s -> %s: %s, seed %llu: %zu operations, %zu -> %zu faces%s\n", a->input.c_str(),
                  a->output.c_str(), a->kind.c_str(), static_cast<unsigned long long>(a->options.seed), r.operations,
                  r.faces_in, r.faces_out, info.coordinates_rounded ? " (STL: coordinates rounded to float)" : "");
    }
    exit_code = kClean;
  });
}

}  // namespace polyheal::cli
