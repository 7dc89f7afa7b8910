// People as articulated primitives: the one place that knows a person's parts, their
// sizes and joints, shared by walkers and sitters (world.cpp poses them, city.cpp and
// office.cpp build them). Object frame: on the ground between the feet (walker) or
// below the seat centre (sitter), x forward, y left, z up.
#pragma once

#include "scenes/world.h"

#include <vector>

namespace segslam::scenes {

// Part order of every person; PartPosesAt() returns poses in this order.
enum PersonPart {
  kTorso = 0,   // frame at the pelvis centre
  kHead,        // frame at the base of the neck
  kUpperArmL,   // frames at the shoulder, elbow, hip and knee joints;
  kLowerArmL,   // limbs hang along -z of their frame when the joint angle is 0
  kUpperArmR,
  kLowerArmR,
  kUpperLegL,
  kLowerLegL,
  kUpperLegR,
  kLowerLegR,
  kNumPersonParts
};

// Materials of one person (indices into World::materials).
struct PersonLook {
  int skin = 0;
  int hair = 0;
  int shirt = 0;
  int pants = 0;
  int shoes = 0;
};

// Joint angles, radians. Flexion is positive forward for hips and shoulders (the limb
// swings toward +x), positive backward for knees and forward for elbows.
struct PersonJoints {
  double pelvis_height_m = 0.92;  // at body_scale 1
  double torso_pitch = 0.0;       // forward lean
  double torso_roll = 0.0;
  double torso_yaw = 0.0;
  double head_yaw = 0.0;
  double head_pitch = 0.0;        // positive looks down
  double hip[2] = {0, 0};         // [left, right]
  double knee[2] = {0, 0};
  double shoulder[2] = {0, 0};
  double shoulder_out[2] = {0.08, 0.08};  // abduction, away from the torso
  double elbow[2] = {0, 0};
  // The body is lifted or lowered until the lower shoe's sole rests on the floor, and
  // pelvis_height_m no longer matters (a walker; a sitter's pelvis is on a seat).
  bool feet_on_floor = false;
};

// Stride length (two steps) of a walker at body_scale 1, metres.
constexpr double kStrideLengthM = 1.45;

// The person's parts with their geoms, at `body_scale` (1 = 1.75 m tall).
std::vector<Part> MakePersonParts(const PersonLook& look, double body_scale);

// A walking pose at gait phase `phase` (cycles; 0 = left leg passing the right).
// `amount` in [0, 1] scales the swing (0 = standing still).
PersonJoints WalkJoints(double phase, double amount);

// A seated pose at time `t_s`; `phase` de-synchronises people; animated = false
// gives the neutral seated pose.
PersonJoints SitJoints(double t_s, double phase, bool animated);

// Folds each elbow up by the least angle (to a degree's scan, then bisected) that keeps
// the forearm and hand clear of `boxes` (box geoms in the object frame): a seated
// person's forearms come to rest on the desk, or pass above it, instead of going through
// it. Continuous in time as long as the clear angles are one range upward, which
// SitJoints' forearms, always pointing forward and up, make so for a desk in front. An
// arm that no angle up to 160 degrees clears is left as it was.
void KeepArmsClear(const std::vector<Geom>& boxes, double body_scale, PersonJoints* joints);

// Part poses in the object frame, in PersonPart order.
std::vector<Eigen::Isometry3d> PersonPartPoses(const PersonJoints& joints, double body_scale);

}  // namespace segslam::scenes
