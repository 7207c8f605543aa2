#include "polyheal/inspect/local_index.h"

#include <boost/container/small_vector.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>

#include "polyheal/inspect/detail/triangle_pair.h"

namespace polyheal {
namespace {

using Tri = detail::Tri<Kernel>;
constexpr std::int32_t kNone = -1;

bool contains(const CGAL::Bbox_3& outer, const CGAL::Bbox_3& b) {
  for (int d = 0; d < 3; ++d)
    if (b.min(d) < outer.min(d) || b.max(d) > outer.max(d)) return false;
  return true;
}

/// Sum of a box's extents: the insertion cost (half the surface-area
/// heuristic's perimeter analogue; cheap and scale-free).
double margin(const CGAL::Bbox_3& b) { return (b.xmax() - b.xmin()) + (b.ymax() - b.ymin()) + (b.zmax() - b.zmin()); }

}  // namespace

// A dynamic bounding-volume hierarchy over face boxes (one leaf per face),
// built top-down by median splits and kept up to date by removing and
// re-inserting the leaves of changed faces (the descent picks the child whose
// box grows least). A uniform grid, the first design, broke on meshes mixing
// scales: a 100k-face fine part beside a few large faces sent every large
// face's query over the whole mesh (BENCHMARKS.md, deintersect notes).
struct LocalIndex::Impl {
  struct Node {
    CGAL::Bbox_3 box;
    std::int32_t parent = kNone, left = kNone, right = kNone;
    std::uint32_t face = 0;  // leaves only
    bool leaf() const { return left == kNone; }
  };

  const Mesh& mesh;
  std::vector<Node> nodes;
  std::vector<std::int32_t> free_nodes;
  std::int32_t root = kNone;
  std::vector<CGAL::Bbox_3> box;          // by face index
  std::vector<std::int32_t> leaf_of;      // by face index; kNone: not indexed
  std::size_t count = 0;
  std::size_t inserted = 0;  // leaves inserted since the tree was last built

  std::optional<VertexIdentityMap> identity;  // kVertexIdentity

  explicit Impl(const Mesh& m) : mesh(m), identity(vertex_identity_map(m)) {}

  /// The id the pair test compares (shared vertex = same id).
  std::uint32_t id_of(vertex_descriptor v) const { return vertex_identity(identity, v); }

  CGAL::Bbox_3 bbox_of(face_descriptor f) const {
    CGAL::Bbox_3 b;
    for (vertex_descriptor v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) b += mesh.point(v).bbox();
    return b;
  }

  std::int32_t make_node() {
    if (!free_nodes.empty()) {
      const std::int32_t n = free_nodes.back();
      free_nodes.pop_back();
      nodes[n] = Node{};
      return n;
    }
    nodes.emplace_back();
    return static_cast<std::int32_t>(nodes.size() - 1);
  }

  void grow(std::size_t i) {
    if (i >= box.size()) {
      box.resize(i + 1);
      leaf_of.resize(i + 1, kNone);
    }
  }

  /// Balanced subtree over leaves [first, last) of `order` (face ids).
  std::int32_t build(std::vector<std::uint32_t>& order, std::size_t first, std::size_t last, std::int32_t parent) {
    const std::int32_t n = make_node();
    nodes[n].parent = parent;
    if (last - first == 1) {
      nodes[n].face = order[first];
      nodes[n].box = box[order[first]];
      leaf_of[order[first]] = n;
      return n;
    }
    CGAL::Bbox_3 centres;
    for (std::size_t k = first; k < last; ++k) {
      const CGAL::Bbox_3& b = box[order[k]];
      const double c[3] = {0.5 * (b.xmin() + b.xmax()), 0.5 * (b.ymin() + b.ymax()), 0.5 * (b.zmin() + b.zmax())};
      centres += CGAL::Bbox_3(c[0], c[1], c[2], c[0], c[1], c[2]);
    }
    int axis = 0;
    for (int d = 1; d < 3; ++d)
      if (centres.max(d) - centres.min(d) > centres.max(axis) - centres.min(axis)) axis = d;
    const std::size_t mid = first + (last - first) / 2;
    std::nth_element(order.begin() + first, order.begin() + mid, order.begin() + last,
                     [&](std::uint32_t x, std::uint32_t y) {
                       return box[x].min(axis) + box[x].max(axis) < box[y].min(axis) + box[y].max(axis);
                     });
    const std::int32_t l = build(order, first, mid, n), r = build(order, mid, last, n);
    nodes[n].left = l;
    nodes[n].right = r;
    nodes[n].box = nodes[l].box + nodes[r].box;
    return n;
  }

