#include "scenes/world.h"

#include "scenes/person.h"

#include <gtest/gtest.h>

namespace segslam::scenes {
namespace {

// A walker on a long straight path along +x.
Object StraightWalker(double speed_mps, bool closed = false) {
  Object o;
  o.instance_id = 1;
  o.coco_category_id = 1;
  o.articulation = Articulation::kWalker;
  PersonLook look;
  o.parts = MakePersonParts(look, 1.0);
  for (Placement& p : o.placement) {
    p.moving = true;
    p.path.waypoints = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(50, 0, 0)};
    p.path.speed_mps = speed_mps;
    p.path.closed = closed;
    p.path.start_offset_m = 5.0;
  }
  return o;
}

TEST(WorldTest, WalkerRootMovesAtItsSpeedFacingForward) {
  const Object o = StraightWalker(1.3);
  const Eigen::Isometry3d a = ObjectPoseAt(o, Pass::kFirst, 2.0);
  const Eigen::Isometry3d b = ObjectPoseAt(o, Pass::kFirst, 6.0);
  EXPECT_NEAR((b.translation() - a.translation()).norm(), 1.3 * 4.0, 1e-6);
  EXPECT_NEAR(a.translation().x(), 5.0 + 1.3 * 2.0, 1e-6);
  EXPECT_NEAR(a.linear().col(0).x(), 1.0, 1e-9);  // +x forward along the path
}

TEST(WorldTest, WalkerLegsAndArmsSwingOverHalfAGaitCycle) {
  const double speed = 1.2;
  const Object o = StraightWalker(speed);
  const double half_cycle_s = 0.5 * kStrideLengthM / speed;
  // Sample the swing extremes: hip angle from the thigh's direction (its -z axis).
  double min_l = 1e9, max_l = -1e9;
  for (double t = 1.0; t < 1.0 + 2 * half_cycle_s; t += 0.01) {
    const auto poses = PartPosesAt(o, Pass::kFirst, t);
    const Eigen::Isometry3d T_root_thigh = poses[kTorso].inverse() * poses[kUpperLegL];
    const Eigen::Vector3d down = -(poses[kUpperLegL].linear().col(2));
    const double swing = std::atan2(down.x(), -down.z());
    (void)T_root_thigh;
    min_l = std::min(min_l, swing);
    max_l = std::max(max_l, swing);
  }
  EXPECT_GT(max_l - min_l, 40 * M_PI / 180);  // about +-25 degrees
  EXPECT_LT(max_l - min_l, 70 * M_PI / 180);

  // Half a cycle later the legs have swapped: the left foot moved relative to the root.
  const double t0 = 2.25 * kStrideLengthM / speed;  // phase 0.25: left leg fully forward
  const auto p0 = PartPosesAt(o, Pass::kFirst, t0);
  const auto p1 = PartPosesAt(o, Pass::kFirst, t0 + half_cycle_s);
  const Eigen::Isometry3d r0 = ObjectPoseAt(o, Pass::kFirst, t0), r1 = ObjectPoseAt(o, Pass::kFirst, t0 + half_cycle_s);
  const Eigen::Vector3d knee_l0 = (r0.inverse() * p0[kLowerLegL]).translation();
  const Eigen::Vector3d knee_l1 = (r1.inverse() * p1[kLowerLegL]).translation();
  const Eigen::Vector3d knee_r0 = (r0.inverse() * p0[kLowerLegR]).translation();
  EXPECT_GT((knee_l0 - knee_l1).norm(), 0.1);
  EXPECT_NEAR(knee_l1.x(), knee_r0.x(), 0.03);  // left now where right was
  // Arms swing opposite to the legs of the same side.
  const Eigen::Vector3d elbow_l0 = (r0.inverse() * p0[kLowerArmL]).translation();
  EXPECT_LT(elbow_l0.x() * knee_l0.x(), 0.0);
}

TEST(WorldTest, StandingWalkerAndStillSitterDoNotMove) {
  Object o = StraightWalker(0.0);
  EXPECT_FALSE(ObjectMovesAt(o, Pass::kFirst, 1.0, 0.1));
  o = StraightWalker(1.0);
  EXPECT_TRUE(ObjectMovesAt(o, Pass::kFirst, 1.0, 0.1));

  Object sitter = StraightWalker(0.0);
  sitter.articulation = Articulation::kSitter;
  for (Placement& p : sitter.placement) p.moving = false;
  EXPECT_TRUE(ObjectMovesAt(sitter, Pass::kFirst, 1.0, 0.2));
  sitter.animated = false;
  EXPECT_FALSE(ObjectMovesAt(sitter, Pass::kFirst, 1.0, 0.2));
  // Seated: the pelvis is at seat height, the knees forward.
  const auto poses = PartPosesAt(sitter, Pass::kFirst, 0.0);
  EXPECT_NEAR(poses[kTorso].translation().z(), 0.52, 0.01);
  EXPECT_GT(poses[kLowerLegL].translation().x(), 0.35);
}

TEST(WorldTest, AbsentObjectHasNoParts) {
  Object o = StraightWalker(1.0);
  o.placement[1].present = false;
  EXPECT_TRUE(PartPosesAt(o, Pass::kSecond, 1.0).empty());
  EXPECT_FALSE(PartPosesAt(o, Pass::kFirst, 1.0).empty());
}

TEST(WorldTest, ClosedLoopTurnsSmoothlyAndWraps) {
  Object car;
  car.parts.resize(1);
  Placement& p = car.placement[0];
  p.moving = true;
  p.path.waypoints = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 0, 0), Eigen::Vector3d(20, 20, 0),
                      Eigen::Vector3d(0, 20, 0)};
  p.path.speed_mps = 5.0;
  p.path.closed = true;
  // After one full loop (80 m) the car is back.
  const Eigen::Isometry3d a = ObjectPoseAt(car, Pass::kFirst, 1.0);
  const Eigen::Isometry3d b = ObjectPoseAt(car, Pass::kFirst, 1.0 + 80.0 / 5.0);
  EXPECT_TRUE(a.isApprox(b, 1e-6));
  // Heading changes by a small step per frame even at the corner.
  double max_step = 0;
  for (double t = 3.0; t < 5.0; t += 1.0 / 15) {
    const Eigen::Matrix3d R0 = ObjectPoseAt(car, Pass::kFirst, t).linear();
    const Eigen::Matrix3d R1 = ObjectPoseAt(car, Pass::kFirst, t + 1.0 / 15).linear();
    max_step = std::max(max_step, Eigen::AngleAxisd(R0.transpose() * R1).angle());
  }
  EXPECT_LT(max_step, 20 * M_PI / 180);
  EXPECT_NEAR(ObjectPoseAt(car, Pass::kFirst, 5.0 + 80.0 / 5).linear().col(0).y(), 1.0, 1e-6);  // going +y after the corner
}

