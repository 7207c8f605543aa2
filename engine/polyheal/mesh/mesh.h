// polyheal — the one working mesh type and the kernels.
//
// Kernel policy (ARCHITECTURE.md): the working mesh is a Surface_mesh over
// Epeck, so intersection points, midpoints and offsets are exact
// constructions. Predicates on the file's own double coordinates use Epick,
// whose filtered predicates are exact on double input.
// Include this header only where CGAL is needed: it is heavy.
#pragma once

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

namespace polyheal {

using Kernel = CGAL::Epeck;        // working kernel: exact constructions
using InputKernel = CGAL::Epick;   // double input: exact filtered predicates
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

using vertex_descriptor = Mesh::Vertex_index;
using face_descriptor = Mesh::Face_index;
using halfedge_descriptor = Mesh::Halfedge_index;

/// Name of the face property holding the input face id (-1: face created by
/// polyheal). Every operation keeps it up to date (STYLE.md habit 6).
inline constexpr const char* kFaceOrigin = "f:polyheal_origin";

}  // namespace polyheal
