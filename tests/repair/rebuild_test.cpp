// polyheal rebuild (Hu, Lee, Blacker & Zhu's overlay grid): dirty soups —
// gaps and overlaps at seams, a missing strip, overlapping copies of a patch,
// edges defined twice, a CAD part with holes — come out closed, 2-manifold,
// oriented and intersection-free (the exact oracle on the written file, and
// TetGen), with the input's surface within one cell of the output.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/topology.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/mesh/weld.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/rebuild.h"
#include "polyheal/repair/regularize.h"
#include "support/builders.h"

using namespace polyheal;

namespace {


/// Writes the output to scratch(`name`), asks TetGen whether it meshes it,
/// and returns the file as read back: every check runs on what was written.
Soup written(const RebuildResult& result, const std::string& name) {
  const std::string p = test::scratch(name);
  write_soup(result.soup, p);
  CHECK(test::tetgen_meshes(p, "tet_" + name));
  return read_soup(p);
}

/// Writes the output to scratch(`name`) and checks the file as read back is
/// certified and TetGen-ready (no simplices closer than TetGen's tolerances)
/// and that `tetgen -pQ` meshes it (without -Y: TetGen may change the
/// surface, where its tolerances bite).
void check_tetgen_ready(const RebuildResult& result, const std::string& name) {
  const std::string path = test::scratch(name);
  write_soup(result.soup, path);
  InspectOptions io;
  io.tetgen_segments = true;
  const Report rep = inspect(read_soup(path), io);
  REQUIRE(rep.certified_clean());
  CHECK(rep.vertices_near_edges.empty());
  CHECK(rep.vertices_near_faces.empty());
  CHECK(rep.edges_near_edges.empty());
  CHECK(rep.tetgen_ready());
  CHECK(test::tetgen_meshes(path, "tet_" + name, "-pQ"));
}

/// The checks every rebuilt solid passes, on the written file.
void check_solid(const Soup& input, const Soup& out, const RebuildReport& r, std::size_t components, long euler) {
  const Report rep = inspect(out);
  CHECK(rep.certified_clean());
  CHECK(rep.components == components);
  CHECK(topology_of(rep).euler == euler);
  CHECK(r.volume);
  CHECK_FALSE(r.unchanged);
  // The written file is what the report measured.
  RebuildReport again = r;
  certify_rebuild(input, out, again);
  CHECK(again.certified);
}

/// Signed volume of a closed, oriented soup.
double volume(const Soup& s) {
  double v = 0;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const Point3d &p = s.points[s.face(f)[0]], &q = s.points[s.face(f)[1]], &w = s.points[s.face(f)[2]];
    v += p[0] * (q[1] * w[2] - q[2] * w[1]) - p[1] * (q[0] * w[2] - q[2] * w[0]) + p[2] * (q[0] * w[1] - q[1] * w[0]);
  }
  return v / 6;
}

/// Adds the quad a, b, c, d (counter-clockwise seen from outside) as two triangles.
void quad(Soup& s, Point3d a, Point3d b, Point3d c, Point3d d) {
  const Index i = Index(s.points.size());
  for (const Point3d& p : {a, b, c, d}) s.points.push_back(p);
  s.add_triangle(i, i + 1, i + 2);
  s.add_triangle(i, i + 2, i + 3);
}

/// A closed cylinder (axis z, radius r, height h): n sectors, `rings` rows
/// of quads on the side, fans on the caps; every face its own corners.
/// Sectors in `missing` are left out of the side (a strip from cap to cap).
Soup cylinder(int n, int rings, double r, double h, std::set<int> missing = {}) {
  Soup s;
  auto at = [&](int k, double z) {
    return Point3d{r * std::cos(2 * kPi * k / n), r * std::sin(2 * kPi * k / n), z};
  };
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < rings && !missing.count(k); ++j)
      quad(s, at(k, h * j / rings), at(k + 1, h * j / rings), at(k + 1, h * (j + 1) / rings), at(k, h * (j + 1) / rings));
    const Index i = Index(s.points.size());
    s.points.push_back({0, 0, 0});
    s.points.push_back(at(k + 1, 0));
    s.points.push_back(at(k, 0));
    s.add_triangle(i, i + 1, i + 2);  // bottom, facing -z
    s.points.push_back({0, 0, h});
    s.points.push_back(at(k, h));
    s.points.push_back(at(k + 1, h));
    s.add_triangle(i + 3, i + 4, i + 5);  // top
  }
  return s;
}

/// The six faces of the box [0, a]^3, each an n x n grid of quads, as
/// separate patches (edges defined twice along the seams).
Soup box_patches(double a, int n) {
  Soup s;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double u0 = a * i / n, u1 = a * (i + 1) / n, v0 = a * j / n, v1 = a * (j + 1) / n;
      quad(s, {u0, v0, 0}, {u0, v1, 0}, {u1, v1, 0}, {u1, v0, 0});  // -z
      quad(s, {u0, v0, a}, {u1, v0, a}, {u1, v1, a}, {u0, v1, a});  // +z
      quad(s, {0, u0, v0}, {0, u0, v1}, {0, u1, v1}, {0, u1, v0});  // -x
      quad(s, {a, u0, v0}, {a, u1, v0}, {a, u1, v1}, {a, u0, v1});  // +x
      quad(s, {u0, 0, v0}, {u1, 0, v0}, {u1, 0, v1}, {u0, 0, v1});  // -y
      quad(s, {u0, a, v0}, {u0, a, v1}, {u1, a, v1}, {u1, a, v0});  // +y
    }
  return s;
}

}  // namespace

TEST_CASE("rebuild: a box of separate patches with gaps, overlaps, T-junctions and a hole", "[rebuild]") {
  const Soup in = read_soup(test::fixture("dirty_box.obj"));
  REQUIRE_FALSE(inspect(in).certified_clean());
  const RebuildResult result = rebuild(in);
  const RebuildReport& r = result.report;
  const Soup out = written(result, "rebuild_dirty_box.off");
  check_solid(in, out, r, 1, 2);
  CHECK(r.largest_gap > 0.049);           // the shrunk +x patch leaves 0.05 gaps...
  CHECK(r.cell > r.largest_gap);          // ... and the cells are wider (§3.1.3)
  CHECK(r.interpolated > 0);              // the hole and the gaps are spanned
  // Every input point (gap rims, overlapping fins 0.05 out) within one cell.
  CHECK(r.input_to_output <= r.cell);
  // The box's volume, less what the cells chamfer off its 12 edges.
  CHECK(std::abs(volume(out) - 1000.0) < 12 * 10 * r.cell * r.cell);
  // Planar coarsening changes no point of the surface: the same volume as the
  // triangles extracted. Decimation then moves it within its tolerance
  // (a quarter cell over the box's 600 units of area).
  RebuildOptions none, planar;
  none.simplify = none.decimate = planar.decimate = false;
  none.certify = planar.certify = false;
  const RebuildResult raw = rebuild(in, none), flat = rebuild(in, planar);
  CHECK(raw.soup.face_count() > 4 * flat.soup.face_count());
  CHECK(std::abs(volume(raw.soup) - volume(flat.soup)) < 1e-9 * 1000);
  CHECK(flat.soup.face_count() > 2 * result.soup.face_count());
  CHECK(std::abs(volume(raw.soup) - volume(out)) < 0.25 * r.cell * 600);
}

