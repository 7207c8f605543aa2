// polyheal — the automatic repair pipeline (see pipeline.h).
#include "polyheal/repair/pipeline.h"

#include <boost/container/small_vector.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <limits>

#include "polyheal/inspect/nesting.h"
#include "polyheal/inspect/predicates.h"
#include "polyheal/inspect/self_intersections.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/hash.h"
#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/weld.h"
#include "polyheal/repair/clean_soup.h"
#include "polyheal/repair/degenerate.h"
#include "polyheal/repair/deintersect.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/near_sheets.h"
#include "polyheal/repair/rebuild.h"
#include "polyheal/repair/regularize.h"
#include "polyheal/repair/short_edges.h"

namespace polyheal {
namespace {

constexpr RepairStep kSteps[] = {kStepClean, kStepDegenerate, kStepDeintersect, kStepRegularize, kStepRebuild};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The surface the pipeline carries from stage to stage, with its exact
/// inspection.
struct State {
  Soup soup;
  Report report;
  std::size_t defects = 0;
  std::array<double, 2> distances{0, 0};  // detail::one_sided_distances(input, soup, measure_bound())
  double hausdorff() const { return std::max(distances[0], distances[1]); }  // to the input
  std::optional<bool> within;  // assess()ed within the deviation limit, no component dropped (asked lazily)
  double deviation = -1;       // the surface moved, as assess()ed with `within`
  std::size_t dropped = 0;     // input components dropped, as assess()ed with `within`
  /// The assess() behind `within`, of this very soup (a turned copy keeps
  /// `within` but not this: which side is inside changed).
  std::optional<Assessment> assessment;
};

/// The surface without its closed components that are no larger than
/// `size` (bounding-box diagonal) and hold what TetGen's tolerances stop on
/// (a sharp fold, a nearly degenerate face, a vertex nearly on an edge or
/// closer than TetGen's shortest edge to another —
/// welded ids, as the report gives them): the flat tetrahedra the
/// grid can leave in a thin gap, which no collapse can fix (every edge of a
/// tetrahedron fails the link condition). `dropped` counts them.
Soup without_tiny_flagged_components(const Soup& s, const Report& r, double size, std::size_t& dropped) {
  dropped = 0;
  const Soup welded = apply_weld(s, weld_identical_points(s.points));
  const Topology t = analyze_topology(welded);
  std::vector<char> flagged(t.components, 0), open(t.components, 0);
  for (const FacePair& p : r.sharp_folds) flagged[t.face_component[p.first]] = 1;
  for (std::size_t f : r.nearly_degenerate_faces) flagged[t.face_component[f]] = 1;
  std::vector<std::size_t> vertex_face(s.points.size(), 0);  // vertices near edges: by a face of theirs
  for (std::size_t f = 0; f < welded.face_count(); ++f)
    for (Index i : welded.face(f)) vertex_face[i] = f;
  for (const VertexNearEdge& v : r.vertices_near_edges) flagged[t.face_component[vertex_face[v.vertex]]] = 1;
  for (const auto& pair : r.close_vertices) flagged[t.face_component[vertex_face[pair[0]]]] = 1;
  for (const Edge& e : t.boundary_edges) open[t.face_component[e.uses.front().face]] = 1;
  const std::vector<Region> regions = component_regions(welded, t);
  std::vector<char> drop(t.components, 0);
  for (std::size_t c = 0; c < t.components; ++c) {
    const Region& g = regions[c];
    const double dx = g.hi[0] - g.lo[0], dy = g.hi[1] - g.lo[1], dz = g.hi[2] - g.lo[2];
    drop[c] = flagged[c] && !open[c] && std::sqrt(dx * dx + dy * dy + dz * dz) <= size;
    dropped += drop[c];
  }
  if (!dropped) return s;
  Soup out;
  out.points = s.points;
  for (std::size_t f = 0; f < s.face_count(); ++f)
    if (!drop[t.face_component[f]]) {
      const FaceView v = s.face(f);
      out.add_face(v.begin(), v.end());
      if (!s.face_group.empty()) out.face_group.push_back(s.face_group[f]);
    }
  out.group_names = s.group_names;
  return out;
}

/// Where the report finds what TetGen's tolerances stop on (sharp folds,
/// nearly degenerate faces, flip hazards, and vertices, edges and faces closer
/// than its shortest edge), as triangles: the faces named, and each vertex
/// named as a point (a zero-area triangle). The rebuild stage keeps no input
/// face near them (RebuildOptions::avoid): the grid re-tessellates there and
/// nowhere else.
std::vector<std::array<Point3d, 3>> tetgen_hazards(const Soup& s, const Report& r) {
  const Soup welded = apply_weld(s, weld_identical_points(s.points));
  std::vector<std::array<Point3d, 3>> out;
  auto face = [&](std::size_t f) {
    const FaceView v = welded.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k)
      out.push_back({welded.points[v[0]], welded.points[v[k]], welded.points[v[k + 1]]});
  };
  auto vertex = [&](Index i) { out.push_back({welded.points[i], welded.points[i], welded.points[i]}); };
  for (const FacePair& p : r.sharp_folds) face(p.first), face(p.second);
  for (const FacePair& p : r.flip_hazards) face(p.first), face(p.second);
  for (std::size_t f : r.nearly_degenerate_faces) face(f);
  for (const VertexNearEdge& v : r.vertices_near_edges) vertex(v.vertex), vertex(v.a), vertex(v.b);
  for (const auto& pair : r.close_vertices) vertex(pair[0]), vertex(pair[1]);
  for (const EdgeNearEdge& e : r.edges_near_edges)
    for (Index i : {e.e[0], e.e[1], e.f[0], e.f[1]}) vertex(i);
  for (const VertexNearFace& v : r.vertices_near_faces) vertex(v.vertex), face(v.face);
  return out;
}

/// How the first clean stage decides on its hole fills. A fill trades
/// boundary edges for whatever the fill crosses; which way ends better is
/// known only at the end (cgal__ALSTOM_TEST4, a CAD part whose fills cross
/// a nearly coplanar fan: more defects filled, so the holes were left open
/// and the grid rebuilt it all, 1.8% of the diagonal from the input; filled,
/// the local moves and the union keep 91% of its area exactly), so a repair
/// that does not end within bounds is tried again from the input the other
/// way (repair()).
enum class Fills {
  by_defects,  // kept when the filled surface has fewer defects (else the cleanup alone may be)
  never,       // the cleanup alone
  always,      // the filled surface, better or not
};

/// How a repair ended, to choose between two (repair()).
struct Standing {
  bool certified = false;
  bool within = false;      // certified, within --max-deviation, no component dropped (assessed)
  double deviation = -1;    // the surface moved (assessed with `within`)
  std::size_t dropped = 0;  // input components dropped (assessed with `within`)
  std::size_t defects = 0;
  /// Ends better than `other`: within bounds where it is not, or certified
  /// where it is not; both certified beyond the bounds, dropping no
  /// component where it drops some, or moving the surface less than half
  /// as far. (By a margin: on shark_b and planar_mesh the other choice
  /// moved it 0.82 times as far, by rebuilding on the grid what the first
  /// kept exactly, 89-95% of the input's area. With 5% of its faces given
  /// again, cgal's degenerated-sd's fills moved it 20.5% of the diagonal,
  /// the other choice 5.96%.)
  bool better_than(const Standing& other) const {
    if (within != other.within) return within;
    if (certified != other.certified) return certified;
    if (!certified) return false;
    if ((dropped == 0) != (other.dropped == 0)) return dropped == 0;
    return 2 * deviation < other.deviation;
  }
};

/// The grid rebuild of the input, made once for both repairs (it starts
/// from the input, not from what the stages before it made): by `simplify`.
using RebuildCache = std::array<std::optional<RebuildResult>, 2>;

class Pipeline {
 public:
  Pipeline(const Soup& input, const RepairOptions& o, RebuildCache& rebuilt, Fills fills = Fills::by_defects)
      : input_(input), o_(o), fills_(fills), rebuilt_(rebuilt) {}

