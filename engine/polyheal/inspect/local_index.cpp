#include "polyheal/inspect/local_index.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "polyheal/inspect/detail/triangle_pair.h"

namespace polyheal {
namespace {

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  std::size_t operator()(const CellKey& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

using Tri = detail::Tri<Kernel>;
constexpr std::int64_t kMaxCellsPerFace = 512;  // larger faces go to the "oversize" list

}  // namespace

struct LocalIndex::Impl {
  const Mesh& mesh;
  double cell = 1.0;
  std::unordered_map<CellKey, std::vector<std::uint32_t>, CellHash> cells;
  std::vector<CGAL::Bbox_3> box;        // by face index
  std::vector<char> indexed, oversize;
  std::vector<std::uint32_t> oversize_faces;
  std::size_t count = 0;

  explicit Impl(const Mesh& m) : mesh(m) {}

  CGAL::Bbox_3 bbox_of(face_descriptor f) const {
    CGAL::Bbox_3 b;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) b += mesh.point(v).bbox();
    return b;
  }
  std::int64_t lo(double v) const { return static_cast<std::int64_t>(std::floor(v / cell)); }

  template <class Visit>
  bool for_each_cell(const CGAL::Bbox_3& b, Visit visit) const {
    const std::int64_t x0 = lo(b.xmin()), x1 = lo(b.xmax()), y0 = lo(b.ymin()), y1 = lo(b.ymax()),
                       z0 = lo(b.zmin()), z1 = lo(b.zmax());
    if ((x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1) > kMaxCellsPerFace) return false;
    for (std::int64_t x = x0; x <= x1; ++x)
      for (std::int64_t y = y0; y <= y1; ++y)
        for (std::int64_t z = z0; z <= z1; ++z) visit(CellKey{x, y, z});
    return true;
  }

  void grow(std::size_t i) {
    if (i >= box.size()) {
      box.resize(i + 1);
      indexed.resize(i + 1, 0);
      oversize.resize(i + 1, 0);
    }
  }

  void erase(std::uint32_t i) {
    if (i >= indexed.size() || !indexed[i]) return;
    auto drop = [&](std::vector<std::uint32_t>& v) {
      auto it = std::find(v.begin(), v.end(), i);
      if (it != v.end()) {
        *it = v.back();
        v.pop_back();
      }
    };
    if (oversize[i]) drop(oversize_faces);
    else
      for_each_cell(box[i], [&](const CellKey& k) {
        auto it = cells.find(k);
        if (it != cells.end()) {
          drop(it->second);
          if (it->second.empty()) cells.erase(it);
        }
      });
    indexed[i] = oversize[i] = 0;
    --count;
  }

  void insert(face_descriptor f) {
    const std::uint32_t i = static_cast<std::uint32_t>(f);
    grow(i);
    erase(i);
    box[i] = bbox_of(f);
    indexed[i] = 1;
    ++count;
    const bool fits = for_each_cell(box[i], [&](const CellKey&) {});
    if (!fits) {
      oversize[i] = 1;
      oversize_faces.push_back(i);
      return;
    }
    for_each_cell(box[i], [&](const CellKey& k) { cells[k].push_back(i); });
  }

  /// The fan triangles of face f with their vertex ids.
  std::vector<Tri> triangles(face_descriptor f) const {
    std::vector<const Point*> p;
    std::vector<std::uint64_t> id;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      p.push_back(&mesh.point(v));
      id.push_back(static_cast<std::uint32_t>(v));
    }
    std::vector<Tri> t;
    for (std::size_t k = 1; k + 1 < p.size(); ++k)
      t.push_back(detail::make_tri<Kernel>(*p[0], *p[k], *p[k + 1], id[0], id[k], id[k + 1]));
    return t;
  }

  static bool any_pair_intersects(const std::vector<Tri>& a, const std::vector<Tri>& b) {
    for (const Tri& x : a)
      for (const Tri& y : b)
        if (pair_intersects(x, y)) return true;
    return false;
  }

  /// The exact test, on InputKernel when all six points are doubles (the
  /// same answer, much cheaper on the coplanar pairs CAD meshes are full of).
  static bool pair_intersects(const Tri& x, const Tri& y) {
    const bool doubles = std::all_of(x.p.begin(), x.p.end(), is_double_point) &&
                         std::all_of(y.p.begin(), y.p.end(), is_double_point);
    if (!doubles) return detail::faces_intersect<Kernel>(x, y);
    auto input = [](const Tri& t) {
      return detail::Tri<InputKernel>{{to_input_point(t.p[0]), to_input_point(t.p[1]), to_input_point(t.p[2])},
                                      t.id, t.degenerate};
    };
    return detail::faces_intersect<InputKernel>(input(x), input(y));
  }

