// polyheal repair IN -o OUT — the automatic pipeline (engine/polyheal/repair/pipeline.h).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <filesystem>
#include <sstream>

#include "certificate.h"
#include "commands.h"
#include "polyheal/repair/pipeline.h"
#include "progress.h"
#include "repair_command.h"
#include "report_json.h"
#include "tetgen_run.h"

namespace polyheal::cli {
namespace {

std::string joined(const std::vector<std::string>& parts) {
  std::string out;
  for (const std::string& p : parts) out += (out.empty() ? "" : ", ") + p;
  return out;
}


struct RepairArgs : RepairFiles {
  std::string steps = "all", weld, t_junction, max_deviation = "1%", certificate, provenance, for_tool, smesh;
  bool no_fill = false, drop_enclosed = false, no_tetgen_run = false, keep_orientation = false;
  RepairOptions options;
};

/// TetGen itself on the surfaces `--for tetgen` calls ready (kTetgenSwitches):
/// the pipeline's candidates and the written file; the last surface's
/// verdict is remembered, so the written file is not meshed twice.
constexpr const char* kTetgenSwitches = "-pQ";
struct TetgenChecks {
  std::string not_run;   // why TetGen was not run ("" when it was)
  std::size_t runs = 0;  // surfaces meshed or refused
  double seconds = 0;
  int final_status = -1;  // on the written surface: 0 meshed, else TetGen's exit status; -1 not run
  Soup last;
  bool last_accepted = false;

  bool accepts(const Soup& s) {
    if (runs && s.same_faces(last)) return last_accepted;
    const TetgenRun run = run_tetgen(s, kTetgenSwitches);
    if (!run.ran) {  // could not start it: not a verdict on the surface
      not_run = run.output;
      final_status = -1;
      return true;
    }
    ++runs;
    seconds += run.seconds;
    last = s;
    last_accepted = run.status == 0;
    final_status = run.status;
    return last_accepted;
  }
};

nlohmann::json kinds_json(const std::vector<std::pair<std::string, std::size_t>>& kinds) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [what, n] : kinds) j[what] = n;
  return j;
}

nlohmann::json tetgen_json(const TetgenChecks& t) {
  return {{"switches", kTetgenSwitches},
          {"not_run", t.not_run.empty() ? nlohmann::json(nullptr) : nlohmann::json(t.not_run)},
          {"runs", t.runs},
          {"seconds", t.seconds},
          {"written_file_status", t.final_status < 0 ? nlohmann::json(nullptr) : nlohmann::json(t.final_status)}};
}

struct Outcome {
  RepairReport report;
  Assessment a;
  double max_deviation = 0;
  int exit_code = kDefects;
  std::vector<std::string> problems;  // why exit 1, one phrase each
  double read_s = 0, repair_s = 0, write_s = 0;
  TetgenChecks tetgen;
};

std::vector<std::string> step_names(unsigned mask) {
  std::vector<std::string> v;
  for (RepairStep s : {kStepClean, kStepDegenerate, kStepDeintersect, kStepRegularize, kStepRebuild})
    if (mask & s) v.push_back(step_name(s));
  return v;
}

nlohmann::json parameters_json(const RepairArgs& a, const Outcome& o) {
  return {{"steps", step_names(a.options.steps)},
          {"weld", a.options.weld > 0 ? a.options.weld : a.options.weld_ratio * o.report.diagonal},
          {"t_junction", a.options.t_junction > 0 ? a.options.t_junction : a.options.t_junction_ratio * o.report.diagonal},
          {"fill_holes", a.options.fill_holes},
          {"max_hole_edges", a.options.max_hole_edges},
          {"max_deviation", o.max_deviation},
          {"max_move_trials", a.options.move_trials},
          {"drop_enclosed", a.drop_enclosed},
          {"orient_outward", a.options.orient_outward},
          {"for", a.for_tool.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.for_tool)}};
}