  /// After run(): how it ended.
  const Standing& standing() const { return standing_; }

  /// After run(): the other way for the hole fills, where the first clean
  /// had a choice (it filled holes, and was not told how to decide) and the
  /// repair did not end within bounds.
  std::optional<Fills> other_fills() const {
    if (fills_ != Fills::by_defects || !fill_choice_ || *fill_choice_ == Fills::by_defects || standing_.within)
      return std::nullopt;
    return *fill_choice_ == Fills::always ? Fills::never : Fills::always;
  }

  RepairResult run() {
    const auto t0 = std::chrono::steady_clock::now();
    RepairReport& r = result_.report;
    cur_ = inspected(input_);
    r.faces_in = input_.face_count();
    r.defects_in = cur_.defects;
    r.defect_kinds_in = defect_kinds(cur_.report, o_.for_tetgen);
    r.diagonal = bbox_diagonal(cur_.report);
    result_.input = cur_.report;
    if (done()) {
      orient_outward();
      r.clean_in = true;
    } else {
      outline(true);
      orient_outward();
    }
    // A float format (STL): what rounding to floats broke is repaired from
    // the rounded surface; the last rounding is what the file holds.
    // The rounded surface with the fewest defects is kept: where rounding
    // merges points a surface needs apart (a pinch vertex's copies: STL has
    // no shared vertices, reading welds them), passes can only move defects.
    std::optional<State> best;
    std::vector<std::array<Point3d, 3>> best_fills;
    std::size_t best_stage = 0;
    for (int pass = 0; o_.float_coordinates; ++pass) {
      round_to_floats();
      if (!best || cur_.defects < best->defects) {
        best = cur_;
        best_fills = result_.hole_fills;
        best_stage = result_.report.stages.size();
      }
      if (done() || pass == kFloatPasses) break;
      outline(false);
      orient_outward();
    }
    if (best && best->defects < cur_.defects) {
      StageReport s;
      s.name = "round to floats";
      s.accepted = true;
      s.faces_out = best->soup.face_count();
      s.defects_after = best->defects;
      s.hausdorff = best->hausdorff();
      s.outcome = "the rounded surface of stage " + std::to_string(best_stage) + " taken back: " +
                  std::to_string(best->defects) + " defects, " + std::to_string(cur_.defects) +
                  " after the repairs since";
      result_.report.stages.push_back(std::move(s));
      cur_ = std::move(*best);
      result_.hole_fills = std::move(best_fills);
    }
    // (assessed where there is a choice to make: a second repair's, or whether to run one)
    const bool choosing = fills_ != Fills::by_defects || (fill_choice_ && *fill_choice_ != Fills::by_defects);
    if (done() && choosing) within_limit(cur_, result_.hole_fills);
    standing_ = standing_of(cur_);
    result_.distances = cur_.distances;
    result_.assessment = std::move(cur_.assessment);
    result_.soup = std::move(cur_.soup);
    r.seconds = seconds_since(t0);
    return std::move(result_);
  }

 private:
  /// Repairs after the first rounding to floats.
  static constexpr int kFloatPasses = 2;

  /// The stages, each run when the inspection of the current surface says
  /// it is needed. `alternatives`: also the union of the surface as it was
  /// before local moves (false after a rounding to floats: its defects are
  /// rounding's, which the moves undo; the union then rounds to floats).
  void outline(bool alternatives) {
    if (wanted(kStepClean) && !cur_.report.closed && !cur_.report.nonmanifold_edges.empty()) flaps();
    if (wanted(kStepClean) && needs_clean()) clean();
    if (wanted(kStepDegenerate) && !done() && !cur_.report.degenerate_faces.empty()) degenerate();
    // Self-intersections: local moves first; on a closed surface the union
    // (regularization) of what they left, and of the surface before them —
    // whichever certified result is closer to the input is kept.
    // The union of the surface before them is not computed when they moved
    // it no farther than the measure's bound (Hausdorff, before to after, by
    // the triangle inequality through the input): moving each surface point
    // by at most m moves a union's boundary and what it absorbs by at most
    // m, so the two unions are as far from the input and move the surface as
    // much, within the bound — a tie, which the current surface keeps. On
    // three overlapping copies of a 1M-face knot that union and its
    // assessment took 52 of 114 s.
    // An inverted part that crosses its neighbours: turned first, or the
    // moves would push it apart from them and the union cut it away.
    if (!done()) orient_outward(true);
    std::optional<Soup> before_moves;  // the closed surface local moves started from
    SurfaceTopology moves_kept;         // its topology, which the moves keep
    if (wanted(kStepDeintersect) && !done() && !cur_.report.self_intersections.empty()) {
      const double before = cur_.hausdorff();
      if (cur_.report.closed && alternatives) {
        before_moves = cur_.soup;
        moves_kept = topology_of(cur_.report);
      }
      const StageReport& moves = deintersect();
      if (!moves.accepted || before + moves.hausdorff <= measure_bound()) before_moves.reset();
    }
    if (wanted(kStepRegularize)) {
      if (!done() && !cur_.report.certified_clean() && cur_.report.closed)
        regularize(cur_.soup, "regularize", &cur_.report.self_intersections, o_.float_coordinates && !alternatives);
      // The topology guard (stage()) keeps what local moves kept apart from
      // a union that would merge it. Where the current surface is the union
      // of what they left and has another topology than the surface they
      // started from, that is gone anyway: the two unions compete on the
      // distance to the input and the surface moved alone (a raw offset:
      // the union of the moved surface has other cavities than the union
      // of the surface as given, which moves nothing and is as close).
      if (before_moves)
        regularize(*before_moves, "regularize (without local moves)", nullptr, false,
                   !(topology_of(cur_.report) == moves_kept));
    }
    // TetGen's tolerances (for_tetgen): nearly degenerate faces and sharp
    // folds on a surface that is otherwise clean, before the grid is tried.
    if (tetgen_pass_due()) tetgen_pass();
    // A certified surface that drops input components (a union that
    // cancelled a double-sided sheet but for a few faces): the grid, which
    // wraps sheets, is tried too. (A dropped component lies wholly farther
    // than the limit from the output: with the input -> output distance
    // within it, up to the measure's bound, none is, and it is not assessed.)
    const bool dropping = wanted(kStepRebuild) && done() && cur_.distances[0] + measure_bound() > deviation_limit() &&
                          !within_limit(cur_, result_.hole_fills) && cur_.dropped > 0;
    if (wanted(kStepRebuild) && (!done() || dropping)) {
      // The grid's coarsening and feature placement can fold faces below
      // TetGen's angle or leave a vertex nearly on an edge; the grid surface
      // is a cell from the input already, and its spikes are about a cell
      // long: collapses may move it that far again. What they cannot fix,
      // the grid without coarsening (more faces) usually avoids.
      const double cell = rebuild(true, dropping);
      if (tetgen_pass_due()) tetgen_pass(cell);
      if (o_.for_tetgen && !done()) {
        rebuild(false);
        if (tetgen_pass_due()) tetgen_pass(cell);
      }
    }
  }

