// Test support: tiny soups built in code, fixture paths, scratch files.
#pragma once

#include <array>
#include <functional>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/mesh/perturb.h"
#include "polyheal/mesh/soup.h"

namespace polyheal::test {

/// A triangle soup from explicit points and faces.
Soup soup(std::initializer_list<Point3d> points, std::initializer_list<std::array<Index, 3>> faces);
/// A closed, outward-oriented tetrahedron with corners (0,0,0), (1,0,0), (0,1,0), (0,0,1), shifted.
Soup tetrahedron(double dx = 0, double dy = 0, double dz = 0);
/// A closed axis-aligned box with corners `lo` and `hi`, facing outwards
/// (or, with `inward`, facing in: a cavity's wall); 12 triangles.
Soup box(const Point3d& lo, const Point3d& hi, bool inward = false);
/// Concatenates soups (indices shifted; points not shared).
Soup concat(const Soup& a, const Soup& b);
/// `s` without the faces `drop` picks (its points all kept): holes.
Soup without_faces(const Soup& s, const std::function<bool(std::size_t)>& drop);
/// A sphere of radius r about the origin: an icosahedron subdivided
/// `levels` times, its vertices pushed onto the sphere (20 * 4^levels faces).
Soup icosphere(double r, int levels);
/// Two icospheres (1280 faces each), b over a, their closest vertices or
/// faces 1e-10 apart: closed and disjoint, so certified clean, but closer
/// than TetGen's shortest edge — an assembly whose parts touch within a
/// tolerance. `over_face`: b's bottom vertex over the inside of a face of
/// a's top vertex (both spheres are symmetric through their centres, so that
/// face and one of b's lie parallel, 1e-10 apart), else over a's top vertex.
/// `touching`: a's top vertex and b's bottom vertex.
Soup touching_spheres(bool over_face, std::array<Point3d, 2>& touching);
/// How far the corners of the faces round the vertex at `v` reach from it.
double ring_radius(const Soup& s, const Point3d& v);

/// The faces as triples of corner positions, each rotated to start at its
/// smallest corner (orientation kept): compares surfaces whatever their
/// numbering.
std::set<std::array<Point3d, 3>> faces_by_position(const Soup& s);

std::string fixture(const std::string& name);   // path under fixtures/
/// perturb() of `s` by `kind` with `seed`, the rest as `polyheal perturb`'s
/// defaults (10% of the faces, epsilon 1e-9 of the local edge).
Soup perturbed(const Soup& s, PerturbKind kind, std::uint64_t seed);
std::string scratch(const std::string& name);   // a fresh path in the build tree
void write_bytes(const std::string& path, const std::string& bytes);
/// Runs a shell command; its stdout and stderr together.
std::string run(const std::string& command);
/// Does `tetgen SWITCHES` tetrahedralise `path` (a surface mesh file)? TetGen
/// writes beside its input, so it works on a copy, scratch(`name`): a name
/// no concurrently running test uses.
bool tetgen_meshes(const std::string& path, const std::string& name, const std::string& switches = "-pYQ");

}  // namespace polyheal::test

/// Every repair test ends with this: the soup is a certified clean solid.
#define CHECK_CERTIFIED(soup_expr) CHECK(::polyheal::inspect(soup_expr).certified_clean())
