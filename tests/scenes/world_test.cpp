#include "scenes/world.h"

#include "scenes/person.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

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

TEST(WorldTest, AbductionSwingsEachArmOutToItsOwnSide) {
  PersonJoints joints;  // upright, arms hanging
  for (int side = 0; side < 2; ++side) {
    joints.shoulder[side] = 0;
    joints.elbow[side] = 0;
    joints.shoulder_out[side] = 20 * M_PI / 180;
  }
  const std::vector<Eigen::Isometry3d> poses = PersonPartPoses(joints, 1.0);
  // The elbow is the lower arm's origin, one upper arm length below the shoulder.
  for (const auto& [shoulder, elbow, outward] : {std::tuple{kUpperArmL, kLowerArmL, 1.0},  // left is +y
                                                 std::tuple{kUpperArmR, kLowerArmR, -1.0}}) {
    const Eigen::Vector3d s = poses[shoulder].translation(), e = poses[elbow].translation();
    const double angle = std::atan2(outward * (e.y() - s.y()), s.z() - e.z());
    EXPECT_NEAR(angle, 20 * M_PI / 180, 1e-9);
  }
}

// A walker's lower shoe rests on the floor through the whole gait, neither sunk into it
// nor floating: the shoes are rigid on the shanks, so the body is lowered or lifted.
TEST(WorldTest, WalkerStandsOnTheFloorThroughTheGait) {
  for (double scale : {0.9, 1.0, 1.1}) {
    const std::vector<Part> parts = MakePersonParts(PersonLook{}, scale);
    for (double amount : {0.0, 0.5, 1.0}) {
      for (int k = 0; k < 40; ++k) {
        const std::vector<Eigen::Isometry3d> poses = PersonPartPoses(WalkJoints(k / 40.0, amount), scale);
        double lowest_m = std::numeric_limits<double>::infinity();
        for (size_t part = 0; part < parts.size(); ++part) {
          for (const Geom& geom : parts[part].geoms) {
            if (geom.shape != Shape::kBox) continue;  // the shoes are the lowest of its boxes
            for (int c = 0; c < 8; ++c) {
              const Eigen::Vector3d corner(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1);
              lowest_m = std::min(lowest_m, (poses[part] * geom.T_parent_geom * corner.cwiseProduct(geom.size)).z());
            }
          }
        }
        EXPECT_NEAR(lowest_m, 0.0, 1e-9) << "scale " << scale << " amount " << amount << " phase " << k / 40.0;
      }
    }
  }
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

TEST(WorldTest, ObjectPosesAtGivesObjectPoseAtBitForBit) {
  Object car;
  car.parts.resize(1);
  Placement& path = car.placement[0];
  path.moving = true;
  path.path.waypoints = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 0, 0), Eigen::Vector3d(20, 20, 0)};
  path.path.speed_mps = 6.0;
  path.path.halts = {{15.0, 2.0}};
  Placement& parked = car.placement[1];
  parked.T_world_object.translation() = Eigen::Vector3d(3, 4, 0);
  std::vector<double> stamps;
  for (int f = 0; f < 150; ++f) stamps.push_back(f / 15.0);  // out, standing, round the corner, back
  for (Pass pass : {Pass::kFirst, Pass::kSecond}) {
    const std::vector<Eigen::Isometry3d> poses = ObjectPosesAt(car, pass, stamps);
    ASSERT_EQ(poses.size(), stamps.size());
    for (std::size_t i = 0; i < stamps.size(); ++i) {
      EXPECT_EQ(poses[i].matrix(), ObjectPoseAt(car, pass, stamps[i]).matrix()) << "pass " << PassIndex(pass) << " t " << stamps[i];
    }
  }
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

// A car at 6 m/s, braking at 2 m/s^2: 3 s and 9 m from cruising to standing.
TEST(WorldTest, HaltBrakesStandsAndPullsAwayWithKnownTimes) {
  const double v = 6.0, a = 2.0, start = 10.0;
  const std::vector<Halt> halts = {{40.0, 5.0}};
  auto at = [&](double t) { return DistanceWithHalts(start, v, halts, a, t); };
  // Cruising until braking starts at 31 m (t = 21 / 6 = 3.5 s).
  EXPECT_DOUBLE_EQ(at(0.0), start);
  EXPECT_NEAR(at(3.5), 31.0, 1e-12);
  // Half-way through braking: 31 + 6 * 1.5 - 0.5 * 2 * 1.5^2 = 37.75 m.
  EXPECT_NEAR(at(5.0), 37.75, 1e-12);
  // Standing from 6.5 s to 11.5 s.
  EXPECT_NEAR(at(6.5), 40.0, 1e-12);
  EXPECT_DOUBLE_EQ(at(9.0), 40.0);
  EXPECT_NEAR(at(11.5), 40.0, 1e-12);
  // Pulling away: 1 s after the green, 0.5 * 2 * 1 = 1 m; back at speed 9 m on.
  EXPECT_NEAR(at(12.5), 41.0, 1e-12);
  EXPECT_NEAR(at(14.5), 49.0, 1e-12);
  // Then 5 s of standing plus 3 s (= v / a) behind the schedule without the halt.
  EXPECT_NEAR(at(20.0), start + v * (20.0 - 8.0), 1e-12);
  // Never backwards, no jumps.
  for (double t = 0; t < 25.0; t += 0.01) {
    EXPECT_GE(at(t + 0.01), at(t) - 1e-12) << t;
    EXPECT_LE(at(t + 0.01) - at(t), v * 0.01 + 1e-9) << t;
  }
  // A halt it is already past at t = 0 does nothing.
  EXPECT_DOUBLE_EQ(DistanceWithHalts(50.0, v, halts, a, 2.0), 62.0);
  // Two halts add their delays.
  const std::vector<Halt> two = {{40.0, 5.0}, {100.0, 2.0}};
  EXPECT_NEAR(DistanceWithHalts(start, v, two, a, 40.0), start + v * (40.0 - 8.0 - 5.0), 1e-12);
}