TEST_CASE("rebuild: the shell round a flat sheet is coarsened without moving it", "[rebuild]") {
  // CGAL's quads_to_stitch: a 1 x 2 sheet of quads in z = 0, its two rows
  // not sharing their vertices. Its shell's broad faces lie in planes of the
  // grid, on no facet: a vertex there and its ring share their z exactly,
  // so the vertex collapses as on a facet plane (before, none did here).
  Soup in;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 2; ++j)
      quad(in, {0.25 * i, 1.0 * j, 0}, {0.25 * (i + 1), 1.0 * j, 0}, {0.25 * (i + 1), 1.0 * (j + 1), 0},
           {0.25 * i, 1.0 * (j + 1), 0});
  RebuildOptions none, planar;
  none.simplify = none.decimate = planar.decimate = false;
  none.certify = planar.certify = false;
  const RebuildResult raw = rebuild(in, none), flat = rebuild(in, planar);
  REQUIRE(raw.report.sheet_facets == 16);
  CHECK(flat.report.collapses > raw.soup.points.size() / 4);  // 43% of the vertices are on a broad face
  CHECK(flat.soup.face_count() == raw.soup.face_count() - 2 * flat.report.collapses);
  CHECK(inspect(flat.soup).certified_clean());
  // The same surface: the same volume, and the centroid and edge midpoints
  // of every face of each on the other.
  CHECK(std::abs(volume(raw.soup) - volume(flat.soup)) < 1e-12 * volume(raw.soup));
  double worst = 0;
  for (const Soup* s : {&raw.soup, &flat.soup}) {
    const detail::SurfaceDistance other(s == &raw.soup ? flat.soup : raw.soup);
    for (std::size_t t = 0; t < s->face_count(); ++t) {
      const Point3d &a = s->points[s->face(t)[0]], &b = s->points[s->face(t)[1]], &c = s->points[s->face(t)[2]];
      for (const Point3d& x : {Point3d{(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3},
                               Point3d{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2},
                               Point3d{(b[0] + c[0]) / 2, (b[1] + c[1]) / 2, (b[2] + c[2]) / 2},
                               Point3d{(c[0] + a[0]) / 2, (c[1] + a[1]) / 2, (c[2] + a[2]) / 2}})
        worst = std::max(worst, other.squared_distance(x));
    }
  }
  CHECK(std::sqrt(worst) < 1e-12);
}

namespace {

/// A fixture rebuilt without decimating (the surface the halves split),
/// then with the halves one after the other, and at once (uncertified).
std::array<RebuildResult, 3> in_halves_and_not(const char* fixture) {
  const Soup in = read_soup(test::fixture(fixture));
  RebuildOptions coarse, one_after_other, at_once;
  coarse.decimate = false;
  coarse.certify = one_after_other.certify = at_once.certify = false;
  one_after_other.halves_in_parallel = false;
  return {rebuild(in, coarse), rebuild(in, one_after_other), rebuild(in, at_once)};
}

}  // namespace

TEST_CASE("rebuild: decimating in two halves at once is decimating them one after the other", "[rebuild]") {
  // Large surfaces are coarsened and decimated in two halves at once, each a
  // mesh of its own, joined again, then the seam between them (the halves
  // restricted to their own side, on the whole surface, give the same
  // coarsening: checked by making the halves unrestricted, 4 failures):
  // the error each face carries, the facet and the
  // sharpening of each vertex must cross into the halves and back (the
  // error did not at first: 20% fewer faces, the surface farther from the
  // extracted one than the tolerance lets it). Done one after the other on
  // the whole surface, the same sweeps decide the same collapses: neither
  // half reads what the other changes, and the joined mesh is built as the
  // whole one is left (vertices and faces in their order: which of an
  // edge's two vertex ids survives a collapse follows the mesh's halfedges,
  // and the sweeps take the vertices in order).
  const auto [before, serial, parallel] = in_halves_and_not("corpus/cgal__non_manifold_face_graph.off");
  REQUIRE(before.soup.points.size() > 2 * 4096);  // swept in halves (from 4096 vertices) at every tolerance
  REQUIRE(before.report.collapses > 4096);          // coarsened in halves (from 4096 vertices that may collapse)
  REQUIRE(serial.soup.face_count() < before.soup.face_count() / 4);
  // The same surface, point for point and face for face, in the same groups.
  CHECK(parallel.soup.points == serial.soup.points);
  CHECK(parallel.soup.indices == serial.soup.indices);
  CHECK(parallel.soup.face_group == serial.soup.face_group);
  CHECK(parallel.report.decimated == serial.report.decimated);
  CHECK(inspect(parallel.soup).certified_clean());
}

TEST_CASE("rebuild: sharpening in two halves at once is sharpening them one after the other", "[rebuild]") {
  // Sharpening moves vertices onto the input's edges and corners, each
  // decided against the faces near its new star: large surfaces do it in
  // two halves at once, each vertex only where all it reads and moves keeps
  // clear of the other half, with an index of its own; the seam after.
  // One after the other on the whole surface, with one index, the same
  // vertices must move to the same places (so neither half read what the
  // other moved). not_convex: 96 facets meeting at sharp edges, some 9000
  // vertices after the planar coarsening, 2000 sharpened.
  const auto [before, serial, parallel] = in_halves_and_not("corpus/trimesh__not_convex.obj");
  REQUIRE(before.soup.points.size() > 2 * 4096);  // sharpened in halves (from 4096 vertices)
  REQUIRE(serial.report.sharpened > 1000);
  CHECK(parallel.report.sharpened == serial.report.sharpened);
  CHECK(parallel.soup.points == serial.soup.points);
  CHECK(parallel.soup.indices == serial.soup.indices);
  CHECK(inspect(parallel.soup).certified_clean());
}