  /// Every coordinate of the current surface to its nearest float, as an
  /// STL writer writes it, and the points that become one welded as an STL
  /// reader reads them back (a face losing a corner becomes zero-area: a
  /// defect the stages remove). Always kept: it is what the file will hold.
  /// The hole fills move with their corners. Nothing to round: no stage.
  void round_to_floats() {
    Soup rounded = cur_.soup;
    std::size_t moved = 0;
    double most = 0;
    for (Point3d& p : rounded.points) {
      const Point3d q = nearest_float(p);
      if (q == p) continue;
      ++moved;
      most = std::max(most, std::sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                                      (q[2] - p[2]) * (q[2] - p[2])));
      p = q;
    }
    if (moved == 0) return;
    if (o_.observer) o_.observer->stage("round to floats");
    const auto t0 = std::chrono::steady_clock::now();
    const Weld weld = weld_identical_points(rounded.points);
    if (weld.merged) rounded = apply_weld(rounded, weld);
    StageReport s;
    s.name = "round to floats";
    State next = inspected(std::move(rounded), &cur_);
    next.distances = detail::one_sided_distances(input_, next.soup, measure_bound());
    for (auto& fill : result_.hole_fills)
      for (Point3d& p : fill) p = nearest_float(p);
    s.accepted = true;
    s.faces_out = next.soup.face_count();
    s.defects_after = next.defects;
    s.hausdorff = next.hausdorff();
    s.max_displacement = most;
    s.counts = {{"vertices_rounded", double(moved)}, {"vertices_merged", double(weld.merged)}};
    s.outcome = std::to_string(moved) + " vertices rounded to floats (STL), " + std::to_string(weld.merged) +
                " merged; " + std::to_string(next.defects) + " defects after, " + std::to_string(cur_.defects) +
                " before";
    cur_ = std::move(next);
    s.seconds = seconds_since(t0);
    result_.report.stages.push_back(std::move(s));
  }

  bool wanted(RepairStep s) const { return (o_.steps & s) != 0; }
  /// How `s` ends, as far as it is known (within_limit() asks the rest).
  Standing standing_of(const State& s) const {
    Standing st;
    st.certified = certified(s.report, o_.for_tetgen);
    st.within = st.certified && s.within.value_or(false);
    st.deviation = s.deviation;
    st.dropped = s.dropped;
    st.defects = s.defects;
    return st;
  }
  bool done() const { return certified(cur_.report, o_.for_tetgen); }
  /// For TetGen: a clean surface its tolerances would still stop.
  bool tetgen_pass_due() const {
    return o_.for_tetgen && wanted(kStepDegenerate) && !done() && cur_.report.certified_clean();
  }

  /// `base`: an inspected surface the stage made `soup` from: its
  /// intersecting pairs serve the faces the stage kept as they were
  /// (find_self_intersections_from).
  State inspected(Soup soup, const State* base = nullptr) const {
    State s;
    InspectOptions io;
    io.tetgen_segments = o_.for_tetgen;
    std::optional<std::vector<FacePair>> pairs;
    if (base) pairs = find_self_intersections_from(soup, base->soup, base->report.self_intersections);
    if (pairs) io.self_intersections = &*pairs;
    s.report = inspect(soup, io);
    // What our checks call TetGen-ready, TetGen itself may still refuse (its
    // boundary recovery rounds Steiner points): where the caller can run it,
    // its verdict counts as one more defect.
    if (o_.for_tetgen && o_.tetgen_accepts && s.report.tetgen_ready() && !o_.tetgen_accepts(soup))
      s.report.tetgen_refused = true;
    s.defects = defect_count(s.report, o_.for_tetgen);
    s.soup = std::move(soup);
    return s;
  }

  double deviation_limit() const { return max_deviation_of(o_, result_.report.diagonal); }
  /// The error bound of the stages' Hausdorff distances to the input: two
  /// surfaces closer than it to each other are a tie.
  double measure_bound() const { return 1e-4 * result_.report.diagonal; }

  /// What the exit code asks of the written file (assess()): the surface
  /// moved no more than the limit and no input component was dropped.
  bool within_limit(State& s, const std::vector<std::array<Point3d, 3>>& fills) const {
    if (!s.within) {
      Assessment a =
          assess(input_, result_.input, s.soup, deviation_limit(), o_.for_tetgen, fills, &s.report, &s.distances);
      s.within = a.within_deviation && a.dropped_components == 0;
      s.deviation = a.deviation;
      s.dropped = a.dropped_components;
      s.assessment = std::move(a);
    }
    return *s.within;
  }

  bool needs_clean() const {
    const Report& r = cur_.report;
    return !r.closed || !r.manifold || !r.oriented || !r.duplicate_faces.empty() || r.non_triangle_faces > 0 ||
           o_.weld > 0 || o_.weld_ratio > 0;
  }

  /// What a stage's candidate must also meet, or may skip, to be kept.
  struct Rule {
    bool only_within = false;   // not kept when it moves the surface beyond --max-deviation
    bool clean_only = false;    // not kept unless certified clean, whatever TetGen defects it has fewer of
    bool any_topology = false;  // a certified candidate of another topology may replace the current one (outline())
    bool always = false;        // kept unless empty, better or not (the choice a second repair makes, repair())
    bool beyond = false;        // both certified beyond the bounds: kept when it ends better (Standing::better_than)
  };

