#include "polyheal/io/read.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <filesystem>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "polyheal/mesh/weld.h"

namespace polyheal {
namespace {

/// Text from the file, for an error message: in quotes, its first 40 bytes,
/// each byte that is not printable ASCII as \xNN (the message stays one
/// readable line whatever the file holds).
std::string excerpt(std::string_view text) {
  static const char* hex = "0123456789abcdef";
  std::string out = "'";
  for (unsigned char c : text.substr(0, 40)) {
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out + (text.size() > 40 ? "...'" : "'");
}

/// Why a coordinate beyond kMaxCoordinate is refused.
std::string beyond_range(std::string_view value) {
  return "coordinate " + excerpt(value) +
         " is beyond +-1e150, the range within which polyheal's distances and tolerances are finite";
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// ---------------------------------------------------------------------------
// Text scanning with line tracking.

struct Text {
  const char* p;
  const char* end;
  std::size_t line = 1;
  const std::string& name;

  [[noreturn]] void fail(const std::string& reason) const {
    throw InputError(name, "line " + std::to_string(line), reason);
  }
  bool at_end() const { return p >= end; }
  static bool blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
  void skip_blanks() {
    while (p < end && blank(*p)) ++p;
  }
  bool at_eol() {
    skip_blanks();
    return p >= end || *p == '\n' || *p == '#';
  }
  /// Skips the rest of the current line, including its newline.
  void next_line() {
    while (p < end && *p != '\n') ++p;
    if (p < end) {
      ++p;
      ++line;
    }
  }
  /// Skips blank lines and `#` comment lines; stops at the first content.
  void skip_empty_lines() {
    for (;;) {
      skip_blanks();
      if (p < end && (*p == '\n' || *p == '#')) {
        next_line();
        continue;
      }
      return;
    }
  }
  /// Next whitespace-delimited token on the current line (empty at end of line).
  std::string_view token() {
    skip_blanks();
    const char* b = p;
    while (p < end && !blank(*p) && *p != '\n') ++p;
    return {b, static_cast<std::size_t>(p - b)};
  }
  std::string_view token_required(const char* what) {
    std::string_view t = at_eol() ? std::string_view{} : token();
    if (t.empty()) fail(std::string("missing ") + what);
    return t;
  }
  double number(const char* what) { return parse_double(token_required(what), what); }
  long long integer(const char* what) { return parse_int(token_required(what), what); }

  double parse_double(std::string_view t, const char* what) const {
    std::string_view s = t;
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    double v = 0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec == std::errc::result_out_of_range) fail(std::string(what) + " " + excerpt(t) + " is out of double range");
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty())
      fail(std::string("non-numeric ") + what + " " + excerpt(t));
    if (!std::isfinite(v)) fail(std::string("non-finite ") + what + " " + excerpt(t));
    if (std::string_view(what) == "coordinate" && std::fabs(v) > kMaxCoordinate) fail(beyond_range(t));
    return v;
  }
  long long parse_int(std::string_view t, const char* what) const {
    std::string_view s = t;
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    long long v = 0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty())
      fail(std::string("non-integer ") + what + " " + excerpt(t));
    return v;
  }
};

/// Vertex ids are 32-bit (mesh/soup.h): more vertices cannot be indexed.
constexpr unsigned long long kMaxVertices = 0xFFFFFFFEull;
std::string too_many_vertices(unsigned long long n) {
  return std::to_string(n) + " vertices: more than polyheal's limit of " + std::to_string(kMaxVertices);
}

void check_index(const Text& t, long long i, std::size_t nv) {
  if (i < 0 || static_cast<unsigned long long>(i) >= nv)
    t.fail("vertex index " + std::to_string(i) + " out of range [0, " + std::to_string(nv) + ")");
}

/// Refuses declared counts that cannot fit in the bytes that are left, before
/// anything is allocated (a header claiming 10^12 faces must not allocate).
void check_declared(const Text& t, unsigned long long count, unsigned long long min_bytes_each,
                    const char* what) {
  const auto left = static_cast<unsigned long long>(t.end - t.p);
  if (count > 0 && (count > left / min_bytes_each + 1))
    t.fail("declares " + std::to_string(count) + " " + what + " but only " + std::to_string(left) +
           " bytes follow");
}

// ---------------------------------------------------------------------------
// OFF

/// A malformed record found by a parallel chunk: where and why.
struct RecordError {
  const char* where = nullptr;
  std::string reason;
};

/// Parses records [first, last) with `parse(i, text)`; on InputError keeps
/// the first one (in file order) of the range.
template <class Parse>
void parse_records(const std::vector<const char*>& lines, const Text& t, std::size_t first, std::size_t last,
                   RecordError& error, Parse parse) {
  for (std::size_t i = first; i < last; ++i) {
    Text r{lines[i], t.end, 0, t.name};
    try {
      parse(i, r);
    } catch (const InputError& e) {
      error = {lines[i], e.reason()};
      return;
    }
  }
}

/// The OFF body after the counts line: one record per content line (blank
/// and `#` lines skipped). Phase 1 finds the content lines (a memchr scan);
/// phase 2 parses vertex and face records in parallel chunks. Of several
/// malformed records the first in file order is reported, with its line, as
/// a sequential reader would.
Soup parse_off_body(Text& t, std::size_t nv, std::size_t nf) {
  const char* body = t.p;
  const std::size_t body_line = t.line;
  auto line_at = [&](const char* where) {
    return body_line + static_cast<std::size_t>(std::count(body, where, '\n'));
  };
  auto fail_at = [&](const char* where, const std::string& reason) -> InputError {
    return InputError(t.name, "line " + std::to_string(line_at(where)), reason);
  };

  std::vector<const char*> lines;  // content line starts, up to one past the declared records
  lines.reserve(nv + nf + 1);
  for (const char* p = body; p < t.end && lines.size() <= nv + nf;) {
    const char* q = p;
    while (q < t.end && Text::blank(*q)) ++q;
    if (q < t.end && *q != '\n' && *q != '#') lines.push_back(q);
    const void* nl = std::memchr(q, '\n', static_cast<std::size_t>(t.end - q));
    p = nl ? static_cast<const char*>(nl) + 1 : t.end;
  }

  Soup s;
  s.points.resize(std::min(nv, lines.size()));
  const std::size_t faces_present = lines.size() > nv ? std::min(nf, lines.size() - nv) : 0;
  constexpr std::size_t kChunk = 1 << 15;
  const std::size_t vertex_chunks = (s.points.size() + kChunk - 1) / kChunk;
  const std::size_t face_chunks = (faces_present + kChunk - 1) / kChunk;
  std::vector<RecordError> errors(vertex_chunks + face_chunks);
  std::vector<std::vector<Index>> chunk_indices(face_chunks);
  std::vector<std::vector<std::uint32_t>> chunk_sizes(face_chunks);

  auto vertex = [&](std::size_t i, Text& r) {
    s.points[i] = {r.number("coordinate"), r.number("coordinate"), r.number("coordinate")};
  };  // the rest of the line (colours, normals) is ignored
  auto run_chunk = [&](std::size_t c) {
    if (c < vertex_chunks) {
      parse_records(lines, t, c * kChunk, std::min(s.points.size(), (c + 1) * kChunk), errors[c], vertex);
      return;
    }
    const std::size_t k = c - vertex_chunks;
    std::vector<Index>& idx = chunk_indices[k];
    std::vector<std::uint32_t>& sizes = chunk_sizes[k];
    auto face = [&](std::size_t, Text& r) {
      const long long n = r.integer("face size");
      if (n < 3) r.fail("face with " + std::to_string(n) + " vertices (fewer than 3)");
      if (static_cast<unsigned long long>(n) > static_cast<unsigned long long>(r.end - r.p))
        r.fail("face declares " + std::to_string(n) + " vertices, more than the bytes left");
      for (long long j = 0; j < n; ++j) {
        const long long i = r.integer("vertex index");
        check_index(r, i, nv);
        idx.push_back(static_cast<Index>(i));
      }
      sizes.push_back(static_cast<std::uint32_t>(n));
    };  // face colours: ignored
    idx.reserve(3 * kChunk);
    parse_records(lines, t, nv + k * kChunk, nv + std::min(faces_present, (k + 1) * kChunk), errors[c], face);
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_chunks + face_chunks, 1), [&](const auto& range) {
    for (std::size_t c = range.begin(); c != range.end(); ++c) run_chunk(c);
  });
  for (const RecordError& e : errors)  // chunks are in file order
    if (e.where) throw fail_at(e.where, e.reason);

