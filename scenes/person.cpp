// Person geometry and joint kinematics. All lengths below are for a 1.75 m person and
// scale with body_scale.
#include "scenes/person.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace segslam::scenes {
namespace {

// Body dimensions (metres, body_scale 1).
struct Body {
  double hip_width = 0.095;        // hip joint offset from the midline
  double shoulder_width = 0.20;    // shoulder joint offset from the midline
  double shoulder_height = 0.50;   // above the pelvis
  double neck_height = 0.56;       // above the pelvis
  double thigh = 0.44, shank = 0.43;
  double upper_arm = 0.29, forearm = 0.26;
  double thigh_r = 0.075, shank_r = 0.055, upper_arm_r = 0.045, forearm_r = 0.038;
};
const Body kBody;

// The shoe: a box on the shank's lower end, toes forward (+x), in the shank's frame.
const Eigen::Vector3d kShoeHalfSize(0.125, 0.05, 0.04);
Eigen::Vector3d ShoeCentre() { return Eigen::Vector3d(0.05, 0, -kBody.shank - 0.005); }

std::array<Eigen::Vector3d, 8> ShoeCorners(double s) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d sign(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1);
    corners[static_cast<size_t>(k)] = (ShoeCentre() + sign.cwiseProduct(kShoeHalfSize)) * s;
  }
  return corners;
}

Geom MakeGeom(Shape shape, Eigen::Vector3d size, Eigen::Vector3d at, int material) {
  Geom g;
  g.shape = shape;
  g.size = size;
  g.T_parent_geom.translation() = at;
  g.material = material;
  return g;
}

// A capsule hanging from its joint along -z.
Geom Limb(double radius, double length, int material, double s) {
  return MakeGeom(Shape::kCapsule, Eigen::Vector3d(radius * s, 0.5 * (length - 2 * radius) * s, 0),
                  Eigen::Vector3d(0, 0, -0.5 * length * s), material);
}

Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).matrix(); }
Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).matrix(); }
Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).matrix(); }

Eigen::Isometry3d Pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

// The forearm's frame at the elbow, from the upper arm's frame at the shoulder.
Eigen::Isometry3d ElbowPose(const Eigen::Isometry3d& T_shoulder, double elbow, double s) {
  return T_shoulder * Pose(Ry(-elbow), Eigen::Vector3d(0, 0, -kBody.upper_arm * s));
}

// The hand: an ellipsoid below the wrist, in the forearm's frame (body_scale 1).
const Eigen::Vector3d kHandHalfSize(0.03, 0.045, 0.08);
double HandCentreZ() { return -kBody.forearm - 0.06; }

// A box geom as the clearance test reads it: the map into its frame, and its half size.
struct Obstacle {
  Eigen::Isometry3d T_box_parent;
  Eigen::Vector3d half_size;
};

// Distance from p to the box, negative inside (by the depth to its nearest face).
double SignedDistanceToBox(const Obstacle& box, const Eigen::Vector3d& p_parent) {
  const Eigen::Vector3d q = (box.T_box_parent * p_parent).cwiseAbs() - box.half_size;
  const double inside = std::min(q.maxCoeff(), 0.0);
  return q.cwiseMax(0.0).norm() + inside;
}

// True when the forearm and hand, posed at T_elbow, keep kMarginM from every box: their
// axis is sampled every centimetre or less, each sample with the limb's radius there
// (the capsule's, then the hand's width tapering to its tip).
bool ForearmClear(const Eigen::Isometry3d& T_elbow, double s, const std::vector<Obstacle>& boxes) {
  constexpr double kMarginM = 0.003;
  const double tip = HandCentreZ() - kHandHalfSize.z();
  const int steps = static_cast<int>(std::ceil(-tip * s / 0.01));
  for (int k = 0; k <= steps; ++k) {
    const double z = tip * k / steps;  // body_scale 1
    // The elbow's own ball stays where it is whatever the elbow's angle: folding cannot
    // clear it, so it is the upper arm's business, not this test's.
    if (z > -kBody.forearm_r) continue;
    double radius = z >= -kBody.forearm ? kBody.forearm_r : 0.0;
    const double u = (z - HandCentreZ()) / kHandHalfSize.z();
    if (std::abs(u) < 1) radius = std::max(radius, kHandHalfSize.y() * std::sqrt(1 - u * u));
    const Eigen::Vector3d p = T_elbow * Eigen::Vector3d(0, 0, z * s);
    for (const Obstacle& box : boxes) {
      if (SignedDistanceToBox(box, p) < radius * s + kMarginM) return false;
    }
  }
  return true;
}

}  // namespace

