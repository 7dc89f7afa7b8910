// ---- Moving actors along the route -----------------------------------------------------
// Moving cars and pedestrians are scripted against the camera: each gets a path on the
// streets of the route and a start offset chosen so that it is in front of the camera
// for a while (ahead in its lane, oncoming, crossing, on the sidewalks, at crosswalks),
// then every candidate is checked at frame rate over both passes for clearance from
// the camera and from the actors placed before it.
//
// This file: the lanes and paths movers take, the frame samples and the tracks of the
// movers placed, and the clearance checks; city_traffic.cpp and city_pedestrians.cpp
// make the movers.
#include "scenes/city_builder_internal.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

namespace segslam::scenes::city_internal {

// A lane through consecutive nodes at `offset` right of the direction of travel, corners
// rounded like the camera's lane, extended straight by ext_before and ext_after.
std::vector<Vec2> CityBuilder::NodeLane(const std::vector<Node>& nodes, double offset, double ext_before, double ext_after) const {
  auto dir = [&](std::size_t k) { return Vec2((NodePos(nodes[k + 1]) - NodePos(nodes[k])).normalized()); };
  std::vector<Vec2> pts;
  const Vec2 d0 = dir(0);
  pts.push_back(NodePos(nodes[0]) - d0 * ext_before + Right(d0) * offset);
  for (std::size_t k = 1; k + 1 < nodes.size(); ++k) {
    const Vec2 a = dir(k - 1), b = dir(k);
    if ((a - b).norm() < 1e-9) continue;
    AppendTurn(nodes[k], a, b, offset, &pts);
  }
  const Vec2 dl = dir(nodes.size() - 2);
  pts.push_back(NodePos(nodes.back()) + dl * ext_after + Right(dl) * offset);
  return pts;
}

// Nodes of the route with the one before the first: the camera's lane is a part of
// NodeLane(RouteNodes(), lane_, e, e) starting at arc length e + block_ / 2.
std::vector<Node> CityBuilder::RouteNodes() const {
  const Node before{2 * nodes_[0].first - nodes_[1].first, 2 * nodes_[0].second - nodes_[1].second};
  std::vector<Node> n = {before};
  n.insert(n.end(), nodes_.begin(), nodes_.end());
  return n;
}

// Whether a ground point is on a raised block (sidewalk) rather than on a street.
bool CityBuilder::OnBlock(const Vec2& p) const {
  if (p.x() < (imin_ - 1) * block_ || p.x() > (imax_ + 1) * block_ || p.y() < (jmin_ - 1) * block_ ||
      p.y() > (jmax_ + 1) * block_) {
    return false;
  }
  const double u = p.x() - block_ * std::round(p.x() / block_), v = p.y() - block_ * std::round(p.y() / block_);
  return std::abs(u) > road_ / 2 && std::abs(v) > road_ / 2;
}

// A walking path through `pts`, resampled every metre, on the sidewalk or the street.
PathMotion CityBuilder::WalkPath(const std::vector<Vec2>& pts) const {
  PathMotion path;
  path.closed = false;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const double len = (pts[i + 1] - pts[i]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len)));
    for (int k = 0; k < n; ++k) {
      const Vec2 q = pts[i] + (pts[i + 1] - pts[i]) * (static_cast<double>(k) / n);
      path.waypoints.push_back(At(q, OnBlock(q) ? kCurbHeightM : 0.0));
    }
  }
  path.waypoints.push_back(At(pts.back(), OnBlock(pts.back()) ? kCurbHeightM : 0.0));
  return path;
}

// Lengthens an open path at both ends so that the mover is on it for the whole of both
// passes: before its start or past its end it would stand still there, and movers timed
// to meet the camera late (or early) would stand in a heap at their paths' ends. Walking
// paths gain points every metre (on the sidewalk or the street, as WalkPath's).
void CityBuilder::CoverBothPasses(PathMotion& path, bool walking) const {
  if (path.closed || path.waypoints.size() < 2) return;
  const double last_s = (std::max(world_.frames_per_pass[0], world_.frames_per_pass[1]) - 1) / s_.camera.fps;
  const auto extension_points = [&](const Eigen::Vector3d& end, const Eigen::Vector3d& inner, double extra_m) {
    const Vec2 from = end.head<2>();
    const Vec2 dir = (from - inner.head<2>()).normalized();
    std::vector<Eigen::Vector3d> pts;  // outward from `end`, the farthest last
    const int n = walking ? std::max(1, static_cast<int>(std::ceil(extra_m))) : 1;
    for (int k = 1; k <= n; ++k) {
      const Vec2 q = from + dir * (extra_m * k / n);
      pts.push_back(At(q, walking && OnBlock(q) ? kCurbHeightM : 0.0));
    }
    return pts;
  };
  constexpr double kSlackM = 1.0;
  const double before_m = kSlackM - PathDistanceAt(path, 0.0);
  if (before_m > 0) {
    std::vector<Eigen::Vector3d> pts = extension_points(path.waypoints[0], path.waypoints[1], before_m);
    path.waypoints.insert(path.waypoints.begin(), pts.rbegin(), pts.rend());
    path.start_offset_m += before_m;
    for (Halt& h : path.halts) h.at_m += before_m;
  }
  const double after_m = PathDistanceAt(path, last_s) + kSlackM - PathLength(path);
  if (after_m > 0) {
    const std::size_t n = path.waypoints.size();
    std::vector<Eigen::Vector3d> pts = extension_points(path.waypoints[n - 1], path.waypoints[n - 2], after_m);
    path.waypoints.insert(path.waypoints.end(), pts.begin(), pts.end());
  }
}