  if (lines.size() < nv)
    throw fail_at(t.end, "file ends after " + std::to_string(lines.size()) + " of " + std::to_string(nv) + " vertices");
  if (faces_present < nf)
    throw fail_at(t.end, "file ends after " + std::to_string(faces_present) + " of " + std::to_string(nf) + " faces");
  if (lines.size() > nv + nf)
    throw fail_at(lines[nv + nf], "unexpected data after the " + std::to_string(nf) + " declared faces");

  std::size_t total = 0;
  for (const auto& v : chunk_indices) total += v.size();
  s.indices.reserve(total);
  s.offsets.reserve(nf + 1);
  for (std::size_t k = 0; k < face_chunks; ++k) {
    s.indices.insert(s.indices.end(), chunk_indices[k].begin(), chunk_indices[k].end());
    for (std::uint32_t n : chunk_sizes[k]) s.offsets.push_back(s.offsets.back() + n);
  }
  return s;
}

Soup parse_off(std::string_view bytes, const std::string& name) {
  Text t{bytes.data(), bytes.data() + bytes.size(), 1, name};
  t.skip_empty_lines();
  std::string_view head = t.token();
  // Some writers glue the counts to the keyword line ("OFF 8 6 0").
  static const char* kHeaders[] = {"OFF", "COFF", "NOFF", "CNOFF", "NCOFF", "STOFF", "STCOFF", "STCNOFF"};
  bool ok = std::any_of(std::begin(kHeaders), std::end(kHeaders), [&](const char* h) { return head == h; });
  if (!ok) {
    if (head.size() >= 3 && head.substr(head.size() - 3) == "OFF")
      t.fail("unsupported OFF variant " + excerpt(head) + " (only 3D OFF is read)");
    t.fail("wrong header: expected 'OFF', found " + excerpt(head));
  }
  if (!t.at_eol()) {
    std::string_view peek = t.token();
    if (peek == "BINARY") t.fail("binary OFF is not supported");
    t.p = peek.data();  // counts on the header line
  } else {
    t.next_line();
    t.skip_empty_lines();
  }
  long long nv = t.integer("vertex count");
  long long nf = t.integer("face count");
  if (!t.at_eol()) t.integer("edge count");
  if (nv < 0 || nf < 0) t.fail("negative vertex or face count");
  if (static_cast<unsigned long long>(nv) > kMaxVertices) t.fail(too_many_vertices(nv));
  t.next_line();
  check_declared(t, static_cast<unsigned long long>(nv), 5, "vertices");
  check_declared(t, static_cast<unsigned long long>(nf), 7, "faces");
  check_declared(t, static_cast<unsigned long long>(nv) * 5 + static_cast<unsigned long long>(nf) * 7, 1,
                 "bytes of vertices and faces");

  return parse_off_body(t, static_cast<std::size_t>(nv), static_cast<std::size_t>(nf));
}