void KeepArmsClear(const std::vector<Geom>& boxes, double s, PersonJoints* joints) {
  if (boxes.empty()) return;
  constexpr double kDeg = M_PI / 180.0;
  constexpr double kMostElbow = 160 * kDeg;  // the hand at the shoulder
  std::vector<Obstacle> obstacles;
  obstacles.reserve(boxes.size());
  for (const Geom& box : boxes) obstacles.push_back({box.T_parent_geom.inverse(), box.size});
  const std::vector<Eigen::Isometry3d> poses = PersonPartPoses(*joints, s);
  for (int side = 0; side < 2; ++side) {
    const Eigen::Isometry3d& T_shoulder = poses[kUpperArmL + 2 * side];
    auto clear = [&](double elbow) { return ForearmClear(ElbowPose(T_shoulder, elbow, s), s, obstacles); };
    double blocked = joints->elbow[side];
    if (clear(blocked)) continue;
    // Scan up in 1-degree steps to the first clear angle, then bisect the last step, so
    // the forearm comes to rest where it first clears. Nothing clear: the arm is left as
    // it was rather than snapped to a far pose.
    double free = blocked;
    bool found = false;
    while (!found && free < kMostElbow) {
      blocked = free;
      free = std::min(kMostElbow, free + 1 * kDeg);
      found = clear(free);
    }
    if (!found) continue;
    for (int i = 0; i < 5; ++i) {  // to 0.03 degrees
      const double mid = 0.5 * (blocked + free);
      (clear(mid) ? free : blocked) = mid;
    }
    joints->elbow[side] = free;
  }
}

std::vector<Part> MakePersonParts(const PersonLook& look, double s) {
  const Body& b = kBody;
  std::vector<Part> parts(kNumPersonParts);

  // Torso: hips in trousers, chest in the shirt, a neck.
  Part& torso = parts[kTorso];
  torso.name = "torso";
  torso.geoms.push_back(MakeGeom(Shape::kBox, Eigen::Vector3d(0.10, 0.165, 0.09) * s,
                                 Eigen::Vector3d(0, 0, 0.0) * s, look.pants));
  torso.geoms.push_back(MakeGeom(Shape::kBox, Eigen::Vector3d(0.11, 0.19, 0.23) * s,
                                 Eigen::Vector3d(0, 0, 0.30) * s, look.shirt));
  torso.geoms.push_back(MakeGeom(Shape::kEllipsoid, Eigen::Vector3d(0.11, 0.215, 0.07) * s,
                                 Eigen::Vector3d(0, 0, 0.49) * s, look.shirt));
  torso.geoms.push_back(MakeGeom(Shape::kCylinder, Eigen::Vector3d(0.05, 0.05, 0) * s,
                                 Eigen::Vector3d(0, 0, 0.57) * s, look.skin));

  // Head: face, hair cap and a nose so the facing direction reads.
  Part& head = parts[kHead];
  head.name = "head";
  head.geoms.push_back(MakeGeom(Shape::kEllipsoid, Eigen::Vector3d(0.095, 0.08, 0.115) * s,
                                Eigen::Vector3d(0.01, 0, 0.16) * s, look.skin));
  head.geoms.push_back(MakeGeom(Shape::kEllipsoid, Eigen::Vector3d(0.09, 0.085, 0.07) * s,
                                Eigen::Vector3d(-0.012, 0, 0.225) * s, look.hair));
  head.geoms.push_back(MakeGeom(Shape::kBox, Eigen::Vector3d(0.02, 0.012, 0.025) * s,
                                Eigen::Vector3d(0.10, 0, 0.15) * s, look.skin));

  // Arms: sleeves on the upper arm, skin forearm with a hand.
  const char* arm_names[4] = {"upper_arm_l", "lower_arm_l", "upper_arm_r", "lower_arm_r"};
  for (int side = 0; side < 2; ++side) {
    Part& upper = parts[kUpperArmL + 2 * side];
    upper.name = arm_names[2 * side];
    upper.geoms.push_back(Limb(b.upper_arm_r, b.upper_arm + 0.04, look.shirt, s));
    Part& lower = parts[kLowerArmL + 2 * side];
    lower.name = arm_names[2 * side + 1];
    lower.geoms.push_back(Limb(b.forearm_r, b.forearm, look.skin, s));
    lower.geoms.push_back(MakeGeom(Shape::kEllipsoid, kHandHalfSize * s, Eigen::Vector3d(0, 0, HandCentreZ()) * s, look.skin));
  }

  // Legs: trousers and shoes.
  const char* leg_names[4] = {"upper_leg_l", "lower_leg_l", "upper_leg_r", "lower_leg_r"};
  for (int side = 0; side < 2; ++side) {
    Part& upper = parts[kUpperLegL + 2 * side];
    upper.name = leg_names[2 * side];
    upper.geoms.push_back(Limb(b.thigh_r, b.thigh + 0.05, look.pants, s));
    Part& lower = parts[kLowerLegL + 2 * side];
    lower.name = leg_names[2 * side + 1];
    lower.geoms.push_back(Limb(b.shank_r, b.shank, look.pants, s));
    lower.geoms.push_back(MakeGeom(Shape::kBox, kShoeHalfSize * s, ShoeCentre() * s, look.shoes));
  }
  return parts;
}