TEST(WorldTest, OpenPathPingPongs) {
  Object o = StraightWalker(1.0);
  o.placement[0].path.start_offset_m = 0.0;
  const Eigen::Isometry3d out = ObjectPoseAt(o, Pass::kFirst, 10.0);
  const Eigen::Isometry3d back = ObjectPoseAt(o, Pass::kFirst, 90.0);  // 40 m back from the end
  EXPECT_NEAR(out.translation().x(), 10.0, 1e-6);
  EXPECT_NEAR(back.translation().x(), 10.0, 1e-6);
  EXPECT_NEAR(back.linear().col(0).x(), -1.0, 1e-6);
}

TEST(WorldTest, CameraPoseInterpolatesAndClamps) {
  World w;
  w.camera.fps = 10;
  for (int k = 0; k <= 10; ++k) {
    CameraKey key;
    key.stamp_s = k * 0.5;
    key.T_wc.translation() = Eigen::Vector3d(k, 0, 1.5);
    key.T_wc.linear() = Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d::UnitY()).matrix();
    w.camera_route[0].keys.push_back(key);
  }
  const Eigen::Isometry3d mid = CameraPoseAt(w, Pass::kFirst, 1.25);
  EXPECT_NEAR(mid.translation().x(), 2.5, 1e-9);  // Catmull-Rom is exact on lines
  EXPECT_NEAR(Eigen::AngleAxisd(mid.linear()).angle(), 0.25, 1e-9);
  EXPECT_TRUE(CameraPoseAt(w, Pass::kFirst, -1.0).isApprox(w.camera_route[0].keys.front().T_wc));
  EXPECT_TRUE(CameraPoseAt(w, Pass::kFirst, 99.0).isApprox(w.camera_route[0].keys.back().T_wc));
}

}  // namespace
}  // namespace segslam::scenes
