// polyheal — the oracle's shape predicates on the working mesh's exact
// (Epeck) points: same semantics as predicates.h, for constructed points.
#pragma once

#include "polyheal/inspect/predicates.h"
#include "polyheal/mesh/mesh.h"

namespace polyheal {

/// Classifies triangle abc exactly (Botsch & Kobbelt §2); thresholds as cosines.
Shape classify_triangle(const Point& a, const Point& b, const Point& c, double cos_cap, double cos_needle);

/// The class of face f of a triangle mesh.
inline Shape classify_face(const Mesh& mesh, face_descriptor f, double cos_cap, double cos_needle) {
  const halfedge_descriptor h = mesh.halfedge(f);
  return classify_triangle(mesh.point(mesh.source(h)), mesh.point(mesh.target(h)),
                           mesh.point(mesh.target(mesh.next(h))), cos_cap, cos_needle);
}

}  // namespace polyheal