  /// The balanced tree again over every indexed face: greedy insertions
  /// never rebalance, and after many edits in one region the descent and
  /// the queries get deep.
  void rebuild() {
    std::vector<std::uint32_t> order;
    for (std::size_t i = 0; i < leaf_of.size(); ++i)
      if (leaf_of[i] != kNone) order.push_back(static_cast<std::uint32_t>(i));
    nodes.clear();
    free_nodes.clear();
    root = kNone;
    inserted = 0;
    if (!order.empty()) root = build(order, 0, order.size(), kNone);
  }

  void refit(std::int32_t n) {
    for (; n != kNone; n = nodes[n].parent) nodes[n].box = nodes[nodes[n].left].box + nodes[nodes[n].right].box;
  }

  void erase(std::uint32_t i) {
    if (i >= leaf_of.size() || leaf_of[i] == kNone) return;
    const std::int32_t leaf = leaf_of[i];
    leaf_of[i] = kNone;
    --count;
    free_nodes.push_back(leaf);
    const std::int32_t parent = nodes[leaf].parent;
    if (parent == kNone) {
      root = kNone;
      return;
    }
    const std::int32_t sibling = nodes[parent].left == leaf ? nodes[parent].right : nodes[parent].left;
    const std::int32_t grand = nodes[parent].parent;
    nodes[sibling].parent = grand;
    free_nodes.push_back(parent);
    if (grand == kNone) {
      root = sibling;
      return;
    }
    (nodes[grand].left == parent ? nodes[grand].left : nodes[grand].right) = sibling;
    refit(grand);
  }

  /// Indexes f (again); false when its leaf only took the new box.
  bool insert(face_descriptor f) {
    const std::uint32_t i = static_cast<std::uint32_t>(f);
    grow(i);
    const CGAL::Bbox_3 b = bbox_of(f);
    if (leaf_of[i] != kNone) {
      // A face that moved within its parent's box keeps its leaf: the
      // ancestors still hold it (local edits mostly move faces that little;
      // removing and re-inserting was a descent from the root each time).
      const std::int32_t leaf = leaf_of[i], parent = nodes[leaf].parent;
      if (parent == kNone || contains(nodes[parent].box, b)) {
        box[i] = nodes[leaf].box = b;
        return false;
      }
      erase(i);
    }
    box[i] = b;
    ++count;
    const std::int32_t leaf = make_node();
    nodes[leaf].face = i;
    nodes[leaf].box = box[i];
    leaf_of[i] = leaf;
    if (root == kNone) {
      root = leaf;
      return true;
    }
    // Descend to the sibling whose box grows least by taking the new one.
    std::int32_t at = root;
    while (!nodes[at].leaf()) {
      const Node& n = nodes[at];
      const double grow_l = margin(nodes[n.left].box + box[i]) - margin(nodes[n.left].box);
      const double grow_r = margin(nodes[n.right].box + box[i]) - margin(nodes[n.right].box);
      at = grow_l <= grow_r ? n.left : n.right;
    }
    const std::int32_t parent = make_node(), old_parent = nodes[at].parent;
    nodes[parent].parent = old_parent;
    nodes[parent].left = at;
    nodes[parent].right = leaf;
    nodes[at].parent = nodes[leaf].parent = parent;
    if (old_parent == kNone) root = parent;
    else (nodes[old_parent].left == at ? nodes[old_parent].left : nodes[old_parent].right) = parent;
    refit(parent);
    return true;
  }

  /// A triangle ready for the pair test: on InputKernel when its corners are
  /// doubles (converted once, not once per pair), exact otherwise. The
  /// corners stay where they are in the mesh (which does not change during
  /// a query): copying a lazy point is an atomic reference count, and most
  /// pairs never need the exact form.
  struct Prepared {
    std::array<const Point*, 3> corner;
    bool doubles;
    detail::Tri<InputKernel> input;  // doubles only
    std::optional<Tri> exact;        // not doubles only
    /// The exact form (made, for a triangle of doubles).
    Tri exact_form() const {
      if (exact) return *exact;
      return {{*corner[0], *corner[1], *corner[2]}, input.id, input.degenerate};
    }
  };
  /// Faces are triangles, or polygons fanned (rare): no heap for the usual case.
  using Fan = boost::container::small_vector<Prepared, 2>;

  static Prepared prepare(const Point& a, const Point& b, const Point& c, std::uint64_t ia, std::uint64_t ib,
                          std::uint64_t ic) {
    if (!(is_double_point(a) && is_double_point(b) && is_double_point(c)))
      return {{&a, &b, &c}, false, {}, detail::make_tri<Kernel>(a, b, c, ia, ib, ic)};
    // Degeneracy decided once, on the doubles (the same points, the same
    // exact answer as on the lazy ones, without their filter's overhead).
    return {{&a, &b, &c},
            true,
            detail::make_tri<InputKernel>(to_input_point(a), to_input_point(b), to_input_point(c), ia, ib, ic),
            std::nullopt};
  }

