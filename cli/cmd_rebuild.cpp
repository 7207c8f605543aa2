// polyheal rebuild IN -o OUT — Hu, Lee, Blacker & Zhu's overlay-grid cleanup.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "polyheal/repair/rebuild.h"
#include "progress.h"
#include "repair_command.h"

namespace polyheal::cli {
namespace {

nlohmann::json regions_json(const std::vector<Region>& regions) {
  auto a = nlohmann::json::array();
  for (const Region& g : regions) a.push_back({{"count", g.count}, {"min", g.lo}, {"max", g.hi}});
  return a;
}

struct RebuildArgs : RepairFiles {
  std::string cell;  // "0.5" (model units) or "1%" (of the bbox diagonal)
  std::string sheets = "shell";
  RebuildOptions options;
};

nlohmann::json to_json(const RebuildArgs& a, const RebuildReport& r, double read_s, double write_s) {
  return {
      {"schema", "polyheal.rebuild/1"},
      {"input", a.input},
      {"output", a.output},
      {"certified", r.certified},
      {"unchanged", r.unchanged},
      {"cleaned", r.cleaned},
      {"volume", r.volume},
      {"parameters",
       {{"cell", r.cell}, {"cell_rule", r.cell_rule}, {"refine", a.options.refine},
        {"feature_angle", a.options.feature_angle},
        {"simplify", a.options.simplify}, {"sharpen", a.options.sharpen}, {"keep_clean", a.options.keep_clean},
        {"keep_regions", a.options.keep_regions},
        {"sheets", a.sheets}}},
      {"input_mesh",
       {{"faces", r.faces},
        {"vertices", r.vertices},
        {"groups", r.groups},
        {"zero_area_faces", r.zero_area_faces},
        {"reoriented_faces", r.reoriented_faces},
        {"inside_out_faces", r.inside_out_faces},
        {"duplicate_faces", r.duplicate_faces},
        {"stitched_edges", r.stitched_edges},
        {"boundary_loops", r.boundary_loops},
        {"sheet_facets", r.sheet_facets},
        {"thin_facets", r.thin_facets},
        {"outlying_pieces", r.outlying_pieces},
        {"shell", r.shell},
        {"diagonal", r.diagonal},
        {"largest_gap", r.largest_gap}}},
      {"grid",
       {{"depth", r.depth},
        {"octree_nodes", r.octree_nodes},
        {"boundary_cells", r.boundary_cells},
        {"closure_cells", r.closure_cells},
        {"halvings", r.halvings},
        {"refined_tets", r.refined_tets},
        {"bisections", r.bisections},
        {"leaf_tets", r.leaf_tets},
        {"finest_cell", std::ldexp(r.cell, -r.finest_level / 3)},
        {"thickened_corners", r.thickened_corners},
        {"corners", r.corners},
        {"inside_corners", r.inside_corners},
        {"crossed_edges", r.crossed_edges},
        {"facet_crossings", r.facet_crossings},
        {"interpolated", r.interpolated}}},
      {"output_mesh",
       {{"beads_dropped", r.beads_dropped},
        {"extracted_faces", r.extracted_faces},
        {"kept_faces", r.kept_faces},
        {"kept_patches", r.kept_patches},
        {"patches_given_up", r.patches_given_up},
        {"planar_collapses", r.collapses},
        {"coarsening_retries", r.coarsening_retries},
        {"decimated", r.decimated},
        {"sharpened", r.sharpened},
        {"faces", r.faces_out},
        {"vertices", r.vertices_out},
        {"components", r.components_out},
        {"face_groups", r.face_groups}}},
      {"check",
       {{"closed", r.closed},
        {"manifold", r.manifold},
        {"oriented", r.oriented},
        {"self_intersections", r.self_intersections},
        {"degenerate_faces", r.degenerate}}},
      {"hausdorff", r.hausdorff},
      {"hausdorff_error_bound", r.hausdorff_error_bound},
      {"input_to_output", r.input_to_output},
      {"output_to_input", r.output_to_input},
      {"lost",
       {{"faces", r.lost_faces},
        {"components", r.lost_components},
        {"area_fraction", r.lost_area_fraction},
        {"where", regions_json(r.lost_regions)}}},  // each component lost: faces, bounding box
      {"open_loops", regions_json(r.open_loops)},   // each open boundary loop of the input: edges, bounding box
      {"absorbed_faces", r.absorbed_faces},
      {"hausdorff_cells", r.cell > 0 && r.hausdorff >= 0 ? r.hausdorff / r.cell : -1},
      {"seconds",
       {{"read", read_s},
        {"prepare", r.seconds_prepare},
        {"octree", r.seconds_octree},
        {"winding", r.seconds_winding},
        {"extract", r.seconds_extract},
        {"refine", r.seconds_refine},
        {"simplify", r.seconds_simplify},
        {"write_and_certify", write_s}}},
  };
}

/// "N edges in [x y z]-[x y z]; ..." for the first few regions.
std::string where(const std::vector<Region>& regions, const char* what) {
  std::string out;
  char buf[256];
  for (std::size_t i = 0; i < regions.size() && i < 5; ++i) {
    const Region& g = regions[i];
    std::snprintf(buf, sizeof buf, "%s%zu %s in [%g %g %g]-[%g %g %g]", i ? "; " : "", g.count, what, g.lo[0], g.lo[1],
                  g.lo[2], g.hi[0], g.hi[1], g.hi[2]);
    out += buf;
  }
  if (regions.size() > 5) out += "; and " + std::to_string(regions.size() - 5) + " more (--json lists all)";
  return out;
}

void print_text(const RebuildArgs& a, const RebuildReport& r) {
  std::printf("%s -> %s: rebuild on an overlay grid\n", a.input.c_str(), a.output.c_str());
  std::printf("  input: %zu faces, %zu vertices, %zu groups; %zu zero-area and %zu duplicate faces left out, %zu faces "
              "reoriented, %zu boundary loops\n",
              r.faces, r.vertices, r.groups, r.zero_area_faces, r.duplicate_faces, r.reoriented_faces,
              r.boundary_loops);
  if (r.inside_out_faces)
    std::printf("  %zu faces of components facing inwards (inside out, or a cavity of one) turned outward\n",
                r.inside_out_faces);
  if (r.unchanged) {
    std::printf("  input is already closed, 2-manifold, oriented and intersection-free: written unchanged\n");
  } else if (r.cleaned) {
    std::printf("  closed by the exact cleanup alone (no grid, no coordinate changed): %zu repeated-index and %zu "
                "duplicate faces dropped, %zu faces reoriented, %zu edges stitched\n",
                r.zero_area_faces, r.duplicate_faces, r.reoriented_faces, r.stitched_edges);
  } else {
    std::printf("  grid: cell %g (%s; largest gap %g, diagonal %g), depth %d, %zu octree nodes, %zu boundary "
                "cells + %zu closing gaps and holes\n",
                r.cell, r.cell_rule.c_str(), r.largest_gap, r.diagonal, r.depth, r.octree_nodes, r.boundary_cells,
                r.closure_cells);
    if (r.refined_tets)
      std::printf("  refined: %zu tetrahedra missed the surface (spikes, thin parts, acute edges, rims) and were bisected "
                  "(%zu bisections in all, down to cell %g); %zu tetrahedra\n",
                  r.refined_tets, r.bisections, std::ldexp(r.cell, -r.finest_level / 3), r.leaf_tets);
    if (r.thickened_corners)
      std::printf("  %zu corners within a finest step of parts thinner than that: inside (a shell one step thick)\n",
                  r.thickened_corners);
    if (r.beads_dropped)
      std::printf("  %zu extracted pieces smaller than a cell dropped: beads of a thin part another piece stands for\n",
                  r.beads_dropped);
    if (r.sheet_facets)
      std::printf("  %zu facets bound no volume (open or double-sided sheets): %s\n", r.sheet_facets,
                  r.shell > 0 ? ("wrapped in a shell of half-thickness " + std::to_string(r.shell)).c_str()
                              : "left out (--sheets drop)");
    if (r.thin_facets)
      std::printf("  %zu facets of parts thinner than a cell: wrapped in the shell too\n", r.thin_facets);
    if (r.outlying_pieces)
      std::printf("  %zu pieces of facets still more than 0.6 cell outside the surface: wrapped in the shell too\n",
                  r.outlying_pieces);
    std::printf("  corners: %zu, %zu inside; %zu crossed grid edges: %zu on facets, %zu interpolated across "
                "gaps/holes\n",
                r.corners, r.inside_corners, r.crossed_edges, r.facet_crossings, r.interpolated);
    if (!r.volume) {
      std::printf("  => the soup encloses no volume (no grid corner has winding number > 1/2; %zu open boundary "
                  "loops; --sheets shell would wrap them): the input is written as read, NOT CERTIFIED\n",
                  r.boundary_loops);
      if (!r.open_loops.empty()) std::printf("  open loops: %s\n", where(r.open_loops, "edges").c_str());
      return;
    }
    if (a.options.keep_regions)
      std::printf("  clean regions: %zu input faces kept exactly, in %zu patches zipped to the grid surface; %zu "
                  "patches given up (grid surface there)\n",
                  r.kept_faces, r.kept_patches, r.patches_given_up);
    std::printf("  output: %zu faces extracted, %zu planar vertices collapsed, %zu decimated -> %zu faces, %zu "
                "vertices, %zu components, %zu face groups\n",
                r.extracted_faces, r.collapses, r.decimated, r.faces_out, r.vertices_out, r.components_out,
                r.face_groups);
  }
  std::printf("  time: prepare %.3f s, octree %.3f s, winding %.3f s, extract %.3f s, refine %.3f s, simplify %.3f s, "
              "certify %.3f s\n",
              r.seconds_prepare, r.seconds_octree, r.seconds_winding, r.seconds_extract, r.seconds_refine,
              r.seconds_simplify, r.seconds_certify);
  if (r.hausdorff >= 0)
    std::printf("  Hausdorff distance to the input: %g (+%g) = %.3g cells; input to output %g (detail lost), output "
                "to input %g (gap and hole fills)\n",
                r.hausdorff, r.hausdorff_error_bound, r.cell > 0 ? r.hausdorff / r.cell : 0.0, r.input_to_output,
                r.output_to_input);
  if (r.absorbed_faces)
    std::printf("  %zu input faces lie inside the volume, farther than two cells from its surface (inner walls, "
                "enclosed parts): absorbed\n",
                r.absorbed_faces);
  if (r.lost_faces)
    std::printf("  %zu input faces (%.3g%% of the area) are farther than two cells from the output and outside it: "
                "not represented (sheets left out, parts thinner than a cell)%s\n",
                r.lost_faces, 100 * r.lost_area_fraction,
                r.lost_components ? (", " + std::to_string(r.lost_components) + " whole components LOST").c_str() : "");
  if (!r.lost_regions.empty()) std::printf("  lost components: %s\n", where(r.lost_regions, "faces").c_str());
  if (r.certified)
    std::printf("  => CERTIFIED: closed, 2-manifold, oriented, no degenerate face, no self-intersection\n");
  else
    std::printf("  => NOT CERTIFIED: closed %s, manifold %s, oriented %s, %zu self-intersecting pairs, %zu "
                "degenerate faces, %zu input components lost\n",
                r.closed ? "yes" : "no", r.manifold ? "yes" : "no", r.oriented ? "yes" : "no", r.self_intersections,
                r.degenerate, r.lost_components);
}

}  // namespace

void add_rebuild(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RebuildArgs>();
  CLI::App* cmd = app.add_subcommand(
      "rebuild", "Rebuild dirty faceted geometry (gaps, holes, overlaps) into a watertight volume on an overlay grid "
                 "(Hu, Lee, Blacker & Zhu)");
  cmd->footer(
      "Any soup is accepted: no manifoldness or closure needed; polygons are fanned,\n"
      "zero-area faces left out, inconsistently oriented components made consistent,\n"
      "components facing inwards (inside out, by the winding number) turned outward.\n"
      "An octree is refined where it meets the facets down to the cell size, and\n"
      "its tetrahedra bisected further where they miss the surface (--refine); each\n"
      "grid corner is inside when its generalised winding number is above 1/2 (gaps\n"
      "and holes are spanned, overlaps count once). Facets that bound no volume\n"
      "(open or double-sided sheets) are wrapped in a shell 0.9 cell thick on each\n"
      "side, unless --sheets drop; so are parts thinner than a cell, and pieces of\n"
      "facets still more than 0.6 cell outside the surface after refinement. The\n"
      "output is the boundary of the inside corners (marching tetrahedra), its\n"
      "vertices on the exact crossings of grid edges with facets, interpolated\n"
      "across gaps, holes and shells: closed, 2-manifold and oriented by\n"
      "construction. Input faces far from every defect are kept exactly\n"
      "and zipped to it (--no-keep rebuilds them too). A zip the exact oracle\n"
      "rejects is mended first (the grid faces it crosses are cut away, the patch\n"
      "shrinks where it folds or necks) and zipped again; a patch that still fails\n"
      "is left to the grid. Planar regions are coarsened without moving the\n"
      "surface, the rest decimated within a quarter cell (each collapse checked\n"
      "exactly for self-intersection). Faces are grouped by the input's groups (OBJ\n"
      "g, STL solids), else by --feature-angle (OBJ output keeps them). A clean input\n"
      "is written unchanged; one that repair's exact cleanup alone closes (identical\n"
      "vertices shared, repeated-index and duplicate faces dropped, orientation made\n"
      "consistent and outward, matching borders stitched; no coordinate changed) is\n"
      "written cleaned, without a grid. The written file is read back and checked exactly; the\n"
      "distances input->output and output->input are measured, and input faces the\n"
      "output does not represent are counted.\n\n"
      "Exit 0 when the written file is closed, 2-manifold, oriented, without\n"
      "degenerate faces or self-intersections, and no input component is lost;\n"
      "1 otherwise (also when, with --sheets drop, the soup encloses no volume:\n"
      "then the input is written as read); 2 on error.");
  add_repair_files(cmd, *args, "polyheal.rebuild/1", "",
                   "input soup (.off, .obj, .stl, .ply): any faces, open, non-manifold, overlapping");
  cmd->add_option("--cell", args->cell,
                  "cell size: model units, or a percentage of the bbox diagonal (default: 1% of the diagonal, or "
                  "1.25 x the largest gap between boundary loops if larger)");
  cmd->add_option("--refine", args->options.refine,
                  "halvings of the cell where the grid misses the surface: a tetrahedron of the grid holding both "
                  "sides of a part thinner than itself or an acute edge (facets more than 120 degrees apart), or, "
                  "with all its corners outside, the rim of a hole, is bisected, down to cell / 2^N (default 2; 0: "
                  "uniform cells)")
      ->check(CLI::Range(0, 8));
  cmd->add_option("--feature-angle", args->options.feature_angle,
                  "degrees: output faces whose normals differ by less join one face group (input without groups)")
      ->check(CLI::Range(0.0, 180.0));
  cmd->add_flag("--no-simplify{false}", args->options.simplify,
                "keep every extracted triangle (no planar coarsening, no decimation)");
  cmd->add_flag("--always{false}", args->options.keep_clean, "rebuild on the grid even an input that is clean, or that the exact cleanup closes");
  cmd->add_flag("--no-keep{false}", args->options.keep_regions,
                "rebuild clean regions too (by default input faces far from every defect are kept exactly and "
                "zipped to the grid surface)");
  cmd->add_flag("--no-sharpen{false}", args->options.sharpen,
                "leave sharp edges chamfered (no moving of vertices onto the input's edges and corners)");
  cmd->add_option("--sheets", args->sheets,
                  "facets that bound no volume (open or double-sided sheets): 'shell' wraps them 0.9 cell thick on "
                  "each side (default), 'drop' leaves them out (reported lost)")
      ->check(CLI::IsMember({"shell", "drop"}));
  cmd->callback([args, &exit_code] {
    double ratio = -1;
    parse_length("--cell", args->cell, args->options.cell, ratio);
    args->options.cell_ratio = ratio;
    args->options.decimate = args->options.simplify;  // --no-simplify keeps every extracted triangle
    args->options.sheets = args->sheets == "shell";
    TtyProgress progress;
    double read_s = 0;
    const Soup soup = read_repair_input(*args, progress, read_s);
    args->options.observer = &progress;
    args->options.certify = false;  // certified below, on the file as written
    RebuildResult result = run_repair(*args, [&] { return rebuild(soup, args->options); });
    RebuildReport& r = result.report;
    double write_s = 0;
    finish_repair(
        result.soup, *args, progress, write_s,
        [&](const Soup& written) {
          certify_rebuild(soup, written, r);
          return r.certified;
        },
        [&] { return to_json(*args, r, read_s, write_s); },
        [&] {
          r.seconds_certify = write_s;
          print_text(*args, r);
        },
        exit_code);
  });
}

}  // namespace polyheal::cli
