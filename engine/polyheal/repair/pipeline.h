// polyheal — the automatic repair pipeline (`polyheal repair`, issue 7).
//
// An outline of stages, each run only when the exact inspection of the
// current surface says it is needed, and kept only when it helps:
//   1. clean       soup-level defects (clean_soup.h): weld, drop repeated-index
//                  and duplicate faces, close T-junction cracks, orient,
//                  split non-manifold points, stitch borders, fill holes. Moves no coordinate (unless
//                  a near weld is asked for).
//   2. degenerate  exactly zero-area faces (Botsch & Kobbelt, degenerate.h),
//                  with cap/needle thresholds at their limits: only faces
//                  that are defects are touched, not mere bad shapes.
//   3. deintersect self-intersections by local moves (Yamakawa & Shimada,
//                  deintersect.h): small displacements, faces elsewhere keep
//                  their coordinates.
//   4. regularize  when local repair cannot finish on a closed surface: the
//                  union's boundary (Jung, Shin & Choi, regularize.h); every
//                  output triangle lies on the input surface.
//   5. rebuild     the last resort for anything else (Hu et al., rebuild.h):
//                  an overlay-grid volume around the input, within a cell.
//   6. orient      a certified surface whose outermost components face
//                  inwards (inside out, inspect/nesting.h) has them turned
//                  outwards, with the components inside them. Moves nothing.
// With for_tetgen, a clean surface that TetGen's tolerances would still stop
// (nearly degenerate faces, sharp folds) goes through the degenerate engine
// at 179.9/0.1 degrees with folds counted as bad, before the rebuild and
// again on the rebuild's result; where the caller runs TetGen itself
// (tetgen_accepts), a surface it refuses counts as a defect. A result with no
// face left is never kept.
// The caller writes the result and assesses the written file (assess()):
// certification, Hausdorff distance, dropped components, provenance.
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

enum RepairStep : unsigned {
  kStepClean = 1u << 0,
  kStepDegenerate = 1u << 1,
  kStepDeintersect = 1u << 2,
  kStepRegularize = 1u << 3,
  kStepRebuild = 1u << 4,
  kAllSteps = 0x1Fu,
};

/// "clean", "degenerate", ...; parse_steps("clean,deintersect") -> mask
/// (throws std::invalid_argument naming an unknown step).
const char* step_name(RepairStep step);
unsigned parse_steps(const std::string& list);

struct RepairOptions {
  unsigned steps = kAllSteps;
  double weld = 0;                  // model units: also weld vertices closer than this (0: identical only)
  double weld_ratio = 0;            // the same as a fraction of the bbox diagonal (used when weld is 0)
  double t_junction = 0;            // model units: close T-junction cracks this wide (clean_soup.h)
  double t_junction_ratio = 1e-9;   // the same as a fraction of the bbox diagonal (used when t_junction is 0)
  bool fill_holes = true;
  std::size_t max_hole_edges = 0;   // leave longer boundary loops open (0: fill all)
  bool for_tetgen = false;          // also remove what trips TetGen's tolerances (Report::tetgen_ready)
  /// Model units: how far the surface may move (the CLI's --max-deviation);
  /// 0: max_deviation_ratio x bbox diagonal. Where local moves leave the
  /// surface farther, a certified union within it is kept instead.
  double max_deviation = 0;
  double max_deviation_ratio = 0.01;
  /// Turn components that are inside out (inspect/nesting.h) outwards, with
  /// what lies inside them, once the surface is certified (false: keep the
  /// orientation; the CLI's --keep-orientation).
  bool orient_outward = true;
  /// With for_tetgen: TetGen itself, run on each surface our checks call
  /// TetGen-ready (the CLI runs `tetgen -pQ` when installed); false marks
  /// it refused (Report::tetgen_refused), a defect the later stages work on
  /// like any other. Empty: TetGen is not run.
  std::function<bool(const Soup&)> tetgen_accepts;
  /// The output format holds float32 coordinates only (STL): the result is
  /// rounded to floats, inspected as rounded, and repaired again where the
  /// rounding broke it (up to twice more), so that what is certified is what
  /// the file will hold. False: doubles (OFF, OBJ, PLY).
  bool float_coordinates = false;
  /// The local moves' work budget, in trials (DeintersectOptions::max_trials;
  /// 0: none): beyond it, the union of what they left follows (pipeline.cpp).
  std::size_t move_trials = 60000;
  Observer* observer = nullptr;
};

struct StageReport {
  std::string name;
  bool accepted = false;           // its result replaced the current surface
  std::string outcome;             // one line: what it did, or why it was refused / not kept
  std::size_t faces_out = 0;
  std::size_t defects_after = 0;   // defect_count() of its result
  double hausdorff = -1;           // its result to the input (symmetric; -1: not measured)
  double max_displacement = -1;    // largest vertex move, where the stage moves vertices (-1: n/a)
  double seconds = 0;
  std::vector<std::pair<std::string, double>> counts;  // stage-specific numbers, for the JSON report
};