  /// The fan triangles of face f with their vertex ids.
  Fan triangles(face_descriptor f) const {
    boost::container::small_vector<vertex_descriptor, 8> v;
    for (vertex_descriptor u : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) v.push_back(u);
    Fan t;
    for (std::size_t k = 1; k + 1 < v.size(); ++k)
      t.push_back(prepare(mesh.point(v[0]), mesh.point(v[k]), mesh.point(v[k + 1]), id_of(v[0]), id_of(v[k]),
                          id_of(v[k + 1])));
    return t;
  }

  static bool any_pair_intersects(const Fan& a, const Fan& b) {
    for (const Prepared& x : a)
      for (const Prepared& y : b)
        if (pair_intersects(x, y)) return true;
    return false;
  }

  /// The exact test, on InputKernel when all six points are doubles (the
  /// same answer, much cheaper on the coplanar pairs CAD meshes are full of).
  static bool pair_intersects(const Prepared& x, const Prepared& y) {
    if (x.doubles && y.doubles) return detail::faces_intersect<InputKernel>(x.input, y.input);
    if (x.exact && y.exact) return detail::faces_intersect<Kernel>(*x.exact, *y.exact);
    return detail::faces_intersect<Kernel>(x.exact_form(), y.exact_form());  // one of doubles: rare
  }

  /// Indexed faces whose boxes meet b (sorted unless told not to).
  void candidates_of(const CGAL::Bbox_3& b, std::vector<std::uint32_t>& out, bool sorted = true) const {
    out.clear();
    if (root == kNone) return;
    boost::container::small_vector<std::int32_t, 64> stack{root};
    while (!stack.empty()) {
      const Node& n = nodes[stack.back()];
      stack.pop_back();
      if (!CGAL::do_overlap(n.box, b)) continue;
      if (n.leaf()) {
        out.push_back(n.face);
      } else {
        stack.push_back(n.left);
        stack.push_back(n.right);
      }
    }
    if (sorted) std::sort(out.begin(), out.end());
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
      const Fan tf = triangles(f);
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
  std::vector<std::uint32_t> order;
  for (face_descriptor f : mesh.faces()) {
    const std::uint32_t i = static_cast<std::uint32_t>(f);
    impl_->grow(i);
    impl_->box[i] = impl_->bbox_of(f);
    order.push_back(i);
  }
  impl_->count = order.size();
  impl_->nodes.reserve(2 * order.size());
  if (!order.empty()) impl_->root = impl_->build(order, 0, order.size(), kNone);
}

LocalIndex::~LocalIndex() = default;

void LocalIndex::update(const std::vector<face_descriptor>& faces) {
  for (face_descriptor f : faces) impl_->inserted += impl_->insert(f);
  if (impl_->inserted > 2 * impl_->count + 1024) impl_->rebuild();
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
  std::vector<Impl::Fan> tris;
  std::vector<CGAL::Bbox_3> boxes;
  for (const auto& t : proposed) {
    const Point &a = mesh.point(t[0]), &b = mesh.point(t[1]), &c = mesh.point(t[2]);
    tris.push_back({Impl::prepare(a, b, c, impl_->id_of(t[0]), impl_->id_of(t[1]), impl_->id_of(t[2]))});
    boxes.push_back(a.bbox() + b.bbox() + c.bbox());
  }
  for (std::size_t i = 0; i < tris.size(); ++i)
    for (std::size_t j = i + 1; j < tris.size(); ++j)
      if (CGAL::do_overlap(boxes[i], boxes[j]) && Impl::any_pair_intersects(tris[i], tris[j])) return true;
  // One descent for the whole fan (its triangles' boxes overlap: one query
  // each visited the same nodes again), and each face found prepared once.
  CGAL::Bbox_3 all;
  for (const CGAL::Bbox_3& b : boxes) all += b;
  std::vector<std::uint32_t> candidates;
  impl_->candidates_of(all, candidates, false);
  for (std::uint32_t g : candidates) {
    if (std::binary_search(skip.begin(), skip.end(), g)) continue;
    const CGAL::Bbox_3& bg = impl_->box[g];
    std::optional<Impl::Fan> fan;
    for (std::size_t i = 0; i < tris.size(); ++i) {
      if (!CGAL::do_overlap(boxes[i], bg)) continue;
      if (!fan) fan = impl_->triangles(face_descriptor(g));
      if (Impl::any_pair_intersects(tris[i], *fan)) return true;
    }
  }
  return false;
}

std::vector<face_descriptor> LocalIndex::faces_meeting(const CGAL::Bbox_3& box) const {
  std::vector<std::uint32_t> candidates;
  impl_->candidates_of(box, candidates);
  std::vector<face_descriptor> out;
  out.reserve(candidates.size());
  for (std::uint32_t f : candidates) out.emplace_back(f);
  return out;
}

std::size_t LocalIndex::size() const { return impl_->count; }

}  // namespace polyheal