// ---------------------------------------------------------------------------
// OBJ

Soup parse_obj(std::string_view bytes, const std::string& name) {
  Text t{bytes.data(), bytes.data() + bytes.size(), 1, name};
  Soup s;
  std::int32_t group = -1;
  std::unordered_map<std::string, std::int32_t> group_ids;
  struct Pending {
    std::size_t line;
    long long index;
  };
  std::vector<Pending> forward;  // positive indices beyond the vertices seen so far
  std::vector<long long> face;
  while (!t.at_end()) {
    t.skip_empty_lines();
    if (t.at_end()) break;
    std::string_view kw = t.token();
    if (kw == "v") {
      s.points.push_back({t.number("coordinate"), t.number("coordinate"), t.number("coordinate")});
    } else if (kw == "f") {
      face.clear();
      while (!t.at_eol()) {
        std::string_view tok = t.token();
        std::string_view first = tok.substr(0, tok.find('/'));
        long long i = t.parse_int(first, "vertex index");
        if (i == 0) t.fail("vertex index 0 (OBJ indices start at 1)");
        if (i < 0) {
          i = static_cast<long long>(s.points.size()) + i;
          if (i < 0) t.fail("relative vertex index " + std::string(first) + " before the first vertex");
        } else {
          i -= 1;
          if (static_cast<std::size_t>(i) >= s.points.size()) forward.push_back({t.line, i});
        }
        face.push_back(i);
      }
      if (face.size() < 3) t.fail("face with " + std::to_string(face.size()) + " vertices (fewer than 3)");
      for (long long i : face) s.indices.push_back(static_cast<Index>(i));
      s.offsets.push_back(s.indices.size());
      s.face_group.push_back(group);
    } else if (kw == "g") {
      std::string gname;
      while (!t.at_eol()) {
        if (!gname.empty()) gname += ' ';
        gname += std::string(t.token());
      }
      if (gname.empty()) gname = "default";
      auto [it, inserted] = group_ids.emplace(gname, static_cast<std::int32_t>(s.group_names.size()));
      if (inserted) s.group_names.push_back(gname);
      group = it->second;
    } else if (kw.empty() || !std::all_of(kw.begin(), kw.end(), [](char c) {
                 return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
               })) {
      t.fail("not an OBJ statement: " + excerpt(kw));
    }
    // vt, vn, vp, o, s, l, usemtl, mtllib, ...: not geometry we read.
    t.next_line();
  }
  for (const Pending& f : forward)
    if (static_cast<std::size_t>(f.index) >= s.points.size())
      throw InputError(name, "line " + std::to_string(f.line),
                       "vertex index " + std::to_string(f.index + 1) + " out of range [1, " +
                           std::to_string(s.points.size()) + "]");
  if (s.group_names.empty()) s.face_group.clear();
  if (s.face_count() == 0) throw InputError(name, "", "no faces ('f' statements) in OBJ file");
  if (s.points.size() > kMaxVertices) throw InputError(name, "", too_many_vertices(s.points.size()));
  return s;
}