PathMotion CityBuilder::DrivePath(const std::vector<Vec2>& pts) {
  PathMotion path;
  path.closed = false;
  for (const Vec2& q : pts) path.waypoints.push_back(At(q, 0.0));
  return path;
}

RouteLanes CityBuilder::MakeRouteLanes() const {
  const double ext = RouteLanes::kExtensionM;
  const std::vector<Node> fnodes = RouteNodes();
  const std::vector<Node> gnodes(fnodes.rbegin(), fnodes.rend());
  // A second lane in the camera's direction when the road is wide enough.
  const double inner_lane = lane_ - 3.3;
  const bool two_lanes = inner_lane >= 1.4;
  const double same_offset = two_lanes ? inner_lane : lane_;
  return {Poly2(NodeLane(fnodes, lane_, ext, ext)), Poly2(NodeLane(fnodes, same_offset, ext, ext)),
          Poly2(NodeLane(gnodes, same_offset + 0.1, ext, ext)), ext + block_ / 2, two_lanes};
}

// Frame samples of both passes, and the camera car's track at them: a car of kCarDims
// whose front bumper is kCameraToBumperM ahead of the camera, heading along the route
// (pass 2's camera_offset_m moves it, camera_yaw_offset_deg only turns the camera on it).
void CityBuilder::MakeSamples() {
  samples_.clear();
  camera_car_ = Track{};
  camera_car_.half_length = kCarDims.half_length;
  camera_car_.half_width = kCarDims.half_width;
  camera_car_.car = true;
  camera_car_.radius = std::hypot(kCarDims.half_length, kCarDims.half_width);
  for (Pass pass : kBothPasses) {
    sample_stamps_[PassIndex(pass)].clear();
    for (int f = 0; f < world_.frames_per_pass[PassIndex(pass)]; ++f) {
      const double t = FrameStamp(world_, f);
      samples_.push_back({pass, t, CameraPoseAt(world_, pass, t).translation().head<2>()});
      sample_stamps_[PassIndex(pass)].push_back(t);
      // Both passes keep the same timing: pass 1's optical axis is the route's heading.
      const Vec2 heading = CameraPoseAt(world_, Pass::kFirst, t).linear().col(2).head<2>().normalized();
      camera_car_.pos.push_back(samples_.back().camera + (kCameraToBumperM - kCarDims.half_length) * heading);
      camera_car_.heading.push_back(heading);
      camera_car_.present.push_back(1);
    }
  }
}

Track CityBuilder::TrackOf(const Object& o, double half_length, double half_width, bool car) const {
  Track tr;
  tr.half_length = half_length;
  tr.half_width = half_width;
  tr.car = car;
  tr.radius = std::hypot(half_length, half_width);
  tr.radius_with_car_margin = std::hypot(half_length + kCarMarginM, half_width + kCarMarginM);
  tr.radius_with_person_margin = std::hypot(half_length + kPersonMarginM, half_width + kPersonMarginM);
  for (Pass pass : kBothPasses) {  // the order of samples_
    const bool present = o.placement[PassIndex(pass)].present;
    for (const Eigen::Isometry3d& T : ObjectPosesAt(o, pass, sample_stamps_[PassIndex(pass)])) {
      tr.pos.push_back(T.translation().head<2>());
      const double yaw = std::atan2(T.linear()(1, 0), T.linear()(0, 0));
      tr.heading.push_back(Vec2(std::cos(yaw), std::sin(yaw)));
      tr.present.push_back(present);
    }
  }
  return tr;
}