nlohmann::json to_json(const RepairArgs& args, const Outcome& o) {
  const Assessment& a = o.a;
  const double diag = a.diagonal > 0 ? a.diagonal : 1.0;
  nlohmann::json stages = nlohmann::json::array();
  for (const StageReport& s : o.report.stages) {
    nlohmann::json counts = nlohmann::json::object();
    for (const auto& [k, v] : s.counts) counts[k] = v;
    stages.push_back({{"name", s.name},
                      {"accepted", s.accepted},
                      {"outcome", s.outcome},
                      {"faces", s.faces_out},
                      {"defects_after", s.defects_after},
                      {"hausdorff", s.hausdorff},
                      {"max_displacement", s.max_displacement},
                      {"seconds", s.seconds},
                      {"counts", counts}});
  }
  return {{"schema", "polyheal.repair/1"},
          {"input", args.input},
          {"output", args.output},
          {"certified", a.certified},
          {"exit_code", o.exit_code},
          {"problems", o.problems},
          {"parameters", parameters_json(args, o)},
          {"input_mesh",
           {{"faces", o.report.faces_in},
            {"defects", o.report.defects_in},
            {"defect_kinds", kinds_json(o.report.defect_kinds_in)},
            {"certified_clean", o.report.clean_in}}},
          {"stages", stages},
          {"output_mesh", checks_json(a.out)},
          {"defects_after", defect_count(a.out, args.options.for_tetgen)},
          {"deviation",
           {{"surface_moved", a.deviation},
            {"hausdorff", a.hausdorff},
            {"hausdorff_relative", a.hausdorff >= 0 ? a.hausdorff / diag : -1},
            {"input_to_output", a.input_to_output},
            {"output_to_input", a.output_to_input},
            {"error_bound", a.error_bound},
            {"max_deviation", o.max_deviation},
            {"within", a.within_deviation},
            {"absorbed_faces", a.absorbed_faces},
            {"fill_faces", a.fill_faces},
            {"fill_distance", a.fill_distance},
            {"absorbed_area_fraction", a.area_in > 0 ? a.area_absorbed / a.area_in : 0.0}}},
          {"components",
           {{"input", a.components_in}, {"output", a.components_out}, {"dropped", a.dropped_components},
            {"absorbed", a.absorbed_components}}},
          {"kept",
           {{"faces", a.faces_kept},
            {"face_fraction", a.out.faces ? double(a.faces_kept) / double(a.out.faces) : 0.0},
            {"area_fraction_of_input", a.area_in > 0 ? a.area_kept / a.area_in : 0.0},
            {"area_ratio", a.area_in > 0 ? a.area_out / a.area_in : 0.0}}},
          {"tetgen_smesh", args.smesh.empty() ? nlohmann::json(nullptr) : nlohmann::json(args.smesh)},
          {"tetgen_run", args.options.for_tetgen ? tetgen_json(o.tetgen) : nlohmann::json(nullptr)},
          {"seconds", {{"read", o.read_s}, {"repair", o.repair_s}, {"write_and_verify", o.write_s}}},
          {"peak_memory_mb", peak_memory_mb()}};
}