// ---------------------------------------------------------------------------
// STL

/// STL stores every triangle's corners separately: weld the corners that have
/// identical coordinates (+0.0 and -0.0 are one point) and number the points
/// in order of first appearance.
Soup weld_stl_corners(std::vector<Point3d>&& corners) {
  const Weld weld = weld_identical_points(corners);
  Soup s;
  std::vector<Index> id(corners.size());
  s.points.reserve(corners.size() - weld.merged);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (weld.representative[i] == i) {
      id[i] = static_cast<Index>(s.points.size());
      s.points.push_back(corners[i]);
    } else {
      id[i] = id[weld.representative[i]];
    }
  }
  s.indices = std::move(id);
  s.offsets.resize(corners.size() / 3 + 1);
  for (std::size_t f = 0; f < s.offsets.size(); ++f) s.offsets[f] = 3 * f;
  return s;
}

Soup parse_stl_ascii(std::string_view bytes, const std::string& name) {
  Text t{bytes.data(), bytes.data() + bytes.size(), 1, name};
  std::vector<Point3d> corners;
  auto expect = [&](std::string_view word) {
    t.skip_empty_lines();
    std::string_view got = t.token();
    if (got != word)
      t.fail("expected '" + std::string(word) + "', found " + excerpt(got));
  };
  bool any_solid = false;
  std::vector<std::string> solids;     // solid names (group names when there are several)
  std::vector<std::int32_t> solid_of;  // per facet
  for (;;) {
    t.skip_empty_lines();
    if (t.at_end()) break;
    expect("solid");
    any_solid = true;
    std::string solid_name;
    for (std::string_view w = t.token(); !w.empty(); w = t.token())
      solid_name += (solid_name.empty() ? "" : " ") + std::string(w.substr(0, 200));
    solids.push_back(solid_name.empty() ? "solid" + std::to_string(solids.size()) : solid_name);
    t.next_line();
    for (;;) {
      t.skip_empty_lines();
      if (t.at_end()) t.fail("file ends inside a solid (missing 'endsolid')");
      std::string_view kw = t.token();
      if (kw == "endsolid") {
        t.next_line();
        break;
      }
      if (kw != "facet") t.fail("expected 'facet' or 'endsolid', found " + excerpt(kw));
      t.next_line();  // normal: ignored, recomputed from the vertices when needed
      expect("outer");
      t.next_line();
      for (int k = 0; k < 3; ++k) {
        expect("vertex");
        corners.push_back({t.number("coordinate"), t.number("coordinate"), t.number("coordinate")});
        if (!t.at_eol()) t.fail("extra data after vertex coordinates");
        t.next_line();
      }
      t.skip_empty_lines();
      if (t.token() != "endloop") t.fail("facet with more than 3 vertices or missing 'endloop'");
      t.next_line();
      expect("endfacet");
      t.next_line();
      solid_of.push_back(static_cast<std::int32_t>(solids.size() - 1));
    }
  }
  if (!any_solid) t.fail("no 'solid' in ASCII STL");
  Soup s = weld_stl_corners(std::move(corners));
  if (solids.size() > 1) {  // several solids: each is a group (a CAD face or body)
    s.face_group = std::move(solid_of);
    s.group_names = std::move(solids);
  }
  return s;
}