// How clear a track is: min over frames of distance to the camera / min_camera_m and
// the separating-axis ratio against placed actors; >= 1 is clear. Stops below `floor`.
double CityBuilder::Clearance(const Track& tr, double min_camera_m, double floor) const {
  double score = 1e9;
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    if (!tr.present[i]) continue;
    score = std::min(score, (tr.pos[i] - samples_[i].camera).norm() / min_camera_m);
    for (const Track& other : tracks_) {
      if (!other.present[i]) continue;
      const bool cars = tr.car && other.car;
      const double margin = cars ? kCarMarginM : kPersonMarginM;
      // The ratio is at least |d| / (sqrt(2) (r_a + r_b)), with r the radius of an
      // inflated footprint: one of a's two axes carries |d| / sqrt(2) of the distance d,
      // and no extent along an axis exceeds r. Pairs that far apart cannot lower the
      // score (with a margin for rounding), so they are skipped.
      const double radii = cars ? tr.radius_with_car_margin + other.radius_with_car_margin
                                : tr.radius_with_person_margin + other.radius_with_person_margin;
      if ((other.pos[i] - tr.pos[i]).squaredNorm() * (1.0 - 1e-9) > 2.0 * radii * radii * score * score) continue;
      score = std::min(score, SatRatio(tr, other, i, margin));
    }
    if (score <= floor) break;
  }
  return score;
}

// Whether the track's body touches no placed actor's body at any sample (footprints
// without margins; a separating-axis ratio >= 1 for two rectangles means apart).
bool CityBuilder::BodiesClear(const Track& tr) const {
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    if (!tr.present[i]) continue;
    for (const Track& other : tracks_) {
      if (!other.present[i]) continue;
      const double radii = tr.radius + other.radius;
      if ((other.pos[i] - tr.pos[i]).squaredNorm() > radii * radii) continue;
      if (SatRatio(tr, other, i, 0.0) < 1.0) return false;
    }
  }
  return true;
}

// Whether the track's body keeps kCameraCarToVehicleM (a car) or kCameraCarToPersonM
// from the camera car's at every sample (footprints inflated by half of it each, a
// separating-axis ratio >= 1 means that far apart).
bool CityBuilder::CameraCarClear(const Track& tr) const {
  const double margin = 0.5 * (tr.car ? kCameraCarToVehicleM : kCameraCarToPersonM);
  // Pairs further apart than sqrt(2) times the inflated radii are clear (Clearance).
  const double radii = std::hypot(tr.half_length + margin, tr.half_width + margin) +
                       std::hypot(camera_car_.half_length + margin, camera_car_.half_width + margin);
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    if (!tr.present[i]) continue;
    if ((camera_car_.pos[i] - tr.pos[i]).squaredNorm() > 2.0 * radii * radii) continue;
    if (SatRatio(tr, camera_car_, i, margin) < 1.0) return false;
  }
  return true;
}

// Tries paths from `make(attempt)` on the object (moving, on the same path in each pass
// it is `present` in, absent from the other) and keeps the clearest of those whose body
// touches no other actor's and keeps clear of the camera car's (CameraCarClear),
// recording its track. When `attempts` find no such path, up to three times as many
// more are tried; when none does either, the object is taken out of the world again (it
// is the last one added) and false is returned: a crowd denser than the streets hold
// gets fewer actors, never actors that run through each other or the camera car.
bool CityBuilder::PlaceMover(int index, const std::array<bool, 2>& present, double half_length, double half_width, bool car,
                             double min_camera_m, int attempts, const std::function<PathMotion(int)>& make) {
  Object& o = world_.objects[index];
  double best = -1;
  bool best_clear = false;
  std::array<Placement, 2> best_placement = o.placement;
  Track best_track;
  for (int a = 0; a < 4 * attempts && !(a >= attempts && best_clear); ++a) {
    Placement p;
    p.present = true;
    p.moving = true;
    p.path = make(a);
    CoverBothPasses(p.path, /*walking=*/!car);
    Placement absent;
    absent.present = false;
    o.placement = {present[0] ? p : absent, present[1] ? p : absent};
    Track tr = TrackOf(o, half_length, half_width, car);
    // Once a clear path is kept, Clearance may stop as soon as it cannot beat it.
    const double score = Clearance(tr, min_camera_m, best_clear ? best : -1.0);
    if (best_clear && score <= best) continue;
    // Margins >= 1: bodies apart.
    const bool clear = (score >= 1.0 || BodiesClear(tr)) && CameraCarClear(tr);
    if (clear != best_clear ? clear : score > best) {
      best = score;
      best_clear = clear;
      best_placement = o.placement;
      best_track = std::move(tr);
    }
    if (best >= 1.0) break;
  }
  if (!best_clear) {
    assert(index + 1 == static_cast<int>(world_.objects.size()));
    world_.objects.pop_back();
    ++movers_left_out_;
    return false;
  }
  o.placement = best_placement;
  tracks_.push_back(std::move(best_track));
  return true;
}

}  // namespace segslam::scenes::city_internal
