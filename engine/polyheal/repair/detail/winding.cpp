#include "polyheal/repair/detail/winding.h"

#include <boost/container/small_vector.hpp>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "polyheal/mesh/vec3.h"

namespace polyheal::detail {
namespace {

// Far: beyond beta times a cluster's radius. With the second-order term,
// 2.25 evaluates a fifth fewer triangles exactly than 2.5 with the dipole
// alone, and mostly errs less: against the exact sum at 800 points in and
// near the boxes of eight corpus meshes, the mean error lower on seven
// (shark_b 0.020 -> 0.006; holes 0.004 -> 0.006), the largest on six
// (shark_b 0.110 -> 0.034; mech-holes-shark 0.030 -> 0.039), all under 0.04.
constexpr double kBeta = 2.25, kBetaStrict = 8;
constexpr std::size_t kLeaf = 8;
// Subtrees over this many triangles build their halves in parallel.
constexpr std::size_t kParallelBuild = 4096;

/// The nodes of a subtree over n triangles (its shape depends on n only:
/// the left half takes n / 2).
std::size_t node_count(std::size_t n) { return n <= kLeaf ? 1 : 1 + node_count(n / 2) + node_count(n - n / 2); }

double dist(const Point3d& a, const Point3d& b) { return norm(sub(a, b)); }

}  // namespace

WindingNumber::WindingNumber(const std::vector<Point3d>& points, const std::vector<std::array<Index, 3>>& tris)
    : points_(points), tris_(tris) {
  order_.resize(tris.size());
  std::iota(order_.begin(), order_.end(), 0);
  centroid_.resize(tris.size());
  twice_area_.resize(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (int a = 0; a < 3; ++a) centroid_[t][a] = (P(t, 0)[a] + P(t, 1)[a] + P(t, 2)[a]) / 3;
    twice_area_[t] = normal(P(t, 0), P(t, 1), P(t, 2));
  }
  if (order_.empty()) return;
  nodes_.resize(node_count(order_.size()));
  // Isolated: a thread waiting for the halves runs only their tasks (not,
  // say, an outer loop's next iteration that asks for this same hierarchy).
  tbb::this_task_arena::isolate([&] { build(0, 0, order_.size(), 1); });
  // The leaves' triangles, in the order the nodes hold them, side by side
  // (what evaluate() reads most, without an index and a point lookup per
  // corner); what only build() needed goes.
  corners_.resize(order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i)
    for (int k = 0; k < 3; ++k) corners_[i][std::size_t(k)] = P(order_[i], k);
  std::vector<std::size_t>().swap(order_);
  std::vector<Point3d>().swap(centroid_);
  std::vector<Point3d>().swap(twice_area_);
}

double WindingNumber::operator()(const Point3d& q) const {
  const double w = evaluate(q, kBeta);
  return std::abs(w - 0.5) < 0.05 ? evaluate(q, kBetaStrict) : w;
}

double WindingNumber::on_face(const Point3d& q, std::size_t t) const {
  return evaluate(q, kBeta) - solid_angle(t, q) / (4 * M_PI);
}

double WindingNumber::share(std::size_t t, const Point3d& q) const { return solid_angle(t, q) / (4 * M_PI); }

double WindingNumber::evaluate(const Point3d& q, double beta) const {
  if (nodes_.empty()) return 0;
  double sum = 0;
  boost::container::small_vector<std::size_t, 64> stack;  // (depth-first: at most the tree's depth + 1)
  stack.push_back(0);
  while (!stack.empty()) {
    const Node& n = nodes_[stack.back()];
    stack.pop_back();
    const double d[3] = {n.center[0] - q[0], n.center[1] - q[1], n.center[2] - q[2]};
    const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (r2 > beta * beta * n.radius * n.radius) {
      // The far field's Taylor expansion (Barill et al. 2018): the
      // cluster's area vectors about its centre c, to second order; with
      // r = c - q,
      //   N.r / |r|^3 + tr(M) / |r|^3 - 3 r.M r / |r|^5,
      // N the sum of the area vectors a n, M the sum of a n (x - c)^T over
      // the triangles (exact with their centroids x at second order).
      const double r3 = r2 * std::sqrt(r2);
      const std::array<double, 9>& m = n.moment;
      const double mr[3] = {m[0] * d[0] + m[1] * d[1] + m[2] * d[2], m[3] * d[0] + m[4] * d[1] + m[5] * d[2],
                            m[6] * d[0] + m[7] * d[1] + m[8] * d[2]};
      const double rmr = d[0] * mr[0] + d[1] * mr[1] + d[2] * mr[2];
      sum += (n.normal[0] * d[0] + n.normal[1] * d[1] + n.normal[2] * d[2] + m[0] + m[4] + m[8]) / r3 -
             3 * rmr / (r3 * r2);
    } else if (n.left < 0) {
      for (std::size_t i = n.first; i < n.last; ++i) sum += solid_angle(corners_[i], q);
    } else {
      stack.push_back(std::size_t(n.left));
      stack.push_back(std::size_t(n.left) + 1);
    }
  }
  return sum / (4 * M_PI);
}

double WindingNumber::solid_angle(std::size_t t, const Point3d& q) const {
  return solid_angle({P(t, 0), P(t, 1), P(t, 2)}, q);
}

double WindingNumber::solid_angle(const std::array<Point3d, 3>& p, const Point3d& q) {
  double a[3], b[3], c[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = p[0][i] - q[i];
    b[i] = p[1][i] - q[i];
    c[i] = p[2][i] - q[i];
  }
  const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  const double lc = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
  const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
  const double ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
  return 2 * std::atan2(det, la * lb * lc + ab * lc + bc * la + ca * lb);
}

/// Fills node `slot` with the triangles order_[first, last); its children
/// are the pair at `next`, their descendants after them, the left's first
/// (the slots a depth-first build allocating as it goes would give). The
/// halves are disjoint ranges and slots, so large ones build in parallel.
void WindingNumber::build(std::size_t slot, std::size_t first, std::size_t last, std::size_t next) {
  Node n;
  n.first = first;
  n.last = last;
  double area = 0;
  Point3d lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t i = first; i < last; ++i) {
    const std::size_t t = order_[i];
    const Point3d& m = twice_area_[t];
    const double A = 0.5 * std::sqrt(dot(m, m));
    for (int a = 0; a < 3; ++a) n.normal[a] += 0.5 * m[a];
    area += A;
    for (int a = 0; a < 3; ++a) {
      n.center[a] += A * centroid_[t][a];
      lo[a] = std::min(lo[a], centroid_[t][a]);
      hi[a] = std::max(hi[a], centroid_[t][a]);
    }
  }
  for (int a = 0; a < 3; ++a) n.center[a] = area > 0 ? n.center[a] / area : (lo[a] + hi[a]) / 2;
  for (std::size_t i = first; i < last; ++i) {
    const std::size_t t = order_[i];
    const Point3d& m = twice_area_[t];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) n.moment[std::size_t(3 * a + b)] += 0.5 * m[a] * (centroid_[t][b] - n.center[b]);
  }
  for (std::size_t i = first; i < last; ++i)
    for (int k = 0; k < 3; ++k) n.radius = std::max(n.radius, dist(n.center, P(order_[i], k)));
  if (last - first > kLeaf) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const std::size_t mid = (first + last) / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + last,
                     [&](std::size_t x, std::size_t y) { return centroid_[x][axis] < centroid_[y][axis]; });
    n.left = std::ptrdiff_t(next);
    const std::size_t right_next = next + 2 + node_count(mid - first) - 1;
    auto left = [&] { build(next, first, mid, next + 2); };
    auto right = [&] { build(next + 1, mid, last, right_next); };
    if (last - first > kParallelBuild) {
      tbb::parallel_invoke(left, right);
    } else {
      left();
      right();
    }
  }
  nodes_[slot] = n;
}

}  // namespace polyheal::detail
