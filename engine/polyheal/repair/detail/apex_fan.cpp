#include "polyheal/repair/detail/apex_fan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "polyheal/mesh/vec3.h"

namespace polyheal::detail {
namespace {

constexpr std::size_t kMaxRings = 40;

/// Distance from p to segment uv.
double distance_to_segment(const Point3d& p, const Point3d& u, const Point3d& v) {
  const Point3d d = sub(v, u);
  const double dd = squared_norm(d);
  const double t = dd > 0 ? std::clamp(dot(sub(p, u), d) / dd, 0.0, 1.0) : 0.0;
  return norm(sub(p, add(u, mul(d, t))));
}

struct Ring {
  double r;                          // nominal distance from the apex
  std::vector<std::size_t> spokes;   // in fan order
  std::vector<std::size_t> ids;      // the plan's vertex ids, per spoke
};

}  // namespace

std::optional<ApexFanPlan> plan_apex_fan(const Point3d& a, const std::vector<Point3d>& link, double tolerance,
                                         double needle_angle, double cap_angle) {
  const std::size_t n = link.size();
  if (n < 4 || !(tolerance > 0)) return std::nullopt;
  std::vector<Point3d> u(n);  // unit spokes
  std::vector<double> length(n);
  for (std::size_t i = 0; i < n; ++i) {
    length[i] = norm(sub(link[i], a));
    if (!(length[i] > 0)) return std::nullopt;
    u[i] = mul(sub(link[i], a), 1 / length[i]);
  }
  auto angle = [&](std::size_t p, std::size_t q) { return std::acos(std::clamp(dot(u[p], u[q]), -1.0, 1.0)); };
  const double needle = needle_angle * kPi / 180;
  // the spokes left at a: their angles there clear the needle angle by 10%
  const double enough = 1.1 * needle;
  // a trapezoid between rings r > r' with sectors psi wide: smallest angle
  // about atan(r' psi / (r - r')), kept above 1.5 needle angles
  const double tan_strip = std::tan(1.5 * needle);

  auto gaps = [&](const std::vector<std::size_t>& s) {
    double lo = std::numeric_limits<double>::infinity(), sum = 0;
    for (std::size_t k = 0; k < s.size(); ++k) {
      const double g = angle(s[k], s[(k + 1) % s.size()]);
      lo = std::min(lo, g);
      sum += g;
    }
    return std::pair<double, double>{lo, sum / double(s.size())};
  };
  // how far the chords between the kept spokes of s are from the fan, per
  // unit distance from a: the original spokes between them off the chord
  auto deviation = [&](const std::vector<std::size_t>& s) {
    double worst = 0;
    for (std::size_t k = 0; k < s.size(); ++k) {
      const std::size_t p = s[k], q = s[(k + 1) % s.size()];
      for (std::size_t i = (p + 1) % n; i != q; i = (i + 1) % n)
        worst = std::max(worst, distance_to_segment(u[i], u[p], u[q]));
    }
    return worst;
  };
  // every other spoke; an odd count leaves one gap of three
  auto coarsen = [](const std::vector<std::size_t>& s) {
    std::vector<std::size_t> out;
    const std::size_t end = s.size() % 2 ? s.size() - 1 : s.size();
    for (std::size_t k = 0; k < end; k += 2) out.push_back(s[k]);
    return out;
  };

  // The narrow cone's tip moved along its axis (the spokes' mean) by the
  // least distance, found by bisection, that makes the gaps between the
  // points of `ring` clear `enough` seen from it; at most half the tolerance.
  ApexFanPlan plan;
  plan.apex = a;
  auto settle_apex = [&](const Ring& ring) {
    Point3d axis{0, 0, 0};
    for (std::size_t s : ring.spokes) axis = add(axis, u[s]);
    const double na = norm(axis);
    if (!(na > 0)) return false;
    axis = mul(axis, 1 / na);
    std::vector<Point3d> p;
    for (std::size_t s : ring.spokes) p.push_back(add(a, mul(u[s], ring.r)));
    auto clears = [&](double d) {
      const Point3d c = add(a, mul(axis, d));
      for (std::size_t k = 0; k < p.size(); ++k) {
        const Point3d x = sub(p[k], c), y = sub(p[(k + 1) % p.size()], c);
        if (angle_between(x, y) < enough) return false;
      }
      return true;
    };
    double hi = std::min(0.5 * tolerance, 0.5 * ring.r), lo = 0;
    if (!clears(hi)) return false;
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (lo + hi);
      (clears(mid) ? hi : lo) = mid;
    }
    plan.apex = add(a, mul(axis, hi));
    plan.moved = true;
    return true;
  };

