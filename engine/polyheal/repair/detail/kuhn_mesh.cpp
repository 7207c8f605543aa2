// polyheal — Kuhn's triangulation refined by Maubach's bisection (see kuhn_mesh.h).
#include "polyheal/repair/detail/kuhn_mesh.h"

#include <stdexcept>

namespace polyheal::detail {
namespace {

constexpr int kBits = 21;  // per fine-lattice coordinate in a key

std::uint64_t pack(std::int64_t i, std::int64_t j, std::int64_t k) {
  return (std::uint64_t(i) << (2 * kBits)) | (std::uint64_t(j) << kBits) | std::uint64_t(k);
}

// Kuhn's six paths from (0,0,0) to (1,1,1): the axes in the order taken.
constexpr int kPaths[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

}  // namespace

KuhnMesh::KuhnMesh(int halvings) : halvings_(halvings) {
  if (halvings < 0 || halvings > 8) throw std::invalid_argument("KuhnMesh: halvings must be in [0, 8]");
}

std::int64_t KuhnMesh::find_cube(std::int64_t i, std::int64_t j, std::int64_t k) const {
  const auto it = cube_index_.find(pack(i, j, k));
  return it == cube_index_.end() ? -1 : std::int64_t(it->second);
}

std::int64_t KuhnMesh::find_corner(const Coord& p) const {
  const auto it = corner_index_.find(pack(p[0], p[1], p[2]));
  return it == corner_index_.end() ? -1 : std::int64_t(it->second);
}

std::uint32_t KuhnMesh::corner_at(const Coord& p) {
  for (std::int64_t x : p)
    if (x < 0 || x >= (std::int64_t(1) << kBits)) throw std::out_of_range("KuhnMesh: corner off the lattice");
  const auto [it, added] = corner_index_.emplace(pack(p[0], p[1], p[2]), std::uint32_t(corners_.size()));
  if (added) {
    corners_.push_back(p);
    star_.emplace_back();
  }
  return it->second;
}

std::uint32_t KuhnMesh::add_tet(const Tet& t) {
  const std::uint32_t id = std::uint32_t(tets_.size());
  tets_.push_back(t);
  for (std::uint32_t v : t.v) star_[v].push_back(id);
  return id;
}

std::pair<std::uint32_t, bool> KuhnMesh::add_cube(std::int64_t i, std::int64_t j, std::int64_t k) {
  const auto [it, added] = cube_index_.emplace(pack(i, j, k), std::uint32_t(cubes_.size()));
  if (!added) return {it->second, false};
  const std::uint32_t c = it->second;
  cubes_.push_back({i, j, k});
  const std::int64_t s = scale();
  std::vector<std::uint32_t> queue;
  for (const auto& path : kPaths) {
    Coord p{i * s, j * s, k * s};
    Tet t{};
    t.v[0] = corner_at(p);
    for (int step = 0; step < 3; ++step) {
      p[path[step]] += s;
      t.v[step + 1] = corner_at(p);
    }
    t.cube = c;
    t.tag = 3;
    t.level = 0;
    t.leaf = true;
    queue.push_back(add_tet(t));
  }
  conform(queue);
  return {c, true};
}

bool KuhnMesh::hanging(const Tet& t) const {
  for (const auto& e : kEdges) {
    const Coord &a = corners_[t.v[e[0]]], &b = corners_[t.v[e[1]]];
    Coord m;
    bool on_lattice = true;
    for (int x = 0; x < 3 && on_lattice; ++x) {
      on_lattice = ((a[x] + b[x]) & 1) == 0;
      m[x] = (a[x] + b[x]) / 2;
    }
    if (on_lattice && find_corner(m) >= 0) return true;
  }
  return false;
}

void KuhnMesh::bisect_one(std::uint32_t id, std::vector<std::uint32_t>& queue) {
  const Tet t = tets_[id];  // a copy: add_tet may reallocate
  const int k = t.tag;
  const Coord &a = corners_[t.v[0]], &b = corners_[t.v[k]];
  Coord m;
  for (int x = 0; x < 3; ++x) {
    if ((a[x] + b[x]) & 1) throw std::logic_error("KuhnMesh: bisection below the fine lattice");
    m[x] = (a[x] + b[x]) / 2;
  }
  const bool fresh = find_corner(m) < 0;
  const std::uint32_t z = corner_at(m);
  tets_[id].leaf = false;
  Tet first = t, second = t;
  // (x0, .., x(k-1), z, x(k+1), .., x3) and (x1, .., xk, z, x(k+1), .., x3)
  first.v[k] = z;
  for (int x = 0; x < k; ++x) second.v[x] = t.v[x + 1];
  second.v[k] = z;
  first.tag = second.tag = std::uint8_t(k > 1 ? k - 1 : 3);
  first.level = second.level = std::uint8_t(t.level + 1);
  queue.push_back(add_tet(first));
  queue.push_back(add_tet(second));
  if (fresh) {
    // Every leaf with the edge just cut now has a hanging node.
    for (std::uint32_t u : star_[t.v[0]])
      if (tets_[u].leaf)
        for (std::uint32_t w : tets_[u].v)
          if (w == t.v[k]) queue.push_back(u);
  }
}

void KuhnMesh::conform(std::vector<std::uint32_t>& queue) {
  while (!queue.empty()) {
    const std::uint32_t id = queue.back();
    queue.pop_back();
    if (tets_[id].leaf && hanging(tets_[id])) bisect_one(id, queue);
  }
}

std::size_t KuhnMesh::bisect(const std::vector<std::uint32_t>& tets) {
  const std::size_t before = tets_.size();
  std::vector<std::uint32_t> queue;
  for (std::uint32_t id : tets)
    if (tets_[id].leaf && tets_[id].level < max_level()) bisect_one(id, queue);
  conform(queue);
  return (tets_.size() - before) / 2;
}

int KuhnMesh::orientation(const Tet& t) const {
  const Coord &p = corners_[t.v[0]], &q = corners_[t.v[1]], &r = corners_[t.v[2]], &s = corners_[t.v[3]];
  const std::int64_t u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const std::int64_t v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  const std::int64_t w[3] = {s[0] - p[0], s[1] - p[1], s[2] - p[2]};
  // Edges are at most 2^halvings * sqrt(3) long: the products fit easily.
  const std::int64_t det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                           u[2] * (v[0] * w[1] - v[1] * w[0]);
  return det > 0 ? 1 : -1;
}

bool KuhnMesh::across_cube_face(const Tet& t, int f, Coord& neighbour) const {
  const std::int64_t s = scale();
  const Coord& c = cubes_[t.cube];
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const std::int64_t plane = (c[axis] + side) * s;
      bool on = true;
      for (int x = 0; x < 4 && on; ++x)
        if (x != f) on = corners_[t.v[x]][axis] == plane;
      if (on) {
        neighbour = c;
        neighbour[axis] += side ? 1 : -1;
        return true;
      }
    }
  return false;
}

}  // namespace polyheal::detail
