// Time queries on a World: camera poses, object poses along their paths, and the
// articulated poses of people.
#include "scenes/world.h"

#include "scenes/person.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace segslam::scenes {
namespace {

// Arc-length parametrisation of a polyline (closed: the last point joins the first).
struct Polyline {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> cumulative;  // arc length at each point, plus the closing point
  double length = 0.0;
  bool closed = false;

  Polyline(const std::vector<Eigen::Vector3d>& waypoints, bool is_closed)
      : points(waypoints), closed(is_closed) {
    if (closed && !points.empty()) points.push_back(points.front());
    cumulative.assign(points.size(), 0.0);
    for (std::size_t i = 1; i < points.size(); ++i) {
      cumulative[i] = cumulative[i - 1] + (points[i] - points[i - 1]).norm();
    }
    length = cumulative.empty() ? 0.0 : cumulative.back();
  }

  // Point at arc length s: wrapped on closed paths, clamped on open ones.
  Eigen::Vector3d At(double s) const {
    if (points.size() == 1 || length <= 0.0) return points.front();
    if (closed) {
      s = std::fmod(s, length);
      if (s < 0) s += length;
    } else {
      s = std::clamp(s, 0.0, length);
    }
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), s);
    const std::size_t i = std::clamp<std::size_t>(it - cumulative.begin(), 1, points.size() - 1);
    const double seg = cumulative[i] - cumulative[i - 1];
    const double u = seg > 0 ? (s - cumulative[i - 1]) / seg : 0.0;
    return points[i - 1] + u * (points[i] - points[i - 1]);
  }

  double ShortestSegment() const {
    double m = length;
    for (std::size_t i = 1; i < points.size(); ++i) {
      m = std::min(m, cumulative[i] - cumulative[i - 1]);
    }
    return m;
  }
};

double SmoothStep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

double Yaw(const Eigen::Vector3d& d) { return std::atan2(d.y(), d.x()); }

// Half the window over which corners are rounded: longer for faster movers (a car
// turns on a wider arc than a person), never more than a third of a segment.
double TurnHalfWindow(const PathMotion& path, const Polyline& line) {
  return std::min(std::clamp(0.5 * path.speed_mps, 0.3, 3.0), 0.3 * line.ShortestSegment());
}

Eigen::Isometry3d PoseOf(const Eigen::Vector3d& position, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
  T.translation() = position;
  return T;
}

// Pose on the path at arc length s (distance travelled since the path's start); `line`
// is Polyline(path.waypoints, path.closed).
Eigen::Isometry3d PathPose(const PathMotion& path, const Polyline& line, double s) {
  if (line.points.size() < 2 || line.length <= 1e-9) return PoseOf(path.waypoints.front(), 0.0);
  const double d = TurnHalfWindow(path, line);

  // Closed loop: the chord midpoint rounds the corners; the chord gives the heading.
  if (path.closed) {
    const Eigen::Vector3d a = line.At(s - d), b = line.At(s + d);
    return PoseOf(0.5 * (a + b), Yaw(b - a));
  }

  // Open path: ping-pong. `u` runs over [0, 2L); the way back mirrors the way out.
  const double L = line.length;
  double u = std::fmod(s, 2.0 * L);
  if (u < 0) u += 2.0 * L;
  const bool outward = u <= L;
  const double a_len = outward ? u : 2.0 * L - u;
  const Eigen::Vector3d a = line.At(a_len - d), b = line.At(a_len + d);
  const Eigen::Vector3d position = 0.5 * (a + b);
  double yaw = Yaw(b - a) + (outward ? 0.0 : M_PI);

  // Turn around smoothly over `r` metres either side of each end.
  const double r = std::min(0.5, 0.2 * L);
  if (std::abs(u - L) < r) {
    const double end_yaw = Yaw(line.At(L) - line.At(L - 2 * d));
    yaw = end_yaw + M_PI * SmoothStep((u - L + r) / (2 * r));
  } else if (u < r || u > 2.0 * L - r) {
    const double p = u > L ? u - 2.0 * L : u;
    const double start_yaw = Yaw(line.At(2 * d) - line.At(0.0));
    yaw = start_yaw + M_PI + M_PI * SmoothStep((p + r) / (2 * r));
  }
  return PoseOf(position, yaw);
}

