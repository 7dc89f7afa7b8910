// The city's pedestrians (city_movers.cpp places them): walking along the sidewalks of
// the route's streets, and crossing at crosswalks ahead or in front of a standing camera.
#include "scenes/city_builder_internal.h"
#include "scenes/person.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace segslam::scenes::city_internal {

Object& CityBuilder::MakePedestrian(std::mt19937_64& rng) {
  Object& o = b_.AddObject("person");
  o.articulation = Articulation::kWalker;
  o.body_scale = Uniform(rng, 0.92, 1.08);
  o.gait_phase_offset = Uniform(rng, 0, 1);
  PersonLook look;
  const float skin = static_cast<float>(Uniform(rng, 0.35, 0.95));
  look.skin = b_.AddMaterial("skin", look_.skin_texture, Eigen::Vector4f(skin, skin * 0.78f, skin * 0.62f, 1));
  look.hair = b_.AddMaterial("hair", -1, Eigen::Vector4f(0.1f, 0.07f, 0.05f, 1) * static_cast<float>(Uniform(rng, 0.5, 3.0)));
  auto cloth = [&](const std::string& name) {
    const Eigen::Vector4f c(static_cast<float>(Uniform(rng, 0.15, 1)), static_cast<float>(Uniform(rng, 0.15, 1)),
                            static_cast<float>(Uniform(rng, 0.15, 1)), 1);
    return b_.AddMaterial(name, look_.clothes_textures[UniformInt(rng, 0, 5)], c);
  };
  look.shirt = cloth("shirt");
  look.pants = cloth("pants");
  look.shoes = b_.AddMaterial("shoes", -1, Eigen::Vector4f(0.1f, 0.1f, 0.1f, 1) * static_cast<float>(Uniform(rng, 1, 4)));
  world_.materials[look.hair].rgba.w() = 1;
  world_.materials[look.shoes].rgba.w() = 1;
  o.parts = MakePersonParts(look, o.body_scale);
  return o;
}

// The crosswalks pedestrians cross: those before the red lights when there are any,
// else those before the intersections ahead on the route.
std::vector<Crosswalk> CityBuilder::CrosswalksOnRoute(const RouteLanes& lanes) const {
  // An explicit Vec2: an Eigen expression of a temporary must not be returned.
  const auto crosswalk_before = [&](std::size_t k) -> Vec2 {
    return NodePos(nodes_[k]) - kStreetDirs[dirs_[k]] * (road_ / 2 + 2.0);
  };
  std::vector<Crosswalk> crosswalks;
  for (const RedLight& r : red_lights_) crosswalks.push_back({crosswalk_before(r.node), r.arrive, 0.0, &r});
  if (!red_lights_.empty()) return crosswalks;
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const Vec2 a = kStreetDirs[dirs_[k]];
    const Vec2 centre = crosswalk_before(k);
    const double s = lanes.forward.Closest(centre + Right(a) * lane_) - lanes.f0;
    if (s > 24.0 && s < camera_lane_.Length() + 30.0) crosswalks.push_back({centre, a, s, nullptr});
  }
  return crosswalks;
}

// How far from the curb a pedestrian walks along a sidewalk: drawn over its middle and
// kept in the strip between the trees and lamps and the benches (the scenario's
// smallest sidewalk leaves that strip room).
double CityBuilder::SidewalkLineFromCurb(std::mt19937_64& rng) const {
  return std::clamp(walk_ * Uniform(rng, 0.45, 0.6), kWalkStripNearM, walk_ - kWalkStripFarM);
}

// The same, keeping right: the strip's half toward the buildings for one walking with
// them on the right hand, toward the curb otherwise, the halves a body's width apart
// so that people meeting each other pass. A strip too narrow for that is shared.
double CityBuilder::KeepRightLineFromCurb(std::mt19937_64& rng, bool buildings_on_the_right) const {
  const double near = kWalkStripNearM, far = walk_ - kWalkStripFarM;
  const double band = 0.5 * (far - near - 2 * kWalkerClearanceM);
  if (band < 0) return SidewalkLineFromCurb(rng);
  return buildings_on_the_right ? Uniform(rng, far - band, far) : Uniform(rng, near, near + band);
}