// Halts nearer than v^2 / a after the one before: the mover cannot get back to its
// cruising speed between them, so it speeds up over half the way and brakes over the
// other half. A car at 10 m/s braking at 2 m/s^2 takes 5 s and 25 m to stop.
TEST(WorldTest, NearHaltsAreReachedWithoutCruisingNeverBackwards) {
  const double v = 10.0, a = 2.0;
  const std::vector<Halt> halts = {{40.0, 3.0}, {67.0, 3.0}, {70.0, 1.0}, {200.0, 2.0}};
  auto at = [&](double t) { return DistanceWithHalts(0.0, v, halts, a, t); };
  // Braking from 15 m at 1.5 s, standing at 40 m from 6.5 s to 9.5 s.
  EXPECT_NEAR(at(1.5), 15.0, 1e-12);
  EXPECT_DOUBLE_EQ(at(8.0), 40.0);
  // 27 m to the next: sqrt(13.5) s speeding up over 13.5 m, as long braking over the rest.
  const double hop_s = std::sqrt(13.5);
  EXPECT_NEAR(at(9.5 + hop_s), 53.5, 1e-9);
  EXPECT_NEAR(at(9.5 + 2 * hop_s + 1.5), 67.0, 1e-12);
  // 3 m on to the third (sqrt(1.5) s each way), 1 s there, then back to speed over 25 m.
  const double at_70_s = 9.5 + 2 * hop_s + 3.0 + 2 * std::sqrt(1.5);
  EXPECT_NEAR(at(at_70_s + 0.5), 70.0, 1e-12);
  EXPECT_NEAR(at(at_70_s + 6.0), 95.0, 1e-9);
  EXPECT_NEAR(at(at_70_s + 7.0), 105.0, 1e-9);
  // The fourth, far enough from the third, as usual: braking from 175 m.
  EXPECT_NEAR(at(at_70_s + 6.0 + 8.0 + 5.0 + 1.0), 200.0, 1e-9);
  // Never backwards, no jumps, never faster than cruising.
  const double dt = 0.001;
  double worst_back = 0, worst_step = 0;
  for (double t = 0; t < 60.0; t += dt) {
    worst_back = std::max(worst_back, at(t) - at(t + dt));
    worst_step = std::max(worst_step, at(t + dt) - at(t));
  }
  EXPECT_LE(worst_back, 1e-12);
  EXPECT_LE(worst_step, v * dt + 1e-9);
}

// A halt at the start itself: the mover stands there from t = 0, then pulls away.
TEST(WorldTest, HaltAtTheStartIsAStandingStart) {
  const double v = 6.0, a = 2.0;
  const std::vector<Halt> halts = {{30.0, 4.0}};
  auto at = [&](double t) { return DistanceWithHalts(30.0, v, halts, a, t); };
  EXPECT_DOUBLE_EQ(at(0.0), 30.0);
  EXPECT_DOUBLE_EQ(at(3.9), 30.0);
  EXPECT_NEAR(at(5.0), 31.0, 1e-12);
  EXPECT_NEAR(at(7.0), 39.0, 1e-12);
  EXPECT_NEAR(at(8.0), 45.0, 1e-12);
}

TEST(WorldTest, HaltingCarStandsStillOnItsPath) {
  Object o;
  o.parts.resize(1);  // rigid: its part moves with the root
  o.placement[0].moving = true;
  o.placement[0].path.waypoints = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(200, 0, 0)};
  o.placement[0].path.closed = false;
  o.placement[0].path.speed_mps = 6.0;
  o.placement[0].path.halts = {{30.0, 4.0}};
  // Braking from 21 m at 3.5 s, standing from 6.5 s to 10.5 s.
  EXPECT_NEAR(ObjectPoseAt(o, Pass::kFirst, 8.0).translation().x(), 30.0, 1e-9);
  EXPECT_FALSE(ObjectMovesAt(o, Pass::kFirst, 8.0, 1.0));
  EXPECT_TRUE(ObjectMovesAt(o, Pass::kFirst, 10.5, 0.1));
  EXPECT_TRUE(ObjectMovesAt(o, Pass::kFirst, 1.0, 0.1));
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
