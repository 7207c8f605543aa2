// polyheal — how the components of a closed surface nest, and which of them
// face the wrong way (exact).
//
// A closed, oriented 2-manifold without self-intersection bounds a volume
// when every component not inside another faces outwards: a component that
// encloses negative volume inside another is a cavity (or, inside a cavity,
// an island facing the cavity's way), but one inside no other encloses
// "everything outside it", which no tool means — the file is inside out.
// Nesting is decided by CGAL's Side_of_triangle_mesh (ray parity, Epick
// predicates: exact on the double coordinates), volume signs by
// enclosed_volume_sign (exact). No CGAL in this header.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "polyheal/inspect/self_intersections.h"
#include "polyheal/mesh/soup.h"
#include "polyheal/mesh/topology.h"

namespace polyheal {

struct Nesting {
  std::size_t components = 0;
  std::vector<std::size_t> face_component;  // faces connected through shared (welded) edges
  std::vector<int> volume_sign;             // per component, exact
  /// Per component: encloses negative volume and lies inside no other.
  std::vector<char> inside_out;
  /// Per component: to be turned so that the surface bounds a volume.
  /// inside_out, and inside such a component every one that faces against
  /// its depth (islands outwards at even depth, cavities inwards at odd
  /// depth; an inside-out file's cavities faced outwards). Components
  /// inside no inside-out one are left as they are: an outward part inside
  /// a solid may be an embedded part, not a cavity gone wrong.
  std::vector<char> turned;
  std::size_t inside_out_count = 0;
  std::size_t cavity_count = 0;  // negative volume, inside another component
};

/// Precondition: `soup` is closed, 2-manifold, consistently oriented and has
/// no self-intersection (Report::certified_clean()); otherwise nesting is
/// undefined and the result meaningless. Containment is tested only where
/// it matters (a component with negative volume), after a bounding-box test.
///
/// `crossing`: components may cross one another (each still closed and
/// oriented; a surface before its union is taken). Then c lies inside d
/// when the greater part of its area does (64 faces spread over c, each
/// standing for its area at its centroid, tested against d exactly), and a
/// component with negative volume is a cavity when the greater part of its
/// area lies inside the others (their union), inside out otherwise: an
/// inverted part of an assembly that overlaps its neighbours is turned, and
/// its union with them taken, where a cavity that breaks through a wall
/// stays one (the union then opens it).
Nesting nesting(const Soup& soup, bool crossing = false);

/// nesting(welded) for a soup without two identical points, given its
/// analyze_topology() (the inspection has both).
Nesting nesting_of_welded(const Soup& welded, const Topology& topology);

/// For a closed, manifold, oriented surface whose components cross one
/// another (`pairs`: its intersecting face pairs, indices into `soup`): per
/// pair of components that cross, how far a vertex of one lies inside the
/// other from its surface (the deeper direction; up to 256 vertices in the
/// other's box sampled, exact side test, distance in doubles: a
/// measurement), and the smaller one's bounding-box diagonal. Empty when a
/// component crosses itself or nothing crosses. Parts that reach into each
/// other deeper than a limit are not separated by local moves within it.
/// `apart`: when both parts enclose positive volume (neither is a cavity's
/// wall), how far the smaller one strays from the other's surface (the
/// largest distance of up to 256 of its vertices spread over it; +infinity
/// otherwise): small, they are one part given twice, or nearly, which no
/// local move makes two.
struct Interpenetration {
  double depth = 0;
  double part = 0;
  double apart = std::numeric_limits<double>::infinity();
};
std::vector<Interpenetration> interpenetrations(const Soup& soup, const std::vector<FacePair>& pairs);

/// `soup` with every face reversed (the same first corner, the other way round).
Soup reversed(const Soup& soup);

/// `soup` with the faces of every `turned` component reversed (points and
/// face groups kept): a surface that bounds a volume with its faces outwards.
Soup turned_outward(const Soup& soup, const Nesting& n, std::size_t* faces_turned = nullptr);

}  // namespace polyheal
