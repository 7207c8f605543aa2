// polyheal offset IN -d D -o OUT — raw offset, then Jung, Shin & Choi's regularization.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/repair/offset.h"
#include "progress.h"
#include "regularize_report.h"
#include "repair_command.h"

namespace polyheal::cli {
namespace {

struct OffsetArgs : RepairFiles {
  double distance = 0;
  std::string tolerance;  // "0.01" (model units) or "1%" (of |d|)
  bool raw = false;
  std::string raw_output;
  OffsetOptions options;
};

nlohmann::json to_json(const OffsetArgs& a, const OffsetReport& r, double read_s, double write_s) {
  nlohmann::json j = {
      {"schema", "polyheal.offset/1"},
      {"input", a.input},
      {"output", a.output},
      {"parameters",
       {{"distance", r.distance}, {"tolerance", r.tolerance}, {"chord_angle_degrees", r.chord_angle_degrees}}},
      {"faces", r.faces},
      {"sharp_edges", r.sharp_edges},
      {"corner_vertices", r.corner_vertices},
      {"raw",
       {{"faces", r.raw_faces},
        {"vertices", r.raw_vertices},
        {"face_triangles", r.face_triangles},
        {"strip_triangles", r.strip_triangles},
        {"patch_triangles", r.patch_triangles},
        {"seconds", r.seconds_raw}}},
      {"regularized", r.regularized},
      {"pockets_removed", r.pockets_removed},
      {"pocket_faces", r.pocket_faces},
  };
  if (r.regularized) {
    j["regularize"] = regularize_json(a, r.regularize, read_s, write_s);
    j["certified"] = r.regularize.certified;
  } else {
    j["certified"] = false;
  }
  return j;
}

void print_text(const OffsetArgs& a, const OffsetReport& r) {
  std::printf("%s -> %s: offset by %g\n", a.input.c_str(), a.output.c_str(), r.distance);
  std::printf("  raw offset: %zu faces -> %zu triangles (%zu face, %zu strip, %zu patch), %zu sharp edges, %zu "
              "corners; chord tolerance %g (%.3g deg), %.3f s\n",
              r.faces, r.raw_faces, r.face_triangles, r.strip_triangles, r.patch_triangles, r.sharp_edges,
              r.corner_vertices, r.tolerance, r.chord_angle_degrees, r.seconds_raw);
  if (r.pockets_removed)
    std::printf("  removed %zu pockets (%zu faces): components nearer the input than |d| (raw-offset folds)\n",
                r.pockets_removed, r.pocket_faces);
  if (r.regularized) print_regularize_text(a, r.regularize);
  else std::printf("  => raw offset written, not regularized (--raw): NOT CERTIFIED\n");
}

}  // namespace

void add_offset(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<OffsetArgs>();
  CLI::App* cmd = app.add_subcommand("offset", "Offset a closed mesh by a distance, then regularize the raw offset "
                                               "(Jung, Shin & Choi)");
  cmd->footer(
      "Raw offset: every face moves by D along its normal; at sharp edges (faces\n"
      "whose normals differ by more than the chord angle) cylindrical strips, at\n"
      "vertices where three or more sharp sectors meet spherical patches, of radius\n"
      "|D|, refined until chords stay within --tolerance of the circle. Smooth\n"
      "regions move their vertices along their normal. D > 0 offsets outwards,\n"
      "D < 0 inwards. The raw offset overlaps itself where it folds; regularization\n"
      "(see `polyheal regularize --help`) keeps the boundary of the union it\n"
      "encloses, exactly. The input must be a closed, oriented 2-manifold.\n\n"
      "Exit 0 when the written file is closed, 2-manifold, oriented, without\n"
      "degenerate faces or self-intersections; 1 otherwise; 2 on error.");
  add_repair_files(cmd, *args, "polyheal.offset/1", "list every intersecting pair left (default: the first 10)");
  cmd->add_option("-d,--distance", args->distance, "offset distance, model units (> 0 outwards, < 0 inwards)")
      ->required();
  cmd->add_option("--tolerance", args->tolerance,
                  "chord tolerance of strips and patches: model units, or a percentage of |D| (default 1%)");
  cmd->add_flag("--raw", args->raw, "write the raw offset, not regularized (exit 1: not certified)");
  cmd->callback([args, &exit_code] {
    if (!(args->distance != 0)) throw CLI::ValidationError("--distance", "must be non-zero");
    double ratio = -1;
    parse_length("--tolerance", args->tolerance, args->options.tolerance, ratio);
    if (ratio > 0) args->options.tolerance = ratio * std::abs(args->distance);
    args->options.distance = args->distance;
    args->options.regularize = !args->raw;
    TtyProgress progress;
    double read_s = 0;
    const Soup soup = read_repair_input(*args, progress, read_s);
    args->options.observer = &progress;
    args->options.certify = false;  // certified below, on the file as written
    args->options.float_coordinates = float_output(*args);
    OffsetResult result = run_repair(*args, [&] { return offset(soup, args->options); });
    OffsetReport& r = result.report;
    double write_s = 0;
    finish_repair(
        result.soup, *args, progress, write_s,
        [&](const Soup& written) {
          if (!r.regularized) return false;
          certify(result.raw, written, result.source_face, r.regularize, result.scanned);
          return r.regularize.certified;
        },
        [&] {
          r.regularize.seconds_certify = write_s;
          return to_json(*args, r, read_s, write_s);
        },
        [&] {
          r.regularize.seconds_certify = write_s;
          print_text(*args, r);
        },
        exit_code);
  });
}

}  // namespace polyheal::cli