TEST_CASE("rebuild: a cylinder with a missing strip from cap to cap", "[rebuild]") {
  const Soup in = cylinder(48, 6, 2.0, 5.0, {10, 11});  // a strip 30 degrees wide
  const Report rin = inspect(in);
  REQUIRE(rin.boundary_edges.size() > 0);
  const RebuildResult result = rebuild(in);
  const Soup out = written(result, "rebuild_cylinder_strip.off");
  check_solid(in, out, result.report, 1, 2);
  CHECK(result.report.input_to_output <= result.report.cell);
  // The strip is filled across (its chord is 2r sin 15 deg from the arc, at most
  // r (1 - cos 15 deg) = 0.07 inside it), not left open or bulged.
  const double full = kPi * 4.0 * 5.0;
  CHECK(volume(out) > 0.97 * full);
  CHECK(volume(out) < full);
}

TEST_CASE("rebuild: two overlapping copies of a patch", "[rebuild]") {
  // The box's top given twice: once in place, once shifted 0.04 along x and
  // 0.02 up — overlapping facets, a fin past the edge.
  Soup in = box_patches(4.0, 4);
  const Soup top = box_patches(4.0, 4);
  for (std::size_t f = 0; f < top.face_count(); ++f) {
    const FaceView v = top.face(f);
    if (top.points[v[0]][2] != 4.0 || top.points[v[1]][2] != 4.0 || top.points[v[2]][2] != 4.0) continue;
    const Index i = Index(in.points.size());
    for (Index k : v) in.points.push_back({top.points[k][0] + 0.04, top.points[k][1], 4.02});
    in.add_triangle(i, i + 1, i + 2);
  }
  REQUIRE(inspect(in).components > 1);
  const RebuildResult result = rebuild(in);
  const Soup out = written(result, "rebuild_overlap.off");
  check_solid(in, out, result.report, 1, 2);
  CHECK(result.report.input_to_output <= result.report.cell);
  CHECK(std::abs(volume(out) - 64.0) < 64.0 * 0.02);
}

TEST_CASE("rebuild: a soup whose every edge is defined twice keeps the torus's genus", "[rebuild]") {
  // The torus fixture with every face on its own three points, and one band
  // of faces given twice: duplicated edges and faces everywhere.
  const Soup torus = read_soup(test::fixture("torus.off"));
  Soup in;
  for (std::size_t f = 0; f < torus.face_count(); ++f) {
    const Index i = Index(in.points.size());
    for (Index k : torus.face(f)) in.points.push_back(torus.points[k]);
    in.add_triangle(i, i + 1, i + 2);
    if (f % 48 == 0) in.add_triangle(i, i + 1, i + 2);
  }
  REQUIRE(inspect(in).duplicate_faces.size() > 0);
  const RebuildResult result = rebuild(in);
  const Soup out = written(result, "rebuild_duplicated_edges.off");
  check_solid(in, out, result.report, 1, 0);  // genus 1
  CHECK(result.report.input_to_output <= result.report.cell);
  CHECK(result.report.output_to_input <= result.report.cell);
}

TEST_CASE("rebuild: faces given twice, either way round, change nothing (an export's repeats)", "[rebuild]") {
  // A reversed stray copy cancels its face in the winding number: the face,
  // bounding no volume then, went into the shell (2 components here, 35 on
  // cgal__pig). Resolved as the cleanup resolves them, the repeats and the
  // unwelded copies of corners leave the rebuild as it is without them.
  const Soup in = read_soup(test::fixture("corpus/cgal__elephant-with-holes.off"));
  const Soup dup = test::perturbed(in, PerturbKind::duplicates, 3);
  const std::size_t repeats = dup.face_count() - in.face_count();
  REQUIRE(repeats > 100);
  const RebuildResult plain = rebuild(in), repeated = rebuild(dup);
  CHECK(repeated.report.duplicate_faces == repeats);
  CHECK(repeated.report.sheet_facets == 0);
  REQUIRE(repeated.soup.face_count() == plain.soup.face_count());
  CHECK(repeated.soup.points == plain.soup.points);
  bool same_faces = true;
  for (std::size_t f = 0; f < plain.soup.face_count(); ++f)
    same_faces = same_faces && std::equal(plain.soup.face(f).begin(), plain.soup.face(f).end(),
                                          repeated.soup.face(f).begin());
  CHECK(same_faces);
  check_solid(dup, written(repeated, "rebuild_repeats.off"), repeated.report, 1,
              topology_of(inspect(plain.soup)).euler);
}

TEST_CASE("rebuild: a mechanical part with holes (corpus)", "[rebuild]") {
  const Soup in = read_soup(test::fixture("mech-holes-shark.off"));
  const Report rin = inspect(in);
  REQUIRE(rin.boundary_edges.size() > 0);
  const RebuildResult result = rebuild(in);
  const RebuildReport& r = result.report;
  const Soup out = written(result, "rebuild_mech.off");
  check_solid(in, out, r, 1, topology_of(inspect(out)).euler);
  CHECK(r.interpolated > 0);  // the holes are closed
  // Away from the holes the input surface is within one cell of the output;
  // across a hole the fill spans the opening (the 1/2 level of the winding
  // number), and where a hole cuts a sharp edge it does not rebuild the edge.
  const Soup w = apply_weld(in, weld_identical_points(in.points));
  std::vector<Point3d> rim;
  for (const EdgeRef& e : rin.boundary_edges) {
    rim.push_back(in.points[e.a]);
    rim.push_back(in.points[e.b]);
  }
  const detail::SurfaceDistance to_output(out);
  std::size_t checked = 0;
  double worst = 0;
  for (std::size_t f = 0; f < w.face_count(); ++f)
    for (Index v : w.face(f)) {
      const Point3d& p = in.points[v];
      bool near_hole = false;
      for (const Point3d& q : rim)
        if (std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]) < 3 * r.cell) {
          near_hole = true;
          break;
        }
      if (near_hole) continue;
      ++checked;
      worst = std::max(worst, std::sqrt(to_output.squared_distance(p)));
    }
  CHECK(checked > in.points.size() / 2);
  CHECK(worst <= r.cell);
}

namespace {

/// Each face's three corners (sorted, orientation ignored), for comparing
/// the faces of two soups by position.
std::multiset<std::array<Point3d, 3>> corner_sets(const Soup& s) {
  std::multiset<std::array<Point3d, 3>> out;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    std::array<Point3d, 3> c{s.points[s.face(f)[0]], s.points[s.face(f)[1]], s.points[s.face(f)[2]]};
    std::sort(c.begin(), c.end());
    out.insert(c);
  }
  return out;
}

}  // namespace