PersonJoints WalkJoints(double phase, double amount) {
  constexpr double kDeg = M_PI / 180.0;
  const double w = 2.0 * M_PI * phase;
  PersonJoints j;
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? 1.0 : -1.0;  // legs in anti-phase
    const double swing = sign * std::sin(w);      // +1: this leg fully forward
    const double swing_rate = sign * std::cos(w);  // > 0 while the leg swings forward
    j.hip[side] = amount * 27.0 * kDeg * swing;
    // The knee folds while the leg swings through, and stays nearly straight in stance.
    j.knee[side] = amount * (6.0 + 48.0 * std::pow(std::max(0.0, swing_rate), 1.5)) * kDeg;
    // Arms swing against the leg of the same side; elbows bend a little more forward.
    j.shoulder[side] = -amount * 22.0 * kDeg * swing;
    j.elbow[side] = (12.0 + amount * 12.0 * std::max(0.0, -swing)) * kDeg;
  }
  // The body's height follows from the legs: the lower shoe rests on the floor, so the
  // pelvis is highest when the legs pass each other and lowest at full stride.
  j.feet_on_floor = true;
  j.torso_pitch = amount * 4.0 * kDeg;
  j.torso_yaw = amount * 5.0 * kDeg * std::sin(w);  // shoulders counter-rotate the hips
  j.torso_roll = amount * 2.0 * kDeg * std::cos(w);
  j.head_yaw = -j.torso_yaw * 0.8;  // eyes stay on the way ahead
  return j;
}

