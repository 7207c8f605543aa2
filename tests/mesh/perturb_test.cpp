// polyheal perturb: each kind makes the defect it names (as the exact check
// counts it), reproducibly, and leaves the rest of the mesh as it was.
#include <catch2/catch.hpp>

#include <stdexcept>

#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "polyheal/mesh/perturb.h"
#include "support/builders.h"

using namespace polyheal;

namespace {
PerturbResult run(PerturbKind kind, std::uint64_t seed, double fraction = 0.05) {
  PerturbOptions o;
  o.kind = kind;
  o.seed = seed;
  o.fraction = fraction;
  return perturb(read_soup(test::fixture("torus.off")), o);
}
}  // namespace

TEST_CASE("perturb: the same seed gives the same mesh, another seed another", "[perturb]") {
  for (PerturbKind k : {PerturbKind::near_coplanar, PerturbKind::near_collinear, PerturbKind::duplicates,
                        PerturbKind::slivers}) {
    const PerturbResult a = run(k, 7), b = run(k, 7), c = run(k, 8);
    CHECK(a.soup.points == b.soup.points);
    CHECK(a.soup.indices == b.soup.indices);
    CHECK((a.soup.points != c.soup.points || a.soup.indices != c.soup.indices));
    CHECK(a.operations > 0);
  }
}

TEST_CASE("perturb: near-collinear makes one cap per operation, TetGen-nearly-degenerate", "[perturb]") {
  const PerturbResult r = run(PerturbKind::near_collinear, 3);
  const Report rep = inspect(r.soup);
  CHECK(rep.certified_clean());  // still a valid closed surface
  CHECK(rep.caps.size() == r.operations);
  CHECK(rep.nearly_degenerate_faces.size() == r.operations);
  CHECK(r.faces_out == r.faces_in + 2 * r.operations);
}

TEST_CASE("perturb: slivers make two needles per operation", "[perturb]") {
  const PerturbResult r = run(PerturbKind::slivers, 3);
  const Report rep = inspect(r.soup);
  CHECK(rep.certified_clean());
  CHECK(rep.needles.size() == 2 * r.operations);
  CHECK(r.faces_out == r.faces_in + 2 * r.operations);
}

TEST_CASE("perturb: near-coplanar keeps a clean surface with lifted centroids", "[perturb]") {
  const PerturbResult r = run(PerturbKind::near_coplanar, 3);
  const Report rep = inspect(r.soup);
  CHECK(rep.certified_clean());
  CHECK(r.faces_out == r.faces_in + 2 * r.operations);
  CHECK(rep.vertices == read_soup(test::fixture("torus.off")).points.size() + r.operations);
}

TEST_CASE("perturb: duplicates repeat faces and positions", "[perturb]") {
  const PerturbResult r = run(PerturbKind::duplicates, 3);
  const Report rep = inspect(r.soup);
  CHECK_FALSE(rep.duplicate_faces.empty());
  CHECK(rep.merged_identical_vertices > 0);
  CHECK(rep.duplicate_faces.size() + rep.merged_identical_vertices >= r.operations);
  CHECK_THROWS_AS(parse_perturb_kind("noise"), std::invalid_argument);
}