  /// Runs one stage: `run()` returns the candidate surface (or throws
  /// UnsupportedInput: the stage refuses this surface). The candidate
  /// replaces the current surface when it is better (see below), under
  /// `rule`.
  template <class Run>
  StageReport& stage(const char* name, Run run, Rule rule = {}) {
    if (o_.observer) o_.observer->stage(name);
    StageReport s;
    s.name = name;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      pending_fills_.clear();
      State next = inspected(run(s), &cur_);
      s.faces_out = next.soup.face_count();
      s.defects_after = next.defects;
      const bool next_ok = certified(next.report, o_.for_tetgen);
      const double bound = measure_bound();
      next.distances = detail::one_sided_distances(input_, next.soup, bound);
      s.hausdorff = next.hausdorff();
      // Better: certified where the current surface is not; when both are,
      // of the same topology (a union may merge or open up what local moves
      // kept apart) and closer to the input; else fewer defects.
      // An empty result is never better: it drops every component (a sheet
      // of opposite copies cancels to nothing in the clean stage).
      const bool empty = next.soup.face_count() == 0;
      const bool both_ok = next_ok && done();
      const bool same_topology = rule.any_topology || topology_of(next.report) == topology_of(cur_.report);
      bool better = !empty && (both_ok ? same_topology && next.hausdorff() + bound < cur_.hausdorff()
                                       : next_ok || next.defects < cur_.defects);
      // Both certified, but the current surface moved beyond the deviation
      // limit (local moves pushing apart parts that touch or overlap): a
      // candidate within it that drops no component is kept though it has
      // another topology or a larger Hausdorff distance — a union merges
      // what overlapped and removes what lies inside it, moving nothing.
      // (The Hausdorff distance bounds the deviation, so a current surface
      // within the limit by it is never assessed.) A candidate that filled
      // no holes of its own carries the current fills (a stage run from the
      // filled surface), so they are what it is assessed with, as on keeping.
      const std::vector<std::array<Point3d, 3>>& next_fills =
          pending_fills_.empty() ? result_.hole_fills : pending_fills_;
      if (!better && both_ok && !empty && cur_.hausdorff() > deviation_limit() &&
          !within_limit(cur_, result_.hole_fills) && within_limit(next, next_fills)) {
        better = true;
        s.outcome += (s.outcome.empty() ? "" : "; ") +
                     std::string("kept: within --max-deviation, where the current surface is not");
      }
      // Both certified, of the same topology and equally far from the input
      // (within the measure's bound; what differs is the input a union
      // absorbed, the same in both): the one that moved the surface less is
      // the smaller repair — a union of the surface as given moves nothing,
      // local moves before it moved vertices for nothing.
      if (!better && both_ok && !empty && same_topology &&
          std::abs(next.hausdorff() - cur_.hausdorff()) <= bound) {
        const bool cur_within = within_limit(cur_, result_.hole_fills);
        const bool next_within = within_limit(next, next_fills);
        if ((next_within || !cur_within) && next.deviation + bound < cur_.deviation) {
          better = true;
          s.outcome += (s.outcome.empty() ? "" : "; ") +
                       std::string("kept: as far from the input, but moves the surface less");
        }
      }
      // Both certified and beyond the bounds (a union that cancelled a
      // double-sided sheet to a few remnants, dropping components): the grid
      // is kept when it drops none, or moves the surface less than half as
      // far.
      if (!better && both_ok && !empty && rule.beyond && !within_limit(cur_, result_.hole_fills) &&
          !within_limit(next, next_fills) && standing_of(next).better_than(standing_of(cur_))) {
        better = true;
        s.outcome += (s.outcome.empty() ? "" : "; ") +
                     std::string(next.dropped == 0 && cur_.dropped > 0
                                     ? "kept: drops no input component, where the current surface drops some"
                                     : "kept: moves the surface less than half as far as the current one");
      }
      if (!better && !empty && rule.always) {
        better = true;
        s.outcome += (s.outcome.empty() ? "" : "; ") + std::string("kept: the other choice, tried to the end");
      }
      const bool beyond_limit = better && rule.only_within && !within_limit(next, next_fills);
      if (beyond_limit) better = false;
      const bool unclean = better && rule.clean_only && !next.report.certified_clean();
      if (unclean) better = false;
      if (better) {
        s.accepted = true;
        cur_ = std::move(next);
        if (!pending_fills_.empty()) result_.hole_fills = std::move(pending_fills_);
      } else {
        s.outcome += (s.outcome.empty() ? "" : "; ") + std::string("not kept: ") +
                     (beyond_limit ? std::string("the surface moves more than --max-deviation")
                      : unclean    ? std::string("not certified clean")
                      : empty      ? std::string("no face left")
                      : both_ok    ? "another topology than, or farther from the input than, the current surface"
                                   : std::to_string(next.defects) + " defects after, " +
                                         std::to_string(cur_.defects) + " before");
      }
    } catch (const UnsupportedInput& e) {
      s.outcome = std::string("refused: ") + e.what();
    }
    s.seconds = seconds_since(t0);
    result_.report.stages.push_back(std::move(s));
    return result_.report.stages.back();
  }

  /// A certified surface with components inside out (negative volume,
  /// inside no other component; inspect/nesting.h) has them turned
  /// outwards, with the components inside them: cavities stay cavities.
  /// `crossing`: a closed, oriented surface whose components cross one
  /// another, before the moves and the union that resolve that: a component
  /// inside out by the greater part of its area (nesting.h) is turned, so
  /// that the union takes it in rather than cuts it away.
  /// Moves nothing; a stage only when it turns something.
  void orient_outward(bool crossing = false) {
    if (!o_.orient_outward) return;
    const Report& cr = cur_.report;
    // (crossing: one component is the union's own business — regularize
    // turns a surface inside out as a whole.)
    if (crossing ? cr.components < 2 || !cr.closed || !cr.oriented || !cr.nonmanifold_edges.empty() ||
                       cr.self_intersections.empty()
                 : !cr.certified_clean() || cr.inside_out_components == 0)
      return;
    const auto t0 = std::chrono::steady_clock::now();
    const Nesting n = nesting(cur_.soup, crossing);
    if (n.inside_out_count == 0) return;
    if (o_.observer) o_.observer->stage("orient");
    StageReport s;
    s.name = "orient";
    std::size_t faces = 0, components = 0;
    for (char t : n.turned) components += t != 0;
    State next;
    next.soup = turned_outward(cur_.soup, n, &faces);
    // Turning faces changes no position, edge or intersection: the checks
    // are made again for the shape fields (and the caller checks the
    // written file anyway), the intersecting pairs taken as they were;
    // TetGen's verdict does not depend on orientation.
    InspectOptions io;
    io.tetgen_segments = o_.for_tetgen;
    io.self_intersections = &cur_.report.self_intersections;
    next.report = inspect(next.soup, io);
    next.report.tetgen_refused = cur_.report.tetgen_refused;
    next.defects = defect_count(next.report, o_.for_tetgen);
    next.distances = cur_.distances;  // the same triangles: the measure takes no orientation
    next.within = cur_.within;
    next.deviation = cur_.deviation;
    next.dropped = cur_.dropped;
    s.accepted = true;
    s.faces_out = next.soup.face_count();
    s.defects_after = next.defects;
    s.hausdorff = next.hausdorff();
    s.max_displacement = 0;
    s.counts = {{"inside_out_components", double(n.inside_out_count)},
                {"components_turned", double(components)},
                {"faces_turned", double(faces)}};
    s.outcome = std::to_string(n.inside_out_count) + " component" + (n.inside_out_count == 1 ? "" : "s") +
                (crossing ? " inside out (negative volume, the greater part of its area outside the others): "
                          : " inside out (negative volume, inside no other): ") +
                std::to_string(components) +
                " component" + (components == 1 ? "" : "s") + " (" + std::to_string(faces) +
                " faces) turned, so that the surface bounds a volume";
    cur_ = std::move(next);
    s.seconds = seconds_since(t0);
    result_.report.stages.push_back(std::move(s));
  }

  /// Fins and flaps: sheets of faces hanging off the rest along edges with
  /// three or more uses, free along their other edges (a stray triangle on a
  /// solid's edge). No closed surface can keep them without a volume they
  /// do not have; left out (sheets_to_leave_out), they leave the solid they
  /// hang off. Only when they are all that keeps the surface from bounding a
  /// volume (what is left balances: holes are clean's, and leaving flaps
  /// out beside them only sends a surface the grid would close anyway
  /// through local moves first), and only when that moves the surface no
  /// more than --max-deviation (a larger sheet is the grid's: it wraps it).
  void flaps() {
    const Soup welded = apply_weld(cur_.soup, weld_identical_points(cur_.soup.points));
    const SheetsLeftOut sheets = sheets_to_leave_out(welded, true);
    const std::vector<std::size_t>& out = sheets.faces;
    if (out.empty() || sheets.imbalance > 0) return;
    stage(
        "flaps",
        [&](StageReport& s) {
          Soup kept;
          kept.points = cur_.soup.points;
          kept.group_names = cur_.soup.group_names;
          for (std::size_t f = 0, k = 0; f < cur_.soup.face_count(); ++f) {
            if (k < out.size() && out[k] == f) {
              ++k;
              continue;
            }
            const FaceView v = cur_.soup.face(f);
            kept.add_face(v.begin(), v.end());
            if (!cur_.soup.face_group.empty()) kept.face_group.push_back(cur_.soup.face_group[f]);
          }
          s.counts = {{"faces_left_out", double(out.size())}};
          s.outcome = std::to_string(out.size()) + " face" + (out.size() == 1 ? "" : "s") +
                      " of fins, flaps or walls left out (sheets hanging off the rest along edges used 3+ times)";
          return kept;
        },
        Rule{/*only_within=*/true});
  }

  void clean() {
    // The first clean decides on the hole fills (fills_, repair()); later
    // ones (after a rounding to floats) by their defects.
    const Fills fills = fill_choice_ ? Fills::by_defects : fills_;
    if (!o_.fill_holes || fills == Fills::never) {
      clean_with(false);
    } else {
      filled_ = 0;
      const StageReport& s = clean_with(true, fills == Fills::always);
      // The choice, where there was one: the other is a second repair's.
      if (!fill_choice_ && filled_ > 0) fill_choice_ = s.accepted ? Fills::always : Fills::never;
      // Hole fills can cross the rest of the surface (overlapping patches
      // around a gap): then the cleanup alone may still help.
      if (!s.accepted) clean_with(false);
    }
    if (!fill_choice_) fill_choice_ = Fills::by_defects;  // no choice made: no holes to fill
  }

  /// `always`: kept, better or not (Rule::always).
  const StageReport& clean_with(bool fill, bool always = false) {
    Rule rule;
    rule.always = always;
    return stage(fill ? "clean" : "clean (no fill)", [&](StageReport& s) {
      CleanSoupOptions co;
      co.weld = o_.weld > 0 ? o_.weld : o_.weld_ratio * result_.report.diagonal;
      co.t_junction = o_.t_junction > 0 ? o_.t_junction : o_.t_junction_ratio * result_.report.diagonal;
      co.fill_holes = fill;
      co.max_hole_edges = o_.max_hole_edges;
      CleanSoupResult c = clean_soup(cur_.soup, co);
      const CleanSoupReport& r = c.report;
      pending_fills_.clear();
      for (std::size_t f = 0; f < c.soup.face_count(); ++f)
        if (c.source[f] < 0) {
          const FaceView v = c.soup.face(f);
          pending_fills_.push_back({c.soup.points[v[0]], c.soup.points[v[1]], c.soup.points[v[2]]});
        }
      s.counts = {{"welded_identical", double(r.identical_vertices_welded)},
                  {"welded_near", double(r.near_vertices_welded)},
                  {"repeated_index_faces", double(r.repeated_index_faces)},
                  {"t_junctions", double(r.t_junctions)},
                  {"duplicate_faces_dropped", double(r.duplicate_faces_dropped)},
                  {"cancelled_faces", double(r.cancelled_faces)},
                  {"opposite_copies_kept", double(r.opposite_copies_kept)},
                  {"reoriented_faces", double(r.reoriented_faces)},
                  {"split_vertices", double(r.split_vertices)},
                  {"stitched_edges", double(r.stitched_edges)},
                  {"holes", double(r.holes)},
                  {"holes_filled", double(r.holes_filled)},
                  {"hole_faces", double(r.hole_faces)},
                  {"holes_left", double(r.holes_left)}};
      filled_ = r.holes_filled;
      if (r.near_vertices_welded) s.max_displacement = r.max_weld_move;
      std::ostringstream line;
      line << r.repeated_index_faces << " repeated-index and " << r.duplicate_faces_dropped + r.cancelled_faces
           << " duplicate faces dropped";
      if (r.opposite_copies_kept) line << " (" << r.opposite_copies_kept << " of them reversed stray copies)";
      line << ", " << r.t_junctions << " T-junctions closed, " << r.reoriented_faces << " reoriented, " << r.stitched_edges
           << " edges stitched, " << r.holes_filled << " of " << r.holes << " holes filled";
      if (r.near_vertices_welded) line << ", " << r.near_vertices_welded << " near vertices welded";
      s.outcome = line.str();
      return std::move(c.soup);
    }, rule);
  }

  void degenerate() {
    stage("degenerate", [&](StageReport& s) {
      DegenerateOptions d;
      d.cap_angle = 180;    // zero-area faces only: caps and needles are shapes, not defects
      d.needle_angle = 0;
      d.certify = false;
      d.weld = 0;  // the clean stage welds, with the repair's own distances
      d.observer = o_.observer;
      DegenerateResult res = remove_degenerate_faces(cur_.soup, d);
      const DegenerateReport& r = res.report;
      s.counts = {{"zero_area_before", double(r.before.zero_area)},
                  {"zero_area_after", double(r.after.zero_area)},
                  {"slices", double(r.cap_slices + r.needle_slices)},
                  {"collapses", double(r.collapses)},
                  {"flips", double(r.flips)}};
      s.outcome = std::to_string(r.before.zero_area) + " zero-area faces, " + std::to_string(r.after.zero_area) +
                  " left; " + std::to_string(r.collapses) + " collapses, " + std::to_string(r.flips) + " flips";
      return std::move(res.soup);
    });
  }

  /// What TetGen's tolerances stop on, on a clean surface: edges shorter
  /// than its shortest edge collapsed first (it would merge their ends);
  /// then what is left by collapses and flips only; then, if that is not
  /// enough, with cap and needle slicing too — from the surface before the
  /// collapses and flips, not after them: on their result (needles left
  /// between sliver fans) slicing had not finished after 4.5 minutes on a
  /// regularized raw offset of 8.8k faces (anchor +2%; the whole repair
  /// not in 15), against 9 s from the surface before. Each is kept only if
  /// better than the current one.
  void tetgen_pass(double tolerance = -1) {
    if (!cur_.report.close_vertices.empty()) short_edges();
    if (tetgen_pass_due() && close_pair_count(cur_.report) > 0) separate();
    const State before = cur_;
    if (tetgen_pass_due()) tetgen_shapes(tolerance, false, before);
    if (tetgen_pass_due()) tetgen_shapes(tolerance, true, before);
  }

  void short_edges() {
    stage("short edges (TetGen)", [&](StageReport& s) {
      ShortEdgeReport r;
      Soup out = collapse_short_edges(cur_.soup, ShortEdgeOptions{}, r);
      s.max_displacement = r.max_displacement;
      s.counts = {{"close_vertices_before", double(cur_.report.close_vertices.size())},
                  {"collapses", double(r.collapses)},
                  {"collapses_refused", double(r.collapses_undone)}};
      s.outcome = std::to_string(cur_.report.close_vertices.size()) + " vertex pairs closer than TetGen's shortest edge; " +
                  std::to_string(r.collapses) + " short edges collapsed, " + std::to_string(r.collapses_undone) +
                  " refused (a defect around them)" + (r.gave_up ? "; gave up (a defect no collapse explains)" : "");
      return out;
    });
  }

  /// What is still closer than TetGen's shortest edge without sharing a
  /// vertex there (parts face to face, a vertex over another part's face,
  /// crossing edges) is pushed apart, twice that distance per round
  /// (near_sheets.h). Kept only if certified clean.
  void separate() {
    stage("separate near sheets (TetGen)", [&](StageReport& s) {
      SeparateReport r;
      Soup out = separate_near_sheets(cur_.soup, SeparateOptions{}, r, &cur_.report);
      s.max_displacement = r.max_displacement;
      s.counts = {{"pairs_before", double(r.pairs_before)},
                  {"pairs_after", double(r.pairs_after)},
                  {"moved_vertices", double(r.moved_vertices)},
                  {"moves_refused", double(r.refused)}};
      s.outcome = std::to_string(r.pairs_before) + " pairs closer than TetGen's shortest edge, " +
                  std::to_string(r.pairs_after) + " left; " + std::to_string(r.moved_vertices) +
                  " vertices moved apart in " + std::to_string(r.rounds) + " rounds, " + std::to_string(r.refused) +
                  " moves refused (a face would intersect or degenerate)";
      return out;
    }, Rule{/*only_within=*/false, /*clean_only=*/true});
  }

  /// `tolerance`: how far the operations may move the surface (model units;
  /// negative: the degenerate engine's default, 1e-3 of the diagonal).
  /// `slice`: also cut caps and needles (else collapses and flips only).
  /// `start`: the surface to begin with (the current one may be another
  /// stage's result).
  void tetgen_shapes(double tolerance, bool slice, const State& start) {
    stage(slice ? "degenerate (TetGen tolerances)" : "degenerate (TetGen tolerances, no slicing)", [&](StageReport& s) {
      DegenerateOptions d;
      d.tolerance = tolerance;
      d.slice = slice;
      std::size_t dropped = 0;
      const Soup from = without_tiny_flagged_components(
          start.soup, start.report, tolerance >= 0 ? tolerance : d.tolerance_ratio * result_.report.diagonal, dropped);
      d.cap_angle = 179.9;  // far beyond TetGen's 1e-8 relative collinearity, so none is left
      d.needle_angle = 0.1;
      d.fold_angle = InspectOptions{}.tetgen_fold_angle;  // spikes folded onto a neighbour: collapsed
      d.certify = false;
      d.weld = 0;  // as in degenerate(): TetGen's close vertices go by short_edges()
      d.observer = o_.observer;
      DegenerateResult res = remove_degenerate_faces(from, d);
      const DegenerateReport& r = res.report;
      s.counts = {{"caps_before", double(r.before.caps)},   {"needles_before", double(r.before.needles)},
                  {"caps_after", double(r.after.caps)},     {"needles_after", double(r.after.needles)},
                  {"collapses", double(r.collapses)},       {"flips", double(r.flips)},
                  {"sharp_folds_before", double(start.report.sharp_folds.size())},
                  {"tiny_components_removed", double(dropped)}};
      s.outcome = std::to_string(r.before.caps + r.before.needles) + " faces beyond 179.9/0.1 degrees and " +
                  std::to_string(start.report.sharp_folds.size()) + " sharp folds; " +
                  std::to_string(r.after.caps + r.after.needles) + " faces beyond left; " +
                  std::to_string(r.collapses) + " collapses, " + std::to_string(r.flips) + " flips";
      if (dropped)
        s.outcome += "; " + std::to_string(dropped) + " closed components within the tolerance, folded flat, removed";
      return std::move(res.soup);
    });
  }

  const StageReport& deintersect() {
    return stage("deintersect", [&](StageReport& s) {
      // Parts of an assembly that interpenetrate (a vertex of each crossing
      // pair of components deeper inside the other than --max-deviation, or
      // than a tenth of the smaller part: moving a pin half its size out of
      // the hole it sits in is no local repair): no small move separates
      // them, and on such inputs the moves took most of the run (three
      // overlapping rocker arms, 53k faces: 6.5 of 8.4 s) for a union no
      // closer than the union of the surface as given. Nor parts that
      // coincide (the smaller one within that distance of the other's
      // surface all over: a part given twice, 1e-5 apart, crosses its copy
      // everywhere; the moves freed 71 of 1648 faces in 2 s). Refused; the
      // union follows. (A cavity's wall is no part: a thin wall that crosses
      // its cavity is for the moves, or the union would open it.)
      const Report& cr = cur_.report;
      if (cr.components > 1 && cr.closed && cr.oriented && cr.nonmanifold_edges.empty()) {
        constexpr double kPartShare = 0.1;
        const std::vector<Interpenetration> crossings = interpenetrations(cur_.soup, cr.self_intersections);
        bool inseparable = !crossings.empty();
        std::size_t coincide = 0;
        double least = std::numeric_limits<double>::infinity(), farthest = 0;
        for (const Interpenetration& c : crossings) {
          const double limit = std::min(deviation_limit(), kPartShare * c.part);
          if (c.depth > limit) {
            least = std::min(least, c.depth);
          } else if (c.apart <= limit) {
            ++coincide;
            farthest = std::max(farthest, c.apart);
          } else {
            inseparable = false;
          }
        }
        if (inseparable) {
          std::ostringstream why;
          why << "the parts that cross ";
          if (coincide < crossings.size())
            why << "interpenetrate (each crossing pair of components has a vertex " << least
                << " or more inside the other, beyond --max-deviation " << deviation_limit()
                << " or a tenth of the smaller part)" << (coincide ? " or " : "");
          if (coincide)
            why << "coincide (" << coincide << " crossing pair" << (coincide == 1 ? "" : "s")
                << " of components with the smaller part within " << farthest
                << " of the other all over, within --max-deviation and a tenth of the part: a part given twice)";
          why << ": no small local move separates them; their union follows";
          throw UnsupportedInput(why.str());
        }
      }
      DeintersectOptions d;
      d.certify = false;
      d.observer = o_.observer;
      d.known_pairs = &cur_.report.self_intersections;
      // A work budget: local moves are for local defects, and a closed
      // surface crossing itself all over (a raw offset: a quarter of its
      // faces, folded through each other) is the union's. Trials cost ~50 us
      // whatever the mesh; the moves need ~10 a round per intersecting face
      // and free few after the first rounds: on Hand1's +2% raw offset (125k
      // faces, 28.8k intersecting) 20 rounds took 1.75M trials, 103 s, and
      // left 13k, which the union then removed in 0.7 s. Every corpus row
      // needs at most 51k (trimesh box.STL), the default budget 60k (~3 s).
      // After it, the union of what the moves left follows, as when they
      // stop short of clean.
      d.max_trials = o_.move_trials;
      DeintersectResult res = remove_self_intersections(cur_.soup, d);
      const DeintersectReport& r = res.report;
      s.max_displacement = r.max_displacement;
      s.counts = {{"intersecting_faces_in", double(r.intersecting_faces_in)},
                  {"intersecting_faces_left", double(r.intersecting_faces_exact)},
                  {"swaps", double(r.swaps)},
                  {"hammers", double(r.hammers)},
                  {"lifts", double(r.lifts)},
                  {"group_moves", double(r.group_moves)},
                  {"pair_moves", double(r.pair_moves)},
                  {"moved_vertices", double(r.moved_vertices)},
                  {"trials", double(r.trials)}};
      s.outcome = std::to_string(r.intersecting_faces_in) + " intersecting faces, " +
                  std::to_string(r.intersecting_faces_exact) + " left; " + std::to_string(r.swaps) + " swaps, " +
                  std::to_string(r.hammers) + " hammers, " + std::to_string(r.lifts) + " lifts, " +
                  std::to_string(r.group_moves) + " group moves, " +
                  std::to_string(r.pair_moves) + " pair moves";
      if (r.out_of_trials)
        s.outcome += "; stopped after " + std::to_string(r.trials) + " trials (the local moves' budget: " +
                     std::to_string(o_.move_trials) + ")";
      return std::move(res.soup);
    });
  }

  /// `pairs`: from's intersecting pairs, when known (they are searched for
  /// otherwise). `floats`: the union's points rounded to floats, as the file
  /// will hold them — after a rounding to floats only (a union in doubles
  /// first: a float union's moves can leave what the doubles' passes repair,
  /// and the grid then takes over; cycloidal as STL went 22 -> 78 s and kept
  /// 2% of its faces).
  /// `any_topology`: see stage().
  void regularize(const Soup& from, const char* name, const std::vector<FacePair>* pairs = nullptr,
                  bool floats = false, bool any_topology = false) {
    // A closed surface that encloses negative volume (exact sign) is inside
    // out whatever its overlaps: its union is empty (winding numbers <= 0),
    // and the union of the surface turned outwards is what it stands for.
    const bool turn = o_.orient_outward && enclosed_volume_sign(from) < 0;
    const std::string title = turn ? std::string(name) + " (turned outwards)" : std::string(name);
    Rule rule;
    rule.any_topology = any_topology;
    stage(title.c_str(), [&](StageReport& s) {
      RegularizeOptions ro;
      ro.certify = false;
      ro.observer = o_.observer;
      ro.known_pairs = pairs;  // a reversed surface crosses itself where it did
      ro.float_coordinates = floats;
      RegularizeResult res = polyheal::regularize(turn ? reversed(from) : from, ro);
      const RegularizeReport& r = res.report;
      s.counts = {{"intersecting_pairs_in", double(r.intersecting_pairs_in)},
                  {"triangles_split", double(r.triangles_split)},
                  {"invalid", double(r.invalid)},
                  {"components_removed", double(r.components_removed)}};
      s.outcome = std::to_string(r.intersecting_pairs_in) + " intersecting pairs; " +
                  std::to_string(r.triangles_split) + " triangles split, " + std::to_string(r.invalid) +
                  " inside the union removed, " + std::to_string(r.components_removed) + " components enclosed";
      if (turn) s.outcome = "the surface encloses negative volume (inside out): its union turned outwards; " + s.outcome;
      return std::move(res.soup);
    }, rule);
  }

  /// `simplify`: coarsen the grid's planar regions and decimate (rebuild.h).
  /// Returns the grid's cell size (0 when the stage was refused).
  /// `beyond`: the current surface is certified beyond the bounds (Rule::beyond).
  double rebuild(bool simplify, bool beyond = false) {
    // From the input, not the current surface: earlier stages may have
    // closed a sheet by filling its boundary (a flat double layer), which
    // the overlay grid would take for a volume.
    double cell = 0;
    Rule rule;
    rule.beyond = beyond;
    stage(simplify ? "rebuild" : "rebuild (not coarsened)", [&](StageReport& s) {
      RebuildOptions ro;
      ro.simplify = ro.decimate = simplify;
      ro.certify = false;
      ro.keep_clean = false;
      // Not the wrap of what the grid surface still misses: its bumps move
      // the surface up to 0.9 cell, and repair minimises movement. (With it,
      // degenerated-sd's grid surface passed every TetGen-readiness test of
      // ours and TetGen 1.5 threw in delaunizesegments.)
      ro.wrap_outlying = false;
      // For TetGen, the input's own hazards are defects the grid replaces
      // (a certified clean input is otherwise kept whole, hazards and all,
      // and the zip gives every patch up).
      if (o_.for_tetgen) ro.avoid = tetgen_hazards(input_, result_.input);
      ro.observer = o_.observer;
      std::optional<RebuildResult>& made = rebuilt_[simplify ? 1 : 0];
      if (!made) made = polyheal::rebuild(input_, ro);
      RebuildResult res = *made;
      const RebuildReport& r = res.report;
      cell = r.cell;
      s.counts = {{"cell", r.cell},
                  {"boundary_cells", double(r.boundary_cells)},
                  {"sheet_facets", double(r.sheet_facets)},
                  {"thin_facets", double(r.thin_facets)},
                  {"outlying_pieces", double(r.outlying_pieces)},
                  {"extracted_faces", double(r.extracted_faces)}};
      std::ostringstream line;
      line << "overlay grid of cell " << r.cell << " (" << r.cell_rule << "), " << r.faces_out << " faces";
      if (r.kept_patches + r.patches_given_up)
        line << "; " << r.kept_faces << " input faces kept in " << r.kept_patches << " patches (" << r.patches_given_up
             << " given up)";
      if (r.sheet_facets + r.thin_facets)
        line << "; " << r.sheet_facets + r.thin_facets << " sheet or thin facets wrapped in a shell";
      s.outcome = line.str();
      return std::move(res.soup);
    }, rule);
    return cell;
  }

  const Soup& input_;
  const RepairOptions& o_;
  State cur_;
  RepairResult result_;
  std::vector<std::array<Point3d, 3>> pending_fills_;  // of the last clean run, until it is kept
  const Fills fills_;
  RebuildCache& rebuilt_;
  std::optional<Fills> fill_choice_;  // what the first clean chose (by_defects: it had no choice)
  std::size_t filled_ = 0;            // holes the last clean filled
  Standing standing_;
};

