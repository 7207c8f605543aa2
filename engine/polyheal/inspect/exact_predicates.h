// polyheal — the oracle's shape predicates on the working mesh's exact
// (Epeck) points: same semantics as predicates.h, for constructed points.
#pragma once

#include <vector>

#include "polyheal/inspect/predicates.h"
#include "polyheal/mesh/mesh.h"

namespace polyheal {

/// Classifies triangle abc exactly (Botsch & Kobbelt §2); thresholds as cosines.
Shape classify_triangle(const Point& a, const Point& b, const Point& c, double cos_cap, double cos_needle);

/// True when the angle between direction e and the plane with normal n is
/// strictly below the angle whose sine is `sin_threshold` (e nearly parallel
/// to the plane). Exact. Precondition: e and n are not zero.
bool angle_to_plane_less(const Kernel::Vector_3& e, const Kernel::Vector_3& n, double sin_threshold);

/// Do triangles abc and def face the same way: is the dot product of their
/// normals (b - a) x (c - a) and (e - d) x (f - d) positive? Exact: intervals
/// from the points' own approximations first, lazy exact arithmetic only
/// when the sign is uncertain.
bool normals_agree(const Point& a, const Point& b, const Point& c, const Point& d, const Point& e, const Point& f);

/// Index of the corner with the largest interior angle of the polygon
/// (corners in order; exact comparison of the angles' cosines; ties to the
/// lexicographically smallest point, whatever corner the list starts at).
std::size_t largest_angle_corner(const std::vector<Point>& polygon);

/// The class of face f of a triangle mesh.
inline Shape classify_face(const Mesh& mesh, face_descriptor f, double cos_cap, double cos_needle) {
  const halfedge_descriptor h = mesh.halfedge(f);
  return classify_triangle(mesh.point(mesh.source(h)), mesh.point(mesh.target(h)),
                           mesh.point(mesh.target(mesh.next(h))), cos_cap, cos_needle);
}

}  // namespace polyheal