TEST_CASE("rebuild: inconsistently oriented patches are reoriented", "[rebuild]") {
  Soup in = box_patches(2.0, 3);
  for (std::size_t f = 0; f < in.face_count(); f += 3) std::swap(in.indices[3 * f + 1], in.indices[3 * f + 2]);
  // Welded, the patches are a closed box: the exact cleanup alone closes it,
  // every face where it was, a third of them turned.
  const RebuildResult result = rebuild(in);
  CHECK(result.report.cleaned);
  CHECK(result.report.reoriented_faces == in.face_count() / 3);
  const Soup out = written(result, "rebuild_reoriented.off");
  check_solid(in, out, result.report, 1, 2);
  CHECK(std::abs(volume(out) - 8.0) < 1e-12);
  CHECK(corner_sets(out) == corner_sets(in));
  CHECK(result.report.hausdorff == 0);
  // On the grid (--always), reoriented, the box is clean: every facet is
  // kept as it is.
  RebuildOptions always;
  always.keep_clean = false;
  const RebuildResult kept = rebuild(in, always);
  CHECK_FALSE(kept.report.cleaned);
  CHECK(kept.report.reoriented_faces > 0);
  check_solid(in, written(kept, "rebuild_reoriented_grid.off"), kept.report, 1, 2);
  CHECK(kept.report.kept_faces == in.face_count());
  CHECK(kept.soup.face_count() == in.face_count());
  // Sharpening (§5, Fig. 15), on the grid surface (clean regions rebuilt
  // too): box corners come back exactly where the three facet planes meet,
  // and the chamfers the cells cut shrink.
  auto box_corners = [](const Soup& s) {
    std::size_t n = 0;
    for (const Point3d& p : s.points)
      n += (p[0] == 0 || p[0] == 2) && (p[1] == 0 || p[1] == 2) && (p[2] == 0 || p[2] == 2);
    return n;
  };
  RebuildOptions grid = always;
  grid.keep_regions = false;
  const RebuildResult sharp = rebuild(in, grid);
  CHECK(sharp.report.sharpened > 0);
  CHECK(box_corners(sharp.soup) >= 4);
  RebuildOptions blunt = grid;
  blunt.sharpen = false;
  CHECK(box_corners(rebuild(in, blunt).soup) == 0);  // cube marching alone cuts every corner
}

TEST_CASE("rebuild: a soup the exact cleanup closes skips the grid, unless a sheet would be dropped", "[rebuild]") {
  // A box (its corners welded only by position), inside out, with a face
  // repeated, a face copied and a face that repeats an index.
  Soup in = box_patches(2.0, 2);
  for (std::size_t f = 0; f < in.face_count(); ++f) std::swap(in.indices[3 * f + 1], in.indices[3 * f + 2]);
  const std::size_t faces = in.face_count();
  for (int k : {0, 1, 2}) in.indices.push_back(in.indices[3 * 5 + k]);  // a copy of face 5
  in.offsets.push_back(in.indices.size());
  in.add_triangle(in.indices[0], in.indices[0], in.indices[1]);  // zero area, a repeated index
  SECTION("closed by the cleanup: the input's own faces, turned outward") {
    const RebuildResult result = rebuild(in);
    const RebuildReport& r = result.report;
    CHECK(r.cleaned);
    CHECK(r.zero_area_faces == 1);
    CHECK(r.duplicate_faces == 1);
    CHECK(r.reoriented_faces == 0);  // consistent as it was
    CHECK(r.inside_out_faces == faces);
    CHECK(r.boundary_cells == 0);  // no grid
    const Soup out = written(result, "rebuild_cleaned.off");
    check_solid(in, out, r, 1, 2);
    CHECK(out.face_count() == faces);
    CHECK(std::abs(volume(out) - 8.0) < 1e-12);  // outward
    Soup box_only = in;
    box_only.indices.resize(3 * faces);
    box_only.offsets.resize(faces + 1);
    CHECK(corner_sets(out) == corner_sets(box_only));
    CHECK(r.hausdorff == 0);
  }
  SECTION("a double-sided sheet beside it cancels in the cleanup: the grid wraps it instead") {
    Soup sheet;
    quad(sheet, {5, 0, 0}, {6, 0, 0}, {6, 2, 0}, {5, 2, 0});
    quad(sheet, {5, 0, 0}, {5, 2, 0}, {6, 2, 0}, {6, 0, 0});  // the same quad, facing down
    const RebuildResult result = rebuild(test::concat(in, sheet));
    const RebuildReport& r = result.report;
    CHECK_FALSE(r.cleaned);
    CHECK(r.boundary_cells > 0);
    // the copy of face 5 is left out (the sheet's opposite copies stay:
    // nothing around needs either); the box faces a region of winding
    // number -1: over 90% of the facets, so the whole soup counts as inside
    // out and turns (the sheet's two sides too, which changes nothing)
    CHECK(r.duplicate_faces == 1);
    CHECK(r.inside_out_faces == faces + 4);
    CHECK(r.sheet_facets == 4);
    CHECK(r.lost_components == 0);
    CHECK(r.certified);
    CHECK(inspect(result.soup).components == 2);  // the box and the slab
  }
}

TEST_CASE("rebuild: an inside-out soup is turned outward on the grid, its cavity kept", "[rebuild]") {
  // A 4-unit box with a hole (one quad left out) around a 1-unit cavity; as
  // a CAD export inside out would write them: the box facing in, the
  // cavity's walls facing out (into the material).
  Soup outer = box_patches(4.0, 2);
  outer.indices.resize(outer.indices.size() - 6);  // the last quad: a hole in the +y side
  outer.offsets.resize(outer.offsets.size() - 2);
  Soup cavity = box_patches(1.0, 1);
  for (Point3d& p : cavity.points)
    for (double& x : p) x += 1.5;
  const Soup upright = test::concat(outer, [&] {
    Soup c = cavity;
    for (std::size_t f = 0; f < c.face_count(); ++f) std::swap(c.indices[3 * f + 1], c.indices[3 * f + 2]);
    return c;
  }());
  Soup inside_out = upright;
  for (std::size_t f = 0; f < inside_out.face_count(); ++f)
    std::swap(inside_out.indices[3 * f + 1], inside_out.indices[3 * f + 2]);
  const RebuildResult turned = rebuild(inside_out);
  const RebuildReport& r = turned.report;
  CHECK(r.inside_out_faces == inside_out.face_count());
  CHECK(r.sheet_facets == 0);
  const Soup out = written(turned, "rebuild_inside_out.off");
  check_solid(inside_out, out, r, 2, 4);  // the box and its cavity
  CHECK(std::abs(volume(out) - 63.0) < 63.0 * 0.02);
  CHECK(r.input_to_output <= r.cell);
  // The same soup facing the right way comes out the same, nothing turned.
  const RebuildResult as_is = rebuild(upright);
  CHECK(as_is.report.inside_out_faces == 0);
  CHECK(std::abs(volume(as_is.soup) - volume(out)) < 1e-9 * 63.0);
}