double triangle_area(const Point3d& a, const Point3d& b, const Point3d& c) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

double face_area(const Soup& s, std::size_t f) {
  const FaceView v = s.face(f);
  double a = 0;
  for (std::size_t k = 1; k + 1 < v.size(); ++k) a += triangle_area(s.points[v[0]], s.points[v[k]], s.points[v[k + 1]]);
  return a;
}

/// Key of a face by its corner positions in cyclic order, independent of
/// the starting corner and of orientation (provenance: "the same face"):
/// the smallest of its rotations, read either way round.
using Corners = boost::container::small_vector<Point3d, 4>;  // triangles (and quads) without a heap allocation: two per face of a big scan
struct CornerKey {
  Corners p;
  bool operator==(const CornerKey& o) const { return p == o.p; }
};
CornerKey corner_key(const Corners& corners) {
  const std::size_t n = corners.size();
  const Point3d& least = *std::min_element(corners.begin(), corners.end());
  // corner k of the reading starting at r, forwards (way 0) or backwards
  auto at = [&](int way, std::size_t r, std::size_t k) -> const Point3d& {
    return corners[way ? (r + n - k) % n : (r + k) % n];
  };
  int best_way = -1;
  std::size_t best_r = 0;
  for (int way = 0; way < 2; ++way)
    for (std::size_t r = 0; r < n; ++r) {
      if (corners[r] != least) continue;  // the smallest rotation starts at a smallest corner
      bool smaller = best_way < 0;
      for (std::size_t k = 0; k < n && !smaller; ++k) {
        if (at(way, r, k) != at(best_way, best_r, k)) {
          smaller = at(way, r, k) < at(best_way, best_r, k);
          break;
        }
      }
      if (smaller) best_way = way, best_r = r;
    }
  CornerKey key;
  for (std::size_t k = 0; k < n; ++k) key.p.push_back(at(best_way, best_r, k));
  return key;
}
/// A hash of the key consistent with its equality (-0.0 == 0.0: both
/// hashed as +0.0; readers reject NaN).
std::uint64_t hash_of(const CornerKey& k) { return hash_points(k.p.data(), k.p.size()); }
CornerKey corner_key(const Soup& s, std::size_t f) {
  Corners corners;
  for (Index i : s.face(f)) corners.push_back(s.points[i]);
  return corner_key(corners);
}

}  // namespace

