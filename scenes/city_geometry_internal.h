// The geometry the city's traffic scripting checks clearance with: lanes as polylines
// measured by arc length, and the footprints of moving actors sampled at the frames of
// both passes. Private to scenes/ (the city builder, city_*.cpp, and its tests).
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace segslam::scenes::city_internal {

using Vec2 = Eigen::Vector2d;

// An arc-length parametrised 2-D polyline.
struct Poly2 {
  std::vector<Vec2> p;
  std::vector<double> c;
  explicit Poly2(std::vector<Vec2> pts);
  double Length() const { return c.back(); }
  Vec2 At(double s) const;
  Vec2 Tangent(double s) const;
  // Arc length of the point nearest to q, on the segments that reach into [lo_s, hi_s]
  // (a lane that passes the same place twice: the pass meant).
  double Closest(const Vec2& q, double lo_s = -1e18, double hi_s = 1e18) const;
};

// A moving actor's footprint (a rectangle about its position, along its heading) at
// frame samples.
struct Track {
  std::vector<Vec2> pos;
  std::vector<Vec2> heading;  // (cos, sin) of the yaw
  std::vector<char> present;  // per sample: in the world at that time
  double half_length = 0.3, half_width = 0.3;
  bool car = false;
  // Radius of the footprint, bare (BodiesClear) and inflated by each clearance margin
  // (Clearance).
  double radius = 0, radius_with_car_margin = 0, radius_with_person_margin = 0;
};

// Separating-axis ratio of two footprints inflated by `margin`: >= 1 means clear.
double SatRatio(const Track& a, const Track& b, std::size_t i, double margin);

}  // namespace segslam::scenes::city_internal
