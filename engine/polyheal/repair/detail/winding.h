// polyheal — the generalised winding number of a triangle soup (Jacobson et
// al. 2013), hierarchically (Barill et al. 2018): far clusters by their
// expansion to second order, near triangles by their exact solid angle (Van
// Oosterom & Strackee). A measurement in doubles: it labels (grid corners, which side
// of a surface a sheet lies on), it decides no geometric predicate of an
// output.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal::detail {

class WindingNumber {
 public:
  /// Keeps references to `points` and `tris`: they must outlive it, unchanged.
  WindingNumber(const std::vector<Point3d>& points, const std::vector<std::array<Index, 3>>& tris);

  /// The winding number at q. Far clusters are approximated (error a few
  /// percent at most); a value near the 1/2 threshold is evaluated again
  /// with a stricter far field, so that the approximation does not decide.
  double operator()(const Point3d& q) const;
  /// The winding number at q, a point inside triangle t, but for t's own
  /// solid angle (there ±2π by the sign of a zero): the mean of its values
  /// on the two sides, an integer plus 1/2 (the ordinary far field is
  /// enough to round it).
  double on_face(const Point3d& q, std::size_t t) const;
  /// Triangle t's solid angle seen from q, over 4π: its share of the
  /// winding number at q.
  double share(std::size_t t, const Point3d& q) const;

 private:
  struct Node {
    Point3d center{}, normal{};  // area-weighted centroid; sum of area vectors
    std::array<double, 9> moment{};  // sum of area vector x (centroid - center), row-major
    double radius = 0;
    std::ptrdiff_t left = -1;    // children left, left + 1
    std::size_t first = 0, last = 0;
  };
  double evaluate(const Point3d& q, double beta) const;
  double solid_angle(std::size_t t, const Point3d& q) const;
  static double solid_angle(const std::array<Point3d, 3>& corners, const Point3d& q);
  void build(std::size_t slot, std::size_t first, std::size_t last, std::size_t next);
  const Point3d& P(std::size_t t, int k) const { return points_[tris_[t][k]]; }

  const std::vector<Point3d>& points_;
  const std::vector<std::array<Index, 3>>& tris_;
  // build()'s, released after it: the triangles in the nodes' order, their
  // centroids and normals (cross products, twice their area vectors)
  std::vector<std::size_t> order_;
  std::vector<Point3d> centroid_;
  std::vector<Point3d> twice_area_;
  std::vector<Node> nodes_;
  std::vector<std::array<Point3d, 3>> corners_;  // the triangles' corners, in the nodes' order
};

}  // namespace polyheal::detail
