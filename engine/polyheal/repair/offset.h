// polyheal — offsetting a closed mesh: the raw offset of Jung, Shin & Choi's
// §1 (after Jun, "Exact Polyhedral Machining"), then their regularization
// (regularize.h).
//
// `polyheal offset IN -d D -o OUT`:
//   1. raw offset   every face moves by D along its normal. Around each vertex
//                   the fan is cut into sectors at its sharp edges (faces
//                   whose normals differ by more than the chord angle below);
//                   the faces of one sector share one offset vertex, at D
//                   along the sector's angle-weighted normal (a smooth region
//                   moves its vertices along their normal). A sharp edge gets
//                   a cylindrical strip, the arcs of radius |D| around its
//                   ends from one sector's normal to the other's; a vertex
//                   with three or more sectors gets a spherical patch filling
//                   the loop its arcs make. Arcs and patches are refined until
//                   their chords stay within the tolerance of the circle or
//                   sphere of radius |D| (chord angle 2 acos(1 - tol/|D|)).
//                   The result is closed and consistently oriented; where the
//                   offset folds (concave edges outwards, convex ones
//                   inwards, thin parts inwards) it overlaps itself.
//   2. regularize   regularize.h: the boundary of { winding number >= 1 }.
//   3. pockets      where the surface folds at a vertex (concave outwards,
//                   convex inwards) the raw offset's inverted strips and patch
//                   enclose small pockets the winding number counts. The true
//                   offset's boundary is at distance |D| from the input (the
//                   raw offset's chords at least |D| - tol): a regularized
//                   component whose median vertex is nearer than |D| - 2 tol
//                   lies inside the offset and is removed (and counted).
//
// Kernel policy: the raw offset is an approximation by definition (normals,
// arcs: square roots and sines), built in doubles; it *is* the surface the
// output lies on. Everything decided about it afterwards — intersections,
// the valid region, the certificate — is exact on those doubles.
#pragma once

#include <cstddef>
#include <vector>

#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"
#include "polyheal/repair/regularize.h"

namespace polyheal {

struct OffsetOptions {
  double distance = 0;    // > 0 outwards, < 0 inwards (model units)
  double tolerance = -1;  // chord tolerance, model units; negative: 1% of |distance|
  bool regularize = true; // false: the raw offset only
  bool certify = true;    // certify the result (callers that certify the written file say false)
  bool float_coordinates = false;  // the regularized offset rounded to floats (an STL output; RegularizeOptions)
  Observer* observer = nullptr;
};

struct OffsetReport {
  double distance = 0, tolerance = 0, chord_angle_degrees = 0;
  std::size_t faces = 0;                 // input
  std::size_t sharp_edges = 0, corner_vertices = 0;  // corners: vertices with 3+ sectors
  std::size_t face_triangles = 0, strip_triangles = 0, patch_triangles = 0;
  std::size_t raw_faces = 0, raw_vertices = 0;
  double seconds_raw = 0;
  bool regularized = false;
  std::size_t pockets_removed = 0, pocket_faces = 0;  // regularized components inside the offset (see offset.cpp)
  RegularizeReport regularize;           // when regularized
};

struct OffsetResult {
  Soup raw;    // the raw offset
  Soup soup;   // the output (the raw offset itself when not regularized)
  OffsetReport report;
  std::vector<std::size_t> source_face;  // per output face, the raw face it lies on
  std::optional<ScannedSurface> scanned;  // RegularizeResult::scanned, for certify()
};

/// Throws UnsupportedInput for an input that is not a closed, oriented
/// 2-manifold triangle mesh, or has a zero-area face.
OffsetResult offset(const Soup& input, const OffsetOptions& options);

}  // namespace polyheal
