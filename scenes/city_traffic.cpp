// The city's moving cars (city_movers.cpp places them): the vehicles the camera waits
// behind at red lights, and cars ahead of it, oncoming and crossing.
#include "scenes/city_builder_internal.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

namespace segslam::scenes::city_internal {

// The vehicles the camera waits behind at red lights. Each comes along the camera's
// lane ahead of it at the camera's speed, stands at the stop line from a few seconds
// before the camera would stand behind it had it not stopped at the lights before,
// pulls away kReactionS before the camera does, and leaves the route at that
// intersection (straight on where the camera turns, right where it goes straight), so
// no two of them meet in the camera's lane. It makes no stop before its own: it passes
// the lights before ahead of the camera, and ahead of their leads (at least
// kQueueGapM + kLeadFollowS of the speed bumper to bumper), before they turn red, and
// waits out the camera's stops at its own light. One that would have to brake for its
// light before the pass starts brakes from the start (or stands at its stop line from
// the start, if braking from there would put it behind a lead before it).
void CityBuilder::MakeRedLightLeads(const std::vector<Node>& fnodes, const Traffic& traffic) {
  std::mt19937_64 rng = Rng("red_light_leads" + traffic.tag);
  const double v = spec_.camera_speed_mps;
  const double ramp_s = v / kCarAccelMps2, ramp_m = 0.5 * v * ramp_s;
  const double follow_m = kQueueGapM + kLeadFollowS * v;  // bumper to bumper, cruising
  // Of the leads placed: where each is at t = 0 on the camera's lane (camera arc
  // length), cruising at v, and its half length.
  std::vector<std::pair<double, double>> placed;
  double delay_s = 0.0;  // the camera's, from its stops at the lights before
  for (std::size_t k = 0; k < red_lights_.size(); ++k) {
    const RedLight& r = red_lights_[k];
    if (k > 0) delay_s += camera_halts_[k - 1].wait_s + ramp_s;
    if (r.lead_kind.empty()) continue;
    Object& o = b_.AddObject(r.lead_kind);
    o.parts.push_back(MakeVehicle(rng, o.category_name));
    const int index = static_cast<int>(world_.objects.size()) - 1;
    // Straight lead-in long enough that the start offset stays on the path.
    const double ext_before = v * r.stand_from_s + 200.0;
    const double camera_start = ext_before + block_ / 2;  // the camera's start on the path
    const Poly2 lane(NodeLane(fnodes, lane_, ext_before, 300.0));
    const Vec2 stop_line = StopLinePoint(r.node, r.arrive);
    // Where the camera's lane meets the stop line, not where the lane's straight
    // extension past the route's end, or the route again, passes it.
    const double stop_arc_expected =
        camera_start + r.camera_stop_s + kCameraToBumperM + 2 * Dims(r.lead_kind).half_length + kQueueGapM;
    const double stop_arc = lane.Closest(stop_line, stop_arc_expected - 10.0, stop_arc_expected + 10.0);
    std::vector<Vec2> pts;
    for (std::size_t i = 0; i < lane.p.size() && lane.c[i] < stop_arc; ++i) pts.push_back(lane.p[i]);
    pts.push_back(stop_line);
    const bool camera_turns = r.node + 1 < nodes_.size() && dirs_[r.node + 1] != dirs_[r.node];
    const Vec2 node = NodePos(nodes_[r.node]);
    if (camera_turns) {
      pts.push_back(node + Right(r.arrive) * lane_ + r.arrive * 300.0);
    } else {
      const Vec2 exit = Right(r.arrive);
      const Vec2 corner = node + Right(r.arrive) * lane_ + Right(exit) * lane_;
      pts.push_back(corner);
      pts.push_back(corner + exit * 300.0);
    }
    const VehicleDims dims = Dims(r.lead_kind);
    const double stand_at = stop_arc - dims.half_length;  // its front at the stop line
    // Least start offset that keeps it ahead of the leads placed before.
    double least_start = -1e18;
    for (const auto& [at_m, half_length] : placed) {
      least_start = std::max(least_start, camera_start + at_m + half_length + follow_m + dims.half_length);
    }
    const double goes_at = r.stand_until_s - kReactionS;
    const bool kept = PlaceMover(index, traffic.present, dims.half_length, dims.half_width, /*car=*/true,
                                /*min_camera_m=*/3.15, 40, [&](int) {
      PathMotion p = DrivePath(pts);
      p.speed_mps = v;
      p.accel_mps2 = kCarAccelMps2;
      double stands_from = r.stand_from_s - (delay_s + Uniform(rng, 1.5, 4.0));
      p.start_offset_m = stand_at - ramp_m - v * (stands_from - ramp_s);
      if (p.start_offset_m < least_start) {
        stands_from -= (least_start - p.start_offset_m) / v;
        p.start_offset_m = stand_at - ramp_m - v * (stands_from - ramp_s);
      }
      if (stands_from < ramp_s) {
        // Too near its light to cruise ahead that long: braking for it from t = 0 (the
        // camera, braking later from further back, keeps its distance), or, where that
        // would put it behind a lead placed before, standing there from t = 0.
        stands_from = ramp_s;
        p.start_offset_m = stand_at - ramp_m;
        if (p.start_offset_m < least_start) {
          stands_from = 0.0;
          p.start_offset_m = stand_at;
        }
      }
      p.halts = {{stand_at, goes_at - stands_from}};
      return p;
    });
    if (kept) {
      const PathMotion& path = world_.objects[index].placement[traffic.present[0] ? 0 : 1].path;
      placed.push_back({path.start_offset_m - camera_start, dims.half_length});
    }
  }
}

std::vector<Crossing> CityBuilder::CrossingsOnRoute(const RouteLanes& lanes) const {
  std::vector<Crossing> crossings;
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const double s = lanes.forward.Closest(NodePos(nodes_[k])) - lanes.f0;
    if (s > 16.0 && s < camera_lane_.Length() + 20.0) crossings.push_back({nodes_[k], kStreetDirs[dirs_[k]], s});
  }
  return crossings;
}