template <class T>
T load_le(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);  // x86/ARM little endian; STL is little endian
  return v;
}

Soup parse_stl_binary(std::string_view bytes, const std::string& name) {
  const std::uint32_t n = load_le<std::uint32_t>(bytes.data() + 80);
  if (3ull * n > kMaxVertices) throw InputError(name, "byte 80", too_many_vertices(3ull * n));
  std::vector<Point3d> corners(3ull * n);
  for (std::uint32_t f = 0; f < n; ++f) {
    const char* rec = bytes.data() + 84 + 50ull * f;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) {
        const float x = load_le<float>(rec + 12 + 12 * k + 4 * a);
        if (!std::isfinite(x))
          throw InputError(name, "byte " + std::to_string(84 + 50ull * f + 12 + 12 * k + 4 * a),
                           "non-finite coordinate in triangle " + std::to_string(f));
        corners[3ull * f + k][a] = static_cast<double>(x);
      }
  }
  return weld_stl_corners(std::move(corners));
}

bool looks_ascii_stl(std::string_view bytes) {
  std::size_t i = 0;
  while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
  if (bytes.compare(i, 5, "solid") != 0) return false;
  const std::size_t probe = std::min<std::size_t>(bytes.size(), 1024);
  if (std::memchr(bytes.data(), '\0', probe)) return false;
  const std::string_view head = bytes.substr(0, probe);
  return head.find("facet") != std::string_view::npos || head.find("endsolid") != std::string_view::npos;
}

Soup parse_stl(std::string_view bytes, const std::string& name) {
  if (looks_ascii_stl(bytes)) return parse_stl_ascii(bytes, name);
  if (bytes.size() < 84)
    throw InputError(name, "byte " + std::to_string(bytes.size()),
                     "not ASCII STL and too short for binary STL (84-byte header)");
  const std::uint32_t n = load_le<std::uint32_t>(bytes.data() + 80);
  const unsigned long long want = 84ull + 50ull * n;
  if (bytes.size() != want)
    throw InputError(name, "byte 80",
                     "binary STL declares " + std::to_string(n) + " triangles (" + std::to_string(want) +
                         " bytes) but the file has " + std::to_string(bytes.size()) + " bytes");
  return parse_stl_binary(bytes, name);
}