TEST_CASE("rebuild: faces far from every defect keep their exact input coordinates", "[rebuild]") {
  // A torus with a hole (the faces around one vertex left out): the grid
  // spans the opening; the faces at the opening (a corner on its rim) are
  // its defect, and every face more than three cells from them (the margin
  // is two) must come out as it is, zipped to the grid surface. Its
  // facets are several cells wide, so the strips meet the grid's faces on
  // the torus's convex folds: those faces go into the hole and the strip is
  // zipped again.
  const Soup torus = read_soup(test::fixture("torus.off"));
  Soup in;
  in.points = torus.points;
  for (std::size_t f = 0; f < torus.face_count(); ++f) {
    const FaceView v = torus.face(f);
    if (v[0] != 0 && v[1] != 0 && v[2] != 0) in.add_triangle(v[0], v[1], v[2]);
  }
  REQUIRE(in.face_count() < torus.face_count());
  const RebuildResult result = rebuild(in);
  const RebuildReport& r = result.report;
  const Soup out = written(result, "rebuild_kept.off");
  check_solid(in, out, r, 1, 0);
  CHECK(r.kept_patches >= 1);
  std::set<std::array<Point3d, 3>> out_faces;
  for (std::size_t f = 0; f < out.face_count(); ++f) {
    std::array<Point3d, 3> c{out.points[out.face(f)[0]], out.points[out.face(f)[1]], out.points[out.face(f)[2]]};
    std::sort(c.begin(), c.end());
    out_faces.insert(c);
  }
  std::set<Index> on_rim;
  for (const Edge& e : analyze_topology(in).boundary_edges) on_rim.insert({e.a, e.b});
  std::vector<std::array<Point3d, 3>> rim;  // the faces at the opening
  for (std::size_t f = 0; f < in.face_count(); ++f) {
    const FaceView v = in.face(f);
    if (on_rim.count(v[0]) || on_rim.count(v[1]) || on_rim.count(v[2]))
      rim.push_back({in.points[v[0]], in.points[v[1]], in.points[v[2]]});
  }
  REQUIRE_FALSE(rim.empty());
  const detail::SurfaceDistance to_rim(rim);
  std::size_t far = 0, kept = 0;
  for (std::size_t f = 0; f < in.face_count(); ++f) {
    std::array<Point3d, 3> c{in.points[in.face(f)[0]], in.points[in.face(f)[1]], in.points[in.face(f)[2]]};
    bool away = true;
    for (const Point3d& p : c) away = away && to_rim.squared_distance(p) > std::pow(3 * r.cell, 2);
    if (!away) continue;
    ++far;
    std::sort(c.begin(), c.end());
    kept += out_faces.count(c);
  }
  CHECK(far > in.face_count() / 2);
  CHECK(kept == far);
  CHECK(r.kept_faces >= far);
  CHECK(r.input_to_output <= r.cell);
}

TEST_CASE("rebuild: facets far from the defects of a dirty mesh come out exactly as they were", "[rebuild]") {
  // CGAL's pig.stl: 898 self-intersecting pairs, non-manifold edges. Its
  // clean regions are kept (zipped to the grid surface), the rest is the
  // grid's; the report's count is checked on the written file — that many
  // output faces are input faces, corner for corner — and no face of an
  // intersecting pair is among them.
  const Soup in = read_soup(test::fixture("corpus/cgal__pig.stl"));
  const Report rin = inspect(in);
  REQUIRE(rin.self_intersections.size() > 0);
  const RebuildResult result = rebuild(in);
  const RebuildReport& r = result.report;
  const Soup out = written(result, "rebuild_pig.off");
  check_solid(in, out, r, 1, 2);
  CHECK(r.kept_faces > 0);
  auto corners = [](const Soup& s, std::size_t f) {
    std::array<Point3d, 3> c{s.points[s.face(f)[0]], s.points[s.face(f)[1]], s.points[s.face(f)[2]]};
    std::sort(c.begin(), c.end());
    return c;
  };
  std::set<std::array<Point3d, 3>> intersecting, output;
  for (const FacePair& q : rin.self_intersections) {
    intersecting.insert(corners(in, q.first));
    intersecting.insert(corners(in, q.second));
  }
  for (std::size_t f = 0; f < out.face_count(); ++f) output.insert(corners(out, f));
  std::size_t same = 0, defects = 0;
  std::set<std::array<Point3d, 3>> seen;
  for (std::size_t f = 0; f < in.face_count(); ++f) {
    const auto c = corners(in, f);
    if (!output.count(c) || !seen.insert(c).second) continue;
    ++same;
    defects += intersecting.count(c);
  }
  CHECK(same >= r.kept_faces);
  CHECK(defects == 0);
  CHECK(r.input_to_output <= r.cell);
}

TEST_CASE("rebuild: without shells, a soup that encloses nothing gets no invented volume (3.2.7)", "[rebuild]") {
  Soup sheet;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) quad(sheet, {double(i), double(j), 0}, {i + 1.0, double(j), 0}, {i + 1.0, j + 1.0, 0}, {double(i), j + 1.0, 0});
  RebuildOptions drop;
  drop.sheets = false;
  const RebuildResult result = rebuild(sheet, drop);
  CHECK_FALSE(result.report.volume);
  CHECK(result.report.inside_corners == 0);
  CHECK(result.soup.points == sheet.points);  // returned as read
  CHECK(result.soup.indices == sheet.indices);
  CHECK_FALSE(result.report.certified);
}

TEST_CASE("rebuild: a clean input comes out unchanged, or rebuilt on request", "[rebuild]") {
  const Soup torus = read_soup(test::fixture("torus.off"));
  const RebuildResult same = rebuild(torus);
  CHECK(same.report.unchanged);
  CHECK(same.report.certified);
  CHECK(same.soup.points == torus.points);
  CHECK(same.soup.indices == torus.indices);
  RebuildOptions always;
  always.keep_clean = false;
  const RebuildResult rebuilt = rebuild(torus, always);
  CHECK_FALSE(rebuilt.report.unchanged);
  CHECK(rebuilt.report.certified);
  CHECK(rebuilt.report.hausdorff <= rebuilt.report.cell);
}

