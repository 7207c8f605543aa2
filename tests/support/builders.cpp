#include "support/builders.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace polyheal::test {

Soup soup(std::initializer_list<Point3d> points, std::initializer_list<std::array<Index, 3>> faces) {
  Soup s;
  s.points.assign(points.begin(), points.end());
  for (const auto& f : faces) s.add_triangle(f[0], f[1], f[2]);
  return s;
}

Soup tetrahedron(double dx, double dy, double dz) {
  return soup({{dx, dy, dz}, {dx + 1, dy, dz}, {dx, dy + 1, dz}, {dx, dy, dz + 1}},
              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

Soup concat(const Soup& a, const Soup& b) {
  Soup s = a;
  s.append(b);
  return s;
}

std::string fixture(const std::string& name) { return std::string(POLYHEAL_SOURCE_DIR) + "/fixtures/" + name; }

std::string scratch(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(POLYHEAL_BINARY_DIR) / "test-scratch";
  std::filesystem::create_directories(dir);
  const std::filesystem::path p = dir / name;
  std::filesystem::create_directories(p.parent_path());
  std::filesystem::remove_all(p);
  return p.string();
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string run(const std::string& command) {
  std::string out;
  if (FILE* p = ::popen((command + " 2>&1").c_str(), "r")) {
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    ::pclose(p);
  }
  return out;
}

bool tetgen_meshes(const std::string& path, const std::string& name, const std::string& switches) {
  const std::string copy = scratch(name);
  std::filesystem::copy_file(path, copy, std::filesystem::copy_options::overwrite_existing);
  return run("tetgen " + switches + " '" + copy + "' >/dev/null 2>&1; echo \"exit=$?\"").find("exit=0") != std::string::npos;
}

}  // namespace polyheal::test
