#include "polyheal/io/write.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include <tbb/parallel_for.h>

#include "polyheal/mesh/errors.h"

namespace polyheal {

double nearest_float(double v) {
  // Through a float object in memory. GCC 12 at -O2 with -frounding-math
  // (CGAL's interval arithmetic needs it) can drop the round trip
  // double(float(v)): seen on a std::array<double, 3> passed by value to a
  // lambda that rounds each coordinate, which returned it unrounded.
  volatile float f = static_cast<float>(v);
  return f;
}

Point3d nearest_float(const Point3d& p) { return {nearest_float(p[0]), nearest_float(p[1]), nearest_float(p[2])}; }

namespace {

void put_double(std::string& out, double v) {
  char buf[32];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
  out.append(buf, ptr);
}
void put_uint(std::string& out, std::uint64_t v) {
  char buf[24];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, ptr);
}
template <class T>
void put_bin(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // little endian hosts only (x86-64, AArch64)
  out.append(b, sizeof(T));
}

void put_point(std::string& out, const Point3d& p) {
  put_double(out, p[0]);
  out += ' ';
  put_double(out, p[1]);
  out += ' ';
  put_double(out, p[2]);
}

/// Appends put(text, i) for i = 0 .. n - 1 to `out`, in that order; large
/// n in chunks formatted in parallel (a large mesh's text is mostly number
/// formatting), the same bytes.
template <class Put>
void append_each(std::string& out, std::size_t n, const Put& put) {
  constexpr std::size_t kChunk = std::size_t(1) << 14;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  if (chunks <= 1) {
    for (std::size_t i = 0; i < n; ++i) put(out, i);
    return;
  }
  std::vector<std::string> part(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) put(part[c], i);
  });
  std::size_t size = out.size();
  for (const std::string& p : part) size += p.size();
  out.reserve(size);
  for (const std::string& p : part) out += p;
}

/// One line per point: its coordinates.
void put_point_lines(std::string& out, const Soup& s) {
  append_each(out, s.points.size(), [&](std::string& text, std::size_t i) {
    put_point(text, s.points[i]);
    text += '\n';
  });
}

/// One line per face: the corner count, then the 0-based indices (OFF and
/// .smesh share it).
void put_faces(std::string& out, const Soup& s) {
  append_each(out, s.face_count(), [&](std::string& text, std::size_t f) {
    put_uint(text, s.face(f).size());
    for (Index i : s.face(f)) {
      text += ' ';
      put_uint(text, i);
    }
    text += '\n';
  });
}

std::string off(const Soup& s) {
  std::string out = "OFF\n";
  put_uint(out, s.points.size());
  out += ' ';
  put_uint(out, s.face_count());
  out += " 0\n";
  put_point_lines(out, s);
  put_faces(out, s);
  return out;
}

/// TetGen's .smesh (its own surface format, read by `tetgen -p`): part 1
/// the nodes (0-based, shortest round-trip doubles), part 2 the facets,
/// parts 3 and 4 no holes, no regions.
std::string smesh(const Soup& s) {
  std::string out = "# polyheal: surface for TetGen (tetgen -p)\n";
  put_uint(out, s.points.size());
  out += " 3 0 0\n";
  append_each(out, s.points.size(), [&](std::string& text, std::size_t i) {
    put_uint(text, i);
    text += ' ';
    put_point(text, s.points[i]);
    text += '\n';
  });
  put_uint(out, s.face_count());
  out += " 0\n";
  put_faces(out, s);
  out += "0\n0\n";
  return out;
}

std::string obj(const Soup& s) {
  std::string out = "# polyheal\n";
  append_each(out, s.points.size(), [&](std::string& text, std::size_t i) {
    text += "v ";
    put_point(text, s.points[i]);
    text += '\n';
  });
  std::int32_t group = -1;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    if (!s.face_group.empty() && s.face_group[f] != group && s.face_group[f] >= 0) {
      group = s.face_group[f];
      out += "g " + s.group_names[static_cast<std::size_t>(group)] + "\n";
    }
    out += 'f';
    for (Index i : s.face(f)) {
      out += ' ';
      put_uint(out, std::uint64_t(i) + 1);
    }
    out += '\n';
  }
  return out;
}

/// STL holds triangles only: polygons are fan-triangulated.
template <class Emit>
void for_each_fan_triangle(const Soup& s, Emit emit) {
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    FaceView v = s.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k) emit(s.points[v[0]], s.points[v[k]], s.points[v[k + 1]]);
  }
}

bool fits_float(double v) { return nearest_float(v) == v; }