Eigen::Vector3d CatmullRom(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                           const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, double u) {
  const double u2 = u * u, u3 = u2 * u;
  return 0.5 * ((2.0 * p1) + (-p0 + p2) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u2 +
                (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * u3);
}

}  // namespace

double DistanceWithHalts(double start_m, double speed_mps, const std::vector<Halt>& halts, double accel_mps2,
                         double t) {
  const double v = speed_mps, a = accel_mps2;
  if (v <= 0.0 || a <= 0.0) return start_m + v * t;
  const double ramp_s = v / a, ramp_m = 0.5 * v * v / a;  // time and distance to stop from v
  double delay_s = 0.0;  // behind the schedule of cruising straight through
  // Set while the mover stands at a halt (or starts standing) from which it does not get
  // back to cruising speed before braking for the next one: when it pulls away, and where.
  std::optional<double> pull_away_s;
  double from_m = start_m;
  for (std::size_t i = 0; i < halts.size(); ++i) {
    const Halt& h = halts[i];
    // Pulling away from h, it would still be speeding up where it has to brake for the next.
    const bool next_near = i + 1 < halts.size() && halts[i + 1].at_m - h.at_m < 2.0 * ramp_m;
    if (!pull_away_s && h.at_m == start_m) pull_away_s = 0.0;  // a standing start
    double go_s = 0.0;  // when it pulls away from h
    if (!pull_away_s) {
      // Reached at cruising speed: brakes over ramp_m, stands, pulls away over ramp_m.
      if (h.at_m - ramp_m < start_m) continue;  // already past (or braking) at t = 0: ignored
      const double brake_from = (h.at_m - ramp_m - start_m) / v + delay_s;
      if (t < brake_from) break;
      const double tau = t - brake_from;
      if (tau < ramp_s) return h.at_m - ramp_m + v * tau - 0.5 * a * tau * tau;
      if (tau < ramp_s + h.wait_s) return h.at_m;
      if (!next_near) {
        if (tau < 2.0 * ramp_s + h.wait_s) {
          const double go = tau - ramp_s - h.wait_s;
          return h.at_m + 0.5 * a * go * go;
        }
        delay_s += h.wait_s + ramp_s;
        continue;
      }
      go_s = brake_from + ramp_s + h.wait_s;
    } else {
      // Reached from standing at from_m, nearer than v^2 / a: speeds up over the first half
      // of the way and brakes over the second, never reaching cruising speed.
      const double half_s = std::sqrt(std::max(0.0, h.at_m - from_m) / a);
      const double tau = t - *pull_away_s;
      if (tau < half_s) return from_m + 0.5 * a * tau * tau;
      if (tau < 2.0 * half_s) {
        const double left = 2.0 * half_s - tau;
        return h.at_m - 0.5 * a * left * left;
      }
      if (tau < 2.0 * half_s + h.wait_s) return h.at_m;
      go_s = *pull_away_s + 2.0 * half_s + h.wait_s;
      if (!next_near) {
        const double go = t - go_s;
        if (go < ramp_s) return h.at_m + 0.5 * a * go * go;
        // Back at cruising speed ramp_m past h, ramp_s after pulling away.
        delay_s = go_s + ramp_s - (h.at_m + ramp_m - start_m) / v;
        pull_away_s.reset();
        continue;
      }
    }
    pull_away_s = go_s;
    from_m = h.at_m;
  }
  return start_m + v * (t - delay_s);
}

double PathLength(const PathMotion& path) {
  if (path.waypoints.empty()) return 0.0;
  return Polyline(path.waypoints, path.closed).length;
}

double PathDistanceAt(const PathMotion& path, double t) {
  return DistanceWithHalts(path.start_offset_m, path.speed_mps, path.halts, path.accel_mps2, t);
}