// Crossing pedestrian k of `crossers` at `speed`, attempt `a` of its placement: over a
// crosswalk (spread by k for the first attempts), in the middle of the street when the
// camera is 16-32 m before it; at a red light, while the camera stands, and off the
// street before it turns green.
PathMotion CityBuilder::CrossingWalkerMotion(std::mt19937_64& rng, const std::vector<Crosswalk>& crosswalks, int k,
                                             int crossers, double speed, int a) const {
  const Crosswalk& c = crosswalks[(k * crosswalks.size() / crossers + a / 4) % crosswalks.size()];
  const double side = Chance(rng, 0.5) ? 1.0 : -1.0;  // starts right (+1) or left
  // Keeping right on the sidewalks: the first leg walks -before * along towards the
  // crosswalk on this side, the last one after * along away from it on the other (at a
  // light both back the way the camera came). With after = before both legs have the
  // buildings on the same hand, so one line from the curb keeps right on both.
  double before = -1.0, after = -1.0;
  if (!c.light) before = after = Chance(rng, 0.5) ? 1.0 : -1.0;
  const double w = road_ / 2 + KeepRightLineFromCurb(rng, -before * side > 0);
  // A crowd at a red light keeps to the far part of the crosswalk (the near edge is
  // 2.5 m from the camera) and to the sidewalks of the camera's street before and after,
  // off the way the camera takes when the light turns green. Keeping right on the
  // crosswalk too, those starting on the right take its +along half.
  const double across = c.light ? (side > 0 ? Uniform(rng, 0.5, 1.3) : Uniform(rng, -0.5, -0.1))
                                : side * Uniform(rng, 0.3, 1.2);
  const Vec2 line = c.centre + c.along * across;
  const Vec2 from = line + Right(c.along) * side * w, to = line - Right(c.along) * side * w;
  const double leg = 60.0;
  PathMotion p = WalkPath({from + c.along * before * leg, from, to, to + c.along * after * leg});
  p.speed_mps = speed;
  double t_mid;
  if (c.light) {
    const double earliest = c.light->stand_from_s + 1.0;
    const double latest = c.light->stand_until_s - 1.0 - w / speed;
    t_mid = Uniform(rng, earliest, std::max(earliest, latest));
  } else {
    t_mid = CameraTimeAt(std::max(0.0, c.s - Uniform(rng, 16.0, 32.0)));
  }
  p.start_offset_m = leg + w - speed * t_mid;
  return p;
}

// Pedestrian `rank` of `walkers` on the sidewalks, attempt `a`: walks along the street
// 12-30 m ahead of where the camera is at a time spread over the pass (by rank for the
// first ten attempts), on alternating sides.
PathMotion CityBuilder::SidewalkWalkerMotion(std::mt19937_64& rng, const RouteLanes& lanes, int rank, int walkers,
                                             double speed, int a) const {
  const Poly2& forward = lanes.forward;
  const double f0 = lanes.f0;
  const double duration = (world_.frames_per_pass[0] - 1) / s_.camera.fps;
  const double u = a < 10 ? (rank + Uniform(rng, 0.1, 0.9)) / walkers : Uniform(rng, 0, 1);
  const double t_meet = u * duration;
  const double s = CameraArc(t_meet) + Uniform(rng, 12.0, 30.0);
  const Vec2 t = forward.Tangent(f0 + s);
  const Vec2 along = std::abs(t.x()) >= std::abs(t.y()) ? Vec2(t.x() > 0 ? 1 : -1, 0) : Vec2(0, t.y() > 0 ? 1 : -1);
  Vec2 axis = forward.At(f0 + s) - Right(along) * lane_;
  if (along.x() != 0) axis.y() = block_ * std::round(axis.y() / block_);  // snap to the street line
  else axis.x() = block_ * std::round(axis.x() / block_);
  const double side = (rank + a) % 2 == 0 ? 1.0 : -1.0;
  const double heading = Chance(rng, 0.5) ? 1.0 : -1.0;
  const Vec2 at = axis + Right(along) * side * (road_ / 2 + KeepRightLineFromCurb(rng, heading * side > 0));
  const double leg = 80.0;
  PathMotion p = WalkPath({at - along * heading * leg, at + along * heading * leg});
  p.speed_mps = speed;
  p.start_offset_m = leg - speed * t_meet;
  return p;
}

// Pedestrians on the sidewalks of the route's streets, walking both ways, each timed to
// be 12-30 m ahead of the camera at a time spread over the pass; crossing_share of them
// cross the route's street at a crosswalk ahead while the camera is 16-32 m away, or,
// with red lights, over the crosswalk in front of the camera while it stands there.
void CityBuilder::MakePedestrians(const Traffic& traffic) {
  std::mt19937_64 rng = Rng("pedestrians" + traffic.tag);
  const int n = spec_.pedestrians;
  if (n <= 0) return;
  const RouteLanes lanes = MakeRouteLanes();
  const std::vector<Crosswalk> crosswalks = CrosswalksOnRoute(lanes);
  const int crossers = crosswalks.empty() ? 0 : static_cast<int>(std::lround(spec_.crossing_share * n));
  for (int k = 0; k < n; ++k) {
    MakePedestrian(rng);
    const int index = static_cast<int>(world_.objects.size()) - 1;
    const double speed = spec_.pedestrian_speed_mps * Uniform(rng, 0.85, 1.15);
    std::function<PathMotion(int)> make;
    if (k < crossers) {
      make = [&, k, speed](int a) { return CrossingWalkerMotion(rng, crosswalks, k, crossers, speed, a); };
    } else {
      make = [&, rank = k - crossers, speed](int a) {
        return SidewalkWalkerMotion(rng, lanes, rank, n - crossers, speed, a);
      };
    }
    // The crosswalk in front of a standing camera car is 4 m from the camera.
    const double min_camera_m = k < crossers && !red_lights_.empty() ? 3.5 : 4.2;
    PlaceMover(index, traffic.present, 0.3, 0.3, /*car=*/false, min_camera_m, 40, make);
  }
}

}  // namespace segslam::scenes::city_internal