// Route arc length of the camera's turns.
std::vector<double> CityBuilder::TurnsOnRoute(const RouteLanes& lanes) const {
  std::vector<double> turns;
  for (std::size_t k = 1; k + 1 < nodes_.size(); ++k) {
    if (dirs_[k] != dirs_[k + 1]) turns.push_back(lanes.forward.Closest(NodePos(nodes_[k])) - lanes.f0);
  }
  return turns;
}

// Roles in turn: ahead, oncoming, crossing, second ahead, then oncoming and crossing.
// A one-lane queue ahead would run into the vehicles the camera waits behind at red
// lights, so with those the camera's lane holds only them. Without an intersection
// ahead on the route, crossing cars come oncoming instead.
std::vector<CarRole> CityBuilder::MovingCarRoles(bool two_lanes, bool any_crossing) const {
  const bool leads = std::any_of(red_lights_.begin(), red_lights_.end(),
                                 [](const RedLight& r) { return !r.lead_kind.empty(); });
  const bool queue_ahead = two_lanes || !leads;
  const CarRole pattern[] = {CarRole::kAhead, CarRole::kOncoming, CarRole::kCrossing,
                             CarRole::kAhead, CarRole::kOncoming, CarRole::kCrossing};
  std::vector<CarRole> roles;
  for (int k = 0; k < spec_.moving_cars; ++k) {
    CarRole role = k < 6 ? pattern[k] : (k % 2 == 0 ? CarRole::kOncoming : CarRole::kCrossing);
    if (role == CarRole::kAhead && !queue_ahead) role = CarRole::kOncoming;
    if (role == CarRole::kCrossing && !any_crossing) role = CarRole::kOncoming;
    roles.push_back(role);
  }
  return roles;
}