const char* step_name(RepairStep step) {
  switch (step) {
    case kStepClean: return "clean";
    case kStepDegenerate: return "degenerate";
    case kStepDeintersect: return "deintersect";
    case kStepRegularize: return "regularize";
    case kStepRebuild: return "rebuild";
    default: return "?";
  }
}

unsigned parse_steps(const std::string& list) {
  unsigned mask = 0;
  std::istringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    if (item == "all") {
      mask |= kAllSteps;
      continue;
    }
    bool found = false;
    for (RepairStep s : kSteps)
      if (item == step_name(s)) {
        mask |= s;
        found = true;
      }
    if (!found)
      throw std::invalid_argument("unknown step '" + item +
                                  "' (expected clean, degenerate, deintersect, regularize, rebuild or all)");
  }
  return mask;
}

std::vector<std::pair<std::string, std::size_t>> defect_kinds(const Report& r, bool for_tetgen) {
  std::vector<std::pair<std::string, std::size_t>> d;
  auto add = [&](const char* what, std::size_t n) {
    if (n) d.emplace_back(what, n);
  };
  add("boundary edges", r.boundary_edges.size());
  add("non-manifold edges", r.nonmanifold_edges.size());
  add("non-manifold vertices", r.nonmanifold_vertices.size());
  add("misoriented edges", r.misoriented_edges.size());
  add("degenerate faces", r.degenerate_faces.size());
  add("duplicate faces", r.duplicate_faces.size());
  add("intersecting pairs", r.self_intersections.size());
  if (for_tetgen) {
    add("sharp folds", r.sharp_folds.size());
    add("nearly degenerate faces", r.nearly_degenerate_faces.size());
    add("vertices nearly on an edge", r.vertices_near_edges.size());
    add("vertices closer than TetGen's shortest edge", r.close_vertices.size());
    add("edges closer than TetGen's shortest edge", r.edges_near_edges.size());
    add("vertices closer than TetGen's shortest edge to a face", r.vertices_near_faces.size());
    add("face pairs TetGen merges whose flip cuts another face", r.flip_hazards.size());
    add("refused by TetGen itself", r.tetgen_refused ? 1 : 0);
  }
  if (r.faces == 0) d.emplace_back("no face left", 1);
  return d;
}

