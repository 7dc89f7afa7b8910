// The city builder: an AirSim-like city, a street grid around a random car route,
// buildings with detailed facades, sidewalks, markings, street furniture, parked and
// moving cars, pedestrians. Private to scenes/: BuildCity (scenes/builder.h) is its only
// entry; nothing outside scenes/ includes this header.
//
// Layout: street centre lines at x = i * block and y = j * block; cars drive on the
// right. A node is an intersection (i, j). Everything stands on the ground plane z = 0;
// sidewalks are raised by kCurbHeightM.
//
// One class, its members defined by concern:
//   city.cpp              Build()'s order, the route on the street grid, red lights and
//                         the camera's timing, the camera's routes, the lights
//   city_scenery.cpp      textures and materials, ground, streets, blocks, sidewalks,
//                         buildings and facades, street furniture, fixed COCO objects
//   city_parking.cpp      vehicle models, parked cars and pass 2's changes to them
//   city_movers.cpp       moving actors' paths, frame samples, tracks and clearance
//   city_traffic.cpp      the vehicles at red lights, moving cars
//   city_pedestrians.cpp  pedestrians on the sidewalks and crosswalks
//   city_geometry.cpp     polylines and footprints (scenes/city_geometry_internal.h)
#pragma once

#include "scenes/builder.h"
#include "scenes/city_geometry_internal.h"
#include "scenes/city_layout.h"
#include "scenes/city_textures.h"
#include "scenes/picture_pages.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace segslam::scenes::city_internal {

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

using Vec3 = Eigen::Vector3d;
using Node = std::pair<int, int>;

// Street directions by index (+x, +y, -x, -y); dirs_[k] indexes this.
inline const Vec2 kStreetDirs[4] = {Vec2(1, 0), Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1)};

inline Vec2 Right(const Vec2& d) { return Vec2(d.y(), -d.x()); }
inline Vec3 At(const Vec2& p, double z) { return Vec3(p.x(), p.y(), z); }
inline double YawOf(const Vec2& d) { return std::atan2(d.y(), d.x()); }

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

// A light where the camera car stands: behind the stop line, or behind a vehicle
// standing at it.
struct RedLight {
  std::size_t node = 0;          // index into nodes_
  Vec2 arrive;                   // direction the camera arrives in
  double camera_stop_s = 0;      // camera arc length where it stands
  double stand_from_s = 0, stand_until_s = 0;  // on the pass clock
  std::string lead_kind;         // vehicle it waits behind; empty: first in line
};

// A parking slot along a curb.
struct Slot {
  Vec2 curb;     // on the curb's edge, at the middle of the slot
  Vec2 to_road;  // unit, from the curb toward the street's centre line
  Vec2 along_row;  // unit, toward the row's next slot (against the heading on one curb)
  double yaw = 0;
  bool on_route = false;
  int row = 0;  // the slots along one curb between two intersections share a row, in order
};

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

// An intersection the camera approaches during the pass, with its route arc length.
struct Crossing {
  Node node;
  Vec2 arrive;  // direction the camera arrives in
  double s;
};

enum class CarRole { kAhead, kOncoming, kCrossing };

// A crosswalk on an arm the camera arrives on, with its route arc length.
struct Crosswalk {
  Vec2 centre, along;
  double s;
  const RedLight* light;  // where the camera stands before it, or null
};

class CityBuilder {
 public:
  explicit CityBuilder(const Scenario& s);
  World Build();

  int parked_candidates_ = 0;
  int movers_left_out_ = 0;
  int red_lights_left_out_ = 0;

 private:
  Vec2 NodePos(const Node& n) const { return Vec2(n.first * block_, n.second * block_); }

  std::mt19937_64 Rng(const std::string& tag, std::uint64_t i = 0) const {
    return std::mt19937_64(SubSeed(s_.seed, tag, i));
  }

  // city.cpp: the route, red lights and the camera's timing, the camera, the lights.
  void PlanRoute();
  void WalkStreetGrid();
  void SetGridBounds();
  std::vector<Vec2> LaneCorners() const;
  void AppendTurn(const Node& node, const Vec2& a, const Vec2& b, double offset, std::vector<Vec2>* pts) const;
  void SampleLane(const std::vector<Vec2>& pts);
  Vec2 StopLinePoint(std::size_t k, const Vec2& a) const;
  void PlanRedLights();
  double CameraArc(double t) const;
  double CameraTimeAt(double s) const;
  void MakeCameraRoutes();
  void MakeLights();

