// An AirSim-like city: a street grid around a random car route, buildings with detailed
// facades, sidewalks, markings, street furniture, parked and moving cars, pedestrians.
//
// Layout: street centre lines at x = i * block and y = j * block; cars drive on the
// right. A node is an intersection (i, j). Everything stands on the ground plane z = 0;
// sidewalks are raised by kCurbHeightM.
#include "scenes/builder.h"
#include "scenes/city_layout.h"
#include "scenes/city_textures.h"
#include "scenes/picture_pages.h"
#include "scenes/person.h"
#include "scenes/textures.h"


#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

namespace segslam::scenes {
namespace {

constexpr double kCurbHeightM = 0.15;
// Parking slot pitch along the curb, as long as a real parallel stall: a car (4.9 m)
// with room to pull out; a truck (7.2 m) stands only between cars or empty slots.
constexpr double kSlotLengthM = 6.5;
constexpr double kParkedGapM = 0.3;    // least gap between parked vehicles, bumper to bumper
// Vehicle footprints and the street's cross-section (scenes/city_layout.h).
using namespace city_layout;
// Texture detail of the surfaces of one place (street, sidewalk strip, facade): full
// within kNearRouteM of the camera's lane, where the camera sees them from a few metres,
// coarse beyond, where it sees them only from afar. Every surface has its own picture
// either way (scenes/city_textures.h).
constexpr double kNearRouteM = 45.0;
constexpr double kNearPxPerM = 32.0, kFarGroundPxPerM = 8.0, kFarFacadePxPerM = 10.0;
constexpr int kMaxTexturePx = 2040;    // longest side of one surface's picture (a page, less gutters)
constexpr double kRoadTopM = 0.004;    // street surfaces lie on the ground plane
constexpr double kFacadeSkinM = 0.03;  // half thickness of a facade's textured skin
constexpr double kVehiclePxPerM = 40.0;  // a vehicle's paint and glass
constexpr double kStopLineM = 4.0;          // stop line, before the edge of the crossing road
constexpr double kQueueGapM = 2.0;          // bumper to bumper, standing in a queue
constexpr double kCarAccelMps2 = 2.0;       // braking and pulling away at a red light
constexpr double kReactionS = 1.0;          // the camera car starts this long after the car ahead
constexpr double kLeadFollowS = 1.0;        // leads cruising one behind the other: time gap


using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Node = std::pair<int, int>;

// Street directions by index (+x, +y, -x, -y); dirs_[k] indexes this.
const Vec2 kStreetDirs[4] = {Vec2(1, 0), Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1)};

Vec2 Right(const Vec2& d) { return Vec2(d.y(), -d.x()); }
Vec3 At(const Vec2& p, double z) { return Vec3(p.x(), p.y(), z); }
double YawOf(const Vec2& d) { return std::atan2(d.y(), d.x()); }

// A directed street edge between neighbouring nodes.
struct Edge {
  Node from, to;
  bool operator<(const Edge& o) const { return std::tie(from, to) < std::tie(o.from, o.to); }
};

// Materials and textures the city uses, by role.
struct CityLook {
  int ground, bark, metal, dark_metal, railing;
  int clothes_textures[6], skin_texture;
  int rubber, chrome, headlight, taillight, stop_sign, traffic_lamps, wood, red_paint;
  std::vector<int> foliage;
};

class CityBuilder {
 public:
  explicit CityBuilder(const Scenario& s) : s_(s), spec_(s.city), b_(&world_) {
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

  World Build() {
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

 private:
  Vec2 NodePos(const Node& n) const { return Vec2(n.first * block_, n.second * block_); }

  std::mt19937_64 Rng(const std::string& tag, std::uint64_t i = 0) const {
    return std::mt19937_64(SubSeed(s_.seed, tag, i));
  }

  // ---- Textures and materials ------------------------------------------------------
  // The size in pixels of a picture of `size_m` at `px_per_m` (at least 2 x 2).
  static cv::Size PixelsFor(const Vec2& size_m, double px_per_m) {
    return cv::Size(std::max(2, static_cast<int>(std::lround(size_m.x() * px_per_m))),
                    std::max(2, static_cast<int>(std::lround(size_m.y() * px_per_m))));
  }

  // A picture of one place (a street, a facade, a plate) drawn at `px_per_m` over a
  // box face of `size_m`; returns its material. The pictures are packed into a few
  // textures and drawn, in parallel, at the end of Build() (scenes/picture_pages.h).
  int AddPicture(const std::string& name, const Vec2& size_m, double px_per_m, std::function<cv::Mat()> draw) {
    return pictures_.Add(b_, name, PixelsFor(size_m, px_per_m), size_m, std::move(draw));
  }
  // A picture drawn at a fixed size in pixels (plates, signs).
  int AddPicture(const std::string& name, const Vec2& size_m, cv::Size size_px, std::function<cv::Mat()> draw) {
    return pictures_.Add(b_, name, size_px, size_m, std::move(draw));
  }

  // Pixels per metre for a surface spanning [lo, hi] (horizontal extent): full detail
  // near the route, coarse beyond, and never more than kMaxTexturePx on a side.
  double DetailPxPerM(const Vec2& lo, const Vec2& hi, double far_px_per_m, double longest_side_m) const {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < lane_pts_.size(); k += 4) {  // every metre
      const Vec2 q = lane_pts_[k].cwiseMax(lo).cwiseMin(hi);
      nearest = std::min(nearest, (lane_pts_[k] - q).norm());
    }
    const double px_per_m = nearest <= kNearRouteM ? kNearPxPerM : far_px_per_m;
    return std::min(px_per_m, kMaxTexturePx / std::max(longest_side_m, 1e-3));
  }

  void MakeLook() {
    const std::uint64_t seed = s_.seed;
    auto tex = [&](const std::string& name, cv::Mat img, double u, double v) {
      return b_.AddTexture(name, std::move(img), Vec2(u, v));
    };
    auto mat = [&](const std::string& name, int t, Eigen::Vector4f rgba, float spec = 0.1f) {
      return b_.AddMaterial(name, t, rgba, spec);
    };
    const Eigen::Vector4f white(1, 1, 1, 1);
    // Untextured asphalt beyond the streets' surfaces, which have pictures of their own.
    look_.ground = mat("ground", -1, Eigen::Vector4f(0.29f, 0.29f, 0.3f, 1), 0.05f);
    look_.railing = mat("railing", -1, Eigen::Vector4f(0.16f, 0.17f, 0.17f, 1), 0.3f);
    look_.bark = mat("bark", tex("bark", BarkTexture(SubSeed(seed, "bark")), 1, 1), white);
    const int metal_t = tex("metal", MetalTexture(SubSeed(seed, "metal")), 0.5, 0.5);
    look_.metal = mat("metal", metal_t, Eigen::Vector4f(0.75f, 0.78f, 0.78f, 1), 0.4f);
    look_.dark_metal = mat("dark_metal", metal_t, Eigen::Vector4f(0.3f, 0.32f, 0.3f, 1), 0.4f);
    for (int i = 0; i < 6; ++i) {
      look_.clothes_textures[i] = tex("cloth_" + std::to_string(i), ClothTexture(SubSeed(seed, "cloth", i), i), 0.5, 0.5);
    }
    look_.skin_texture = tex("skin", SkinTexture(SubSeed(seed, "skin")), 0.2, 0.2);
    look_.rubber = mat("rubber", -1, Eigen::Vector4f(0.08f, 0.08f, 0.08f, 1));
    look_.chrome = mat("chrome", -1, Eigen::Vector4f(0.7f, 0.7f, 0.72f, 1), 0.8f);
    look_.headlight = mat("headlight", -1, Eigen::Vector4f(0.95f, 0.95f, 0.85f, 1), 0.8f);
    look_.taillight = mat("taillight", -1, Eigen::Vector4f(0.7f, 0.05f, 0.05f, 1), 0.6f);
    look_.stop_sign = mat("stop_sign", tex("stop_sign", StopSignTexture(SubSeed(seed, "stop")), 0.75, 0.75), white);
    look_.traffic_lamps = mat("traffic_lamps", tex("traffic_lamps", TrafficLightTexture(SubSeed(seed, "tl")), 0.35, 0.9), white);
    look_.wood = mat("bench_wood", tex("bench_wood", WoodTexture(SubSeed(seed, "bench")), 1, 1), white);
    look_.red_paint = mat("hydrant_red", -1, Eigen::Vector4f(0.75f, 0.1f, 0.08f, 1), 0.3f);
    const int foliage_t = tex("foliage", FoliageTexture(SubSeed(seed, "foliage")), 2.5, 2.5);
    for (int i = 0; i < 3; ++i) {
      look_.foliage.push_back(mat("foliage_" + std::to_string(i), foliage_t,
                                  Eigen::Vector4f(0.8f + 0.1f * i, 1.0f, 0.8f + 0.08f * i, 1)));
    }
  }

  // ---- Route on the street grid ------------------------------------------------------
  // A random walk over intersections (straight more often than turning, never reusing a
  // street if it can avoid it), then the right-hand lane through it with rounded turns.
  void PlanRoute() {
    WalkStreetGrid();
    SetGridBounds();
    // Directed route edges (the one leading into node 0 included).
    const Node before{nodes_[0].first - static_cast<int>(kStreetDirs[dirs_[0]].x()),
                      nodes_[0].second - static_cast<int>(kStreetDirs[dirs_[0]].y())};
    route_edges_.insert({before, nodes_[0]});
    for (std::size_t k = 1; k < nodes_.size(); ++k) route_edges_.insert({nodes_[k - 1], nodes_[k]});
    SampleLane(LaneCorners());
  }

  void WalkStreetGrid() {
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
  void SetGridBounds() {
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
  std::vector<Vec2> LaneCorners() const {
    const double radius = std::min(6.0, block_ / 5);
    std::vector<Vec2> pts;
    const Vec2 d0 = kStreetDirs[dirs_[0]];
    pts.push_back(NodePos(nodes_[0]) - d0 * (block_ / 2) + Right(d0) * lane_);
    for (std::size_t k = 1; k + 1 < nodes_.size(); ++k) {
      const Vec2 a = kStreetDirs[dirs_[k]], b = kStreetDirs[dirs_[k + 1]];
      if (dirs_[k] == dirs_[k + 1]) continue;
      const Vec2 corner = NodePos(nodes_[k]) + Right(a) * lane_ + Right(b) * lane_;
      const Vec2 centre = corner - a * radius + b * radius;
      for (int i = 0; i <= 12; ++i) {
        const double th = 0.5 * M_PI * i / 12;
        pts.push_back(centre + radius * (-b * std::cos(th) + a * std::sin(th)));
      }
    }
    const Vec2 dl = kStreetDirs[dirs_.back()];
    pts.push_back(NodePos(nodes_.back()) + Right(dl) * lane_);
    return pts;
  }

  // Points every 0.25 m or less along the corners' polyline, cut at the route length.
  void SampleLane(const std::vector<Vec2>& pts) {
    lane_pts_.clear();
    lane_s_.clear();
    double s = 0;
    for (std::size_t i = 0; i + 1 < pts.size() && s < spec_.route_length_m; ++i) {
      const double len = (pts[i + 1] - pts[i]).norm();
      const int n = std::max(1, static_cast<int>(std::ceil(len / 0.25)));
      for (int k = 0; k < n; ++k) {
        const Vec2 p = pts[i] + (pts[i + 1] - pts[i]) * (static_cast<double>(k) / n);
        if (!lane_pts_.empty()) s += (p - lane_pts_.back()).norm();
        lane_pts_.push_back(p);
        lane_s_.push_back(s);
        if (s >= spec_.route_length_m) break;
      }
    }
  }

  Vec2 LaneAt(double s) const {
    s = std::clamp(s, 0.0, lane_s_.back());
    const auto it = std::upper_bound(lane_s_.begin(), lane_s_.end(), s);
    const std::size_t i = std::clamp<std::size_t>(it - lane_s_.begin(), 1, lane_s_.size() - 1);
    const double seg = lane_s_[i] - lane_s_[i - 1];
    const double u = seg > 0 ? (s - lane_s_[i - 1]) / seg : 0;
    return lane_pts_[i - 1] + u * (lane_pts_[i] - lane_pts_[i - 1]);
  }

  // ---- Red lights and the camera's timing -------------------------------------------------
  // A light where the camera car stands: behind the stop line, or behind a vehicle
  // standing at it.
  struct RedLight {
    std::size_t node = 0;          // index into nodes_
    Vec2 arrive;                   // direction the camera arrives in
    double camera_stop_s = 0;      // camera arc length where it stands
    double stand_from_s = 0, stand_until_s = 0;  // on the pass clock
    std::string lead_kind;         // vehicle it waits behind; empty: first in line
  };

  // Stop line on the camera's lane before node k, arriving in direction a.
  Vec2 StopLinePoint(std::size_t k, const Vec2& a) const {
    return NodePos(nodes_[k]) - a * (road_ / 2 + kStopLineM) + Right(a) * lane_;
  }

  // Lights at the candidates spread over the route. The camera car brakes from its
  // cruising speed at kCarAccelMps2 and must be back at that speed before it brakes for
  // the next light (DistanceWithHalts), so a light it stands at nearer than v^2 / 2a to the
  // start or v^2 / a to the light before is passed over for the next candidate; lights
  // that find none are left out (red_lights_left_out_).
  void PlanRedLights() {
    red_lights_.clear();
    camera_halts_.clear();
    red_lights_left_out_ = 0;
    if (spec_.red_lights <= 0) return;
    std::mt19937_64 rng = Rng("red_lights");
    const Poly2 lane(lane_pts_);
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
      if (on_route && r.camera_stop_s >= 40.0 && r.camera_stop_s <= lane_s_.back() - 15.0) candidates.push_back(r);
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
  double CameraArc(double t) const {
    return DistanceWithHalts(0.0, spec_.camera_speed_mps, camera_halts_, kCarAccelMps2, t);
  }

  // First time the camera reaches arc length s.
  double CameraTimeAt(double s) const {
    double lo = 0.0, hi = s / spec_.camera_speed_mps;
    for (const Halt& h : camera_halts_) hi += h.wait_s + spec_.camera_speed_mps / kCarAccelMps2;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (CameraArc(mid) >= s - 1e-9 ? hi : lo) = mid;
    }
    return hi;
  }

  // ---- Static scenery ----------------------------------------------------------------
  void MakeGround() {
    // An untextured plane under everything; the streets' surfaces lie on it
    // (MakeStreetSurfaces) and the sidewalks and buildings stand on it.
    const double margin = 2.5 * block_;
    const Vec2 lo = Vec2((imin_ - 1) * block_ - margin, (jmin_ - 1) * block_ - margin);
    const Vec2 hi = Vec2((imax_ + 1) * block_ + margin, (jmax_ + 1) * block_ + margin);
    Geom g;
    g.shape = Shape::kPlane;
    g.size = Vec3(0.5 * (hi.x() - lo.x()), 0.5 * (hi.y() - lo.y()), 0);
    g.T_parent_geom.translation() = At(0.5 * (lo + hi), 0);
    g.material = look_.ground;
    world_.static_geoms.push_back(g);
  }

  // Every street between two intersections and every intersection of the blocks' grid a
  // slab of its own asphalt, with the markings that lie on it painted in.
  void MakeStreetSurfaces() {
    const auto add = [&](const Vec2& lo, const Vec2& hi, const std::string& tag, std::uint64_t index) {
      GroundPatch patch;
      patch.lo_m = lo;
      patch.hi_m = hi;
      patch.px_per_m = DetailPxPerM(lo, hi, kFarGroundPxPerM, (hi - lo).maxCoeff());
      std::vector<RoadMarking> on_patch;
      for (const RoadMarking& m : markings_) {
        const double reach = m.half_m.norm();
        if ((m.centre_m.array() + reach > lo.array()).all() && (m.centre_m.array() - reach < hi.array()).all()) {
          on_patch.push_back(m);
        }
      }
      const std::uint64_t seed = SubSeed(s_.seed, tag, index);
      const int m = AddPicture(tag, hi - lo, patch.SizePx(), [seed, patch, on_patch] { return StreetTexture(seed, patch, on_patch); });
      world_.static_geoms.push_back(MakeBox(At(0.5 * (lo + hi), kRoadTopM / 2), At(0.5 * (hi - lo), kRoadTopM / 2), m));
    };
    const Vec2 half_road = Vec2::Constant(road_ / 2);
    for (int i = imin_ - 1; i <= imax_ + 1; ++i) {
      for (int j = jmin_ - 1; j <= jmax_ + 1; ++j) {
        const std::uint64_t index = static_cast<std::uint64_t>((i + 1000) * 4096 + (j + 1000));
        const Vec2 c = NodePos({i, j});
        add(c - half_road, c + half_road, "intersection", index);
        if (i <= imax_) add(c + Vec2(road_ / 2, -road_ / 2), NodePos({i + 1, j}) + Vec2(-road_ / 2, road_ / 2), "street_x", index);
        if (j <= jmax_) add(c + Vec2(-road_ / 2, road_ / 2), NodePos({i, j + 1}) + Vec2(road_ / 2, -road_ / 2), "street_y", index);
      }
    }
  }

  // A block between street lines i..i+1 and j..j+1: a raised sidewalk slab and
  // buildings on lots around its edge.
  void MakeBlocks() {
    for (int i = imin_ - 1; i <= imax_; ++i) {
      for (int j = jmin_ - 1; j <= jmax_; ++j) {
        std::mt19937_64 rng = Rng("block", static_cast<std::uint64_t>((i + 1000) * 4096 + (j + 1000)));
        const Vec2 lo = NodePos({i, j}) + Vec2::Constant(road_ / 2);
        const Vec2 hi = NodePos({i + 1, j + 1}) - Vec2::Constant(road_ / 2);
        const std::uint64_t block_index = static_cast<std::uint64_t>((i + 1000) * 4096 + (j + 1000));
        MakeSidewalks(lo, hi, block_index, Uniform(rng, 0.3, 0.6));
        // Lots: 2-3 columns by 2 rows, all touching a street.
        const Vec2 in_lo = lo + Vec2::Constant(walk_), in_hi = hi - Vec2::Constant(walk_);
        const int nx = UniformInt(rng, 2, 3);
        std::vector<double> xs = {in_lo.x()}, ys = {in_lo.y(), 0.5 * (in_lo.y() + in_hi.y()) + Uniform(rng, -2, 2), in_hi.y()};
        for (int k = 1; k < nx; ++k) {
          xs.push_back(in_lo.x() + (in_hi.x() - in_lo.x()) * (k + Uniform(rng, -0.15, 0.15)) / nx);
        }
        xs.push_back(in_hi.x());
        for (int a = 0; a + 1 < static_cast<int>(xs.size()); ++a) {
          for (int c = 0; c < 2; ++c) {
            // The sides of the lot on the block's edge face a street.
            const std::array<bool, 4> street_sides = {a == 0, a + 2 == static_cast<int>(xs.size()), c == 0, c == 1};
            MakeBuilding(rng, Vec2(xs[a], ys[c]), Vec2(xs[a + 1], ys[c + 1]), street_sides);
          }
        }
      }
    }
  }

  // The sidewalks of the block [lo, hi]: four paved strips along its edges, each with a
  // picture of its own, around an untextured slab under the lots.
  void MakeSidewalks(const Vec2& lo, const Vec2& hi, std::uint64_t block_index, double paver_m) {
    const Vec2 w = Vec2::Constant(walk_);
    // Four strips, none overlapping: along x the whole block, along y between them.
    const std::array<std::pair<Vec2, Vec2>, 4> strips = {{
        {lo, Vec2(hi.x(), lo.y() + walk_)},                             // along x, low y
        {Vec2(lo.x(), hi.y() - walk_), hi},                             // along x, high y
        {Vec2(lo.x(), lo.y() + walk_), Vec2(lo.x() + walk_, hi.y() - walk_)},  // along y, low x
        {Vec2(hi.x() - walk_, lo.y() + walk_), Vec2(hi.x(), hi.y() - walk_)},  // along y, high x
    }};
    for (std::size_t k = 0; k < strips.size(); ++k) {
      const auto& [a, b] = strips[k];
      GroundPatch patch;
      patch.lo_m = a;
      patch.hi_m = b;
      patch.px_per_m = DetailPxPerM(a, b, kFarGroundPxPerM, (b - a).maxCoeff());
      const std::uint64_t seed = SubSeed(s_.seed, "sidewalk", block_index * 4 + k);
      const int m = AddPicture("sidewalk", b - a, patch.SizePx(), [seed, patch, paver_m] { return PavedStripTexture(seed, patch, paver_m); });
      world_.static_geoms.push_back(MakeBox(At(0.5 * (a + b), kCurbHeightM / 2), At(0.5 * (b - a), kCurbHeightM / 2), m));
    }
    const int inner = b_.AddMaterial("lot_ground", -1, Eigen::Vector4f(0.55f, 0.55f, 0.53f, 1));
    world_.static_geoms.push_back(MakeBox(At(0.5 * (lo + hi), kCurbHeightM / 2), At(0.5 * (hi - lo) - w, kCurbHeightM / 2), inner));
  }

  // A building on the lot [lo, hi]: an untextured body in its own colour; each side that
  // faces a street (street_sides: low x, high x, low y, high y) carries a facade of its
  // own (floors, bays, windows, shops with their own names), with balconies and awnings
  // where that facade has them; a cornice and now and then a rooftop structure.
  void MakeBuilding(std::mt19937_64& rng, Vec2 lo, Vec2 hi, const std::array<bool, 4>& street_sides) {
    // Occasional setback from the street and narrow gaps between neighbours.
    const double setback = Chance(rng, 0.25) ? Uniform(rng, 0.3, 1.5) : 0.0;
    lo += Vec2::Constant(setback * 0.5 + 0.1);
    hi -= Vec2::Constant(setback * 0.5 + 0.1);
    const double height = Chance(rng, 0.3) ? Uniform(rng, 22, 40) : Uniform(rng, 8, 22);
    const Vec2 c = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    const FacadeStyle styles[4] = {FacadeStyle::kBrick, FacadeStyle::kConcrete, FacadeStyle::kGlass, FacadeStyle::kPlaster};
    const FacadeStyle style = styles[UniformInt(rng, 0, 3)];
    const bool shops = Chance(rng, 0.7);
    const std::uint64_t building_seed = SubSeed(s_.seed, "building", building_count_++);
    const double z0 = kCurbHeightM;
    // The facades' layouts first: the body takes the colour of their walls.
    const Vec2 normals[4] = {Vec2(-1, 0), Vec2(1, 0), Vec2(0, -1), Vec2(0, 1)};
    std::vector<std::pair<int, FacadeLayout>> faces;
    for (int side = 0; side < 4; ++side) {
      if (!street_sides[side]) continue;
      const double width = side < 2 ? 2 * half.y() : 2 * half.x();
      faces.emplace_back(side, PlanFacade(building_seed, side, width, height, style, shops));
    }
    const cv::Scalar wall = faces.empty() ? cv::Scalar(150, 150, 150) : faces.front().second.wall_bgr;
    const Eigen::Vector4f body_rgba(float(wall[2] / 255), float(wall[1] / 255), float(wall[0] / 255), 1);
    const int body = b_.AddMaterial("building_body", -1, body_rgba);
    world_.static_geoms.push_back(MakeBox(At(c, z0 + height / 2), At(half, height / 2), body));
    for (const auto& [side, layout] : faces) {
      const Vec2 n = normals[side];
      const Vec2 mid = c + n * std::abs(n.dot(half));
      const double px_per_m = DetailPxPerM(mid - half.cwiseProduct(n.cwiseAbs().reverse()), mid + half.cwiseProduct(n.cwiseAbs().reverse()),
                                           kFarFacadePxPerM, std::max(layout.width_m, height));
      const std::uint64_t seed = SubSeed(building_seed, "facade", static_cast<std::uint64_t>(side));
      const int skin = AddPicture("facade", Vec2(layout.width_m, height), px_per_m,
                                  [seed, layout = layout, px_per_m] { return FacadeTexture(seed, layout, px_per_m); });
      MakeFacade(layout, skin, c, half, n, z0);
    }
    // A cornice that breaks the silhouette, and a plant room or stair housing on some roofs.
    Eigen::Vector4f trim_rgba = body_rgba * static_cast<float>(Uniform(rng, 0.7, 0.9));
    trim_rgba.w() = 1;
    const int trim = b_.AddMaterial("building_trim", -1, trim_rgba);
    world_.static_geoms.push_back(MakeBox(At(c, z0 + height + 0.4), At(half + Vec2::Constant(0.15), 0.4), trim));
    if (Chance(rng, 0.5)) {
      const Vec2 size(Uniform(rng, 0.2, 0.45) * half.x(), Uniform(rng, 0.2, 0.45) * half.y());
      const Vec2 at = c + Vec2(Uniform(rng, -0.4, 0.4) * half.x(), Uniform(rng, -0.4, 0.4) * half.y());
      const double h = Uniform(rng, 1.5, 3.5);
      world_.static_geoms.push_back(MakeBox(At(at, z0 + height + 0.8 + h / 2), At(size, h / 2), trim));
    }
  }

  // The facade `layout` on the side of the body (centre c, half extents `half`) whose
  // outward normal is `n`: a thin textured skin on the wall, and the layout's balconies
  // and awnings as geometry.
  void MakeFacade(const FacadeLayout& layout, int skin, const Vec2& c, const Vec2& half, const Vec2& n, double z0) {
    const double w = layout.width_m, h = layout.height_m;
    const double yaw = YawOf(n);
    // Seen from the street, the facade's x runs to the viewer's right: n rotated by -90 deg.
    const Vec2 right = Right(n) * -1.0;
    const Vec2 wall = c + n * std::abs(n.dot(half));
    const Vec2 left_edge = wall - right * (w / 2);
    world_.static_geoms.push_back(MakeBox(At(wall + n * kFacadeSkinM, z0 + h / 2), Vec3(kFacadeSkinM, w / 2, h / 2), skin, yaw));
    const auto on_facade = [&](double x_m, double out_m) { return left_edge + right * x_m + n * (2 * kFacadeSkinM + out_m); };
    if (!layout.balconies.empty()) {
      const cv::Scalar bgr = layout.trim_bgr;
      const int slab = b_.AddMaterial("balcony", -1, Eigen::Vector4f(float(bgr[2] / 255), float(bgr[1] / 255), float(bgr[0] / 255), 1));
      for (const FacadeLayout::Opening& b : layout.balconies) {
        const double depth = 1.0, bw = b.x1_m - b.x0_m, mid = 0.5 * (b.x0_m + b.x1_m);
        world_.static_geoms.push_back(MakeBox(At(on_facade(mid, depth / 2), z0 + b.z0_m - 0.08), Vec3(depth / 2, bw / 2, 0.08), slab, yaw));
        world_.static_geoms.push_back(MakeBox(At(on_facade(mid, depth - 0.02), z0 + b.z0_m + 0.5), Vec3(0.02, bw / 2, 0.5), look_.railing, yaw));
      }
    }
    for (const FacadeLayout::Shop& shop : layout.shops) {
      if (!shop.awning) continue;
      // A fabric awning under the sign, sloping 15 degrees down toward the street.
      const cv::Scalar bgr = shop.awning_bgr;
      const int fabric = b_.AddMaterial("awning", -1, Eigen::Vector4f(float(bgr[2] / 255), float(bgr[1] / 255), float(bgr[0] / 255), 1));
      const double depth = 1.3, tilt = 15.0 * M_PI / 180;
      Geom g = MakeBox(At(on_facade(0.5 * (shop.x0_m + shop.x1_m), 0.5 * depth * std::cos(tilt)),
                          z0 + layout.ground_floor_m - 1.0 - 0.5 * depth * std::sin(tilt)),
                       Vec3(depth / 2, (shop.x1_m - shop.x0_m) / 2 - 0.2, 0.03), fabric, yaw);
      g.T_parent_geom.linear() = g.T_parent_geom.linear() * Eigen::AngleAxisd(tilt, Vec3::UnitY()).matrix();
      world_.static_geoms.push_back(g);
    }
  }

  // Markings, furniture and fixed COCO objects along every street of the inner grid.
  void MakeStreets() {
    std::mt19937_64 rng = Rng("streets");
    for (int i = imin_; i <= imax_; ++i) {
      for (int j = jmin_; j <= jmax_; ++j) {
        const Node n{i, j};
        // Streets leaving this node in +x and +y.
        for (int axis = 0; axis < 2; ++axis) {
          const Node m = axis == 0 ? Node{i + 1, j} : Node{i, j + 1};
          if (m.first > imax_ || m.second > jmax_) continue;
          MakeStreetSegment(rng, n, m);
        }
        MakeIntersection(rng, n);
      }
    }
  }

  bool OnRoute(const Node& a, const Node& b) const {
    return route_edges_.count({a, b}) || route_edges_.count({b, a});
  }

  void MakeStreetSegment(std::mt19937_64& rng, const Node& a, const Node& b) {
    const Vec2 pa = NodePos(a), pb = NodePos(b);
    const Vec2 d = (pb - pa).normalized(), r = Right(d);
    const double yaw = YawOf(d);
    const double clear = road_ / 2 + 4.0;  // past the crosswalks
    const double len = block_ - 2 * clear;
    // Centre line: dashes 3 m long every 9 m (painted into the street's surface), from
    // where the last repainting happened to start.
    // (Its own generator: the markings change nothing else of the street.)
    std::mt19937_64 paint = Rng("centre_line", static_cast<std::uint64_t>((a.first + 1000) * 4096 + (a.second + 1000)) * 2 +
                                                   (b.first != a.first ? 0 : 1));
    for (double s = clear + Uniform(paint, 0, 6); s + 3.0 <= block_ - clear + 1e-9; s += 9.0) {
      markings_.push_back({pa + d * (s + 1.5), Vec2(1.5, 0.075), yaw});
    }
    // The parking lanes' lines along both curbs.
    for (double side : {-1.0, 1.0}) {
      markings_.push_back({pa + d * (block_ / 2) + r * side * (road_ / 2 - kParkingLaneM), Vec2(len / 2 + 2.5, 0.06), yaw});
    }
    // Sidewalk furniture on both sides: trees, lamps, benches, hydrants, parking slots.
    for (double side : {-1.0, 1.0}) {
      const Vec2 curb = r * side * (road_ / 2);
      const Vec2 out = r * side;  // from the road toward the buildings
      double s = clear + Uniform(rng, 0, 4);
      int k = 0;
      while (s < block_ - clear) {
        const Vec2 p = pa + d * s + curb + out * kFurnitureLineM;
        if (k % 3 == 1) {
          MakeLamp(p, -out);
        } else {
          MakeTree(rng, p);
        }
        s += Uniform(rng, 8, 13);
        ++k;
      }
      // Parking slots along the curb, heading with the traffic on that side.
      const Vec2 heading = side > 0 ? d : Vec2(-d);
      const bool on_route = OnRoute(a, b);
      // The row starts 0.25 m past the stop lines' centres (0.05 m past their edges) at
      // both ends, and vehicles in its end slots stay within them (ParkingLot::Fits), so
      // none stands on a stop line or a crosswalk.
      const int row = slots_.empty() ? 0 : slots_.back().row + 1;
      const int row_slots = static_cast<int>(std::floor((len - 0.5) / kSlotLengthM + 1e-9));
      const double row_start = clear + (len - row_slots * kSlotLengthM) / 2;
      for (int k = 0; k < row_slots; ++k) {
        Slot slot;
        slot.curb = pa + d * (row_start + (k + 0.5) * kSlotLengthM) + curb;
        slot.to_road = -out;
        slot.along_row = d;
        slot.yaw = YawOf(heading);
        slot.on_route = on_route;
        slot.row = row;
        slots_.push_back(slot);
      }
      // A few fixed COCO objects near the route: benches and hydrants.
      if (on_route && Chance(rng, 0.5)) {
        MakeBench(pa + d * Uniform(rng, clear + 2, block_ - clear - 2) + curb + out * (walk_ - kBenchFromFarEdgeM), YawOf(-out));
      }
      if (on_route && Chance(rng, 0.5)) {
        MakeHydrant(pa + d * Uniform(rng, clear, block_ - clear) + curb + out * 0.45);
      }
    }
  }

  void MakeIntersection(std::mt19937_64& rng, const Node& n) {
    const Vec2 c = NodePos(n);
    // Crosswalks on the arms, each painted to its own measure as crossings are (some
    // arms have none, some a ladder's side bars), so that no two intersections show the
    // same pattern of stripe corners; a stop line before each on the incoming lane.
    std::mt19937_64 paint = Rng("crosswalks", static_cast<std::uint64_t>((n.first + 1000) * 4096 + (n.second + 1000)));
    for (const Vec2& d : kStreetDirs) {
      const double stop_half = Uniform(paint, 0.15, 0.25);
      markings_.push_back({c + d * (road_ / 2 + kStopLineM) + Right(-d) * (road_ / 4), Vec2(stop_half, road_ / 4 - 0.3), YawOf(d)});
      if (Chance(paint, 0.15)) continue;
      const double length = Uniform(paint, 2.4, 3.2);
      const double from_edge = Uniform(paint, 0.3, kStopLineM - stop_half - 0.2 - length);
      const Vec2 p = c + d * (road_ / 2 + from_edge + length / 2);
      const double half_width = road_ / 2 - Uniform(paint, 0.4, 1.0);
      const double stripe = Uniform(paint, 0.4, 0.6), pitch = stripe + Uniform(paint, 0.35, 0.7);
      for (double across = -half_width + Uniform(paint, 0, pitch - stripe) + stripe / 2; across + stripe / 2 <= half_width;
           across += pitch) {
        markings_.push_back({p + Right(d) * across, Vec2(length / 2, stripe / 2), YawOf(d)});
      }
      if (Chance(paint, 0.3)) {  // a ladder: bars along both ends of the stripes
        for (double end : {-1.0, 1.0}) {
          markings_.push_back({p + d * (end * (length / 2 + 0.1)), Vec2(0.08, half_width), YawOf(d)});
        }
      }
    }
    // Near the route: traffic lights at two corners, or a stop sign.
    bool near_route = false;
    for (const Node& m : nodes_) near_route |= std::abs(m.first - n.first) + std::abs(m.second - n.second) <= 1;
    if (!near_route) return;
    const double q = road_ / 2 + 0.5;
    if (Chance(rng, 0.6)) {
      MakeTrafficLight(c + Vec2(q, -q), Vec2(-1, 0));
      MakeTrafficLight(c + Vec2(-q, q), Vec2(1, 0));
    } else {
      MakeStopSign(c + Vec2(-q, -q), Vec2(0, -1));
    }
  }

  void MakeTree(std::mt19937_64& rng, const Vec2& p) {
    const double h = Uniform(rng, 3.0, 4.5), crown = Uniform(rng, 1.6, 2.4);
    world_.static_geoms.push_back(MakeRod(At(p, kCurbHeightM), At(p, kCurbHeightM + h + 0.5), Uniform(rng, 0.12, 0.2), look_.bark));
    const int foliage = look_.foliage[UniformInt(rng, 0, 2)];
    world_.static_geoms.push_back(MakeShape(Shape::kEllipsoid, At(p, kCurbHeightM + h + crown * 0.8),
                                            Vec3(crown, crown * Uniform(rng, 0.85, 1.1), crown * 1.1), foliage,
                                            Eigen::AngleAxisd(Uniform(rng, 0, M_PI), Vec3::UnitZ()).matrix()));
    // A second, smaller crown for an irregular outline.
    world_.static_geoms.push_back(MakeShape(Shape::kEllipsoid, At(p + Vec2(Uniform(rng, -0.8, 0.8), Uniform(rng, -0.8, 0.8)), kCurbHeightM + h + crown * 1.5),
                                            Vec3::Constant(crown * 0.65), foliage));
    // A tree grate around the trunk.
    world_.static_geoms.push_back(MakeBox(At(p, kCurbHeightM + 0.005), Vec3(0.6, 0.6, 0.005), look_.dark_metal));
  }

  void MakeLamp(const Vec2& p, const Vec2& toward_road) {
    const double h = 6.0;
    world_.static_geoms.push_back(MakeRod(At(p, kCurbHeightM), At(p, kCurbHeightM + h), 0.08, look_.dark_metal));
    const Vec2 tip = p + toward_road * 1.4;
    world_.static_geoms.push_back(MakeRod(At(p, kCurbHeightM + h - 0.1), At(tip, kCurbHeightM + h + 0.15), 0.05, look_.dark_metal));
    world_.static_geoms.push_back(MakeBox(At(tip, kCurbHeightM + h + 0.05), Vec3(0.35, 0.16, 0.08), look_.metal, YawOf(toward_road)));
    // A sign board with its own text.
    const std::uint64_t seed = SubSeed(s_.seed, "street_sign", sign_count_++);
    const int board = AddPicture("street_sign", Vec2(0.6, 0.8), cv::Size(128, 160), [seed] { return StreetSignTexture(seed); });
    world_.static_geoms.push_back(MakeBox(At(p + toward_road * 0.12, kCurbHeightM + 2.6), Vec3(0.02, 0.3, 0.4), board, YawOf(toward_road)));
  }

  // ---- Fixed COCO objects --------------------------------------------------------------
  Object& Fixed(const std::string& category, const Vec2& p, double yaw) {
    Object& o = b_.AddObject(category);
    o.parts.push_back(Part{category, {}});
    for (Placement& pl : o.placement) pl.T_world_object = PoseXYZYaw(At(p, kCurbHeightM), yaw);
    return o;
  }

  void MakeTrafficLight(const Vec2& p, const Vec2& facing) {
    Object& o = Fixed("traffic light", p, YawOf(facing));
    auto& g = o.parts[0].geoms;
    g.push_back(MakeRod(Vec3(0, 0, 0), Vec3(0, 0, 3.2), 0.07, look_.dark_metal));
    g.push_back(MakeBox(Vec3(0.05, 0, 3.65), Vec3(0.12, 0.17, 0.45), look_.traffic_lamps));
    g.push_back(MakeBox(Vec3(-0.06, 0, 3.65), Vec3(0.02, 0.25, 0.55), look_.dark_metal));
  }

  void MakeStopSign(const Vec2& p, const Vec2& facing) {
    Object& o = Fixed("stop sign", p, YawOf(facing));
    auto& g = o.parts[0].geoms;
    g.push_back(MakeRod(Vec3(0, 0, 0), Vec3(0, 0, 2.2), 0.035, look_.metal));
    g.push_back(MakeBox(Vec3(0.04, 0, 2.35), Vec3(0.015, 0.375, 0.375), look_.stop_sign));
  }

  void MakeHydrant(const Vec2& p) {
    Object& o = Fixed("fire hydrant", p, 0.0);
    auto& g = o.parts[0].geoms;
    g.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.35), Vec3(0.13, 0.35, 0), look_.red_paint));
    g.push_back(MakeShape(Shape::kSphere, Vec3(0, 0, 0.72), Vec3(0.14, 0, 0), look_.red_paint));
    g.push_back(MakeRod(Vec3(0, -0.22, 0.48), Vec3(0, 0.22, 0.48), 0.05, look_.chrome));
    g.push_back(MakeRod(Vec3(0, 0, 0.48), Vec3(0.2, 0, 0.48), 0.06, look_.red_paint));
  }