TEST_CASE("rebuild: a grid finer than the limit is refused", "[rebuild]") {
  RebuildOptions o;
  o.cell_ratio = 0.0005;
  o.max_cells = 1000;
  CHECK_THROWS_AS(rebuild(read_soup(test::fixture("dirty_box.obj")), o), UnsupportedInput);
  // ... also where the octree's nodes meet enough facets to be refined in
  // parallel (256): the refusal comes out of the worker threads.
  const Soup many = cylinder(64, 8, 1.0, 2.0);
  REQUIRE(many.face_count() >= 1024);
  CHECK_THROWS_AS(rebuild(many, o), UnsupportedInput);
}

TEST_CASE("rebuild: an open sheet beside a solid is wrapped in a shell, or reported lost", "[rebuild]") {
  Soup in = box_patches(2.0, 2);
  for (int i = 0; i < 2; ++i)  // a flat sheet 3 units beside the box: it encloses nothing
    quad(in, {5.0 + i, 0, 0}, {6.0 + i, 0, 0}, {6.0 + i, 2, 0}, {5.0 + i, 2, 0});
  SECTION("shell (default): a slab 0.9 cell thick on each side, nothing lost") {
    const RebuildResult result = rebuild(in);
    const RebuildReport& r = result.report;
    const Soup out = written(result, "rebuild_sheet_shell.off");
    check_solid(in, out, r, 2, 4);  // the box and the slab
    CHECK(r.sheet_facets == 4);
    CHECK(r.shell == RebuildOptions().sheet_shell * r.cell);
    CHECK(r.lost_faces == 0);
    // box 8 + slab 2 x 2 x (2 shell); the slab's rim is rounded off within a shell
    const double slab = volume(out) - 8.0;
    CHECK(slab > 0.7 * 4.0 * 2 * r.shell);
    CHECK(slab < 1.1 * (2 + 2 * r.shell) * (2 + 2 * r.shell) * 2 * r.shell);
    CHECK(r.input_to_output <= 1.1 * r.cell);
  }
  SECTION("drop: the sheet is reported lost and the result is not certified") {
    RebuildOptions drop;
    drop.sheets = false;
    const RebuildResult result = rebuild(in, drop);
    const RebuildReport& r = result.report;
    CHECK(r.volume);
    CHECK(r.lost_components == 1);
    CHECK(r.lost_faces == 4);
    CHECK(r.lost_area_fraction > 0.05);
    CHECK_FALSE(r.certified);
    CHECK(inspect(result.soup).certified_clean());  // the box itself is fine
    // ... and where: the sheet's faces and box, and its open loop
    REQUIRE(r.lost_regions.size() == 1);
    CHECK(r.lost_regions[0].count == 4);
    CHECK(r.lost_regions[0].lo == Point3d{5, 0, 0});
    CHECK(r.lost_regions[0].hi == Point3d{7, 2, 0});
    REQUIRE(r.open_loops.size() == 1);
    CHECK(r.open_loops[0].count == 6);  // the 2 x 1 strip of quads: 2 + 1 + 2 + 1 unit edges
    CHECK(r.open_loops[0].lo == Point3d{5, 0, 0});
    CHECK(r.open_loops[0].hi == Point3d{7, 2, 0});
  }
}

TEST_CASE("rebuild: a component inside another is absorbed, not lost", "[rebuild]") {
  Soup in = box_patches(4.0, 2);
  Soup inner = box_patches(1.0, 1);
  for (Point3d& p : inner.points)
    for (double& x : p) x += 1.5;
  in = test::concat(in, inner);
  RebuildOptions always;  // the nested boxes are a clean input as they stand
  always.keep_clean = false;
  const RebuildResult result = rebuild(in, always);
  CHECK(result.report.absorbed_faces == inner.face_count());
  CHECK(result.report.lost_components == 0);
  CHECK(result.report.certified);
  CHECK(inspect(result.soup).components == 1);
}

TEST_CASE("rebuild: output faces keep the input's groups (CAD faces)", "[rebuild]") {
  // The box's six sides as six named groups, edges defined twice at the seams.
  Soup in = box_patches(3.0, 2);
  in.group_names = {"bottom", "top", "left", "right", "front", "back"};
  in.face_group.resize(in.face_count());
  for (std::size_t f = 0; f < in.face_count(); ++f) in.face_group[f] = std::int32_t((f / 2) % 6);
  RebuildOptions always;  // the patches weld into a clean box: rebuild it anyway
  always.keep_clean = false;
  const RebuildResult result = rebuild(in, always);
  CHECK_FALSE(result.report.unchanged);
  CHECK(result.report.certified);
  CHECK(result.report.face_groups == 6);
  REQUIRE(result.soup.face_group.size() == result.soup.face_count());
  // Faces well inside a side carry that side's group.
  std::size_t checked = 0;
  for (std::size_t f = 0; f < result.soup.face_count(); ++f) {
    Point3d c{0, 0, 0};
    for (Index v : result.soup.face(f))
      for (int a = 0; a < 3; ++a) c[a] += result.soup.points[v][a] / 3;
    if (c[2] > 2.99 && c[0] > 0.5 && c[0] < 2.5 && c[1] > 0.5 && c[1] < 2.5) {
      CHECK(result.soup.face_group[f] == 1);
      ++checked;
    }
  }
  CHECK(checked > 0);
}

TEST_CASE("rebuild: a plate thinner than a cell is wrapped, not lost", "[rebuild]") {
  Soup in = box_patches(4.0, 2);
  for (Point3d& p : in.points) p[2] *= 0.00125;  // 4 x 4 x 0.005; the default cell is 0.057
  // Take one face out so that the plate is not already clean.
  Soup holed;
  holed.points = in.points;
  for (std::size_t f = 1; f < in.face_count(); ++f) holed.add_face(in.face(f).begin(), in.face(f).end());
  const RebuildResult result = rebuild(holed);
  const RebuildReport& r = result.report;
  REQUIRE(r.cell > 10 * 0.005);
  const Soup out = written(result, "rebuild_thin_plate.off");
  check_solid(holed, out, r, 1, 2);
  CHECK(r.thin_facets > 0);
  CHECK(r.lost_faces == 0);
  CHECK(r.input_to_output <= 1.1 * r.cell);
  // The shell holds the plate within a cell: no finer cells are made for it
  // (refined to an eighth of a cell over its whole area, this plate made 2.8
  // million tetrahedra where the uniform grid has 31 thousand).
  CHECK(r.refined_tets == 0);
  // Without shells the plate falls between the corners and is reported lost.
  RebuildOptions drop;
  drop.sheets = false;
  CHECK_FALSE(rebuild(holed, drop).report.certified);
}

