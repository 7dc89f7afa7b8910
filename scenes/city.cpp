// The city world (scenes/builder.h's BuildCity): the order in which CityBuilder builds it,
// the camera's route on the street grid, the red lights it stops at and its timing, the
// camera's routes and the lights. The rest of the builder: scenes/city_builder_internal.h.
#include "scenes/city_builder_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>

namespace segslam::scenes::city_internal {

CityBuilder::CityBuilder(const Scenario& s) : s_(s), spec_(s.city), b_(&world_) {
  block_ = spec_.block_size_m;
  road_ = spec_.road_width_m;
  walk_ = spec_.sidewalk_width_m;
  lane_ = DrivingLaneOffsetM(road_);
  // Two buses passing each other keep 0.2 m apart (the oncoming lane is 0.1 m further
  // out, MakeRouteLanes); Scenario's lower bound on the road width ensures it.
  if (2 * lane_ + 0.1 < 2 * kBusDims.half_width + 0.2) {
    throw std::invalid_argument("city.road_width_m " + std::to_string(road_) +
                                " m cannot hold two parking lanes and two driving lanes");
  }
}

World CityBuilder::Build() {
  world_.name = s_.name;
  world_.kind = "city";
  world_.seed = s_.seed;
  world_.camera = s_.camera;
  world_.sky_rgb = Eigen::Vector3f(0.62f, 0.74f, 0.9f);
  MakeLook();
  PlanRoute();
  PlanRedLights();
  MakeGround();
  MakeBlocks();
  MakeStreets();
  MakeStreetSurfaces();
  MakeCameraRoutes();
  MakeSamples();
  MakeParkedCars();
  if (spec_.pass2_new_traffic) {
    for (const Traffic& traffic : {Traffic{{true, false}, ""}, Traffic{{false, true}, "/pass2"}}) {
      MakeMovingCars(traffic);
      MakePedestrians(traffic);
    }
  } else {
    MakeMovingCars(Traffic{});
    MakePedestrians(Traffic{});
  }
  MakeLights();
  pictures_.Pack(&world_);
  return std::move(world_);
}

// ---- Route on the street grid ------------------------------------------------------
// A random walk over intersections (straight more often than turning, never reusing a
// street if it can avoid it), then the right-hand lane through it with rounded turns.
void CityBuilder::PlanRoute() {
  WalkStreetGrid();
  SetGridBounds();
  // Directed route edges (the one leading into node 0 included).
  const Node before{nodes_[0].first - static_cast<int>(kStreetDirs[dirs_[0]].x()),
                    nodes_[0].second - static_cast<int>(kStreetDirs[dirs_[0]].y())};
  route_edges_.insert({before, nodes_[0]});
  for (std::size_t k = 1; k < nodes_.size(); ++k) route_edges_.insert({nodes_[k - 1], nodes_[k]});
  SampleLane(LaneCorners());
}

void CityBuilder::WalkStreetGrid() {
  std::mt19937_64 rng = Rng("route");
  int dir = UniformInt(rng, 0, 3);
  Node node{0, 0};
  nodes_ = {node};
  dirs_ = {dir};
  std::set<std::pair<Node, Node>> used;
  const auto step = [](const Node& from, int direction) {
    return Node{from.first + static_cast<int>(kStreetDirs[direction].x()),
                from.second + static_cast<int>(kStreetDirs[direction].y())};
  };
  // Enough streets for the route plus the half block before the first node.
  const int edges_needed = static_cast<int>(std::ceil(spec_.route_length_m / block_)) + 2;
  for (int e = 0; e < edges_needed; ++e) {
    // Candidate directions: straight, left, right, in random preference.
    std::vector<int> options = {dir, (dir + 1) % 4, (dir + 3) % 4};
    const double r = Uniform(rng, 0, 1);
    if (r > 0.55) std::swap(options[0], options[r > 0.775 ? 1 : 2]);
    int chosen = options[0];
    for (int o : options) {
      const Node next = step(node, o);
      if (!used.count({std::min(node, next), std::max(node, next)})) {
        chosen = o;
        break;
      }
    }
    const Node next = step(node, chosen);
    used.insert({std::min(node, next), std::max(node, next)});
    node = next;
    dir = chosen;
    nodes_.push_back(node);
    dirs_.push_back(dir);
  }
  // dirs_[k] is the direction arriving at nodes_[k] (k >= 1); dirs_[0] = leaving node 0.
  dirs_[0] = dirs_[1];
}

// One block of margin around the route for streets with buildings on both sides, and a
// second ring of blocks so views down streets end in buildings.
void CityBuilder::SetGridBounds() {
  imin_ = imax_ = jmin_ = jmax_ = 0;
  for (const Node& n : nodes_) {
    imin_ = std::min(imin_, n.first);
    imax_ = std::max(imax_, n.first);
    jmin_ = std::min(jmin_, n.second);
    jmax_ = std::max(jmax_, n.second);
  }
  imin_ -= 1, jmin_ -= 1, imax_ += 1, jmax_ += 1;
}

// The lane's corner points: from mid-block before node 0, through rounded corners, to
// the last node.
std::vector<Vec2> CityBuilder::LaneCorners() const {
  std::vector<Vec2> pts;
  const Vec2 d0 = kStreetDirs[dirs_[0]];
  pts.push_back(NodePos(nodes_[0]) - d0 * (block_ / 2) + Right(d0) * lane_);
  for (std::size_t k = 1; k + 1 < nodes_.size(); ++k) {
    const Vec2 a = kStreetDirs[dirs_[k]], b = kStreetDirs[dirs_[k + 1]];
    if (dirs_[k] == dirs_[k + 1]) continue;
    AppendTurn(nodes_[k], a, b, lane_, &pts);
  }
  const Vec2 dl = kStreetDirs[dirs_.back()];
  pts.push_back(NodePos(nodes_.back()) + Right(dl) * lane_);
  return pts;
}

// The points of a turn at `node` from direction a to direction b, on a lane `offset`
// right of the direction of travel: a quarter circle, the same for every lane's corners.
void CityBuilder::AppendTurn(const Node& node, const Vec2& a, const Vec2& b, double offset,
                             std::vector<Vec2>* pts) const {
  const double radius = std::min(6.0, block_ / 5);
  const Vec2 corner = NodePos(node) + Right(a) * offset + Right(b) * offset;
  const Vec2 centre = corner - a * radius + b * radius;
  for (int i = 0; i <= 12; ++i) {
    const double th = 0.5 * M_PI * i / 12;
    pts->push_back(centre + radius * (-b * std::cos(th) + a * std::sin(th)));
  }
}

// Points every 0.25 m or less along the corners' polyline, cut at the route length.
void CityBuilder::SampleLane(const std::vector<Vec2>& pts) {
  std::vector<Vec2> lane_pts;
  double s = 0;
  for (std::size_t i = 0; i + 1 < pts.size() && s < spec_.route_length_m; ++i) {
    const double len = (pts[i + 1] - pts[i]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / 0.25)));
    for (int k = 0; k < n; ++k) {
      const Vec2 p = pts[i] + (pts[i + 1] - pts[i]) * (static_cast<double>(k) / n);
      if (!lane_pts.empty()) s += (p - lane_pts.back()).norm();
      lane_pts.push_back(p);
      if (s >= spec_.route_length_m) break;
    }
  }
  camera_lane_ = Poly2(std::move(lane_pts));
}