  // city_scenery.cpp: textures and materials, static scenery, fixed COCO objects.
  static cv::Size PixelsFor(const Vec2& size_m, double px_per_m);
  int AddPicture(const std::string& name, const Vec2& size_m, double px_per_m, std::function<cv::Mat()> draw);
  int AddPicture(const std::string& name, const Vec2& size_m, cv::Size size_px, std::function<cv::Mat()> draw);
  double DetailPxPerM(const Vec2& lo, const Vec2& hi, double far_px_per_m, double longest_side_m) const;
  void MakeLook();
  void MakeGround();
  void MakeStreetSurfaces();
  void MakeBlocks();
  void MakeSidewalks(const Vec2& lo, const Vec2& hi, std::uint64_t block_index, double paver_m);
  void MakeBuilding(std::mt19937_64& rng, Vec2 lo, Vec2 hi, const std::array<bool, 4>& street_sides);
  void MakeFacade(const FacadeLayout& layout, int skin, const Vec2& c, const Vec2& half, const Vec2& n, double z0);
  void MakeStreets();
  bool OnRoute(const Node& a, const Node& b) const;
  void MakeStreetSegment(std::mt19937_64& rng, const Node& a, const Node& b);
  void MakeIntersection(std::mt19937_64& rng, const Node& n);
  void MakeTree(std::mt19937_64& rng, const Vec2& p);
  void MakeLamp(const Vec2& p, const Vec2& toward_road);
  Object& Fixed(const std::string& category, const Vec2& p, double yaw);
  void MakeTrafficLight(const Vec2& p, const Vec2& facing);
  void MakeStopSign(const Vec2& p, const Vec2& facing);
  void MakeHydrant(const Vec2& p);
  void MakeBench(const Vec2& p, double yaw);

  // city_parking.cpp: vehicles, parked cars.
  Part MakeVehicle(std::mt19937_64& rng, const std::string& kind);
  std::string VehicleKind(std::mt19937_64& rng, bool allow_bus);
  static VehicleDims Dims(const std::string& kind);
  void MakeParkedCars();

  // city_movers.cpp: paths, samples, tracks and clearance of moving actors.
  std::vector<Vec2> NodeLane(const std::vector<Node>& nodes, double offset, double ext_before, double ext_after) const;
  std::vector<Node> RouteNodes() const;
  bool OnBlock(const Vec2& p) const;
  PathMotion WalkPath(const std::vector<Vec2>& pts) const;
  void CoverBothPasses(PathMotion& path, bool walking) const;
  static PathMotion DrivePath(const std::vector<Vec2>& pts);
  RouteLanes MakeRouteLanes() const;
  void MakeSamples();
  Track TrackOf(const Object& o, double half_length, double half_width, bool car) const;
  double Clearance(const Track& tr, double min_camera_m, double floor) const;
  bool BodiesClear(const Track& tr) const;
  bool CameraCarClear(const Track& tr) const;
  bool PlaceMover(int index, const std::array<bool, 2>& present, double half_length, double half_width, bool car,
                  double min_camera_m, int attempts, const std::function<PathMotion(int)>& make);
  static constexpr double kCarMarginM = 0.3;     // cars keep 0.6 m between bodies
  static constexpr double kPersonMarginM = 0.1;  // people 0.2 m from anyone
  // Least gap between the camera car's body and a moving vehicle's or a person's, a hard
  // requirement (CameraCarClear).
  static constexpr double kCameraCarToVehicleM = 1.0;
  static constexpr double kCameraCarToPersonM = 0.5;

  // city_traffic.cpp: the vehicles at red lights, moving cars.
  void MakeRedLightLeads(const std::vector<Node>& fnodes, const Traffic& traffic);
  std::vector<Crossing> CrossingsOnRoute(const RouteLanes& lanes) const;
  std::vector<double> TurnsOnRoute(const RouteLanes& lanes) const;
  std::vector<CarRole> MovingCarRoles(bool two_lanes, bool any_crossing) const;
  PathMotion AheadMotion(std::mt19937_64& rng, const RouteLanes& lanes, int rank, double half_length, int a,
                         double previous_gap, double previous_speed) const;
  PathMotion OncomingMotion(std::mt19937_64& rng, const RouteLanes& lanes, const std::vector<double>& turns, int rank,
                            int count, int a) const;
  PathMotion CrossingMotion(std::mt19937_64& rng, const std::vector<Crossing>& crossings, int rank, int count,
                            int a) const;
  void MakeMovingCars(const Traffic& traffic);

  // city_pedestrians.cpp: pedestrians.
  Object& MakePedestrian(std::mt19937_64& rng);
  std::vector<Crosswalk> CrosswalksOnRoute(const RouteLanes& lanes) const;
  double SidewalkLineFromCurb(std::mt19937_64& rng) const;
  double KeepRightLineFromCurb(std::mt19937_64& rng, bool buildings_on_the_right) const;
  PathMotion CrossingWalkerMotion(std::mt19937_64& rng, const std::vector<Crosswalk>& crosswalks, int k,
                                  int crossers, double speed, int a) const;
  PathMotion SidewalkWalkerMotion(std::mt19937_64& rng, const RouteLanes& lanes, int rank, int walkers,
                                  double speed, int a) const;
  void MakePedestrians(const Traffic& traffic);

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
  Poly2 camera_lane_{{}};  // the route's lane, sampled every 0.25 m or less (SampleLane)
  std::vector<Slot> slots_;
  std::vector<Sample> samples_;  // frames of both passes
  std::array<std::vector<double>, 2> sample_stamps_;  // samples_' stamps, per pass
  std::vector<Track> tracks_;    // placed moving actors
  Track camera_car_;             // the car the camera rides on, at the samples
  std::vector<RedLight> red_lights_;
  std::vector<Halt> camera_halts_;  // the red lights, by camera arc length
};

}  // namespace segslam::scenes::city_internal