// Ahead in the camera's direction, attempt `a` of its placement. Two lanes: in the
// inner one at about the traffic's speed. One lane: a queue in front of the camera,
// each car (rank 0 first) at least as fast as the one behind it, which is placed at
// `previous_gap` ahead of the camera with `previous_speed`.
PathMotion CityBuilder::AheadMotion(std::mt19937_64& rng, const RouteLanes& lanes, int rank, double half_length, int a,
                                    double previous_gap, double previous_speed) const {
  PathMotion p = DrivePath(lanes.same.p);
  if (lanes.two_lanes) {
    p.speed_mps = spec_.moving_car_speed_mps * Uniform(rng, 0.9, 1.2);
    p.start_offset_m = lanes.f0 + Uniform(rng, 5.0, 25.0);
    return p;
  }
  // Later attempts widen the ranges, up to three times the speed ahead and 80 m more
  // gap (PlaceMover's retries go on with the widest).
  const int widen = std::min(a, 39);
  const double slack = 0.05 * widen;
  if (rank == 0) {
    p.speed_mps = std::max(spec_.camera_speed_mps, spec_.moving_car_speed_mps) * Uniform(rng, 1.0, 1.04 + slack);
    p.start_offset_m = lanes.f0 + Uniform(rng, 7.5, 10.0 + 2 * widen) + (half_length - 2.45);
  } else {
    p.speed_mps = previous_speed * Uniform(rng, 1.0, 1.03 + slack);
    p.start_offset_m = lanes.f0 + previous_gap + Uniform(rng, 11.0, 16.0 + 2 * widen) + (half_length - 2.45);
  }
  return p;
}

// Oncoming: meets the camera at a route position spread over the route (by rank among
// `count` oncoming cars for the first ten attempts), not in a turn, where it would pass
// beside the camera out of view.
PathMotion CityBuilder::OncomingMotion(std::mt19937_64& rng, const RouteLanes& lanes, const std::vector<double>& turns, int rank,
                                       int count, int a) const {
  PathMotion p = DrivePath(lanes.opposite.p);
  p.speed_mps = spec_.moving_car_speed_mps * Uniform(rng, 0.85, 1.15);
  const double lo = 10.0, hi = camera_lane_.Length() - 5.0;
  const double u = a < 10 ? (rank + Uniform(rng, 0.15, 0.85)) / count : Uniform(rng, 0, 1);
  double s_meet = lo + (hi - lo) * u;
  for (double s_turn : turns) {
    if (std::abs(s_meet - s_turn) < 15.0) s_meet = s_turn + (s_meet < s_turn ? -15.0 : 15.0);
  }
  const double q_meet = lanes.opposite.Closest(lanes.forward.At(lanes.f0 + s_meet));
  p.start_offset_m = q_meet - p.speed_mps * CameraTimeAt(s_meet);
  return p;
}

// Crossing: through an intersection ahead while the camera is 12-32 m before it; with
// red lights, through one where the camera stands, while it stands. The first ten
// attempts spread the cars over the intersections by rank among `count`.
PathMotion CityBuilder::CrossingMotion(std::mt19937_64& rng, const std::vector<Crossing>& crossings, int rank, int count,
                                       int a) const {
  const double ext = RouteLanes::kExtensionM;
  if (!red_lights_.empty()) {
    const std::size_t pick = a < 10 ? (rank + a / 3) % red_lights_.size()
                                    : UniformInt(rng, 0, static_cast<int>(red_lights_.size()) - 1);
    const RedLight& r = red_lights_[pick];
    const Vec2 d = Right(r.arrive) * (Chance(rng, 0.5) ? 1.0 : -1.0);
    const Vec2 centre = NodePos(nodes_[r.node]) + Right(d) * lane_;
    PathMotion p = DrivePath({centre - d * ext, centre + d * ext});
    p.speed_mps = spec_.moving_car_speed_mps * Uniform(rng, 0.85, 1.15);
    const double t_cross = Uniform(rng, r.stand_from_s + 0.5, r.stand_until_s - 0.5);
    p.start_offset_m = ext - p.speed_mps * t_cross;
    return p;
  }
  const Crossing& c = crossings[a < 10 ? (rank * crossings.size() / std::max(1, count) + a / 3) % crossings.size()
                                       : UniformInt(rng, 0, static_cast<int>(crossings.size()) - 1)];
  const Vec2 d = Right(c.arrive) * (Chance(rng, 0.5) ? 1.0 : -1.0);
  const Vec2 centre = NodePos(c.node) + Right(d) * lane_;
  PathMotion p = DrivePath({centre - d * ext, centre + d * ext});
  p.speed_mps = spec_.moving_car_speed_mps * Uniform(rng, 0.85, 1.15);
  const double t_cross = CameraTimeAt(std::max(0.0, c.s - Uniform(rng, 12.0, 32.0)));
  p.start_offset_m = ext - p.speed_mps * t_cross;
  return p;
}