  std::vector<Ring> rings;
  {
    Ring outer{*std::min_element(length.begin(), length.end()), {}, {}};
    for (std::size_t i = 0; i < n; ++i) {
      outer.spokes.push_back(i);
      outer.ids.push_back(1 + i);
    }
    rings.push_back(outer);
  }
  while (true) {
    const Ring& ring = rings.back();
    const auto [lo, mean] = gaps(ring.spokes);
    if (lo >= enough && ring.spokes.size() >= 3) break;
    if (rings.size() > kMaxRings) return std::nullopt;
    const bool can_coarsen = ring.spokes.size() >= 6;
    if (!can_coarsen && ring.spokes.size() >= 3 && settle_apex(ring)) break;
    const std::vector<std::size_t> coarse = can_coarsen ? coarsen(ring.spokes) : std::vector<std::size_t>{};
    const double dev = can_coarsen ? deviation(coarse) : 0;
    const double reach = !can_coarsen ? 0 : dev > 0 ? 0.5 * tolerance / dev : std::numeric_limits<double>::infinity();
    // a coarsening band is about as deep as the outer ring's sectors are wide
    const double coarse_at = ring.r * (1 - std::min(0.5, mean));
    Ring next;
    if (can_coarsen && coarse_at <= reach) {
      next.r = coarse_at;
      next.spokes = coarse;
    } else {
      next.r = std::max(ring.r * tan_strip / (lo + tan_strip), reach / (1 - std::min(0.5, mean)));
      next.spokes = ring.spokes;
    }
    if (!(next.r > 0) || !(next.r < ring.r)) return std::nullopt;
    for (std::size_t s : next.spokes) {
      next.ids.push_back(1 + n + plan.points.size());
      const double t = next.r / length[s];
      plan.points.push_back(add(a, mul(sub(link[s], a), t)));
    }
    rings.push_back(std::move(next));
  }
  plan.rings = rings.size() - 1;

  // positions, for shapes
  auto position = [&](std::size_t id) {
    if (id == 0) return plan.apex;
    if (id <= n) return link[id - 1];
    return plan.points[id - 1 - n];
  };
  auto worst_angle = [&](std::size_t x, std::size_t y, std::size_t z) {
    const auto [lo, hi] = angle_range(position(x), position(y), position(z));
    return std::min(lo, 180 - hi);
  };
  auto emit = [&](std::size_t x, std::size_t y, std::size_t z, std::size_t first, std::size_t last) {
    plan.triangles.push_back({x, y, z});
    plan.sectors.push_back({first, last});
  };
  for (std::size_t j = 0; j + 1 < rings.size(); ++j) {
    const Ring &out = rings[j], &in = rings[j + 1];
    const std::size_t m = out.spokes.size();
    // where each inner spoke is among the outer ones
    std::vector<std::size_t> at(in.spokes.size());
    for (std::size_t k = 0, o = 0; k < in.spokes.size(); ++k) {
      while (out.spokes[o] != in.spokes[k]) ++o;
      at[k] = o;
    }
    for (std::size_t k = 0; k < in.spokes.size(); ++k) {
      const std::size_t kn = (k + 1) % in.spokes.size();
      const std::size_t o0 = at[k], span = (at[kn] + m - o0) % m == 0 ? m : (at[kn] + m - o0) % m;
      const std::size_t ip = in.ids[k], iq = in.ids[kn];
      const std::size_t first = in.spokes[k], last = (in.spokes[kn] + n - 1) % n;
      auto outer = [&](std::size_t t) { return out.ids[(o0 + t) % m]; };
      if (span == 1) {  // a trapezoid: the diagonal leaving the better worst angle
        const double one = std::min(worst_angle(ip, outer(0), outer(1)), worst_angle(ip, outer(1), iq));
        const double other = std::min(worst_angle(ip, outer(0), iq), worst_angle(iq, outer(0), outer(1)));
        if (one >= other) {
          emit(ip, outer(0), outer(1), first, last);
          emit(ip, outer(1), iq, first, last);
        } else {
          emit(ip, outer(0), iq, first, last);
          emit(iq, outer(0), outer(1), first, last);
        }
        continue;
      }
      const std::size_t half = span / 2;
      for (std::size_t t = 0; t < half; ++t) emit(ip, outer(t), outer(t + 1), first, last);
      emit(ip, outer(half), iq, first, last);
      for (std::size_t t = half; t < span; ++t) emit(iq, outer(t), outer(t + 1), first, last);
    }
  }
  {
    const Ring& in = rings.back();
    for (std::size_t k = 0; k < in.spokes.size(); ++k) {
      const std::size_t kn = (k + 1) % in.spokes.size();
      emit(0, in.ids[k], in.ids[kn], in.spokes[k], (in.spokes[kn] + n - 1) % n);
    }
  }
  // on doubles, with a margin the exact check after it does not have
  for (const auto& t : plan.triangles)
    if (!angles_within(position(t[0]), position(t[1]), position(t[2]), 1.02 * needle_angle, cap_angle))
      return std::nullopt;
  return plan;
}

}  // namespace polyheal::detail