// ---------------------------------------------------------------------------
// PLY

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

std::size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::i8: case PlyType::u8: return 1;
    case PlyType::i16: case PlyType::u16: return 2;
    case PlyType::i32: case PlyType::u32: case PlyType::f32: return 4;
    case PlyType::f64: return 8;
  }
  return 0;
}

bool ply_type(std::string_view s, PlyType& t) {
  static const std::pair<const char*, PlyType> table[] = {
      {"char", PlyType::i8},    {"int8", PlyType::i8},     {"uchar", PlyType::u8},   {"uint8", PlyType::u8},
      {"short", PlyType::i16},  {"int16", PlyType::i16},   {"ushort", PlyType::u16}, {"uint16", PlyType::u16},
      {"int", PlyType::i32},    {"int32", PlyType::i32},   {"uint", PlyType::u32},   {"uint32", PlyType::u32},
      {"float", PlyType::f32},  {"float32", PlyType::f32}, {"double", PlyType::f64}, {"float64", PlyType::f64}};
  for (auto& [n, ty] : table)
    if (s == n) {
      t = ty;
      return true;
    }
  return false;
}

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::u8;
  PlyType type = PlyType::f32;
};
struct PlyElement {
  std::string name;
  unsigned long long count = 0;
  std::vector<PlyProperty> props;
};

/// Reads binary PLY values of either endianness, tracking the byte offset.
struct PlyBinary {
  std::string_view bytes;
  std::size_t pos;
  bool big_endian;
  const std::string& name;