PersonJoints SitJoints(double t, double phase, bool animated) {
  constexpr double kDeg = M_PI / 180.0;
  PersonJoints j;
  j.pelvis_height_m = 0.52;
  const double a = animated ? 1.0 : 0.0;
  const double p = 2.0 * M_PI * phase;
  // Slow, de-synchronised sinusoids: leaning, turning to talk, gesturing.
  j.torso_pitch = (3.0 + a * 6.0 * std::sin(2 * M_PI * t / 5.3 + p)) * kDeg;
  j.torso_roll = a * 2.5 * std::sin(2 * M_PI * t / 7.1 + 2 * p) * kDeg;
  j.torso_yaw = a * 8.0 * std::sin(2 * M_PI * t / 6.7 + 3 * p) * kDeg;
  j.head_yaw = a * 25.0 * std::sin(2 * M_PI * t / 4.9 + 1.3 * p) * kDeg;
  j.head_pitch = (5.0 + a * 8.0 * std::sin(2 * M_PI * t / 3.7 + p)) * kDeg;
  for (int side = 0; side < 2; ++side) {
    const double q = p + side * 1.7;
    j.hip[side] = (88.0 + (side == 0 ? 2.0 : -3.0)) * kDeg;
    j.knee[side] = (85.0 + a * 4.0 * std::sin(2 * M_PI * t / 8.3 + q)) * kDeg;
    j.shoulder[side] = (30.0 + a * 25.0 * std::sin(2 * M_PI * t / 3.1 + q)) * kDeg;
    // Forearms forward and up, as over a desk when typing or gesturing: their angle from
    // straight down (torso lean, shoulder and elbow together) stays above 95 degrees, so a
    // desk in front is met from above, never from below, and KeepArmsClear() can rest
    // them on it without a jump.
    const double forearm_from_down = (110.0 + a * 15.0 * std::sin(2 * M_PI * t / 2.3 + 2 * q)) * kDeg;
    j.elbow[side] = forearm_from_down - j.shoulder[side] - j.torso_pitch;
    j.shoulder_out[side] = (10.0 + a * 6.0 * std::sin(2 * M_PI * t / 4.1 + q)) * kDeg;
  }
  return j;
}

std::vector<Eigen::Isometry3d> PersonPartPoses(const PersonJoints& j, double s) {
  const Body& b = kBody;
  std::vector<Eigen::Isometry3d> poses(kNumPersonParts);

  // Pelvis and torso. Sitters sit with the pelvis over the object origin minus a bit,
  // so the body sits on the seat rather than above the chair's front edge.
  const Eigen::Isometry3d T_obj_pelvis =
      Pose(Rz(j.torso_yaw * 0.4), Eigen::Vector3d(0, 0, j.pelvis_height_m * s));
  const Eigen::Isometry3d T_obj_torso =
      T_obj_pelvis * Pose(Rz(j.torso_yaw * 0.6) * Ry(j.torso_pitch) * Rx(j.torso_roll),
                          Eigen::Vector3d::Zero());
  poses[kTorso] = T_obj_torso;
  poses[kHead] = T_obj_torso * Pose(Rz(j.head_yaw) * Ry(j.head_pitch),
                                    Eigen::Vector3d(0, 0, b.neck_height * s));

  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? 1.0 : -1.0;  // left is +y
    // Arm: shoulder flexion about y (forward = rotation by -angle), abduction about x
    // (the hanging arm's hand swings out to its own side, +y for the left arm).
    const Eigen::Isometry3d T_shoulder =
        T_obj_torso * Pose(Rx(y * j.shoulder_out[side]) * Ry(-j.shoulder[side]),
                           Eigen::Vector3d(0, y * b.shoulder_width, b.shoulder_height) * s);
    poses[kUpperArmL + 2 * side] = T_shoulder;
    poses[kLowerArmL + 2 * side] = ElbowPose(T_shoulder, j.elbow[side], s);

    // Leg: hip flexion about y, the knee folds the shank backward. Legs hang from the
    // pelvis, not the torso, so leaning does not move the feet.
    const Eigen::Isometry3d T_hip =
        T_obj_pelvis * Pose(Ry(-j.hip[side]), Eigen::Vector3d(0, y * b.hip_width, -0.02) * s);
    poses[kUpperLegL + 2 * side] = T_hip;
    poses[kLowerLegL + 2 * side] =
        T_hip * Pose(Ry(j.knee[side]), Eigen::Vector3d(0, 0, -b.thigh * s));
  }
  if (j.feet_on_floor) {
    // The shoes are rigid on the shanks (no ankle): the lowest of their box corners
    // touches the floor.
    double lowest_m = std::numeric_limits<double>::infinity();
    for (int side = 0; side < 2; ++side) {
      for (const Eigen::Vector3d& corner : ShoeCorners(s)) {
        lowest_m = std::min(lowest_m, (poses[kLowerLegL + 2 * side] * corner).z());
      }
    }
    for (Eigen::Isometry3d& pose : poses) pose.translation().z() -= lowest_m;
  }
  return poses;
}

}  // namespace segslam::scenes