std::string stl(const Soup& s, bool ascii, bool& rounded) {
  rounded = false;
  for (const Point3d& p : s.points)
    for (double c : p) rounded |= !fits_float(c);
  std::string out;
  if (ascii) {
    out = "solid polyheal\n";
    for_each_fan_triangle(s, [&](const Point3d& a, const Point3d& b, const Point3d& c) {
      out += "facet normal 0 0 0\nouter loop\n";
      for (const Point3d* p : {&a, &b, &c}) {
        out += "vertex ";
        put_point(out, nearest_float(*p));
        out += '\n';
      }
      out += "endloop\nendfacet\n";
    });
    out += "endsolid polyheal\n";
    return out;
  }
  out.assign(80, '\0');
  const char tag[] = "binary STL written by polyheal";
  std::memcpy(out.data(), tag, sizeof tag - 1);
  std::uint32_t n = 0;
  for_each_fan_triangle(s, [&](const Point3d&, const Point3d&, const Point3d&) { ++n; });
  put_bin(out, n);
  out.reserve(84 + 50ull * n);
  for_each_fan_triangle(s, [&](const Point3d& a, const Point3d& b, const Point3d& c) {
    for (int k = 0; k < 3; ++k) put_bin(out, 0.0f);  // normal: readers recompute it
    for (const Point3d* p : {&a, &b, &c})
      for (double x : *p) put_bin(out, static_cast<float>(x));
    put_bin(out, std::uint16_t(0));
  });
  return out;
}

std::string ply(const Soup& s, bool ascii) {
  std::string out = "ply\nformat ";
  out += ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
  out += "comment polyheal\nelement vertex ";
  put_uint(out, s.points.size());
  out += "\nproperty double x\nproperty double y\nproperty double z\nelement face ";
  put_uint(out, s.face_count());
  out += "\nproperty list uint int vertex_indices\nend_header\n";
  if (ascii) {
    put_point_lines(out, s);
    put_faces(out, s);
    return out;
  }
  append_each(out, s.points.size(), [&](std::string& bytes, std::size_t i) {
    for (double c : s.points[i]) put_bin(bytes, c);
  });
  append_each(out, s.face_count(), [&](std::string& bytes, std::size_t f) {
    FaceView v = s.face(f);
    put_bin(bytes, static_cast<std::uint32_t>(v.size()));
    for (Index i : v) put_bin(bytes, static_cast<std::int32_t>(i));
  });
  return out;
}

}  // namespace

std::string serialize_smesh(const Soup& soup) { return smesh(soup); }

std::string serialize_soup(const Soup& soup, Format format, bool ascii, bool* rounded) {
  bool r = false;
  std::string out;
  switch (format) {
    case Format::off: out = off(soup); break;
    case Format::obj: out = obj(soup); break;
    case Format::stl: out = stl(soup, ascii, r); break;
    case Format::ply: out = ply(soup, ascii); break;
  }
  if (rounded) *rounded = r;
  return out;
}

void refuse_to_clobber(const std::string& input, const std::string& output, bool allow) {
  std::error_code ec;
  if (!allow && std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec))
    throw OutputError(output + ": is the input file; refusing to overwrite it (pass --overwrite to allow)");
}

void check_output_path(const std::string& path, bool allow_overwrite, bool mesh) {
  if (mesh) {
    try {
      format_from_path(path);
    } catch (const InputError& e) {
      throw OutputError(e.what());
    }
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw OutputError(path + ": is a directory");
  if (!allow_overwrite && std::filesystem::exists(path, ec))
    throw OutputError(path + ": exists; refusing to overwrite it (pass --overwrite to allow)");
}

void write_file_atomically(const std::string& path, const std::string& data, bool allow_overwrite) {
  namespace fs = std::filesystem;
  check_output_path(path, allow_overwrite);
  fs::path target(path);
  fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string tmpl = (dir / ("." + target.filename().string() + ".polyheal-XXXXXX")).string();
  int fd = ::mkstemp(tmpl.data());
  if (fd < 0) throw OutputError(path + ": cannot create a temporary file in " + dir.string() + ": " + std::strerror(errno));
  const char* p = data.data();
  std::size_t left = data.size();
  while (left > 0) {
    ssize_t w = ::write(fd, p, left);
    if (w < 0) {
      if (errno == EINTR) continue;
      const std::string why = std::strerror(errno);
      ::close(fd);
      ::unlink(tmpl.c_str());
      throw OutputError(path + ": write failed: " + why);
    }
    p += w;
    left -= static_cast<std::size_t>(w);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmpl.c_str());
    throw OutputError(path + ": write failed: " + why);
  }
  ::chmod(tmpl.c_str(), 0644);
  if (std::rename(tmpl.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmpl.c_str());
    throw OutputError(path + ": cannot move the written file into place: " + why);
  }
}

WriteInfo write_soup(const Soup& soup, const std::string& path, const WriteOptions& options) {
  WriteInfo info;
  check_output_path(path, options.allow_overwrite, true);
  info.format = format_from_path(path);
  const std::string data = serialize_soup(soup, info.format, options.ascii, &info.coordinates_rounded);
  info.bytes = data.size();
  write_file_atomically(path, data, options.allow_overwrite);
  return info;
}

}  // namespace polyheal