// ---- Red lights and the camera's timing -------------------------------------------------
// Stop line on the camera's lane before node k, arriving in direction a.
Vec2 CityBuilder::StopLinePoint(std::size_t k, const Vec2& a) const {
  return NodePos(nodes_[k]) - a * (road_ / 2 + kStopLineM) + Right(a) * lane_;
}

// Lights at the candidates spread over the route. The camera car brakes from its
// cruising speed at kCarAccelMps2 and must be back at that speed before it brakes for
// the next light (DistanceWithHalts), so a light it stands at nearer than v^2 / 2a to the
// start or v^2 / a to the light before is passed over for the next candidate; lights
// that find none are left out (red_lights_left_out_).
void CityBuilder::PlanRedLights() {
  red_lights_.clear();
  camera_halts_.clear();
  red_lights_left_out_ = 0;
  if (spec_.red_lights <= 0) return;
  std::mt19937_64 rng = Rng("red_lights");
  const Poly2& lane = camera_lane_;
  // Candidates: every intersection the camera reaches with room to brake before it and
  // to see the scene after it. The walk goes on past the route's end: an intersection
  // there has its stop line off the camera's lane (whose nearest point is elsewhere).
  std::vector<RedLight> candidates;
  for (std::size_t k = 1; k < nodes_.size(); ++k) {
    RedLight r;
    r.node = k;
    r.arrive = kStreetDirs[dirs_[k]];
    const Vec2 stop = StopLinePoint(k, r.arrive) - r.arrive * kCameraToBumperM;
    r.camera_stop_s = lane.Closest(stop);
    const bool on_route = (lane.At(r.camera_stop_s) - stop).norm() < 0.1;
    if (on_route && r.camera_stop_s >= 40.0 && r.camera_stop_s <= camera_lane_.Length() - 15.0) candidates.push_back(r);
  }
  const double v = spec_.camera_speed_mps;
  const double brake_m = 0.5 * v * v / kCarAccelMps2;
  const int n = std::min(spec_.red_lights, static_cast<int>(candidates.size()));
  std::size_t next = 0;  // the first candidate after the last light made
  for (int i = 0; i < n; ++i) {
    // The first light and every other one after it wait behind a vehicle; its kind is
    // drawn even where the scenario names it, so the other lights draw as before.
    std::string lead_kind;
    if (red_lights_.size() % 2 == 0) {
      lead_kind = VehicleKind(rng, /*allow_bus=*/true);
      if (spec_.red_light_lead != "random") lead_kind = spec_.red_light_lead;
    }
    for (std::size_t c = std::max(next, (2 * i + 1) * candidates.size() / (2 * n)); c < candidates.size(); ++c) {
      RedLight r = candidates[c];  // spread over the route
      r.lead_kind = lead_kind;
      if (!r.lead_kind.empty()) r.camera_stop_s -= 2 * Dims(r.lead_kind).half_length + kQueueGapM;
      const bool room = camera_halts_.empty() ? r.camera_stop_s >= brake_m
                                              : r.camera_stop_s - camera_halts_.back().at_m >= 2 * brake_m;
      if (!room) continue;
      camera_halts_.push_back({r.camera_stop_s, spec_.red_light_s});
      red_lights_.push_back(r);
      next = c + 1;
      break;
    }
  }
  red_lights_left_out_ = spec_.red_lights - static_cast<int>(red_lights_.size());
  for (RedLight& r : red_lights_) {
    r.stand_from_s = CameraTimeAt(r.camera_stop_s);
    r.stand_until_s = r.stand_from_s + spec_.red_light_s;
  }
}