  [[noreturn]] void fail(const std::string& reason) const {
    throw InputError(name, "byte " + std::to_string(pos), reason);
  }
  double read(PlyType t) {
    const std::size_t n = ply_size(t);
    if (pos + n > bytes.size()) fail("file ends inside the data (truncated binary PLY)");
    unsigned char b[8];
    std::memcpy(b, bytes.data() + pos, n);
    if (big_endian) std::reverse(b, b + n);
    pos += n;
    switch (t) {
      case PlyType::i8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::u8: return b[0];
      case PlyType::i16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::u16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::i32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::u32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::f32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::f64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }
};

Soup parse_ply(std::string_view bytes, const std::string& name) {
  Text t{bytes.data(), bytes.data() + bytes.size(), 1, name};
  if (t.token() != "ply") t.fail("wrong header: expected 'ply'");
  t.next_line();
  enum { ascii, le, be } format = ascii;
  bool have_format = false;
  std::vector<PlyElement> elements;
  for (;;) {
    if (t.at_end()) t.fail("file ends inside the header (no 'end_header')");
    std::string_view kw = t.token();
    if (kw == "end_header") {
      t.next_line();
      break;
    }
    if (kw == "format") {
      std::string_view f = t.token();
      if (f == "ascii") format = ascii;
      else if (f == "binary_little_endian") format = le;
      else if (f == "binary_big_endian") format = be;
      else t.fail("unknown PLY format " + excerpt(f));
      have_format = true;
    } else if (kw == "element") {
      PlyElement e;
      e.name = std::string(t.token_required("element name"));
      long long c = t.integer("element count");
      if (c < 0) t.fail("negative element count");
      e.count = static_cast<unsigned long long>(c);
      elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (elements.empty()) t.fail("property before any element");
      PlyProperty p;
      std::string_view ty = t.token_required("property type");
      if (ty == "list") {
        p.is_list = true;
        if (!ply_type(t.token_required("list count type"), p.count_type)) t.fail("unknown list count type");
        if (ply_type(t.token_required("list item type"), p.type) == false) t.fail("unknown list item type");
      } else if (!ply_type(ty, p.type)) {
        t.fail("unknown property type " + excerpt(ty));
      }
      p.name = std::string(t.token_required("property name"));
      elements.back().props.push_back(std::move(p));
    } else if (kw != "comment" && kw != "obj_info" && !kw.empty()) {
      t.fail("unexpected header line " + excerpt(kw));
    }
    t.next_line();
  }
  if (!have_format) t.fail("PLY header has no 'format' line");

  // Locate vertex coordinates and face indices; validate counts against size.
  const PlyElement* vert = nullptr;
  const PlyElement* face = nullptr;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") vert = &e;
    if (e.name == "face") face = &e;
    unsigned long long min_record = 0;
    for (const PlyProperty& p : e.props) min_record += format == ascii ? 2 : ply_size(p.is_list ? p.count_type : p.type);
    if (min_record == 0) min_record = 1;
    if (format == ascii) check_declared(t, e.count, min_record, (excerpt(e.name) + " records").c_str());
  }
  if (!vert) throw InputError(name, "header", "PLY has no 'vertex' element");
  if (!face) throw InputError(name, "header", "PLY has no 'face' element");
  int xyz[3] = {-1, -1, -1};
  for (std::size_t k = 0; k < vert->props.size(); ++k)
    for (int a = 0; a < 3; ++a)
      if (vert->props[k].name == std::string(1, char('x' + a)) && !vert->props[k].is_list) xyz[a] = int(k);
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) throw InputError(name, "header", "PLY vertex lacks x, y or z");
  int list = -1;
  for (std::size_t k = 0; k < face->props.size(); ++k)
    if (face->props[k].is_list && (face->props[k].name == "vertex_indices" || face->props[k].name == "vertex_index"))
      list = int(k);
  if (list < 0) throw InputError(name, "header", "PLY face lacks a 'vertex_indices' list");
  // A scalar face property naming the CAD face (patch) each face belongs to.
  int group_prop = -1;
  for (std::size_t k = 0; k < face->props.size() && group_prop < 0; ++k)
    for (const char* g : {"patch_id", "patch", "face_group", "group", "part", "region", "segment", "label"})
      if (!face->props[k].is_list && face->props[k].name == g) group_prop = int(k);
  std::map<long long, std::int32_t> group_of_value;

  Soup s;
  PlyBinary bin{bytes, static_cast<std::size_t>(t.p - bytes.data()), format == be, name};
  if (format != ascii) {
    unsigned long long need = 0, left = bytes.size() - bin.pos;
    for (const PlyElement& e : elements) {
      unsigned long long rec = 0;
      for (const PlyProperty& p : e.props) rec += ply_size(p.is_list ? p.count_type : p.type);
      if (rec && e.count > left / rec) bin.fail("declares " + std::to_string(e.count) + " " + excerpt(e.name) +
                                                " records but only " + std::to_string(left) + " bytes follow");
      need += e.count * rec;
      if (need > left) bin.fail("declared elements need at least " + std::to_string(need) + " bytes but only " +
                                std::to_string(left) + " follow");
    }
    s.points.reserve(vert->count);
    s.offsets.reserve(face->count + 1);
  }
  if (vert->count > kMaxVertices) throw InputError(name, "header", too_many_vertices(vert->count));
  std::vector<double> values;
  for (const PlyElement& e : elements) {
    const bool is_vert = &e == vert, is_face = &e == face;
    for (unsigned long long r = 0; r < e.count; ++r) {
      if (format == ascii) {
        t.skip_empty_lines();
        if (t.at_end()) t.fail("file ends after " + std::to_string(r) + " of " + std::to_string(e.count) +
                               " " + excerpt(e.name) + " records");
      }
      Point3d pt{};
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& p = e.props[k];
        auto value = [&](PlyType ty, const char* what) {
          if (format == ascii) {
            std::string_view tok = t.token_required(what);
            return (ty == PlyType::f32 || ty == PlyType::f64) ? t.parse_double(tok, what)
                                                              : double(t.parse_int(tok, what));
          }
          const std::size_t at = bin.pos;
          double v = bin.read(ty);
          if (!std::isfinite(v)) { bin.pos = at; bin.fail(std::string("non-finite ") + what); }
          return v;
        };
        if (!p.is_list) {
          const std::size_t at = bin.pos;
          double v = value(p.type, "value");
          if (is_vert) for (int a = 0; a < 3; ++a) if (int(k) == xyz[a]) {
            pt[a] = v;
            if (std::fabs(v) > kMaxCoordinate) {
              char text[32];
              std::snprintf(text, sizeof text, "%.17g", v);
              const std::string why = beyond_range(text);
              if (format == ascii) t.fail(why);
              bin.pos = at;
              bin.fail(why);
            }
          }
          if (is_face && int(k) == group_prop) {
            const long long id = std::llround(v);
            const auto [it, inserted] = group_of_value.emplace(id, std::int32_t(s.group_names.size()));
            if (inserted) s.group_names.push_back(face->props[k].name + " " + std::to_string(id));
            s.face_group.push_back(it->second);
          }
          continue;
        }
        double n = value(p.count_type, "list size");
        if (n < 0) { if (format == ascii) t.fail("negative list size"); bin.fail("negative list size"); }
        values.clear();
        for (double i = 0; i < n; ++i) values.push_back(value(p.type, "list item"));
        if (is_face && int(k) == list) {
          if (values.size() < 3) {
            const std::string why = "face with " + std::to_string(values.size()) + " vertices (fewer than 3)";
            if (format == ascii) t.fail(why);
            bin.fail(why);
          }
          for (double i : values) {
            if (i < 0 || i >= double(vert->count) || i != std::floor(i)) {
              const std::string why = "vertex index " + std::to_string((long long)i) + " out of range [0, " +
                                      std::to_string(vert->count) + ")";
              if (format == ascii) t.fail(why);
              bin.fail(why);
            }
            s.indices.push_back(static_cast<Index>(i));
          }
          s.offsets.push_back(s.indices.size());
        }
      }
      if (is_vert) s.points.push_back(pt);
      if (format == ascii) {
        if (!t.at_eol()) t.fail("extra values in " + excerpt(e.name) + " record");
        t.next_line();
      }
    }
  }
  if (format == ascii) {
    t.skip_empty_lines();
    if (!t.at_end()) t.fail("unexpected data after the declared elements");
  } else if (bin.pos != bytes.size()) {
    bin.fail("unexpected " + std::to_string(bytes.size() - bin.pos) + " bytes after the declared elements");
  }
  return s;
}

}  // namespace