TEST_CASE("rebuild: a spike thinner than a cell is followed by refinement to its tip (5)", "[rebuild]") {
  // A box of separate patches (dirty at its seams) with a closed square
  // pyramid standing in its top face: base 0.02 (one cell) at z = 0.99,
  // apex at z = 1.5. The uniform grid sees none of the spike (it is thinner
  // than a cell all along); refined tetrahedra follow it down to the finest
  // level (a quarter of a cell by default), and a shell one finest step
  // thick takes it to the tip.
  Soup in = box_patches(1.0, 2);
  const Index b = Index(in.points.size());
  for (const Point3d& p : {Point3d{0.49, 0.49, 0.99}, Point3d{0.51, 0.49, 0.99}, Point3d{0.51, 0.51, 0.99},
                           Point3d{0.49, 0.51, 0.99}, Point3d{0.5, 0.5, 1.5}})
    in.points.push_back(p);
  for (int k = 0; k < 4; ++k) in.add_triangle(b + Index(k), b + Index((k + 1) % 4), b + 4);  // sides, facing out
  in.add_triangle(b, b + 2, b + 1);  // base, facing down
  in.add_triangle(b, b + 3, b + 2);
  RebuildOptions uniform;
  uniform.refine = 0;
  uniform.wrap_outlying = false;  // which would wrap what the grid misses in a cell-thick shell
  const RebuildResult coarse = rebuild(in, uniform);
  REQUIRE(coarse.report.certified);
  CHECK(coarse.report.input_to_output > 10 * coarse.report.cell);  // the spike is lost: the case is at stake
  const RebuildResult result = rebuild(in);
  const RebuildReport& r = result.report;
  CHECK(r.cell == coarse.report.cell);
  const Soup out = written(result, "rebuild_spike.off");
  check_solid(in, out, r, 1, 2);
  CHECK(inspect(out).sharp_folds.empty());
  CHECK(r.refined_tets > 0);
  CHECK(r.finest_level == 3 * r.halvings);
  CHECK(r.thickened_corners > 0);
  CHECK(r.input_to_output <= r.cell);
  CHECK(r.output_to_input <= r.cell);
}

TEST_CASE("rebuild: the deer's antler and ear tips are followed, and the coarsening makes no fold at a crease",
          "[rebuild]") {
  // V-HACD's deer (fixtures): the uniform grid leaves its antler and ear
  // tips three cells out. Refined to an eighth of a cell, the planar
  // coarsening of the refined surface folded once where nearly collinear
  // triangles met along an edge (the exact check found it, and the
  // coarsening was done again with the vertices there held back). It no
  // longer makes triangles that thin (TetGen's tolerance), and no longer
  // folds here: the retry stays as the guard, not needed on this input.
  const Soup in = read_soup(test::fixture("deer_bound.off"));
  RebuildOptions uniform;
  uniform.refine = 0;
  uniform.wrap_outlying = false;  // which would wrap what the grid misses in a cell-thick shell
  const RebuildResult coarse = rebuild(in, uniform);
  const double coarse_miss = measure_loss(in, coarse.soup, 2 * coarse.report.cell, true).outside_distance;
  CHECK(coarse_miss > 2 * coarse.report.cell);  // the case is at stake
  RebuildOptions fine;
  fine.refine = 3;
  const RebuildResult result = rebuild(in, fine);
  const RebuildReport& r = result.report;
  CHECK(r.coarsening_retries == 0);
  const Soup out = written(result, "rebuild_deer_refined.off");
  const Report rep = inspect(out);
  CHECK(rep.certified_clean());
  // No faces folded flat onto each other (TetGen refuses them): decimating
  // the refined tips made three before the decimation refused folds.
  CHECK(rep.sharp_folds.empty());
  RebuildReport again = r;
  certify_rebuild(in, out, again);
  CHECK(again.certified);
  // The input outside the output (its removed inner walls aside) is within a cell of it.
  CHECK(measure_loss(in, out, 2 * r.cell, true).outside_distance <= r.cell);
}

TEST_CASE("rebuild: input left more than a cell outside the surface joins the shell", "[rebuild]") {
  // CGAL's non_manifold_face_graph (corpus): two open sheets joined by one
  // upright triangle. Behind the lower sheet and part of the upper one the
  // winding number is just above 1/2, so those facets count as bounding a
  // volume, but the 1/2 level leaves them near their edges (up to 8 cells
  // of the upper sheet were outside the output before). The pieces still
  // more than 0.6 of a cell outside after refinement join the shell.
  const Soup in = read_soup(test::fixture("corpus/cgal__non_manifold_face_graph.off"));
  const RebuildResult result = rebuild(in);
  const RebuildReport& r = result.report;
  CHECK(r.sheet_facets > 0);
  CHECK(r.outlying_pieces > 0);
  RebuildOptions without;  // the case is at stake: without the wrap, the upper sheet is cells out
  without.wrap_outlying = false;
  CHECK(measure_loss(in, rebuild(in, without).soup, 2 * r.cell, true).outside_distance > 4 * r.cell);
  const Soup out = written(result, "rebuild_nonmanifold_sheets.off");
  CHECK(inspect(out).certified_clean());
  CHECK(r.lost_faces == 0);
  RebuildReport again = r;
  certify_rebuild(in, out, again);
  CHECK(again.certified);
  // Every input point outside the output is within a cell of it (points
  // inside, on the sheets at the middle of their shells, are a cell in).
  CHECK(measure_loss(in, out, 2 * r.cell, true).outside_distance <= r.cell);
}

TEST_CASE("rebuild: rounded crossings on one straight line make no slivers TetGen refuses", "[rebuild]") {
  // Grid crossings (and sharpened vertices) along one line of an input
  // facet are collinear but for their rounding to doubles, so the exact
  // oracle sees three of them as a triangle; TetGen's relative tolerance
  // sees a segment with a vertex on it, and stops. Measured before the
  // checks: CGAL's tetrahedron crossed by a triangle (its planar coarsening
  // joined such crossings) came out with 9 nearly degenerate faces and 15
  // vertices nearly on an edge; bones (its sharpening moved a third vertex
  // onto an input edge between two already on it) with 1 and 1; trimesh's
  // random soup with 2 vertices on an edge three faces away (the surface
  // reaches the crossing line of two facets from two sides, and sharpening
  // put both sides on it).
  const std::pair<const char*, const char*> cases[] = {
      {"corpus/cgal__tetra_intersected_by_triangle.off", "rebuild_slivers_tetra.off"},
      {"bones.off", "rebuild_slivers_bones.off"},
      {"corpus/trimesh__soup.stl", "rebuild_slivers_soup.off"}};
  for (const auto& [name, scratch] : cases) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    const RebuildResult result = rebuild(in);
    REQUIRE_FALSE(result.report.cleaned);  // the grid's surface is at stake
    const Soup out = written(result, scratch);
    InspectOptions io;
    io.tetgen_segments = true;
    const Report rep = inspect(out, io);
    CHECK(rep.certified_clean());
    CHECK(rep.nearly_degenerate_faces.empty());
    CHECK(rep.vertices_near_edges.empty());
    // What TetGen's tolerances asked before the simplex-pair searches (the
    // next test holds what they find on bones).
    CHECK(rep.sharp_folds.empty());
    CHECK(rep.close_vertices.empty());
    CHECK(rep.edges_near_edges.empty());
    CHECK(rep.flip_hazards.empty());
  }
}

