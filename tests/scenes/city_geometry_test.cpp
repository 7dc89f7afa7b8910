// Tests of scenes/city_geometry_internal.h: arc length along polylines, and the
// separating-axis clearance of two footprints.
#include "scenes/city_geometry_internal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace segslam::scenes::city_internal {
namespace {

// An L: 10 m along +x, then 5 m along +y.
Poly2 LShape() { return Poly2({Vec2(0, 0), Vec2(10, 0), Vec2(10, 5)}); }

TEST(Poly2Test, ArcLengthRunsAlongTheSegments) {
  const Poly2 l = LShape();
  EXPECT_DOUBLE_EQ(l.Length(), 15.0);
  EXPECT_TRUE(l.At(4.0).isApprox(Vec2(4, 0)));
  EXPECT_TRUE(l.At(12.0).isApprox(Vec2(10, 2)));
  // Clamped to the ends.
  EXPECT_TRUE(l.At(-3.0).isApprox(Vec2(0, 0)));
  EXPECT_TRUE(l.At(99.0).isApprox(Vec2(10, 5)));
  EXPECT_TRUE(l.Tangent(4.0).isApprox(Vec2(1, 0)));
  EXPECT_TRUE(l.Tangent(12.0).isApprox(Vec2(0, 1)));
}

TEST(Poly2Test, ClosestIsTheNearestPointsArcLength) {
  const Poly2 l = LShape();
  EXPECT_NEAR(l.Closest(Vec2(3, 1)), 3.0, 1e-12);
  EXPECT_NEAR(l.Closest(Vec2(11, 4)), 14.0, 1e-12);
  EXPECT_NEAR(l.Closest(Vec2(-2, -2)), 0.0, 1e-12);
}

TEST(Poly2Test, ClosestWithinAWindowPicksThePassMeant) {
  // Out along +x and back: every point of the line is passed twice.
  const Poly2 there_and_back({Vec2(0, 0), Vec2(10, 0), Vec2(10, 0.001), Vec2(0, 0.001)});
  EXPECT_NEAR(there_and_back.Closest(Vec2(4, 0), 0.0, 10.0), 4.0, 1e-9);
  EXPECT_NEAR(there_and_back.Closest(Vec2(4, 0), 12.0, 20.0), 16.001, 1e-9);
}

// A footprint at one sample.
Track Footprint(const Vec2& pos, double yaw, double half_length, double half_width) {
  Track t;
  t.pos = {pos};
  t.heading = {Vec2(std::cos(yaw), std::sin(yaw))};
  t.present = {1};
  t.half_length = half_length;
  t.half_width = half_width;
  return t;
}

TEST(SatRatioTest, OneMeansTouching) {
  const Track a = Footprint(Vec2(0, 0), 0.0, 2.0, 1.0);
  // Nose to tail, 1 m apart: the ratio along x is 5 / (2 + 2).
  EXPECT_DOUBLE_EQ(SatRatio(a, Footprint(Vec2(5, 0), 0.0, 2.0, 1.0), 0, 0.0), 5.0 / 4.0);
  // Side by side, touching.
  EXPECT_DOUBLE_EQ(SatRatio(a, Footprint(Vec2(0, 2), 0.0, 2.0, 1.0), 0, 0.0), 1.0);
  // Overlapping.
  EXPECT_LT(SatRatio(a, Footprint(Vec2(1, 1), 0.0, 2.0, 1.0), 0, 0.0), 1.0);
  // A margin inflates both: 1 m apart along x is clear at 0.4 m each, not at 0.6 m.
  EXPECT_GE(SatRatio(a, Footprint(Vec2(5, 0), 0.0, 2.0, 1.0), 0, 0.4), 1.0);
  EXPECT_LT(SatRatio(a, Footprint(Vec2(5, 0), 0.0, 2.0, 1.0), 0, 0.6), 1.0);
}

TEST(SatRatioTest, SymmetricAndClearBeyondTheCircumscribedCircles) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Track a = Footprint(Vec2(4 * u(rng), 4 * u(rng)), M_PI * u(rng), 1.5 + u(rng), 0.6 + 0.3 * u(rng));
    const Track b = Footprint(Vec2(4 * u(rng), 4 * u(rng)), M_PI * u(rng), 1.5 + u(rng), 0.6 + 0.3 * u(rng));
    EXPECT_NEAR(SatRatio(a, b, 0, 0.1), SatRatio(b, a, 0, 0.1), 1e-12);
    const double ra = std::hypot(a.half_length, a.half_width), rb = std::hypot(b.half_length, b.half_width);
    if ((a.pos[0] - b.pos[0]).norm() > ra + rb) {
      EXPECT_GE(SatRatio(a, b, 0, 0.0), 1.0);
    }
  }
}

}  // namespace
}  // namespace segslam::scenes::city_internal