Format format_from_path(const std::string& path) {
  std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext == ".off") return Format::off;
  if (ext == ".obj") return Format::obj;
  if (ext == ".stl") return Format::stl;
  if (ext == ".ply") return Format::ply;
  throw InputError(path, "", "unknown file extension '" + ext + "' (expected .off, .obj, .stl or .ply)");
}

Soup parse_soup(std::string_view bytes, Format format, const std::string& name) {
  if (bytes.empty()) throw InputError(name, "", "empty file");
  switch (format) {
    case Format::off: return parse_off(bytes, name);
    case Format::obj: return parse_obj(bytes, name);
    case Format::stl: return parse_stl(bytes, name);
    case Format::ply: return parse_ply(bytes, name);
  }
  throw InputError(name, "", "unknown format");
}

Soup read_soup(const std::string& path) {
  const Format format = format_from_path(path);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, "", "is a directory, not a mesh file");
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "", "no such file");
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError(path, "", "not a regular file");
  }
  const std::size_t size = static_cast<std::size_t>(st.st_size);
  if (size == 0) {
    ::close(fd);
    throw InputError(path, "", "empty file");
  }
  // Map the file read-only: no copy, and the parsers read it in place.
  void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) throw InputError(path, "", std::string("cannot map: ") + std::strerror(errno));
  struct Unmap {
    void* p;
    std::size_t n;
    ~Unmap() { ::munmap(p, n); }
  } unmap{map, size};
  return parse_soup(std::string_view(static_cast<const char*>(map), size), format, path);
}

}  // namespace polyheal