  void MakeBench(const Vec2& p, double yaw) {
    Object& o = Fixed("bench", p, yaw);
    auto& g = o.parts[0].geoms;
    g.push_back(MakeBox(Vec3(0, 0, 0.45), Vec3(0.22, 0.9, 0.03), look_.wood));
    g.push_back(MakeBox(Vec3(-0.22, 0, 0.75), Vec3(0.03, 0.9, 0.2), look_.wood));
    for (double y : {-0.8, 0.8}) g.push_back(MakeBox(Vec3(0, y, 0.21), Vec3(0.2, 0.03, 0.21), look_.dark_metal));
  }

  // ---- Cars ----------------------------------------------------------------------------
  // A car, truck or bus as one rigid part; object frame on the ground at the centre,
  // x forward.
  Part MakeVehicle(std::mt19937_64& rng, const std::string& kind) {
    static const Eigen::Vector4f kPalette[] = {
        {0.95f, 0.95f, 0.95f, 1}, {0.08f, 0.08f, 0.09f, 1}, {0.6f, 0.62f, 0.65f, 1}, {0.7f, 0.08f, 0.07f, 1},
        {0.1f, 0.2f, 0.55f, 1},   {0.35f, 0.36f, 0.38f, 1}, {0.1f, 0.3f, 0.15f, 1},  {0.95f, 0.75f, 0.1f, 1},
        {0.5f, 0.25f, 0.1f, 1},   {0.3f, 0.5f, 0.7f, 1}};
    // Its own shade of a common colour, and plates with its own registration.
    const std::uint64_t vehicle_seed = SubSeed(s_.seed, "vehicle", vehicle_count_++);
    std::mt19937_64 own(vehicle_seed);
    Eigen::Vector4f colour = kPalette[UniformInt(rng, 0, 9)];
    colour.head<3>() = (colour.head<3>() * static_cast<float>(Uniform(own, 0.85, 1.1))).cwiseMin(1.f);
    // Paint and glass of its own (panel gaps, scratches, dirt; what shows through the
    // windows), each picture as large as the largest face it covers.
    const auto paint_of = [&](const std::string& name, const Vec2& size_m, const Eigen::Vector4f& rgba, std::uint64_t index) {
      const std::uint64_t seed = SubSeed(vehicle_seed, name, index);
      const cv::Size px = PixelsFor(size_m, kVehiclePxPerM);
      return pictures_.Add(b_, name, px, size_m, [seed, px] { return VehiclePaintTexture(seed, px); }, rgba, 0.5f, 0.5f);
    };
    const auto glass_of = [&](const Vec2& size_m) {
      const std::uint64_t seed = SubSeed(vehicle_seed, "glass");
      const cv::Size px = PixelsFor(size_m, kVehiclePxPerM);
      return pictures_.Add(b_, "car_glass", px, size_m, [seed, px] { return VehicleGlassTexture(seed, px); },
                           Eigen::Vector4f::Ones(), 0.6f);
    };
    const int plate = AddPicture("plate", Vec2(0.52, 0.13), cv::Size(256, 64), [vehicle_seed] { return NumberPlateTexture(vehicle_seed); });
    Part part{"body", {}};
    auto& g = part.geoms;
    auto wheels = [&](double L, double W, double r) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).matrix();
      for (double x : {-0.33 * L, 0.33 * L}) {
        for (double y : {-1.0, 1.0}) {
          g.push_back(MakeShape(Shape::kCylinder, Vec3(x, y * (W / 2 - 0.14), r), Vec3(r, 0.12, 0), look_.rubber, R));
          g.push_back(MakeShape(Shape::kCylinder, Vec3(x, y * (W / 2 - 0.01), r), Vec3(r * 0.55, 0.005, 0), look_.chrome, R));
        }
      }
    };
    auto lights_and_plates = [&](double L, double W, double z) {
      for (double y : {-1.0, 1.0}) {
        g.push_back(MakeBox(Vec3(L / 2, y * (W / 2 - 0.22), z), Vec3(0.02, 0.16, 0.06), look_.headlight));
        g.push_back(MakeBox(Vec3(-L / 2, y * (W / 2 - 0.2), z), Vec3(0.02, 0.14, 0.07), look_.taillight));
      }
      g.push_back(MakeBox(Vec3(L / 2 + 0.01, 0, z - 0.2), Vec3(0.01, 0.26, 0.065), plate));
      g.push_back(MakeBox(Vec3(-L / 2 - 0.01, 0, z - 0.1), Vec3(0.01, 0.26, 0.065), plate));
    };
    if (kind == "truck") {
      const double L = Uniform(rng, 6.0, 7.0), W = 2.3;
      const int paint = paint_of(kind + "_paint", Vec2(W, 1.9), colour, 0);
      g.push_back(MakeBox(Vec3(L / 2 - 0.9, 0, 1.45), Vec3(0.9, W / 2, 0.95), paint));           // cab
      g.push_back(MakeBox(Vec3(L / 2 - 0.35, 0, 1.85), Vec3(0.36, W / 2 - 0.08, 0.4), glass_of(Vec2(W, 0.8))));  // windscreen
      const int cargo = paint_of("truck_cargo", Vec2(L - 1.9, 2.7), Eigen::Vector4f(0.92f, 0.92f, 0.9f, 1), 1);
      g.push_back(MakeBox(Vec3(-0.95, 0, 1.9), Vec3(L / 2 - 0.95, W / 2, 1.35), cargo));          // box
      const std::uint64_t logo_seed = SubSeed(vehicle_seed, "logo");
      const int logo = AddPicture("truck_logo", Vec2(3.2, 1.2), cv::Size(320, 120), [logo_seed] { return CompanyLogoTexture(logo_seed); });
      g.push_back(MakeBox(Vec3(-0.95, W / 2 + 0.005, 2.0), Vec3(1.6, 0.005, 0.6), logo));
      g.push_back(MakeBox(Vec3(0, 0, 0.55), Vec3(L / 2, W / 2 - 0.1, 0.12), look_.dark_metal));   // chassis
      wheels(L, W, 0.45);
      lights_and_plates(L, W, 0.75);
    } else if (kind == "bus") {
      const double L = 11.0, W = 2.5;
      g.push_back(MakeBox(Vec3(0, 0, 1.75), Vec3(L / 2, W / 2, 1.3), paint_of(kind + "_paint", Vec2(L, 2.6), colour, 0)));
      const int glass = glass_of(Vec2(L, 1.6));
      g.push_back(MakeBox(Vec3(0, 0, 2.15), Vec3(L / 2 - 0.4, W / 2 + 0.01, 0.5), glass));
      g.push_back(MakeBox(Vec3(L / 2 + 0.01, 0, 2.0), Vec3(0.01, W / 2 - 0.1, 0.8), glass));
      wheels(L * 0.85, W, 0.5);
      lights_and_plates(L, W, 0.8);
    } else {
      const double L = Uniform(rng, 4.1, 4.8), W = Uniform(rng, 1.75, 1.9), hb = Uniform(rng, 0.32, 0.4);
      const double cabin_l = L * Uniform(rng, 0.45, 0.6);
      const int paint = paint_of(kind + "_paint", Vec2(L, W), colour, 0);
      g.push_back(MakeBox(Vec3(0, 0, 0.28 + hb), Vec3(L / 2, W / 2, hb), paint));  // lower body
      g.push_back(MakeBox(Vec3(-0.08 * L, 0, 0.28 + 2 * hb + 0.24), Vec3(cabin_l / 2, W / 2 - 0.1, 0.24), glass_of(Vec2(cabin_l, W))));
      g.push_back(MakeBox(Vec3(-0.08 * L, 0, 0.28 + 2 * hb + 0.5), Vec3(cabin_l / 2 - 0.1, W / 2 - 0.12, 0.025), paint));  // roof
      g.push_back(MakeBox(Vec3(L / 2 - 0.05, 0, 0.4), Vec3(0.08, W / 2, 0.1), look_.rubber));    // bumpers
      g.push_back(MakeBox(Vec3(-L / 2 + 0.05, 0, 0.4), Vec3(0.08, W / 2, 0.1), look_.rubber));
      for (double y : {-1.0, 1.0}) {  // mirrors
        g.push_back(MakeBox(Vec3(0.18 * L, y * (W / 2 + 0.08), 0.28 + 2 * hb + 0.1), Vec3(0.06, 0.08, 0.06), paint));
      }
      wheels(L, W, 0.32);
      lights_and_plates(L, W, 0.28 + hb + 0.1);
    }
    return part;
  }

  std::string VehicleKind(std::mt19937_64& rng, bool allow_bus) {
    const double r = Uniform(rng, 0, 1);
    if (r < 0.12) return "truck";
    if (allow_bus && r < 0.2) return "bus";
    return "car";
  }

  struct Slot {
    Vec2 curb;     // on the curb's edge, at the middle of the slot
    Vec2 to_road;  // unit, from the curb toward the street's centre line
    Vec2 along_row;  // unit, toward the row's next slot (against the heading on one curb)
    double yaw = 0;
    bool on_route = false;
    int row = 0;  // the slots along one curb between two intersections share a row, in order
  };

  // A vehicle parked in a slot in one pass: its shift toward the row's next slot and its
  // half length.
  struct ParkedVehicle {
    double shift_m = 0, half_length = 0;
  };

  // Which slot holds which vehicle in each pass, so that no two parked vehicles touch:
  // stalls are 6.5 m long, a truck 7.2 m, and pass 2 moves vehicles along the curb.
  class ParkingLot {
   public:
    explicit ParkingLot(const std::vector<Slot>& slots) : slots_(slots), parked_(slots.size()), used_(slots.size()) {}

    // Whether a vehicle of `half_length` shifted by `shift_m` fits slot i in `pass`: apart
    // from its neighbours, and within its slot at the ends of a row.
    bool Fits(std::size_t i, int pass, double half_length, double shift_m) const {
      for (int dir : {-1, 1}) {
        const std::optional<std::size_t> j = Neighbour(i, dir);
        if (!j && dir * shift_m + half_length > kSlotLengthM / 2 + 1e-9) return false;
        if (!j || !parked_[*j][pass]) continue;
        const double gap = dir * (dir * kSlotLengthM + parked_[*j][pass]->shift_m - shift_m);
        if (gap < half_length + parked_[*j][pass]->half_length + kParkedGapM) return false;
      }
      return true;
    }

    // How far a vehicle in slot i may move along the curb in direction dir (+1 ahead) in
    // `pass`: up to the next vehicle; into an empty neighbouring slot only as far as still
    // leaves room for a car there; at the end of a row, not beyond its own slot.
    double Room(std::size_t i, int pass, double half_length, int dir) const {
      const std::optional<std::size_t> j = Neighbour(i, dir);
      if (!j) return kSlotLengthM / 2 - half_length;
      const std::optional<ParkedVehicle>& other = parked_[*j][pass];
      if (!other) return kSlotLengthM - half_length - kCarDims.half_length - kParkedGapM;
      return kSlotLengthM + dir * other->shift_m - half_length - other->half_length - kParkedGapM;
    }

    // The first slot of `order` not taken before that fits the vehicle in the passes
    // where it is present, or null when none does; marks it taken.
    std::optional<std::size_t> Take(const std::vector<std::size_t>& order, const std::array<bool, 2>& passes,
                                    double half_length) {
      for (std::size_t i : order) {
        if (used_[i]) continue;
        if ((passes[0] && !Fits(i, 0, half_length, 0)) || (passes[1] && !Fits(i, 1, half_length, 0))) continue;
        used_[i] = true;
        for (int pass : {0, 1}) {
          if (passes[pass]) parked_[i][pass] = ParkedVehicle{0, half_length};
        }
        return i;
      }
      return std::nullopt;
    }

    void Leave(std::size_t i, int pass) { parked_[i][pass].reset(); }
    void Park(std::size_t i, int pass, const ParkedVehicle& v) { parked_[i][pass] = v; }

   private:
    std::optional<std::size_t> Neighbour(std::size_t i, int dir) const {
      const std::size_t j = i + dir;
      if (j >= slots_.size() || slots_[j].row != slots_[i].row) return std::nullopt;
      return j;
    }

    const std::vector<Slot>& slots_;
    std::vector<std::array<std::optional<ParkedVehicle>, 2>> parked_;
    std::vector<bool> used_;  // taken in either pass: a slot left in pass 2 stays empty
  };

  // Parked cars at the curbs, most along the route; pass 2 relocates, removes, adds.
  void MakeParkedCars() {
    std::mt19937_64 rng = Rng("parked");
    // Slot order: route slots first, each group shuffled.
    std::vector<std::size_t> route_slots, other_slots;
    for (std::size_t i = 0; i < slots_.size(); ++i) (slots_[i].on_route ? route_slots : other_slots).push_back(i);
    Shuffle(route_slots, rng);
    Shuffle(other_slots, rng);
    std::vector<std::size_t> order = route_slots;
    order.insert(order.end(), other_slots.begin(), other_slots.end());
    ParkingLot lot(slots_);
    auto pose_of = [&](const Slot& slot, const VehicleDims& dims, double shift_m) {
      const Vec2 centre = slot.curb + slot.to_road * (kCurbGapM + dims.half_width) + shift_m * slot.along_row;
      return PoseXYZYaw(At(centre, 0.0), slot.yaw + Uniform(rng, -0.03, 0.03));
    };

    // Pass 1 cars.
    std::vector<int> ids;
    std::vector<std::size_t> own_slots;
    for (int k = 0; k < spec_.parked_cars; ++k) {
      const std::string kind = VehicleKind(rng, false);
      const VehicleDims dims = Dims(kind);
      const std::optional<std::size_t> slot = lot.Take(order, {true, true}, dims.half_length);
      if (!slot) break;
      Object& o = b_.AddObject(kind);
      o.parts.push_back(MakeVehicle(rng, o.category_name));
      o.placement[0].T_world_object = pose_of(slots_[*slot], dims, 0);
      o.placement[1] = o.placement[0];
      ids.push_back(static_cast<int>(world_.objects.size()) - 1);
      own_slots.push_back(*slot);
    }
    // Pass 2: relocate (within the car's own slot, along the curb, or to a free slot),
    // remove, add.
    const ChangePlan plan = PlanSecondPass(static_cast<int>(ids.size()), s_.pass2, rng);
    for (int k : plan.removed) {
      world_.objects[ids[k]].placement[1].present = false;
      lot.Leave(own_slots[k], 1);
    }
    const double shift_m = s_.pass2.relocated_shift_m;
    for (int k : plan.relocated) {
      Object& car = world_.objects[ids[k]];
      const VehicleDims dims = Dims(car.category_name);
      const std::size_t i = own_slots[k];
      lot.Leave(i, 1);
      if (shift_m > 0) {
        // Moved by at least half the option, the preferred way if there is room for that.
        const double want = Uniform(rng, 0.5, 1.0) * shift_m;
        const int preferred = Chance(rng, 0.5) ? 1 : -1;
        std::optional<double> shift;
        for (int dir : {preferred, -preferred}) {
          const double room = lot.Room(i, 1, dims.half_length, dir);
          if (!shift && room >= 0.5 * shift_m) shift = dir * std::min(want, room);
        }
        if (shift) {
          lot.Park(i, 1, {*shift, dims.half_length});
          car.placement[1].T_world_object = pose_of(slots_[i], dims, *shift);
          continue;
        }
        // No room along the curb (a truck between two vehicles): parked elsewhere.
      }
      const std::optional<std::size_t> slot = lot.Take(order, {false, true}, dims.half_length);
      if (!slot) {
        lot.Park(i, 1, {0, dims.half_length});
        continue;
      }
      car.placement[1].T_world_object = pose_of(slots_[*slot], dims, 0);
    }
    for (int k = 0; k < s_.pass2.added; ++k) {
      const std::string kind = VehicleKind(rng, false);
      const VehicleDims dims = Dims(kind);
      const std::optional<std::size_t> slot = lot.Take(order, {false, true}, dims.half_length);
      if (!slot) break;
      Object& o = b_.AddObject(kind);
      o.parts.push_back(MakeVehicle(rng, o.category_name));
      o.placement[0].present = false;
      o.placement[1].T_world_object = pose_of(slots_[*slot], dims, 0);
    }
    parked_candidates_ = static_cast<int>(ids.size());
  }

  // ---- Moving actors along the route -----------------------------------------------------
  // Moving cars and pedestrians are scripted against the camera: each gets a path on the
  // streets of the route and a start offset chosen so that it is in front of the camera
  // for a while (ahead in its lane, oncoming, crossing, on the sidewalks, at crosswalks),
  // then every candidate is checked at frame rate over both passes for clearance from
  // the camera and from the actors placed before it.

  // An arc-length parametrised 2-D polyline.
  struct Poly2 {
    std::vector<Vec2> p;
    std::vector<double> c;
    explicit Poly2(std::vector<Vec2> pts) : p(std::move(pts)), c(p.size(), 0.0) {
      for (std::size_t i = 1; i < p.size(); ++i) c[i] = c[i - 1] + (p[i] - p[i - 1]).norm();
    }
    double Length() const { return c.back(); }
    Vec2 At(double s) const {
      s = std::clamp(s, 0.0, Length());
      const auto it = std::upper_bound(c.begin(), c.end(), s);
      const std::size_t i = std::clamp<std::size_t>(it - c.begin(), 1, p.size() - 1);
      const double seg = c[i] - c[i - 1];
      return p[i - 1] + (seg > 0 ? (s - c[i - 1]) / seg : 0.0) * (p[i] - p[i - 1]);
    }
    Vec2 Tangent(double s) const { return (At(s + 0.5) - At(s - 0.5)).normalized(); }
    // Arc length of the point nearest to q, on the segments that reach into [lo_s, hi_s]
    // (a lane that passes the same place twice: the pass meant).
    double Closest(const Vec2& q, double lo_s = -1e18, double hi_s = 1e18) const {
      double best = 1e18, best_s = 0;
      for (std::size_t i = 1; i < p.size(); ++i) {
        if (c[i] < lo_s || c[i - 1] > hi_s) continue;
        const Vec2 d = p[i] - p[i - 1];
        const double len2 = d.squaredNorm();
        const double u = len2 > 0 ? std::clamp((q - p[i - 1]).dot(d) / len2, 0.0, 1.0) : 0.0;
        const double dist = (p[i - 1] + u * d - q).norm();
        if (dist < best) best = dist, best_s = c[i - 1] + u * (c[i] - c[i - 1]);
      }
      return best_s;
    }
  };

  // A lane through consecutive nodes at `offset` right of the direction of travel, corners
  // rounded like the camera's lane, extended straight by ext_before and ext_after.
  std::vector<Vec2> NodeLane(const std::vector<Node>& nodes, double offset, double ext_before, double ext_after) const {
    const double radius = std::min(6.0, block_ / 5);
    auto dir = [&](std::size_t k) { return Vec2((NodePos(nodes[k + 1]) - NodePos(nodes[k])).normalized()); };
    std::vector<Vec2> pts;
    const Vec2 d0 = dir(0);
    pts.push_back(NodePos(nodes[0]) - d0 * ext_before + Right(d0) * offset);
    for (std::size_t k = 1; k + 1 < nodes.size(); ++k) {
      const Vec2 a = dir(k - 1), b = dir(k);
      if ((a - b).norm() < 1e-9) continue;
      const Vec2 corner = NodePos(nodes[k]) + Right(a) * offset + Right(b) * offset;
      const Vec2 centre = corner - a * radius + b * radius;
      for (int i = 0; i <= 12; ++i) {
        const double th = 0.5 * M_PI * i / 12;
        pts.push_back(centre + radius * (-b * std::cos(th) + a * std::sin(th)));
      }
    }
    const Vec2 dl = dir(nodes.size() - 2);
    pts.push_back(NodePos(nodes.back()) + dl * ext_after + Right(dl) * offset);
    return pts;
  }

  // Nodes of the route with the one before the first: the camera's lane is a part of
  // NodeLane(RouteNodes(), lane_, e, e) starting at arc length e + block_ / 2.
  std::vector<Node> RouteNodes() const {
    const Node before{2 * nodes_[0].first - nodes_[1].first, 2 * nodes_[0].second - nodes_[1].second};
    std::vector<Node> n = {before};
    n.insert(n.end(), nodes_.begin(), nodes_.end());
    return n;
  }

  // Whether a ground point is on a raised block (sidewalk) rather than on a street.
  bool OnBlock(const Vec2& p) const {
    if (p.x() < (imin_ - 1) * block_ || p.x() > (imax_ + 1) * block_ || p.y() < (jmin_ - 1) * block_ ||
        p.y() > (jmax_ + 1) * block_) {
      return false;
    }
    const double u = p.x() - block_ * std::round(p.x() / block_), v = p.y() - block_ * std::round(p.y() / block_);
    return std::abs(u) > road_ / 2 && std::abs(v) > road_ / 2;
  }

  // A walking path through `pts`, resampled every metre, on the sidewalk or the street.
  PathMotion WalkPath(const std::vector<Vec2>& pts) const {
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
  void CoverBothPasses(PathMotion& path, bool walking) const {
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

  static PathMotion DrivePath(const std::vector<Vec2>& pts) {
    PathMotion path;
    path.closed = false;
    for (const Vec2& q : pts) path.waypoints.push_back(At(q, 0.0));
    return path;
  }

  // Frame samples of both passes: camera position and the tracks of placed actors.
  struct Sample {
    Pass pass;
    double t;
    Vec2 camera;
  };
  // The movers of one or both passes, and the tag of their random streams (other tags,
  // other draws: other vehicles and people on other paths at other times).
  struct Traffic {
    std::array<bool, 2> present{true, true};  // indexed by PassIndex()
    std::string tag;
  };

  struct Track {
    std::vector<Vec2> pos;
    std::vector<Vec2> heading;  // (cos, sin) of the yaw
    std::vector<char> present;  // per sample: in the world at that time
    double half_length = 0.3, half_width = 0.3;
    bool car = false;
    // Radius of the footprint, bare (BodiesClear) and inflated by each clearance margin
    // (Clearance).
    double radius = 0, radius_with_car_margin = 0, radius_with_person_margin = 0;
  };
  static constexpr double kCarMarginM = 0.3;     // cars keep 0.6 m between bodies
  static constexpr double kPersonMarginM = 0.1;  // people 0.2 m from anyone
  // Least gap between the camera car's body and a moving vehicle's or a person's, a hard
  // requirement (CameraCarClear).
  static constexpr double kCameraCarToVehicleM = 1.0;
  static constexpr double kCameraCarToPersonM = 0.5;

  // Frame samples of both passes, and the camera car's track at them: a car of kCarDims
  // whose front bumper is kCameraToBumperM ahead of the camera, heading along the route
  // (pass 2's camera_offset_m moves it, camera_yaw_offset_deg only turns the camera on it).
  void MakeSamples() {
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

  Track TrackOf(const Object& o, double half_length, double half_width, bool car) const {
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

  // Separating-axis ratio of two footprints inflated by `margin`: >= 1 means clear.
  static double SatRatio(const Track& a, const Track& b, std::size_t i, double margin) {
    const Vec2& ua = a.heading[i];
    const Vec2& ub = b.heading[i];
    const Vec2 axes[4] = {ua, Vec2(-ua.y(), ua.x()), ub, Vec2(-ub.y(), ub.x())};
    const Vec2 d = b.pos[i] - a.pos[i];
    double best = 0;
    for (const Vec2& u : axes) {
      const double ra = (a.half_length + margin) * std::abs(u.dot(ua)) + (a.half_width + margin) * std::abs(u.x() * -ua.y() + u.y() * ua.x());
      const double rb = (b.half_length + margin) * std::abs(u.dot(ub)) + (b.half_width + margin) * std::abs(u.x() * -ub.y() + u.y() * ub.x());
      best = std::max(best, std::abs(d.dot(u)) / (ra + rb));
    }
    return best;
  }

  // How clear a track is: min over frames of distance to the camera / min_camera_m and
  // the separating-axis ratio against placed actors; >= 1 is clear. Stops below `floor`.
  double Clearance(const Track& tr, double min_camera_m, double floor) const {
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
  bool BodiesClear(const Track& tr) const {
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
  bool CameraCarClear(const Track& tr) const {
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
  template <typename MakePath>
  bool PlaceMover(int index, const std::array<bool, 2>& present, double half_length, double half_width, bool car,
                  double min_camera_m, int attempts, MakePath make) {
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

  static VehicleDims Dims(const std::string& kind) {
    return kind == "bus" ? kBusDims : kind == "truck" ? kTruckDims : kCarDims;
  }

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
  void MakeRedLightLeads(const std::vector<Node>& fnodes, const Traffic& traffic) {
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

  // The lanes along the route (moving cars drive them, pedestrians are placed by the
  // camera's), as polylines extended 300 m at both ends so that no path ends while in view.
  struct RouteLanes {
    static constexpr double kExtensionM = 300.0;
    Poly2 forward;   // the camera's lane
    Poly2 same;      // cars ahead: the inner lane when the road has two, else the camera's
    Poly2 opposite;  // oncoming
    double f0;       // arc on `forward` of the camera's start
    bool two_lanes;
  };

  RouteLanes MakeRouteLanes() const {
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

  // An intersection the camera approaches during the pass, with its route arc length.
  struct Crossing {
    Node node;
    Vec2 arrive;  // direction the camera arrives in
    double s;
  };

  std::vector<Crossing> CrossingsOnRoute(const RouteLanes& lanes) const {
    std::vector<Crossing> crossings;
    for (std::size_t k = 0; k < nodes_.size(); ++k) {
      const double s = lanes.forward.Closest(NodePos(nodes_[k])) - lanes.f0;
      if (s > 16.0 && s < lane_s_.back() + 20.0) crossings.push_back({nodes_[k], kStreetDirs[dirs_[k]], s});
    }
    return crossings;
  }

  // Route arc length of the camera's turns.
  std::vector<double> TurnsOnRoute(const RouteLanes& lanes) const {
    std::vector<double> turns;
    for (std::size_t k = 1; k + 1 < nodes_.size(); ++k) {
      if (dirs_[k] != dirs_[k + 1]) turns.push_back(lanes.forward.Closest(NodePos(nodes_[k])) - lanes.f0);
    }
    return turns;
  }

  enum class CarRole { kAhead, kOncoming, kCrossing };

  // Roles in turn: ahead, oncoming, crossing, second ahead, then oncoming and crossing.
  // A one-lane queue ahead would run into the vehicles the camera waits behind at red
  // lights, so with those the camera's lane holds only them. Without an intersection
  // ahead on the route, crossing cars come oncoming instead.
  std::vector<CarRole> MovingCarRoles(bool two_lanes, bool any_crossing) const {
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
  PathMotion AheadMotion(std::mt19937_64& rng, const RouteLanes& lanes, int rank, double half_length, int a,
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
  PathMotion OncomingMotion(std::mt19937_64& rng, const RouteLanes& lanes, const std::vector<double>& turns, int rank,
                            int count, int a) const {
    PathMotion p = DrivePath(lanes.opposite.p);
    p.speed_mps = spec_.moving_car_speed_mps * Uniform(rng, 0.85, 1.15);
    const double lo = 10.0, hi = lane_s_.back() - 5.0;
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
  PathMotion CrossingMotion(std::mt19937_64& rng, const std::vector<Crossing>& crossings, int rank, int count,
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
  void MakeMovingCars(const Traffic& traffic) {
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

  Object& MakePedestrian(std::mt19937_64& rng) {
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

  // A crosswalk on an arm the camera arrives on, with its route arc length.
  struct Crosswalk {
    Vec2 centre, along;
    double s;
    const RedLight* light;  // where the camera stands before it, or null
  };

  // The crosswalks pedestrians cross: those before the red lights when there are any,
  // else those before the intersections ahead on the route.
  std::vector<Crosswalk> CrosswalksOnRoute(const RouteLanes& lanes) const {
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
      if (s > 24.0 && s < lane_s_.back() + 30.0) crosswalks.push_back({centre, a, s, nullptr});
    }
    return crosswalks;
  }

  // How far from the curb a pedestrian walks along a sidewalk: drawn over its middle and
  // kept in the strip between the trees and lamps and the benches (the scenario's
  // smallest sidewalk leaves that strip room).
  double SidewalkLineFromCurb(std::mt19937_64& rng) const {
    return std::clamp(walk_ * Uniform(rng, 0.45, 0.6), kWalkStripNearM, walk_ - kWalkStripFarM);
  }
  // The same, keeping right: the strip's half toward the buildings for one walking with
  // them on the right hand, toward the curb otherwise, the halves a body's width apart
  // so that people meeting each other pass. A strip too narrow for that is shared.
  double KeepRightLineFromCurb(std::mt19937_64& rng, bool buildings_on_the_right) const {
    const double near = kWalkStripNearM, far = walk_ - kWalkStripFarM;
    const double band = 0.5 * (far - near - 2 * kWalkerClearanceM);
    if (band < 0) return SidewalkLineFromCurb(rng);
    return buildings_on_the_right ? Uniform(rng, far - band, far) : Uniform(rng, near, near + band);
  }

  // Crossing pedestrian k of `crossers` at `speed`, attempt `a` of its placement: over a
  // crosswalk (spread by k for the first attempts), in the middle of the street when the
  // camera is 16-32 m before it; at a red light, while the camera stands, and off the
  // street before it turns green.
  PathMotion CrossingWalkerMotion(std::mt19937_64& rng, const std::vector<Crosswalk>& crosswalks, int k,
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
  PathMotion SidewalkWalkerMotion(std::mt19937_64& rng, const RouteLanes& lanes, int rank, int walkers,
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
  void MakePedestrians(const Traffic& traffic) {
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

  // ---- Camera ----------------------------------------------------------------------------
  void MakeCameraRoutes() {
    const double v = spec_.camera_speed_mps;
    const double duration = CameraTimeAt(lane_s_.back());
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
      const Vec2 fwd = (LaneAt(s + 0.5) - LaneAt(s - 0.5)).normalized();
      const Vec3 eye = At(LaneAt(s), spec_.camera_height_m + 0.01 * bump.Eval(road_t));
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

  void MakeLights() {
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

 public:
  int parked_candidates_ = 0;
  int movers_left_out_ = 0;
  int red_lights_left_out_ = 0;

 private:
  const Scenario& s_;
  const CitySpec& spec_;
  World world_;
  WorldBuilder b_;
  CityLook look_;
  PicturePages pictures_;               // every surface's own picture, packed at the end
  std::vector<RoadMarking> markings_;         // painted into the streets' surfaces
  std::uint64_t building_count_ = 0, sign_count_ = 0, vehicle_count_ = 0;

  double block_, road_, walk_, lane_;
  std::vector<Node> nodes_;
  std::vector<int> dirs_;
  std::set<Edge> route_edges_;
  int imin_ = 0, imax_ = 0, jmin_ = 0, jmax_ = 0;
  std::vector<Vec2> lane_pts_;
  std::vector<double> lane_s_;
  std::vector<Slot> slots_;
  std::vector<Sample> samples_;  // frames of both passes
  std::array<std::vector<double>, 2> sample_stamps_;  // samples_' stamps, per pass
  std::vector<Track> tracks_;    // placed moving actors
  Track camera_car_;             // the car the camera rides on, at the samples
  std::vector<RedLight> red_lights_;
  std::vector<Halt> camera_halts_;  // the red lights, by camera arc length
};

}  // namespace

World BuildCity(const Scenario& scenario) {
  CityBuilder builder(scenario);
  World world = builder.Build();
  RecordSecondPassChanges(&world, builder.parked_candidates_);
  world.movers_left_out = builder.movers_left_out_;
  world.red_lights_left_out = builder.red_lights_left_out_;
  return world;
}

}  // namespace segslam::scenes
