// polyheal — adversarial degenerate tessellations for testing other tools
// (`polyheal perturb`): the configurations CAD exports produce and
// downstream meshers trip over, made reproducibly from a clean mesh.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "polyheal/mesh/soup.h"

namespace polyheal {

enum class PerturbKind {
  near_coplanar,   // a face split in three at its centroid lifted off the plane by epsilon x edge
  near_collinear,  // an edge split at an interior point moved off the line by epsilon x edge: two caps
  duplicates,      // vertices repeated (faces given an identical copy of a corner) and faces repeated
  slivers,         // an edge split epsilon x its length from an end: needles
};

/// "near-coplanar", ...; parse_perturb_kind throws std::invalid_argument.
const char* to_string(PerturbKind kind);
PerturbKind parse_perturb_kind(const std::string& name);

struct PerturbOptions {
  PerturbKind kind = PerturbKind::near_collinear;
  std::uint64_t seed = 1;
  double fraction = 0.1;    // of the faces (or edges) to perturb, 0..1
  double epsilon = 1e-9;    // relative to the local edge length (near-* and slivers)
};

struct PerturbResult {
  Soup soup;
  std::size_t operations = 0;       // faces or edges perturbed
  std::size_t faces_in = 0, faces_out = 0;
};

/// Same input, options and seed: the same output, bit for bit. The input
/// is fanned into triangles first; coordinates of untouched vertices are
/// kept exactly.
PerturbResult perturb(const Soup& input, const PerturbOptions& options);

}  // namespace polyheal
