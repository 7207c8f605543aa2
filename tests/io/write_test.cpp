// Writing: round-trip exact doubles, atomic replacement, never clobbering input.
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <random>

#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "support/builders.h"

using namespace polyheal;
using polyheal::test::scratch;

namespace {

/// A soup with coordinates that need all 17 significant digits.
Soup awkward_soup() {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  Soup s;
  for (int i = 0; i < 60; ++i) s.points.push_back({u(rng), u(rng) * 1e-9, u(rng) * 1e12});
  s.points.push_back({0.1, -0.0, 5e-324});
  for (Index i = 0; i + 2 < s.points.size(); i += 3) s.add_triangle(i, i + 1, i + 2);
  return s;
}

}  // namespace

TEST_CASE("write: OFF, OBJ and PLY round-trip every double bit for bit", "[io][smoke]") {
  const Soup s = awkward_soup();
  for (const char* ext : {".off", ".obj", ".ply"})
    for (bool ascii : {false, true}) {
      INFO(ext << (ascii ? " ascii" : " binary"));
      const std::string path = scratch(std::string("roundtrip") + (ascii ? "_a" : "_b") + ext);
      WriteOptions o;
      o.ascii = ascii;
      const WriteInfo info = write_soup(s, path, o);
      CHECK_FALSE(info.coordinates_rounded);
      const Soup back = read_soup(path);
      REQUIRE(back.points.size() == s.points.size());
      for (std::size_t i = 0; i < s.points.size(); ++i)
        for (int a = 0; a < 3; ++a) REQUIRE(std::memcmp(&back.points[i][a], &s.points[i][a], 8) == 0);
      CHECK(back.indices == s.indices);
    }
}

TEST_CASE("write: a large soup round-trips through OFF exactly (parallel reader)", "[io]") {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  Soup s;
  for (int i = 0; i < 150000; ++i) s.points.push_back({u(rng), u(rng) * 1e-7, u(rng) * 1e9});
  for (Index i = 0; i + 3 < s.points.size(); i += 2) {
    const Index quad[4] = {i, i + 1, i + 3, i + 2};
    if (i % 3 == 0) s.add_face(quad, quad + 4);  // some polygons among the triangles
    else s.add_triangle(i, i + 1, i + 2);
  }
  const std::string path = scratch("large.off");
  write_soup(s, path);
  const Soup back = read_soup(path);
  CHECK(back.points == s.points);
  CHECK(back.indices == s.indices);
  CHECK(back.offsets == s.offsets);
}

TEST_CASE("write: STL says when it rounded doubles to float", "[io]") {
  const Soup s = awkward_soup();
  const std::string path = scratch("rounded.stl");
  CHECK(write_soup(s, path).coordinates_rounded);
  const Soup floats = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 0.5, 0}}, {{0, 1, 2}});
  const std::string exact = scratch("exact.stl");
  CHECK_FALSE(write_soup(floats, exact).coordinates_rounded);
  CHECK(read_soup(exact).points == floats.points);
}

TEST_CASE("write: nearest_float is what binary and ASCII STL hold of each coordinate", "[io]") {
  const Soup s = awkward_soup();
  // Each coordinate rounded the way the pipeline rounds a surface for STL:
  // a std::array copied into a lambda (GCC 12 at -O2 -frounding-math
  // returned such a copy unrounded when it was written double(float(c))).
  auto to_float = [](Point3d p) {
    for (double& c : p) c = nearest_float(c);
    return p;
  };
  std::vector<Point3d> rounded;
  for (const Point3d& p : s.points) rounded.push_back(to_float(p));
  REQUIRE(rounded != s.points);  // the property is at stake: some coordinate is not a float
  for (const Point3d& p : rounded)
    for (double c : p) CHECK(nearest_float(c) == c);
  for (bool ascii : {false, true}) {
    const std::string path = scratch(ascii ? "nearest_ascii.stl" : "nearest_binary.stl");
    WriteOptions o;
    o.ascii = ascii;
    o.allow_overwrite = true;
    write_soup(s, path, o);
    const Soup back = read_soup(path);
    // STL welds identical corners on reading: compare positions face by face
    REQUIRE(back.face_count() == s.face_count());
    for (std::size_t f = 0; f < s.face_count(); ++f)
      for (int k = 0; k < 3; ++k) CHECK(back.points[back.face(f)[k]] == rounded[s.face(f)[k]]);
  }
  CHECK(nearest_float(0x1.8fe67be8b21a5p-3) == 0x1.8fe67cp-3);
}

TEST_CASE("write: refuses to overwrite unless asked, and never clobbers the input", "[io][smoke]") {
  const Soup s = test::tetrahedron();
  // its own directory: tests running in parallel write next to each other
  const std::string path = scratch("write_overwrite/existing.off");
  write_soup(s, path);
  const Soup other = test::tetrahedron(5, 0, 0);
  CHECK_THROWS_AS(write_soup(other, path), OutputError);
  CHECK(read_soup(path).points == s.points);  // untouched
  WriteOptions o;
  o.allow_overwrite = true;
  write_soup(other, path, o);
  CHECK(read_soup(path).points == other.points);

  CHECK_THROWS_AS(refuse_to_clobber(path, path, false), OutputError);
  CHECK_NOTHROW(refuse_to_clobber(path, path, true));
  CHECK_NOTHROW(refuse_to_clobber(path, scratch("elsewhere.off"), false));

  // No temporary file is left behind.
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(path).parent_path()))
    CHECK(e.path().filename().string().find(".polyheal-") == std::string::npos);
}

TEST_CASE("write: a failed write leaves the target untouched", "[io]") {
  const std::string dir = scratch("no_such_dir");
  CHECK_THROWS_AS(write_soup(test::tetrahedron(), dir + "/x.off"), OutputError);
  CHECK_FALSE(std::filesystem::exists(dir + "/x.off"));
}