std::size_t defect_count(const Report& r, bool for_tetgen) {
  std::size_t n = 0;
  for (const auto& [what, count] : defect_kinds(r, for_tetgen)) n += count;
  return n;
}

bool certified(const Report& r, bool for_tetgen) { return for_tetgen ? r.tetgen_ready() : r.certified_clean(); }

namespace {

/// How a repair ended, in words: "certified, surface moved 0.52 (within
/// --max-deviation 1.1)", "12 defects left", ...
std::string ending(const RepairResult& r, const Standing& st) {
  std::ostringstream line;
  if (!st.certified) {
    line << st.defects << " defects left";
    return line.str();
  }
  line << "certified";
  if (!r.assessment) return line.str();
  const Assessment& a = *r.assessment;
  line << ", surface moved " << a.deviation << (a.within_deviation ? " (within" : " (more than") << " --max-deviation "
       << a.max_deviation << ")";
  if (a.dropped_components) line << ", " << a.dropped_components << " input components dropped";
  return line.str();
}

/// The stage that stands for a whole repair whose result was not kept.
StageReport not_kept(const RepairResult& r, const Standing& st, Fills fills, const std::string& why) {
  StageReport s;
  s.name = fills == Fills::never ? "repair with the holes left open" : "repair with the holes filled";
  s.accepted = false;
  s.faces_out = r.soup.face_count();
  s.defects_after = st.defects;
  s.hausdorff = std::max(r.distances[0], r.distances[1]);
  s.seconds = r.report.seconds;
  s.outcome = ending(r, st) + "; not kept: " + why;
  return s;
}

}  // namespace