TEST_CASE("rebuild: no grid vertex is left within TetGen's shortest edge of a kept input face", "[rebuild][tetgen]") {
  // The grid surface of a part thinner than a cell, on the far side of a
  // kept input face, has its vertices on that face's crossings: on bones and
  // on hornbug one was left 1e-17 off the kept face, the tip of a spike every
  // collapse of which moves the surface beyond the decimation's bound (check
  // --tetgen-ready: a vertex-face pair closer than TetGen's shortest edge;
  // tetgen -pQ aborts on those surfaces, -pYQ meshes them). The zip now
  // treats simplices of kept and strip faces that close to others as it
  // treats intersections (the hole widens there, else the patch shrinks).
  // Both still keep input faces, so the seam is at stake.
  for (const char* name : {"bones.off", "corpus/vhacd__hornbug.off"}) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    const RebuildResult result = rebuild(in);
    REQUIRE(result.report.kept_faces > 0);
    check_tetgen_ready(result, std::string("rebuild_seam_") + (name[0] == 'b' ? "bones" : "hornbug") + ".off");
  }
}

TEST_CASE("rebuild: a model far from the origin comes out TetGen-ready", "[rebuild][tetgen]") {
  // Soups moved by (1e6, -2e6, 3e5) (hornbug's size ~3: the doubles' spacing
  // there is ~1e-10, TetGen's shortest edge 3.3e-8). Crossings along one
  // straight line are rounded 1e-10 off it, and faults followed that the
  // check found and TetGen -pQ aborted on: the planar coarsening made slivers
  // 1.9e-10 high (1.5e-8 of their base: not nearly degenerate in TetGen's
  // relative sense, but their apex that close to the face beyond the base);
  // a collapse made an edge x-u passing 3.5e-11 from a neighbour of x
  // (hornbug) or 1e-6 from an edge between two neighbours of x (b9_mesh,
  // diagonal 160): the guards asked only the rings of v and u.
  for (const char* name : {"corpus/vhacd__hornbug.off", "corpus/cgal__b9_mesh.off"}) {
    INFO(name);
    Soup in = read_soup(test::fixture(name));
    for (Point3d& p : in.points) {
      p[0] += 1e6;
      p[1] -= 2e6;
      p[2] += 3e5;
    }
    const RebuildResult result = rebuild(in);
    check_tetgen_ready(result, std::string("rebuild_far_") + (name[7] == 'v' ? "hornbug" : "b9_mesh") + ".off");
  }
}

TEST_CASE("loss measure: on a certified surface the pseudo-normal inside test agrees with the winding number",
          "[rebuild][loss]") {
  // The union of overlapping spheres and of bones absorbs input faces and
  // leaves input lying on the output (the kept pieces of cut faces). The
  // shortcut (certified = true) must find the same faces inside and the same
  // distance from the input outside the output, within the measure's error
  // (5% of `far`), as the winding number everywhere.
  for (const char* name : {"spheres_intersecting.off", "bones.off"}) {
    const Soup in = read_soup(test::fixture(name));
    const Soup out = regularize(in).soup;
    REQUIRE(inspect(out).certified_clean());
    const Report report = inspect(in);
    const double far = 0.005 * bbox_diagonal(report);
    const Loss slow = measure_loss(in, out, far, true, false);
    const Loss fast = measure_loss(in, out, far, true, true);
    INFO(name);
    REQUIRE(slow.absorbed_faces > 0);
    CHECK(fast.absorbed_faces == slow.absorbed_faces);
    CHECK(fast.lost_faces == slow.lost_faces);
    CHECK(fast.absorbed == slow.absorbed);
    CHECK(std::abs(fast.outside_distance - slow.outside_distance) <= 0.05 * far);
  }
}

TEST_CASE("rebuild: input facets near the caller's avoid triangles go to the grid, the rest are kept exactly",
          "[rebuild]") {
  // repair --for tetgen hands the grid what TetGen's tolerances stop on
  // (RebuildOptions::avoid). Two spheres whose parallel faces lie 1e-10
  // apart are clean: without `avoid` the whole surface was one patch and
  // the zip, finding those faces too close, gave it up (no facet kept).
  // With the faces round the touching vertices to avoid, no facet within two
  // cells of them is kept (the zip may take a cell more); every other one is,
  // and the joined surface is TetGen-ready.
  std::array<Point3d, 2> touching;
  const Soup in = test::touching_spheres(true, touching);
  RebuildOptions o;
  o.keep_clean = false;  // a clean input would be returned as it is
  for (const Point3d& v : touching)
    for (std::size_t f = 0; f < in.face_count(); ++f) {
      const FaceView t = in.face(f);
      if (in.points[t[0]] == v || in.points[t[1]] == v || in.points[t[2]] == v)
        o.avoid.push_back({in.points[t[0]], in.points[t[1]], in.points[t[2]]});
    }
  const double near = std::max(test::ring_radius(in, touching[0]), test::ring_radius(in, touching[1]));
  const RebuildResult result = rebuild(in, o);
  CHECK(result.report.kept_patches >= 2);
  check_tetgen_ready(result, "rebuild_avoid.off");
  const std::set<std::array<Point3d, 3>> kept = test::faces_by_position(result.soup);
  std::size_t far = 0, lost = 0;
  for (const auto& f : test::faces_by_position(in)) {
    bool close = false;
    for (const Point3d& c : f)
      for (const Point3d& t : touching) close = close || norm(sub(c, t)) <= near + 3 * result.report.cell;
    if (close) continue;
    ++far;
    lost += kept.count(f) == 0;
  }
  CHECK(far > in.face_count() * 9 / 10);
  CHECK(lost == 0);
}