void print_text(const RepairArgs& args, const Outcome& o) {
  const Assessment& a = o.a;
  const double diag = a.diagonal > 0 ? a.diagonal : 1.0;
  std::printf("%s -> %s\n", args.input.c_str(), args.output.c_str());
  const std::string kinds = o.report.defect_kinds_in.empty() ? "" : " (" + joined(defect_phrases(o.report.defect_kinds_in)) + ")";
  std::printf("  input: %zu faces, %zu defects%s%s\n", o.report.faces_in, o.report.defects_in, kinds.c_str(),
              !o.report.clean_in         ? ""
              : o.report.stages.empty() ? " (certified clean: written unchanged)"
                                        : " (certified clean)");
  for (const StageReport& s : o.report.stages) {
    std::printf("  %-11s %-8s %6.2f s  %zu faces, %zu defects", s.name.c_str(), s.accepted ? "kept" : "not kept",
                s.seconds, s.faces_out, s.defects_after);
    if (s.hausdorff >= 0) std::printf(", Hausdorff %.3g (%.3g%%)", s.hausdorff, 100 * s.hausdorff / diag);
    if (s.max_displacement >= 0) std::printf(", max vertex move %.3g", s.max_displacement);
    std::printf("\n              %s\n", s.outcome.c_str());
  }
  std::printf("  output: %zu faces, %zu components (input %zu); kept %zu input faces exactly (%.1f%% of the input area)\n",
              a.out.faces, a.components_out, a.components_in, a.faces_kept,
              a.area_in > 0 ? 100 * a.area_kept / a.area_in : 0.0);
  std::printf("  surface moved %.6g (%.3g%% of the diagonal; allowed %.3g); Hausdorff %.6g (input->output %.3g, "
              "output->input %.3g)\n",
              a.deviation, 100 * a.deviation / diag, o.max_deviation, a.hausdorff, a.input_to_output,
              a.output_to_input);
  if (a.fill_faces)
    std::printf("  filled: %zu new faces across holes, up to %.3g (%.3g%%) from the input\n",
                a.fill_faces, a.fill_distance, 100 * a.fill_distance / diag);
  if (a.absorbed_faces)
    std::printf("  absorbed: %zu input faces (%.2g%% of the area) farther than %.3g from the output and inside it\n",
                a.absorbed_faces, a.area_in > 0 ? 100 * a.area_absorbed / a.area_in : 0.0, o.max_deviation);
  if (a.dropped_components)
    std::printf("  dropped components: %zu (%zu inside the output's volume)\n", a.dropped_components,
                a.absorbed_components);
  if (const std::string note = inward_note(a.out); !note.empty()) std::printf("  note: %s\n", note.c_str());
  const std::vector<std::string> d = defects(a.out);
  std::string verdict = a.certified ? (args.options.for_tetgen ? "CERTIFIED CLEAN and TetGen-ready" : "CERTIFIED CLEAN")
                                    : "DEFECTS REMAIN:";
  if (!a.certified && args.options.for_tetgen && a.out.certified_clean()) {
    verdict = "clean, but NOT TetGen-ready:";
    for (const std::string& x : defects(a.out, true)) verdict += " " + x + ";";
  }
  for (const std::string& x : d) verdict += " " + x + ";";
  for (const std::string& p : o.problems)
    if (a.certified) verdict += "; " + p;
  if (!args.smesh.empty()) std::printf("  TetGen input: %s\n", args.smesh.c_str());
  if (args.options.for_tetgen) {
    const TetgenChecks& t = o.tetgen;
    if (!t.not_run.empty())
      std::printf("  TetGen itself: not run (%s)\n", t.not_run.c_str());
    else if (t.final_status < 0)
      std::printf("  TetGen itself: tetgen %s on %zu candidate surfaces (%.2f s); not on the written file (not ready)\n",
                  kTetgenSwitches, t.runs, t.seconds);
    else
      std::printf("  TetGen itself: tetgen %s %s the written file (%zu surfaces tried, %.2f s)\n", kTetgenSwitches,
                  t.final_status == 0 ? "meshed" : ("refused (exit " + std::to_string(t.final_status) + ")").c_str(),
                  t.runs, t.seconds);
  }
  std::printf("  => %s (%.2f s)\n", verdict.c_str(), o.read_s + o.repair_s + o.write_s);
}

