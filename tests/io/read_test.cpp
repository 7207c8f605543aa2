// Reading: every supported format, and a clear error for every kind of bad input.
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>

#include "polyheal/io/read.h"
#include "support/builders.h"

using namespace polyheal;
using polyheal::test::scratch;
using polyheal::test::write_bytes;

namespace {

/// Writes `bytes` to a scratch file called `name`, reads it, and returns the
/// InputError's message (empty if it read fine).
std::string read_error(const std::string& name, const std::string& bytes) {
  const std::string path = scratch(name);
  write_bytes(path, bytes);
  try {
    read_soup(path);
  } catch (const InputError& e) {
    CHECK(e.file() == path);
    return e.what();
  }
  return {};
}

std::string binary_stl(std::uint32_t declared, std::size_t records, float first = 0.0f) {
  std::string b(80, '\0');
  b.append(reinterpret_cast<const char*>(&declared), 4);
  for (std::size_t r = 0; r < records; ++r) {
    float v[12] = {0, 0, 0, first, 0, 0, 1, 0, 0, 0, 1, 0};
    b.append(reinterpret_cast<const char*>(v), sizeof v);
    b.append(2, '\0');
  }
  return b;
}

}  // namespace

TEST_CASE("read: malformed input gives one clear error with position", "[io][smoke]") {
  struct Case {
    const char* what;
    const char* name;
    std::string bytes;
    const char* position;  // expected in the message
    std::string reason;    // expected in the message
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Case> cases = {
      {"empty file", "empty.off", "", "", "empty file"},
      {"wrong OFF header", "header.off", "PLY\n3 1 0\n", "line 1", "wrong header"},
      {"wrong PLY header", "header.ply", "off\n", "line 1", "expected 'ply'"},
      {"truncated binary STL: 10 declared, 2 present", "trunc.stl", binary_stl(10, 2), "byte 80",
       "declares 10 triangles"},
      {"binary STL shorter than its header", "short.stl", std::string(40, 'x'), "byte 40", "too short"},
      {"non-numeric coordinate", "nonnum.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "line 4",
       "non-numeric coordinate 'x'"},
      {"NaN coordinate", "nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "line 4", "non-finite"},
      {"Inf coordinate (OBJ)", "inf.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "line 2", "non-finite"},
      {"NaN in binary STL", "nan.stl", binary_stl(1, 1, nan), "byte 96", "non-finite"},
      {"index out of range", "range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6",
       "vertex index 3 out of range"},
      {"OBJ index out of range", "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4", "out of range"},
      {"OBJ index 0", "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4", "index 0"},
      {"face with two vertices", "two.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "line 6", "fewer than 3"},
      {"OBJ face with two vertices", "two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3", "fewer than 3"},
      {"absurd face count", "absurd.off", "OFF\n3 1000000000000 0\n0 0 0\n1 0 0\n0 1 0\n", "line 3",
       "declares 1000000000000 faces"},
      {"absurd PLY count", "absurd.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n"
       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
       "byte", "declares 1000000000000 'vertex' records"},
      {"truncated OFF (the declared counts fit the size)", "trunc.off",
       "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n# padding comment\n", "line 9",
       "file ends after 1 of 2 faces"},
      {"OFF counts larger than the file", "short.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n",
       "line 3", "but only 32 bytes follow"},
      {"extra data after faces", "extra.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "line 7",
       "unexpected data"},
      {"ASCII STL facet with 4 vertices", "quad.stl",
       "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
       "endloop\nendfacet\nendsolid x\n",
       "line 7", "more than 3 vertices"},
      {"truncated binary PLY", "trunc.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
       "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
           std::string(20, '\0'),
       "byte 172", "declares 3 'vertex' records but only 20 bytes follow"},
      {"binary garbage as OBJ", "garbage.obj", std::string("\x01\x02\x03 binary\n", 11), "line 1",
       "not an OBJ statement"},
      // beyond +-1e150 a bbox diagonal (and any tolerance built from it)
      // overflows; `check --tetgen-ready` and `union` died of SIGFPE there
      {"coordinate beyond 1e150 (OFF)", "huge.off",
       "OFF\n4 4 0\n0 0 0\n1e300 0 0\n0 1e300 0\n0 0 1e300\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "line 4",
       "'1e300' is beyond +-1e150"},
      {"coordinate beyond 1e150 (OBJ)", "huge.obj", "v 0 0 0\nv -2e151 0 0\nv 0 1 0\nf 1 2 3\n", "line 2",
       "beyond +-1e150"},
      {"coordinate beyond 1e150 (PLY ascii)", "huge.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1e200 0 0\n0 1 0\n3 0 1 2\n",
       "line 11", "beyond +-1e150"},
      // what the file holds is shown escaped and cut: a control byte printed
      // raw breaks the line in some terminals and tools (Python's splitlines
      // splits at \x1c-\x1e), and a token may be megabytes long
      {"control byte in a coordinate", "control.off", std::string("OFF\n3 1 0\n0 0 0\n1 0.5\x1e 0\n0 1 0\n3 0 1 2\n"),
       "line 4", "non-numeric coordinate '0.5\\x1e'"},
      {"NUL byte in a header", "nul.off", std::string("OF\0F\n3 1 0\n", 11), "line 1", "found 'OF\\x00F'"},
      {"a 100-byte token", "long.off", "OFF\n3 1 0\n0 0 0\n1 " + std::string(100, '7') + "x 0\n0 1 0\n3 0 1 2\n",
       "line 4", "'" + std::string(40, '7') + "...'"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const std::string msg = read_error(c.name, c.bytes);
    REQUIRE_FALSE(msg.empty());
    CHECK(msg.find(c.position) != std::string::npos);
    CHECK(msg.find(c.reason) != std::string::npos);
    // one line of printable text
    CHECK(std::none_of(msg.begin(), msg.end(), [](char ch) { return (ch >= 0 && ch < 0x20) || ch == 0x7f; }));
  }
}

TEST_CASE("read: a directory, a missing file and an unknown extension", "[io][smoke]") {
  const std::string dir = scratch("a_directory.off");
  std::filesystem::create_directories(dir);
  CHECK_THROWS_WITH(read_soup(dir), Catch::Contains("is a directory"));
  CHECK_THROWS_WITH(read_soup(scratch("missing.off")), Catch::Contains("no such file"));
  CHECK_THROWS_WITH(read_soup(scratch("mesh.xyz")), Catch::Contains("unknown file extension"));
}

TEST_CASE("read: coordinates are parsed to the exact double", "[io]") {
  // 0.1 is not representable; the nearest double must come out, bit for bit.
  const std::string path = scratch("exact.off");
  write_bytes(path, "OFF\n3 1 0\n0.1 -0.30000000000000004 1e-320\n1 0 0\n0 1 0\n3 0 1 2\n");
  const Soup s = read_soup(path);
  CHECK(s.points[0][0] == 0.1);
  CHECK(s.points[0][1] == -0.30000000000000004);
  CHECK(s.points[0][2] == 1e-320);  // subnormal survives
  // the largest magnitude accepted, kMaxCoordinate, itself
  const std::string edge = scratch("edge.off");
  write_bytes(edge, "OFF\n3 1 0\n1e150 0 0\n-1e150 0 0\n0 1 0\n3 0 1 2\n");
  CHECK(read_soup(edge).points[1][0] == -kMaxCoordinate);
}

TEST_CASE("read: OBJ groups, polygons, negative and slashed indices", "[io]") {
  const std::string path = scratch("groups.obj");
  write_bytes(path,
              "# comment\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
              "g top\nf 1//1 2//1 3//1 4//1\ng side\nf -4/1/1 -3/1/1 -1/1/1\ng top\nf 1 3 4\n");
  const Soup s = read_soup(path);
  REQUIRE(s.face_count() == 3);
  CHECK(s.face(0).size() == 4);
  CHECK(s.face(1)[2] == 3);
  REQUIRE(s.group_names == std::vector<std::string>{"top", "side"});
  CHECK(s.face_group == std::vector<std::int32_t>{0, 1, 0});
}

TEST_CASE("read: STL flavour by content, welding identical corners", "[io]") {
  // A binary STL whose header starts with "solid" must still read as binary.
  std::string b = binary_stl(2, 2);
  std::memcpy(b.data(), "solid but binary", 16);
  const std::string bin = scratch("solid_binary.stl");
  write_bytes(bin, b);
  const Soup s = read_soup(bin);
  CHECK(s.face_count() == 2);
  CHECK(s.points.size() == 3);  // the two identical triangles share welded corners

  const std::string ascii = scratch("ascii.stl");
  write_bytes(ascii,
              "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
              "endfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 -0\nendloop\n"
              "endfacet\nendsolid t\n");
  const Soup a = read_soup(ascii);
  CHECK(a.face_count() == 2);
  CHECK(a.points.size() == 4);  // (0,1,0) and (0,1,-0) are one point
}

TEST_CASE("read: PLY ascii and binary big endian, extra properties skipped", "[io]") {
  const std::string head =
      "ply\nformat %s 1.0\ncomment x\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nproperty int flags\n"
      "element edge 1\nproperty int v1\nproperty int v2\nend_header\n";
  auto header = [&](const char* fmt) {
    char buf[1024];
    std::snprintf(buf, sizeof buf, head.c_str(), fmt);
    return std::string(buf);
  };
  const std::string ascii = scratch("a.ply");
  write_bytes(ascii, header("ascii") + "0 0 0 255\n1 0 0 255\n0 1.5 0 0\n3 0 1 2 7\n0 1\n");
  Soup s = read_soup(ascii);
  REQUIRE(s.face_count() == 1);
  CHECK(s.points[2][1] == 1.5);

  std::string body;
  auto be32 = [&](std::uint32_t v) {
    for (int k = 3; k >= 0; --k) body.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
  };
  auto bef = [&](float f) {
    std::uint32_t v;
    std::memcpy(&v, &f, 4);
    be32(v);
  };
  for (float c : {0.f, 0.f, 0.f}) bef(c);
  body.push_back(1);
  for (float c : {1.f, 0.f, 0.f}) bef(c);
  body.push_back(1);
  for (float c : {0.f, 2.5f, 0.f}) bef(c);
  body.push_back(1);
  body.push_back(3);
  be32(0), be32(1), be32(2), be32(9);
  be32(0), be32(1);
  const std::string bin = scratch("b.ply");
  write_bytes(bin, header("binary_big_endian") + body);
  s = read_soup(bin);
  REQUIRE(s.face_count() == 1);
  CHECK(s.points[2][1] == 2.5);
  CHECK(s.face(0)[2] == 2);
}

TEST_CASE("read: large OFF is parsed in parallel chunks, the first error in file order wins", "[io]") {
  // 100k vertices and 100k faces: several chunks of each kind.
  const std::size_t n = 100000;
  auto body = [&](std::size_t bad_vertex, std::size_t bad_face) {
    std::string off = "OFF\n# a comment line\n" + std::to_string(n) + " " + std::to_string(n) + " 0\n";
    for (std::size_t i = 0; i < n; ++i) {
      if (i == n / 2) off += "\n# blank and comment lines inside the body\n";
      off += i == bad_vertex ? "1 2 oops\n" : std::to_string(i) + " 0.5 -" + std::to_string(i % 7) + "\n";
    }
    for (std::size_t f = 0; f < n; ++f)
      off += f == bad_face ? "3 0 1 " + std::to_string(n) + "\n"
                           : "3 " + std::to_string(f) + " " + std::to_string((f + 1) % n) + " " +
                                 std::to_string((f + 2) % n) + "\n";
    return off;
  };
  const std::size_t none = ~std::size_t(0);
  // Line numbers: 3 header lines, the vertex lines, 2 extra lines after vertex n/2.
  auto vertex_line = [&](std::size_t i) { return 3 + i + 1 + (i >= n / 2 ? 2 : 0); };
  auto face_line = [&](std::size_t f) { return 3 + n + 2 + f + 1; };

  const Soup ok = parse_soup(body(none, none), Format::off, "big.off");
  REQUIRE(ok.points.size() == n);
  REQUIRE(ok.face_count() == n);
  CHECK(ok.points[n - 1][0] == double(n - 1));
  CHECK(ok.points[70001][2] == -double(70001 % 7));
  CHECK(ok.face(n - 1)[2] == 1);

  auto error = [&](std::size_t v, std::size_t f) {
    try {
      parse_soup(body(v, f), Format::off, "big.off");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error(70000, none) == "big.off:line " + std::to_string(vertex_line(70000)) + ": non-numeric coordinate 'oops'");
  CHECK(error(none, 99999) ==
        "big.off:line " + std::to_string(face_line(99999)) + ": vertex index 100000 out of range [0, 100000)");
  // Errors in a vertex chunk and a later face chunk: the earlier one is reported.
  CHECK(error(90000, 10) == error(90000, none));
}

TEST_CASE("read: ASCII STL with several solids gives one group per solid", "[io]") {
  const std::string path = scratch("two_solids.stl");
  write_bytes(path,
              "solid top face\nfacet normal 0 0 1\nouter loop\nvertex 0 0 1\nvertex 1 0 1\nvertex 0 1 1\n"
              "endloop\nendfacet\nendsolid\nsolid\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\n"
              "vertex 1 0 0\nendloop\nendfacet\nfacet normal 0 0 -1\nouter loop\nvertex 1 0 0\nvertex 0 1 0\n"
              "vertex 1 1 0\nendloop\nendfacet\nendsolid\n");
  const Soup s = read_soup(path);
  REQUIRE(s.face_count() == 3);
  CHECK(s.group_names == std::vector<std::string>{"top face", "solid1"});
  CHECK(s.face_group == std::vector<std::int32_t>{0, 1, 1});
  // One solid: no groups (a plain STL).
  const std::string one = scratch("one_solid.stl");
  write_bytes(one, "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                   "endloop\nendfacet\nendsolid x\n");
  CHECK(read_soup(one).face_group.empty());
}

TEST_CASE("read: a PLY face property naming the patch gives one group per patch", "[io]") {
  const std::string path = scratch("patches.ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
              "element face 3\nproperty list uchar int vertex_indices\nproperty int patch_id\nend_header\n"
              "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1 7\n3 0 1 3 4\n3 1 2 3 7\n");
  const Soup s = read_soup(path);
  CHECK(s.group_names == std::vector<std::string>{"patch_id 7", "patch_id 4"});
  CHECK(s.face_group == std::vector<std::int32_t>{0, 1, 0});
}