RepairResult repair(const Soup& input, const RepairOptions& options) {
  if (input.face_count() == 0) throw UnsupportedInput("no faces: nothing to repair");
  RebuildCache rebuilt;
  Pipeline first(input, options, rebuilt);
  RepairResult a = first.run();
  const std::optional<Fills> other = first.other_fills();
  if (!other) return a;
  // The first repair did not end within bounds, and its first clean chose
  // on its hole fills: the other way, from the input, to the end (Fills).
  Pipeline second(input, options, rebuilt, *other);
  RepairResult b = second.run();
  const Fills chosen = *other == Fills::never ? Fills::always : Fills::never;
  const double seconds = a.report.seconds + b.report.seconds;
  if (second.standing().better_than(first.standing())) {
    const StageReport s = not_kept(a, first.standing(), chosen,
                                   std::string("repaired again from the input with the holes ") +
                                       (*other == Fills::never ? "left open" : "filled") + " (below), which ends better");
    b.report.stages.insert(b.report.stages.begin(), s);
    b.report.seconds = seconds;
    return b;
  }
  a.report.stages.push_back(not_kept(b, second.standing(), *other,
                                     "tried from the input because the repair above did not end within bounds; it "
                                     "ends no better"));
  a.report.seconds = seconds;
  return a;
}

double max_deviation_of(const RepairOptions& o, double diagonal) {
  return o.max_deviation > 0 ? o.max_deviation : o.max_deviation_ratio * diagonal;
}

namespace {

/// a.out (written_report, or the inspection of `written`) and what follows
/// from it alone.
void inspect_written(Assessment& a, const Soup& written, bool for_tetgen, const Report* written_report) {
  if (written_report) {
    a.out = *written_report;
  } else {
    InspectOptions io;
    io.tetgen_segments = for_tetgen;
    a.out = inspect(written, io);
  }
  a.certified = certified(a.out, for_tetgen);
  a.components_out = a.out.components;
}

}  // namespace

Assessment reinspected(Assessment measured, const Soup& written, bool for_tetgen) {
  inspect_written(measured, written, for_tetgen, nullptr);
  return measured;
}

Assessment assess(const Soup& input, const Report& in, const Soup& written, double max_deviation, bool for_tetgen,
                  const std::vector<std::array<Point3d, 3>>& hole_fills, const Report* written_report,
                  const std::array<double, 2>* distances) {
  Assessment a;
  inspect_written(a, written, for_tetgen, written_report);
  a.components_in = in.components;
  a.diagonal = bbox_diagonal(in);
  a.max_deviation = max_deviation;
  a.error_bound = 1e-4 * a.diagonal;
  if (written.face_count() && input.face_count()) {
    const std::array<double, 2> d = distances ? *distances : detail::one_sided_distances(input, written, a.error_bound);
    a.input_to_output = d[0];
    a.output_to_input = d[1];
    a.hausdorff = std::max(d[0], d[1]);
    // The input outside the output's volume is measured apart only when the
    // plain distance exceeds the bound (it bounds the refined one).
    const bool refine = a.input_to_output > max_deviation;
    // Every input point within the limit of the output (by the bound, with
    // a margin for the doubles of the nearest-point queries): no input
    // vertex is far from it, so no face is lost or absorbed.
    Loss loss;
    if (refine || a.input_to_output + 2 * a.error_bound > max_deviation)
      loss = measure_loss(input, written, max_deviation, refine, a.certified);
    else
      loss.absorbed.assign(input.face_count(), 0);
    a.dropped_components = loss.lost_components + loss.absorbed_components;
    a.absorbed_components = loss.absorbed_components;
    a.absorbed_faces = loss.absorbed_faces;
    // The surface moved: how far the output is from the input, but for
    // faces spanning input vertices only (hole fills), and the input, but
    // for what the output encloses, from the output.
    // A fill face is one whose corners all lie on one fill triangle, within
    // the measurement's error bound (then it lies on it: the distance to a
    // triangle is convex): the fill itself, or a piece of it a later stage
    // cut (regularize cuts faces along the curves where they cross). Fills
    // are measured apart (fill_distance), not left out.
    const std::unique_ptr<detail::SurfaceDistance> fill_surface =
        hole_fills.empty() ? nullptr : std::make_unique<detail::SurfaceDistance>(hole_fills);
    const double on_fill2 = a.error_bound * a.error_bound;
    const auto on_one_fill = [&](const FaceView& v) {
      const Point3d &p = written.points[v[0]], &q = written.points[v[1]], &r = written.points[v[2]];
      Point3d lo = p, hi = p;
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min({p[k], q[k], r[k]}) - a.error_bound;
        hi[k] = std::max({p[k], q[k], r[k]}) + a.error_bound;
      }
      for (std::size_t t : fill_surface->triangles_near(lo, hi))
        if (fill_surface->squared_distance_to(p, t) <= on_fill2 && fill_surface->squared_distance_to(q, t) <= on_fill2 &&
            fill_surface->squared_distance_to(r, t) <= on_fill2)
          return true;
      return false;
    };
    Soup moved, fills;
    moved.points = fills.points = written.points;
    for (std::size_t f = 0; f < written.face_count(); ++f) {
      const FaceView v = written.face(f);
      const bool fill = v.size() == 3 && fill_surface && on_one_fill(v);
      (fill ? fills : moved).add_face(v.begin(), v.end());
    }
    double output_moved = moved.face_count() ? detail::one_sided_distance(moved, input, a.error_bound) : 0.0;
    a.fill_faces = fills.face_count();
    // The output's faces are the moved ones and the fills: when the moved
    // ones are certainly nearer the input than the output's farthest point
    // (true distance at most output_moved + bound < output_to_input, itself
    // at most the true farthest), that point is on a fill, and
    // output_to_input measures the fills too (as bounded).
    if (fills.face_count())
      a.fill_distance = output_moved + a.error_bound < a.output_to_input
                            ? a.output_to_input
                            : detail::one_sided_distance(fills, input, a.error_bound);
    // The input inside the output's volume was removed, not moved: only
    // what lies outside it counts.
    // (The plain one-sided distance bounds it: the skipping measure may
    // over-estimate where it ran out of budget.)
    const double input_visible = refine ? std::min(loss.outside_distance, a.input_to_output) : a.input_to_output;
    for (std::size_t f = 0; f < input.face_count(); ++f)
      if (loss.absorbed[f]) a.area_absorbed += face_area(input, f);
    a.deviation = std::max(output_moved, input_visible);
  } else if (input.face_count()) {
    a.dropped_components = a.components_in;
  }
  a.within_deviation = a.deviation >= 0 ? a.deviation <= max_deviation : written.face_count() == input.face_count();
  // Provenance: an output face whose corners are exactly an input face's.
  // Input faces in a flat hash table by their key (of copies, the first:
  // inserted in index order), keys of equal hash compared exactly. A
  // node-based hash map of a million keys cost 1.5 s of a 1M-face scan's
  // repair, sorting the hashes and searching them 0.55 s, this 0.2 s.
  std::vector<std::uint64_t> input_hash(input.face_count());
  std::vector<Index> table = empty_table(input.face_count());
  auto slot_of = [&](const CornerKey& key, std::uint64_t h) {
    return probe(table, h, [&](std::size_t s) {
      return input_hash[table[s]] == h && corner_key(input, table[s]) == key;
    });
  };
  for (std::size_t f = 0; f < input.face_count(); ++f) {
    a.area_in += face_area(input, f);
    const CornerKey key = corner_key(input, f);
    input_hash[f] = hash_of(key);
    const std::size_t slot = slot_of(key, input_hash[f]);
    if (table[slot] == kEmptySlot) table[slot] = static_cast<Index>(f);
  }
  a.provenance.assign(written.face_count(), -1);
  for (std::size_t f = 0; f < written.face_count(); ++f) {
    const double area = face_area(written, f);
    a.area_out += area;
    const CornerKey key = corner_key(written, f);
    const Index first = table[slot_of(key, hash_of(key))];
    if (first == kEmptySlot) continue;
    a.provenance[f] = std::int64_t(first);
    ++a.faces_kept;
    a.area_kept += area;
  }
  return a;
}

}  // namespace polyheal