// Moving cars on the streets of the route: ahead of the camera in its direction of
// travel (the other lane if there are two, else its own lane, never slower than the
// camera), oncoming in the opposite lane, and crossing at the route's intersections.
void CityBuilder::MakeMovingCars(const Traffic& traffic) {
  std::mt19937_64 rng = Rng("moving_cars" + traffic.tag);
  // The vehicles the camera waits behind are not counted in moving_cars.
  MakeRedLightLeads(RouteNodes(), traffic);
  if (spec_.moving_cars <= 0) return;
  const RouteLanes lanes = MakeRouteLanes();
  const std::vector<Crossing> crossings = CrossingsOnRoute(lanes);
  const std::vector<double> turns = TurnsOnRoute(lanes);
  const std::vector<CarRole> roles = MovingCarRoles(lanes.two_lanes, !crossings.empty());
  const int n_oncoming = static_cast<int>(std::count(roles.begin(), roles.end(), CarRole::kOncoming));
  const int n_crossing = static_cast<int>(std::count(roles.begin(), roles.end(), CarRole::kCrossing));
  int ahead = 0, oncoming = 0, crossing = 0;
  double ahead_gap = 0, ahead_speed = 0;  // of the last car placed ahead
  for (const CarRole role : roles) {
    // In a one-lane queue ahead every car is a car: a bus there would block the view.
    const bool queued = role == CarRole::kAhead && !lanes.two_lanes;
    Object& o = b_.AddObject(queued ? "car" : VehicleKind(rng, role != CarRole::kAhead));
    o.parts.push_back(MakeVehicle(rng, o.category_name));
    const double hl = Dims(o.category_name).half_length, hw = Dims(o.category_name).half_width;
    const int index = static_cast<int>(world_.objects.size()) - 1;
    std::function<PathMotion(int)> make;
    if (role == CarRole::kAhead) {
      make = [&, rank = ahead, hl](int a) { return AheadMotion(rng, lanes, rank, hl, a, ahead_gap, ahead_speed); };
    } else if (role == CarRole::kOncoming) {
      make = [&, rank = oncoming++](int a) { return OncomingMotion(rng, lanes, turns, rank, n_oncoming, a); };
    } else {
      make = [&, rank = crossing++](int a) { return CrossingMotion(rng, crossings, rank, n_crossing, a); };
    }
    const bool kept = PlaceMover(index, traffic.present, hl, hw, /*car=*/true, /*min_camera_m=*/3.15, 40, make);
    // A car left out does not count: the next one queues behind the last one placed.
    if (role == CarRole::kAhead && kept) ++ahead;
    if (queued && kept) {
      const PathMotion& placed = world_.objects[index].placement[traffic.present[0] ? 0 : 1].path;
      ahead_speed = placed.speed_mps;
      ahead_gap = placed.start_offset_m - lanes.f0;
    }
  }
}

}  // namespace segslam::scenes::city_internal