struct RepairReport {
  std::size_t faces_in = 0, defects_in = 0;
  std::vector<std::pair<std::string, std::size_t>> defect_kinds_in;  // defect_kinds() of the input
  bool clean_in = false;           // the input was certified already: written unchanged (but for an orient stage)
  double diagonal = 0;
  std::vector<StageReport> stages;
  double seconds = 0;
};

/// What a repair did to the surface, measured on the file as written.
struct Assessment {
  Report out;                              // the exact inspection of the written file
  bool certified = false;                  // out.certified_clean() (and tetgen_ready with for_tetgen)
  double hausdorff = -1, input_to_output = -1, output_to_input = -1, error_bound = 0;
  // How far the surface moved: max(output -> input, input -> output), the
  // first over the output faces that are not hole fills (`hole_fills`, and
  // the pieces a later stage cut them into: faces whose corners lie on one
  // fill within error_bound; they add surface across an opening rather than
  // move it; how far they are from the input is fill_distance), the second
  // over the input outside the output's volume (measured apart only when
  // the plain input -> output distance exceeds max_deviation; otherwise
  // that plain distance, an upper bound, is reported). Input faces farther
  // than max_deviation from the output and inside its volume (the inside
  // of interpenetrating parts, inner walls, enclosed components) are
  // absorbed: removed, not moved; their area is reported and whole
  // components of them count as dropped.
  double deviation = -1;
  double fill_distance = 0;
  std::size_t fill_faces = 0;
  std::size_t absorbed_faces = 0;
  double area_absorbed = 0;
  double diagonal = 0;
  std::size_t components_in = 0, components_out = 0;
  std::size_t dropped_components = 0;      // input components with no output face within max_deviation
  std::size_t absorbed_components = 0;     // ... of them, inside the output's volume (inner parts)
  std::size_t faces_kept = 0;              // output faces that are input faces, corner for corner
  std::vector<std::int64_t> provenance;    // per output face: the input face with its exact corners, or -1
  double area_in = 0, area_out = 0, area_kept = 0;  // area_kept: of the kept faces
  double max_deviation = 0;
  bool within_deviation = true;            // deviation <= max_deviation
};

struct RepairResult {
  Soup soup;
  RepairReport report;
  Report input;  // the exact inspection of the input (assess() takes it)
  /// Corners of the triangles the clean stage added to fill holes, as they
  /// are in `soup` (fills a later stage changed are not listed): assess()
  /// reports them apart from moved surface.
  std::vector<std::array<Point3d, 3>> hole_fills;
  /// detail::one_sided_distances(input, soup, 1e-4 x the input's bbox
  /// diagonal) as the stages measured them: {input -> soup, soup -> input}
  /// (assess() takes them for a written file that is `soup`).
  std::array<double, 2> distances{0, 0};
  /// assess() of `soup` with `hole_fills`, where the pipeline made it to
  /// compare candidates (the tie and --max-deviation rules): its
  /// measurements (distances, surface moved, losses, provenance) hold for a
  /// written file that is `soup`; its `out` is the inspection of `soup`,
  /// which a caller certifying the written file makes again.
  std::optional<Assessment> assessment;
};

/// Defects that keep a surface from certification: boundary, non-manifold
/// and misoriented edges, non-manifold vertices, duplicate and degenerate
/// faces, self-intersecting pairs (and, for TetGen, its tolerance issues).
std::size_t defect_count(const Report& r, bool for_tetgen);
/// The same by kind, in the order above: ("boundary edges", n), ... for
/// each kind present; ("no face left", 1) for an empty surface.
std::vector<std::pair<std::string, std::size_t>> defect_kinds(const Report& r, bool for_tetgen);
bool certified(const Report& r, bool for_tetgen);

RepairResult repair(const Soup& input, const RepairOptions& options = {});

/// options.max_deviation, or its ratio of a bbox diagonal.
double max_deviation_of(const RepairOptions& options, double diagonal);

/// `input_report`: inspect(input), which the caller has already made.
/// `written_report`: inspect(written) with tetgen_segments = for_tetgen, if
/// the caller has it (else it is made here). `distances`:
/// detail::one_sided_distances(input, written, 1e-4 x the input's bbox
/// diagonal), if the caller has measured them on this very surface (else
/// they are measured here).
Assessment assess(const Soup& input, const Report& input_report, const Soup& written, double max_deviation,
                  bool for_tetgen,
                  const std::vector<std::array<Point3d, 3>>& hole_fills = {},
                  const Report* written_report = nullptr, const std::array<double, 2>* distances = nullptr);
/// `measured` (an assess() of a surface with the same faces as `written`,
/// e.g. RepairResult::assessment) with the inspection of `written` itself:
/// the certificate is made on the file, the measurements are kept.
Assessment reinspected(Assessment measured, const Soup& written, bool for_tetgen);

}  // namespace polyheal