void run(RepairArgs& args, int& exit_code) {
  TtyProgress progress;
  Outcome o;
  for (const std::string* extra : {&args.certificate, &args.provenance})
    if (!extra->empty()) {
      refuse_to_clobber(args.input, *extra, false);
      check_output_path(*extra, args.overwrite);
    }
  const Soup input = read_repair_input(args, progress, o.read_s);
  args.options.observer = &progress;
  args.options.float_coordinates = float_output(args);
  args.options.fill_holes = !args.no_fill;
  args.options.orient_outward = !args.keep_orientation;
  try {
    args.options.steps = parse_steps(args.steps);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--steps", e.what());
  }
  parse_length("--weld", args.weld, args.options.weld, args.options.weld_ratio);
  parse_length("--t-junction", args.t_junction, args.options.t_junction, args.options.t_junction_ratio);
  args.options.for_tetgen = args.for_tool == "tetgen";
  if (args.options.for_tetgen) {
    o.tetgen.not_run = args.no_tetgen_run ? "--no-tetgen-run" : !tetgen_installed() ? "tetgen is not installed" : "";
    if (o.tetgen.not_run.empty()) args.options.tetgen_accepts = [&o](const Soup& s) { return o.tetgen.accepts(s); };
  }
  parse_length("--max-deviation", args.max_deviation, args.options.max_deviation, args.options.max_deviation_ratio);

  const auto t0 = std::chrono::steady_clock::now();
  RepairResult result = run_repair(args, [&] { return repair(input, args.options); });
  o.report = std::move(result.report);
  o.repair_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.max_deviation = max_deviation_of(args.options, o.report.diagonal);

  finish_repair(
      result.soup, args, progress, o.write_s,
      [&](const Soup& written) {
        progress.stage("assessing the written file");
        // The distances the pipeline measured hold when the file reads back
        // as the surface it measured (else, e.g. STL's floats, measured here);
        // so does its assessment of that surface, where it made one — but for
        // the inspection, which certifies the file as read back.
        const bool same = written.same_faces(result.soup);
        o.a = same && result.assessment
                  ? reinspected(*result.assessment, written, args.options.for_tetgen)
                  : assess(input, result.input, written, o.max_deviation, args.options.for_tetgen, result.hole_fills,
                           nullptr, same ? &result.distances : nullptr);
        if (o.a.certified && args.options.tetgen_accepts) {
          progress.stage("TetGen on the written file");
          o.a.out.tetgen_refused = !o.tetgen.accepts(written);
          o.a.certified = !o.a.out.tetgen_refused;
        } else {
          o.tetgen.final_status = -1;  // not run on the written file
        }
        if (!o.a.certified)
          o.problems.push_back(args.options.for_tetgen && o.a.out.certified_clean()
                                   ? "clean but not TetGen-ready: " + joined(defects(o.a.out, true))
                                   : std::string("not certified"));
        if (args.options.for_tetgen) {
          // The surface as written, in TetGen's own format beside it.
          args.smesh = (std::filesystem::path(args.output).replace_extension(".smesh")).string();
          refuse_to_clobber(args.input, args.smesh, false);
          write_file_atomically(args.smesh, serialize_smesh(written), true);
        }
        if (!o.a.within_deviation) {
          std::ostringstream s;
          s << "surface moved " << o.a.deviation << ", more than --max-deviation " << o.max_deviation;
          o.problems.push_back(s.str());
        }
        const std::size_t dropped =
            o.a.dropped_components - (args.drop_enclosed ? o.a.absorbed_components : std::size_t(0));
        if (dropped) o.problems.push_back(std::to_string(dropped) + " input components dropped");
        o.exit_code = o.problems.empty() ? kClean : kDefects;
        if (!args.provenance.empty()) {
          std::string text;
          for (std::int64_t p : o.a.provenance) text += (p >= 0 ? std::to_string(p) : std::string("new")) + "\n";
          write_file_atomically(args.provenance, text, args.overwrite);
        }
        if (!args.certificate.empty()) {
          nlohmann::json extra = {{"certified", o.a.certified},
                                  {"exit_code", o.exit_code},
                                  {"problems", o.problems},
                                  {"hausdorff", o.a.hausdorff},
                                  {"surface_moved", o.a.deviation},
                                  {"hausdorff_relative", o.a.diagonal > 0 ? o.a.hausdorff / o.a.diagonal : -1},
                                  {"dropped_components", o.a.dropped_components}};
          if (args.options.for_tetgen) extra["tetgen_run"] = tetgen_json(o.tetgen);
          // The checks are what `check --certificate` can redo on the file;
          // TetGen's own verdict is recorded beside them, in tetgen_run.
          Report checked = o.a.out;
          checked.tetgen_refused = false;
          write_certificate(args.certificate,
                            make_certificate("repair", args.input, args.output, checked, parameters_json(args, o), extra),
                            args.overwrite);
        }
        return o.exit_code == kClean;
      },
      [&] { return to_json(args, o); }, [&] { print_text(args, o); }, exit_code);
}

}  // namespace

