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

#include "polyheal/mesh/soup.h"

#include <cstdint>
#include <optional>

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

/// True when p's exact coordinates are doubles (its interval approximation
/// is a point): input vertices, not constructed ones. Predicates on such
/// points may run on InputKernel, whose exact fallback (Mpzf) is far cheaper
/// than the lazy kernel's rationals.
inline bool is_double_point(const Point& p) {
  const auto& a = p.approx();
  return a.x().is_point() && a.y().is_point() && a.z().is_point();
}
inline InputKernel::Point_3 to_input_point(const Point& p) {
  const auto& a = p.approx();
  return {a.x().inf(), a.y().inf(), a.z().inf()};
}

/// Name of the vertex property (char) marking vertices no repair may remove
/// (the copies of a split pinch point: removing one would tear it apart).
inline constexpr const char* kVertexPinned = "v:polyheal_pinned";
inline std::optional<Mesh::Property_map<vertex_descriptor, char>> vertex_pinned_map(const Mesh& mesh) {
  const auto [map, found] = mesh.property_map<vertex_descriptor, char>(kVertexPinned);
  if (!found) return std::nullopt;
  return map;
}

/// Name of the vertex property (std::uint32_t) giving the identity a vertex
/// has for the oracle: the copies of a split pinch point share one (they are
/// one vertex in the file); every other vertex — including those a repair
/// adds later, which get the property's default kOwnIdentity — is itself.
/// Set by mark_split_pinches (convert.h); read through vertex_identity().
inline constexpr const char* kVertexIdentity = "v:polyheal_identity";
inline constexpr std::uint32_t kOwnIdentity = 0xFFFFFFFFu;
using VertexIdentityMap = Mesh::Property_map<vertex_descriptor, std::uint32_t>;
inline std::optional<VertexIdentityMap> vertex_identity_map(const Mesh& mesh) {
  const auto [map, found] = mesh.property_map<vertex_descriptor, std::uint32_t>(kVertexIdentity);
  if (!found) return std::nullopt;
  return map;
}
/// The id under which the oracle compares v (shared vertex = same id).
inline std::uint32_t vertex_identity(const std::optional<VertexIdentityMap>& map, vertex_descriptor v) {
  const std::uint32_t i = map ? (*map)[v] : kOwnIdentity;
  return i == kOwnIdentity ? static_cast<std::uint32_t>(v) : i;
}

/// p's coordinates as doubles for measurements and choices (shape quality,
/// distances, directions): the nearest double to each exact coordinate.
/// Not CGAL::to_double, whose answer on a lazy number depends on whether its
/// exact value was computed before (the interval is tightened then): a
/// repair's choices would depend on which exact tests happened to run, and
/// a faster filter would change its output. The exact value is computed
/// once per point and kept by the lazy kernel.
Point3d approx_point3d(const Point& p);

using FaceOriginMap = Mesh::Property_map<face_descriptor, std::int64_t>;

/// Name of the face property (char) marking faces that lie in the input
/// surface: input faces and the pieces slicing cuts them into. Repairs that
/// reshape a face clear it (the tolerance bookkeeping of shape_decimation).
inline constexpr const char* kFaceOnInput = "f:polyheal_on_input";
using FaceFlagMap = Mesh::Property_map<face_descriptor, char>;

/// The on-input map of `mesh`, added (every face on the input) if missing.
inline FaceFlagMap face_on_input_map(Mesh& mesh) { return mesh.add_property_map<face_descriptor, char>(kFaceOnInput, 1).first; }

/// The face-origin map of `mesh`, if it has one. (The one place that spells
/// Surface_mesh::property_map, whose return type changed after CGAL 5.5.)
inline std::optional<FaceOriginMap> face_origin_map(const Mesh& mesh) {
  const auto [map, found] = mesh.property_map<face_descriptor, std::int64_t>(kFaceOrigin);
  if (!found) return std::nullopt;
  return map;
}

}  // namespace polyheal
