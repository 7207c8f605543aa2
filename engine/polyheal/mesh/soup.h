// polyheal — the polygon soup: what every reader returns.
//
// Points are the file's doubles, bit for bit. Faces are index lists stored
// compactly (CSR): face f is indices[offsets[f] .. offsets[f+1]). No CGAL here,
// so that I/O and the CLI compile fast.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace polyheal {

using Point3d = std::array<double, 3>;
using Index = std::uint32_t;

/// The largest coordinate magnitude the readers accept. Predicates are exact
/// at any magnitude, but tolerances and distances are doubles: squared
/// lengths of a mesh within +-1e150 stay finite (beyond it a bbox diagonal
/// overflows to infinity and a tolerance built from it has no exact value).
inline constexpr double kMaxCoordinate = 1e150;

/// A read-only view of one face's vertex indices.
struct FaceView {
  const Index* first;
  const Index* last;
  const Index* begin() const { return first; }
  const Index* end() const { return last; }
  std::size_t size() const { return static_cast<std::size_t>(last - first); }
  Index operator[](std::size_t i) const { return first[i]; }
};

struct Soup {
  std::vector<Point3d> points;
  std::vector<Index> indices;             // all faces' vertex indices, concatenated
  std::vector<std::size_t> offsets{0};    // size = face count + 1
  std::vector<std::int32_t> face_group;   // empty, or one group id per face (-1: none)
  std::vector<std::string> group_names;   // group id -> name (OBJ `g`)

  std::size_t face_count() const { return offsets.size() - 1; }
  FaceView face(std::size_t f) const {
    return {indices.data() + offsets[f], indices.data() + offsets[f + 1]};
  }
  template <class It>
  void add_face(It first, It last) {
    indices.insert(indices.end(), first, last);
    offsets.push_back(indices.size());
  }
  void add_triangle(Index a, Index b, Index c) {
    indices.push_back(a);
    indices.push_back(b);
    indices.push_back(c);
    offsets.push_back(indices.size());
  }
  bool is_triangle_soup() const { return indices.size() == 3 * face_count(); }
  /// The same points and faces, corner for corner (groups aside).
  bool same_faces(const Soup& other) const {
    return points == other.points && indices == other.indices && offsets == other.offsets;
  }

  /// Appends `other`'s points and faces (its indices shifted past ours; no
  /// point shared). Face groups are dropped.
  void append(const Soup& other) {
    const Index shift = static_cast<Index>(points.size());
    points.insert(points.end(), other.points.begin(), other.points.end());
    for (Index i : other.indices) indices.push_back(i + shift);
    for (std::size_t f = 1; f < other.offsets.size(); ++f) offsets.push_back(offsets.back() + (other.offsets[f] - other.offsets[f - 1]));
    face_group.clear();
    group_names.clear();
  }
};

}  // namespace polyheal
