#include "scenes/city_geometry_internal.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace segslam::scenes::city_internal {

Poly2::Poly2(std::vector<Vec2> pts) : p(std::move(pts)), c(p.size(), 0.0) {
  for (std::size_t i = 1; i < p.size(); ++i) c[i] = c[i - 1] + (p[i] - p[i - 1]).norm();
}

Vec2 Poly2::At(double s) const {
  s = std::clamp(s, 0.0, Length());
  const auto it = std::upper_bound(c.begin(), c.end(), s);
  const std::size_t i = std::clamp<std::size_t>(it - c.begin(), 1, p.size() - 1);
  const double seg = c[i] - c[i - 1];
  return p[i - 1] + (seg > 0 ? (s - c[i - 1]) / seg : 0.0) * (p[i] - p[i - 1]);
}

Vec2 Poly2::Tangent(double s) const { return (At(s + 0.5) - At(s - 0.5)).normalized(); }

double Poly2::Closest(const Vec2& q, double lo_s, double hi_s) const {
  double best = 1e18, best_s = 0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    if (c[i] < lo_s || c[i - 1] > hi_s) continue;
    const Vec2 d = p[i] - p[i - 1];
    const double len2 = d.squaredNorm();
    const double u = len2 > 0 ? std::clamp((q - p[i - 1]).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (p[i - 1] + u * d - q).norm();
    if (dist < best) best = dist, best_s = c[i - 1] + u * (c[i] - c[i - 1]);
  }
  return best_s;
}

double SatRatio(const Track& a, const Track& b, std::size_t i, double margin) {
  const Vec2& ua = a.heading[i];
  const Vec2& ub = b.heading[i];
  const Vec2 axes[4] = {ua, Vec2(-ua.y(), ua.x()), ub, Vec2(-ub.y(), ub.x())};
  const Vec2 d = b.pos[i] - a.pos[i];
  double best = 0;
  for (const Vec2& u : axes) {
    const double ra = (a.half_length + margin) * std::abs(u.dot(ua)) + (a.half_width + margin) * std::abs(u.x() * -ua.y() + u.y() * ua.x());
    const double rb = (b.half_length + margin) * std::abs(u.dot(ub)) + (b.half_width + margin) * std::abs(u.x() * -ub.y() + u.y() * ub.x());
    best = std::max(best, std::abs(d.dot(u)) / (ra + rb));
  }
  return best;
}

}  // namespace segslam::scenes::city_internal