// Camera arc length at time t of a pass (both passes keep the same timing).
double CityBuilder::CameraArc(double t) const {
  return DistanceWithHalts(0.0, spec_.camera_speed_mps, camera_halts_, kCarAccelMps2, t);
}

// First time the camera reaches arc length s.
double CityBuilder::CameraTimeAt(double s) const {
  double lo = 0.0, hi = s / spec_.camera_speed_mps;
  for (const Halt& h : camera_halts_) hi += h.wait_s + spec_.camera_speed_mps / kCarAccelMps2;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (CameraArc(mid) >= s - 1e-9 ? hi : lo) = mid;
  }
  return hi;
}

// ---- Camera and lights ------------------------------------------------------------------
void CityBuilder::MakeCameraRoutes() {
  const double v = spec_.camera_speed_mps;
  const double duration = CameraTimeAt(camera_lane_.Length());
  const int frames = static_cast<int>(std::floor(duration * s_.camera.fps + 1e-9)) + 1;
  world_.frames_per_pass = {frames, frames};
  std::mt19937_64 rng = Rng("camera_shake");
  const SmoothNoise pitch = SmoothNoise::Make(rng, 0.7), roll = SmoothNoise::Make(rng, 0.5), bump = SmoothNoise::Make(rng, 1.1);
  CameraRoute route;
  const int keys = static_cast<int>(std::ceil(duration * s_.camera.fps)) + 1;
  for (int k = 0; k < keys; ++k) {
    const double t = std::min(duration, k / s_.camera.fps);
    const double s = CameraArc(t);
    // Heading from the lane tangent; a small ride shake in pitch, roll and height that
    // comes from the road, so it follows the distance driven (still while standing).
    const double road_t = s / v;
    const Vec2 fwd = (camera_lane_.At(s + 0.5) - camera_lane_.At(s - 0.5)).normalized();
    const Vec3 eye = At(camera_lane_.At(s), spec_.camera_height_m + 0.01 * bump.Eval(road_t));
    Eigen::Matrix3d R = LookAt(eye, eye + At(fwd, 0.0));
    R = R * Eigen::AngleAxisd(0.003 * pitch.Eval(road_t), Vec3::UnitX()).matrix() *
        Eigen::AngleAxisd(0.002 * roll.Eval(road_t), Vec3::UnitZ()).matrix();
    CameraKey key;
    key.stamp_s = t;
    key.T_wc.linear() = R;
    key.T_wc.translation() = eye;
    if (!route.keys.empty() && t <= route.keys.back().stamp_s + 1e-9) continue;
    route.keys.push_back(key);
  }
  world_.camera_route[0] = route;
  world_.camera_route[1] = OffsetRoute(route, s_.pass2.camera_offset_m, s_.pass2.camera_yaw_offset_deg);
}

void CityBuilder::MakeLights() {
  Light sun;
  sun.directional = true;
  sun.direction = Vec3(-0.35, -0.25, -0.9).normalized();
  sun.position = Vec3(0, 0, 100);
  sun.diffuse = Eigen::Vector3f(0.75f, 0.72f, 0.66f);
  sun.ambient = Eigen::Vector3f(0.38f, 0.4f, 0.44f);
  sun.specular = Eigen::Vector3f(0.2f, 0.2f, 0.2f);
  world_.lights.push_back(sun);
  Light fill = sun;  // sky light from the other side, so shaded facades keep detail
  fill.direction = Vec3(0.4, 0.3, -0.6).normalized();
  fill.diffuse = Eigen::Vector3f(0.22f, 0.24f, 0.28f);
  fill.ambient = Eigen::Vector3f::Zero();
  fill.specular = Eigen::Vector3f::Zero();
  world_.lights.push_back(fill);
}

}  // namespace segslam::scenes::city_internal

namespace segslam::scenes {

World BuildCity(const Scenario& scenario) {
  city_internal::CityBuilder builder(scenario);
  World world = builder.Build();
  RecordSecondPassChanges(&world, builder.parked_candidates_);
  world.movers_left_out = builder.movers_left_out_;
  world.red_lights_left_out = builder.red_lights_left_out_;
  return world;
}

}  // namespace segslam::scenes