  /// Indexed faces whose cells b overlaps, sorted and unique.
  void candidates_of(const CGAL::Bbox_3& b, std::vector<std::uint32_t>& out) const {
    out.assign(oversize_faces.begin(), oversize_faces.end());
    const bool fits = for_each_cell(b, [&](const CellKey& k) {
      auto it = cells.find(k);
      if (it != cells.end()) out.insert(out.end(), it->second.begin(), it->second.end());
    });
    if (!fits)  // a huge query box: every indexed face
      for (std::uint32_t g = 0; g < indexed.size(); ++g)
        if (indexed[g]) out.push_back(g);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  /// Calls found(f, g) for each intersecting pair; stops when it returns false.
  template <class Found>
  void query(const std::vector<face_descriptor>& faces, Found found) const {
    std::vector<std::uint32_t> asked;
    for (face_descriptor f : faces) asked.push_back(static_cast<std::uint32_t>(f));
    std::sort(asked.begin(), asked.end());
    std::vector<std::uint32_t> candidates;
    for (face_descriptor f : faces) {
      const std::uint32_t i = static_cast<std::uint32_t>(f);
      const CGAL::Bbox_3 b = bbox_of(f);
      const std::vector<Tri> tf = triangles(f);
      candidates_of(b, candidates);
      for (std::uint32_t j : candidates) {
        if (j == i) continue;
        if (j < i && std::binary_search(asked.begin(), asked.end(), j)) continue;  // reported from j's side
        if (!CGAL::do_overlap(b, box[j])) continue;
        if (any_pair_intersects(tf, triangles(face_descriptor(j))) && !found(f, face_descriptor(j))) return;
      }
    }
  }
};

LocalIndex::LocalIndex(const Mesh& mesh) : impl_(std::make_unique<Impl>(mesh)) {
  double extent = 0;
  std::size_t n = 0;
  for (face_descriptor f : mesh.faces()) {
    const CGAL::Bbox_3 b = impl_->bbox_of(f);
    extent += std::max({b.xmax() - b.xmin(), b.ymax() - b.ymin(), b.zmax() - b.zmin()});
    ++n;
  }
  if (n > 0 && extent > 0) impl_->cell = 2.0 * extent / static_cast<double>(n);
  impl_->cells.reserve(2 * n);
  for (face_descriptor f : mesh.faces()) impl_->insert(f);
}

LocalIndex::~LocalIndex() = default;

void LocalIndex::update(const std::vector<face_descriptor>& faces) {
  for (face_descriptor f : faces) impl_->insert(f);
}

void LocalIndex::remove(face_descriptor f) { impl_->erase(static_cast<std::uint32_t>(f)); }

std::vector<std::pair<face_descriptor, face_descriptor>> LocalIndex::intersections(
    const std::vector<face_descriptor>& faces) const {
  std::vector<std::pair<face_descriptor, face_descriptor>> out;
  impl_->query(faces, [&](face_descriptor f, face_descriptor g) {
    out.emplace_back(f, g);
    return true;
  });
  return out;
}

bool LocalIndex::intersects(const std::vector<face_descriptor>& faces) const {
  bool any = false;
  impl_->query(faces, [&](face_descriptor, face_descriptor) {
    any = true;
    return false;
  });
  return any;
}

bool LocalIndex::would_intersect(const std::vector<std::array<vertex_descriptor, 3>>& proposed,
                                 const std::vector<face_descriptor>& replaced) const {
  const Mesh& mesh = impl_->mesh;
  std::vector<std::uint32_t> skip;
  for (face_descriptor f : replaced) skip.push_back(static_cast<std::uint32_t>(f));
  std::sort(skip.begin(), skip.end());
  std::vector<std::vector<Tri>> tris;
  std::vector<CGAL::Bbox_3> boxes;
  for (const auto& t : proposed) {
    const Point &a = mesh.point(t[0]), &b = mesh.point(t[1]), &c = mesh.point(t[2]);
    tris.push_back({detail::make_tri<Kernel>(a, b, c, static_cast<std::uint32_t>(t[0]),
                                             static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2]))});
    boxes.push_back(a.bbox() + b.bbox() + c.bbox());
  }
  for (std::size_t i = 0; i < tris.size(); ++i)
    for (std::size_t j = i + 1; j < tris.size(); ++j)
      if (CGAL::do_overlap(boxes[i], boxes[j]) && Impl::any_pair_intersects(tris[i], tris[j])) return true;
  std::vector<std::uint32_t> candidates;
  for (std::size_t i = 0; i < tris.size(); ++i) {
    impl_->candidates_of(boxes[i], candidates);
    for (std::uint32_t g : candidates) {
      if (std::binary_search(skip.begin(), skip.end(), g) || !CGAL::do_overlap(boxes[i], impl_->box[g])) continue;
      if (Impl::any_pair_intersects(tris[i], impl_->triangles(face_descriptor(g)))) return true;
    }
  }
  return false;
}

std::size_t LocalIndex::size() const { return impl_->count; }

}  // namespace polyheal