void add_repair(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RepairArgs>();
  CLI::App* cmd = app.add_subcommand("repair", "Repair any mesh automatically into a certified clean solid boundary");
  cmd->footer(
      "Stages, each run only when the exact inspection says it is needed and kept only\n"
      "when it reduces the defects:\n"
      "  clean        weld identical (and, with --weld, near) vertices; drop repeated-index\n"
      "               and duplicate faces (opposite copies cancel); close T-junction cracks;\n"
      "               orient; split non-manifold points; stitch borders; fill holes.\n"
      "               Moves no vertex. Before it, fins and flaps (faces hanging off the\n"
      "               rest along edges used 3+ times, free along the others) are left\n"
      "               out when they are all that keeps the surface open and that moves\n"
      "               the surface within --max-deviation.\n"
      "  degenerate   exactly zero-area faces (Botsch & Kobbelt), nothing else\n"
      "  deintersect  self-intersections by small local moves (Yamakawa & Shimada)\n"
      "  regularize   closed surfaces local repair could not finish: the union's boundary\n"
      "               (Jung, Shin & Choi); every output face lies on the input\n"
      "  rebuild      anything else: an overlay-grid volume within about a cell (Hu et al.)\n"
      "  orient       a certified surface inside out (a component with negative volume, inside\n"
      "               no other) is turned outwards with what lies inside it; cavities stay.\n"
      "               Moves no vertex (--keep-orientation: off)\n"
      "  round to floats  an STL output (float32 only): the surface rounded as the file will\n"
      "               hold it, checked, and repaired again where rounding broke it (twice at most)\n"
      "The written file is read back and checked exactly; the report gives, stage by stage,\n"
      "what changed and the Hausdorff distance to the input.\n\n"
      "Exit 0: certified clean, within --max-deviation, no input component dropped;\n"
      "1: otherwise (the report says which); 2: error.");
  add_repair_files(cmd, *args, "polyheal.repair/1", "", "input mesh or soup (.off, .obj, .stl, .ply)");
  cmd->add_option("--steps", args->steps,
                  "comma-separated stages to allow: clean, degenerate, deintersect, regularize, rebuild, or all")
      ->default_str("all");
  cmd->add_option("--weld", args->weld, "also weld vertices closer than D (model units, or P% of the bbox diagonal)");
  cmd->add_option("--t-junction", args->t_junction,
                  "close T-junction cracks: split a boundary edge at a boundary vertex within D of it "
                  "(model units, or P% of the bbox diagonal)")
      ->default_str("1e-7%");
  cmd->add_flag("--no-fill-holes", args->no_fill, "leave boundary loops open");
  cmd->add_option("--max-hole-edges", args->options.max_hole_edges, "fill only loops of at most N edges (0: all)")
      ->default_val(0)
      ->check(count_check());
  cmd->add_option("--max-deviation", args->max_deviation,
                  "exit 1 when the Hausdorff distance to the input exceeds D (model units, or P% of the diagonal)")
      ->default_str("1%");
  cmd->add_option("--max-move-trials", args->options.move_trials,
                  "the local moves' work budget (deintersect stage), in trials (0: none); beyond it the union of "
                  "what they left follows")
      ->default_val(args->options.move_trials)
      ->check(count_check());
  cmd->add_flag("--keep-orientation", args->keep_orientation,
                "do not turn inside-out components (negative volume, inside no other) outwards");
  cmd->add_flag("--drop-enclosed", args->drop_enclosed,
                "accept dropping components that lie inside the output's volume (inner parts) with exit 0");
  cmd->add_option("--for", args->for_tool,
                  "tetgen: also require TetGen's tolerances (no fold below 0.1 deg, no nearly collinear face, no "
                  "vertex nearly on an edge it is not on), "
                  "and write OUT.smesh for tetgen -p; when tetgen is installed, every surface that passes is "
                  "also given to tetgen -pQ, and one it refuses counts as a defect")
      ->check(CLI::IsMember({"tetgen"}));
  cmd->add_flag("--no-tetgen-run", args->no_tetgen_run,
                "with --for tetgen: do not run TetGen itself (trust polyheal's TetGen-readiness test alone)");
  cmd->add_option("--certificate", args->certificate,
                  "write a JSON certificate: input and output SHA-256, each check and its result, parameters");
  cmd->add_option("--provenance", args->provenance,
                  "write, one line per output face, the input face it is (same corners, exactly) or 'new'");
  cmd->callback([args, &exit_code] { run(*args, exit_code); });
}

}  // namespace polyheal::cli