Eigen::Isometry3d CameraPoseAt(const World& world, Pass pass, double stamp_s) {
  const std::vector<CameraKey>& keys = world.camera_route[PassIndex(pass)].keys;
  if (keys.empty()) return Eigen::Isometry3d::Identity();
  if (stamp_s <= keys.front().stamp_s) return keys.front().T_wc;
  if (stamp_s >= keys.back().stamp_s) return keys.back().T_wc;

  // The segment [i, i + 1] holding the stamp.
  const auto it = std::upper_bound(keys.begin(), keys.end(), stamp_s,
                                   [](double t, const CameraKey& k) { return t < k.stamp_s; });
  const int n = static_cast<int>(keys.size());
  const int i = static_cast<int>(it - keys.begin()) - 1;
  const double u = (stamp_s - keys[i].stamp_s) / (keys[i + 1].stamp_s - keys[i].stamp_s);

  // Position: Catmull-Rom through the neighbouring keys; rotation: slerp.
  auto P = [&](int k) { return keys[std::clamp(k, 0, n - 1)].T_wc.translation(); };
  const Eigen::Quaterniond q0(keys[i].T_wc.linear()), q1(keys[i + 1].T_wc.linear());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q0.slerp(u, q1).normalized().toRotationMatrix();
  T.translation() = CatmullRom(P(i - 1), P(i), P(i + 1), P(i + 2), u);
  return T;
}

Eigen::Isometry3d ObjectPoseAt(const Object& object, Pass pass, double stamp_s) {
  const Placement& p = object.placement[PassIndex(pass)];
  if (!p.present) return Eigen::Isometry3d::Identity();
  if (!p.moving || p.path.waypoints.empty()) return p.T_world_object;
  return PathPose(p.path, Polyline(p.path.waypoints, p.path.closed), PathDistanceAt(p.path, stamp_s));
}

std::vector<Eigen::Isometry3d> ObjectPosesAt(const Object& object, Pass pass, const std::vector<double>& stamps_s) {
  const Placement& p = object.placement[PassIndex(pass)];
  if (!p.present) return std::vector<Eigen::Isometry3d>(stamps_s.size(), Eigen::Isometry3d::Identity());
  if (!p.moving || p.path.waypoints.empty()) return std::vector<Eigen::Isometry3d>(stamps_s.size(), p.T_world_object);
  const Polyline line(p.path.waypoints, p.path.closed);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(stamps_s.size());
  for (double t : stamps_s) poses.push_back(PathPose(p.path, line, PathDistanceAt(p.path, t)));
  return poses;
}

std::vector<Eigen::Isometry3d> PartPosesAt(const Object& object, Pass pass, double stamp_s) {
  const Placement& p = object.placement[PassIndex(pass)];
  if (!p.present) return {};
  const Eigen::Isometry3d T_world_object = ObjectPoseAt(object, pass, stamp_s);

  // Rigid objects: every part frame is the object frame.
  if (object.articulation == Articulation::kRigid ||
      object.parts.size() != static_cast<std::size_t>(kNumPersonParts)) {
    return std::vector<Eigen::Isometry3d>(object.parts.size(), T_world_object);
  }

  // People: joint angles from the distance walked, or from time when seated.
  PersonJoints joints;
  if (object.articulation == Articulation::kWalker) {
    const bool walking = p.moving && p.path.speed_mps > 0 && p.path.waypoints.size() > 1;
    const double walked_m = walking ? PathDistanceAt(p.path, stamp_s) - p.path.start_offset_m : 0.0;
    const double stride_m = kStrideLengthM * object.body_scale;
    joints = WalkJoints(walked_m / stride_m + object.gait_phase_offset, walking ? 1.0 : 0.0);
  } else {
    joints = SitJoints(stamp_s, object.gait_phase_offset, object.animated);
    KeepArmsClear(p.arm_obstacles, object.body_scale, &joints);
  }
  std::vector<Eigen::Isometry3d> poses = PersonPartPoses(joints, object.body_scale);
  for (Eigen::Isometry3d& T : poses) T = T_world_object * T;
  return poses;
}

bool ObjectMovesAt(const Object& object, Pass pass, double stamp_s, double dt_s) {
  const std::vector<Eigen::Isometry3d> a = PartPosesAt(object, pass, stamp_s);
  const std::vector<Eigen::Isometry3d> b = PartPosesAt(object, pass, stamp_s + dt_s);
  // Moving: any part shifts by more than 1 mm or turns by more than 0.05 degrees.
  constexpr double kMinShiftM = 1e-3;
  constexpr double kMinTurnRad = 0.05 * M_PI / 180.0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    if ((a[i].translation() - b[i].translation()).norm() > kMinShiftM) return true;
    const Eigen::AngleAxisd turn(a[i].linear().transpose() * b[i].linear());
    if (std::abs(turn.angle()) > kMinTurnRad) return true;
  }
  return false;
}

}  // namespace segslam::scenes
