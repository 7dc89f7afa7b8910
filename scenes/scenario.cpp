// Scenario files: a strict, table-driven YAML reader. Every key a file may set is
// registered once in FieldTable with its type and range; the same table writes the
// effective configuration back (ScenarioToYaml) and serves ApplyOverride.
#include "scenes/scenario.h"

#include "core/camera.h"
#include "core/error.h"
#include "core/input_file.h"
#include "core/lens_distortion.h"
#include "core/yaml_file.h"
#include "scenes/city_layout.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

namespace segslam::scenes {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Allowed interval of a number; open ends exclude the bound.
struct Range {
  double lo = -kInf;
  double hi = kInf;
  bool lo_open = false;
  bool hi_open = false;

  bool Contains(double v) const {
    const bool above = lo_open ? v > lo : v >= lo;
    const bool below = hi_open ? v < hi : v <= hi;
    return above && below;
  }
};

Range AtLeast(double lo) { return {lo, kInf, false, false}; }
Range Closed(double lo, double hi) { return {lo, hi, false, false}; }
Range OpenClosed(double lo, double hi) { return {lo, hi, true, false}; }
Range Open(double lo, double hi) { return {lo, hi, true, true}; }

std::string Num(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::string Describe(const Range& r) {
  if (std::isinf(r.hi)) return std::string(r.lo_open ? "> " : ">= ") + Num(r.lo);
  return std::string("in ") + (r.lo_open ? "(" : "[") + Num(r.lo) + ", " + Num(r.hi) +
         (r.hi_open ? ")" : "]");
}

// What a scenario built in code, with no file, is named after in messages.
constexpr const char* kBuiltInCodeOrigin = "<override>";

// "<origin>: <key>: <what>"
Error KeyError(const std::string& origin, const std::string& key, const std::string& what) {
  return Error(origin + ": " + key + ": " + what);
}

std::string ScalarText(const YAML::Node& node) {
  if (node.IsScalar()) return PrintableText(node.Scalar());
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

double ReadNumber(const YAML::Node& node, const std::string& origin, const std::string& key) {
  if (!node.IsScalar()) {
    throw KeyError(origin, key, "expected a number (got " + ScalarText(node) + ")");
  }
  double v = 0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    throw KeyError(origin, key, "expected a number (got '" + PrintableText(node.Scalar()) + "')");
  }
  if (!std::isfinite(v)) {
    throw KeyError(origin, key, "expected a finite number (got '" + PrintableText(node.Scalar()) + "')");
  }
  return v;
}

// One settable key: how to read it into the scenario and how to write it back.
struct Field {
  std::function<void(const YAML::Node&)> read;
  std::function<YAML::Node()> write;
};

// All keys of a scenario, bound to one Scenario object. Registration order is the
// order ScenarioToYaml writes them.
class FieldTable {
 public:
  FieldTable(Scenario* s, std::string origin) : origin_(std::move(origin)) {
    Add("name", String(&s->name));
    Add("kind", Choice(&s->kind, {"city", "office"}, "kind"));
    Add("seed", Seed(&s->seed, "seed"));

    CameraSpec& c = s->camera;
    Add("camera.width", Int(&c.width, 16, 4096, "camera.width"));
    Add("camera.height", Int(&c.height, 16, 4096, "camera.height"));
    Add("camera.fovy_deg", Double(&c.fovy_deg, Open(10, 170), "camera.fovy_deg"));
    Add("camera.fps", Double(&c.fps, OpenClosed(0, 240), "camera.fps"));
    Add("camera.depth_factor", Double(&c.depth_factor, OpenClosed(0, 65535), "camera.depth_factor"));
    Add("camera.near_m", Double(&c.near_m, Open(0, 10), "camera.near_m"));
    Add("camera.far_m", Double(&c.far_m, OpenClosed(0, 100000), "camera.far_m"));
    Add("camera.distortion", Distortion(&c.distortion, "camera.distortion"));

    SensorSpec& n = s->sensor;
    Add("sensor.enabled", Bool(&n.enabled, "sensor.enabled"));
    Add("sensor.depth_noise_sigma_at_1m",
        Double(&n.depth_noise_sigma_at_1m, Closed(0, 0.1), "sensor.depth_noise_sigma_at_1m"));
    Add("sensor.depth_quantization",
        Double(&n.depth_quantization, Closed(0, 1), "sensor.depth_quantization"));
    Add("sensor.max_depth_m", Double(&n.max_depth_m, AtLeast(0), "sensor.max_depth_m"));
    Add("sensor.min_depth_m", Double(&n.min_depth_m, AtLeast(0), "sensor.min_depth_m"));
    Add("sensor.edge_dropout", Double(&n.edge_dropout, Closed(0, 1), "sensor.edge_dropout"));
    Add("sensor.rgb_noise_sigma", Double(&n.rgb_noise_sigma, Closed(0, 50), "sensor.rgb_noise_sigma"));
    Add("sensor.motion_blur", Bool(&n.motion_blur, "sensor.motion_blur"));
    Add("sensor.exposure_s", Double(&n.exposure_s, Closed(0, 0.1), "sensor.exposure_s"));

    SecondPassSpec& p = s->pass2;
    Add("pass2.relocated_share", Double(&p.relocated_share, Closed(0, 1), "pass2.relocated_share"));
    Add("pass2.relocated_shift_m", Double(&p.relocated_shift_m, Closed(0, 2.5), "pass2.relocated_shift_m"));
    Add("pass2.removed_share", Double(&p.removed_share, Closed(0, 1), "pass2.removed_share"));
    Add("pass2.added", Int(&p.added, 0, 200, "pass2.added"));
    Add("pass2.camera_offset_m", Vec3(&p.camera_offset_m, Closed(-5, 5), "pass2.camera_offset_m"));
    Add("pass2.camera_yaw_offset_deg",
        Double(&p.camera_yaw_offset_deg, Closed(-180, 180), "pass2.camera_yaw_offset_deg"));

    CitySpec& y = s->city;
    Add("city.route_length_m", Double(&y.route_length_m, Closed(20, 2000), "city.route_length_m"));
    Add("city.camera_speed_mps", Double(&y.camera_speed_mps, OpenClosed(0, 40), "city.camera_speed_mps"));
    Add("city.camera_height_m", Double(&y.camera_height_m, Closed(0.3, 5), "city.camera_height_m"));
    Add("city.block_size_m", Double(&y.block_size_m, Closed(25, 200), "city.block_size_m"));
    // Two parking lanes (2.55 m) and two driving lanes where two buses pass (city.cpp).
    Add("city.road_width_m", Double(&y.road_width_m, Closed(11, 30), "city.road_width_m"));
    // Narrower, pedestrians could not walk between the trees and the benches.
    Add("city.sidewalk_width_m",
        Double(&y.sidewalk_width_m, Closed(city_layout::kMinSidewalkWidthM, 10), "city.sidewalk_width_m"));
    Add("city.parked_cars", Int(&y.parked_cars, 0, 500, "city.parked_cars"));
    Add("city.moving_cars", Int(&y.moving_cars, 0, 100, "city.moving_cars"));
    // Movers are timed by their speed (crossing cars and people reach a crossing when the
    // camera is near it): at 0 they would stand where they cross, in the camera's way.
    Add("city.moving_car_speed_mps",
        Double(&y.moving_car_speed_mps, OpenClosed(0, 30), "city.moving_car_speed_mps"));
    Add("city.pedestrians", Int(&y.pedestrians, 0, 300, "city.pedestrians"));
    Add("city.pedestrian_speed_mps",
        Double(&y.pedestrian_speed_mps, OpenClosed(0, 3), "city.pedestrian_speed_mps"));
    Add("city.crossing_share", Double(&y.crossing_share, Closed(0, 1), "city.crossing_share"));
    Add("city.red_lights", Int(&y.red_lights, 0, 50, "city.red_lights"));
    Add("city.red_light_s", Double(&y.red_light_s, Closed(1, 120), "city.red_light_s"));
    Add("city.red_light_lead",
        Choice(&y.red_light_lead, {"random", "car", "truck", "bus"}, "city.red_light_lead"));
    Add("city.pass2_new_traffic", Bool(&y.pass2_new_traffic, "city.pass2_new_traffic"));

    OfficeSpec& o = s->office;
    Add("office.camera_motion",
        Choice(&o.camera_motion, {"xyz", "static", "rpy", "halfsphere"}, "office.camera_motion"));
    Add("office.frames", Int(&o.frames, 1, 100000, "office.frames"));
    Add("office.room_size_m", RoomSize(o.room_size_m, "office.room_size_m"));
    Add("office.desks", Int(&o.desks, 1, 4, "office.desks"));
    Add("office.moveable_objects", Int(&o.moveable_objects, 0, 60, "office.moveable_objects"));
    Add("office.people_walking", Int(&o.people_walking, 0, 6, "office.people_walking"));
    Add("office.people_sitting", Int(&o.people_sitting, 0, 4, "office.people_sitting"));
    Add("office.walking_speed_mps",
        Double(&o.walking_speed_mps, Closed(0, 2.5), "office.walking_speed_mps"));
    Add("office.walker_route", Choice(&o.walker_route, {"around_desk", "in_front"}, "office.walker_route"));
    Add("office.walker_front_distance_m",
        Double(&o.walker_front_distance_m, Closed(0.5, 1.9), "office.walker_front_distance_m"));
    Add("office.walker_spacing_m", Double(&o.walker_spacing_m, Closed(0.4, 5), "office.walker_spacing_m"));
  }

  const Field* Find(const std::string& key) const {
    auto it = fields_.find(key);
    return it == fields_.end() ? nullptr : &it->second;
  }
  const std::vector<std::string>& Order() const { return order_; }

 private:
  void Add(const std::string& key, Field f) {
    fields_.emplace(key, std::move(f));
    order_.push_back(key);
  }

  Field Double(double* v, Range r, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              const double x = ReadNumber(n, origin, key);
              if (!r.Contains(x)) {
                throw KeyError(origin, key, "must be " + Describe(r) + " (got " + n.Scalar() + ")");
              }
              *v = x;
            },
            [=] { return YAML::Node(*v); }};
  }

  Field Int(int* v, int lo, int hi, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              if (!n.IsScalar()) {
                throw KeyError(origin, key, "expected an integer (got " + ScalarText(n) + ")");
              }
              long long x = 0;
              try {
                x = n.as<long long>();
              } catch (const YAML::Exception&) {
                throw KeyError(origin, key, "expected an integer (got '" + PrintableText(n.Scalar()) + "')");
              }
              if (x < lo || x > hi) {
                const std::string range =
                    hi == std::numeric_limits<int>::max()
                        ? ">= " + std::to_string(lo)
                        : "in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
                throw KeyError(origin, key, "must be " + range + " (got " + n.Scalar() + ")");
              }
              *v = static_cast<int>(x);
            },
            [=] { return YAML::Node(*v); }};
  }

  Field Seed(std::uint64_t* v, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              if (!n.IsScalar()) {
                throw KeyError(origin, key, "expected an integer (got " + ScalarText(n) + ")");
              }
              if (!n.Scalar().empty() && n.Scalar()[0] == '-') {
                throw KeyError(origin, key, "must be >= 0 (got " + n.Scalar() + ")");
              }
              try {
                *v = n.as<std::uint64_t>();
              } catch (const YAML::Exception&) {
                throw KeyError(origin, key, "expected an integer (got '" + PrintableText(n.Scalar()) + "')");
              }
            },
            [=] { return YAML::Node(*v); }};
  }

  Field Bool(bool* v, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              try {
                if (!n.IsScalar()) throw YAML::Exception(YAML::Mark(), "");
                *v = n.as<bool>();
              } catch (const YAML::Exception&) {
                throw KeyError(origin, key, "expected true or false (got " + ScalarText(n) + ")");
              }
            },
            [=] { return YAML::Node(*v); }};
  }

  Field String(std::string* v) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              if (!n.IsScalar()) throw KeyError(origin, "name", "expected a string");
              *v = n.Scalar();
            },
            [=] { return YAML::Node(*v); }};
  }

  Field Choice(std::string* v, std::vector<std::string> choices, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              const std::string x = n.IsScalar() ? n.Scalar() : ScalarText(n);
              for (const std::string& c : choices) {
                if (x == c) {
                  *v = x;
                  return;
                }
              }
              std::string list;
              for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
              throw KeyError(origin, key, "must be one of " + list + " (got '" + PrintableText(x) + "')");
            },
            [=] { return YAML::Node(*v); }};
  }

  // Reads a list of 3 numbers, each in `r`, into out[0..2].
  static void ReadTriple(const YAML::Node& n, const std::string& origin,
                         const std::string& key, Range r, double* out) {
    if (!n.IsSequence() || n.size() != 3) {
      throw KeyError(origin, key, "expected a list of 3 numbers");
    }
    for (int i = 0; i < 3; ++i) {
      const double x = ReadNumber(n[i], origin, key);
      if (!r.Contains(x)) {
        throw KeyError(origin, key, "each value must be " + Describe(r) + " (got " + n[i].Scalar() + ")");
      }
      out[i] = x;
    }
  }

  Field Vec3(Eigen::Vector3d* v, Range r, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              double t[3];
              ReadTriple(n, origin, key, r, t);
              *v = Eigen::Vector3d(t[0], t[1], t[2]);
            },
            [=] {
              YAML::Node out(YAML::NodeType::Sequence);
              for (int i = 0; i < 3; ++i) out.push_back((*v)[i]);
              out.SetStyle(YAML::EmitterStyle::Flow);
              return out;
            }};
  }

  // [k1, k2, p1, p2, k3] (core/lens_distortion.h).
  Field Distortion(LensDistortion* v, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              if (!n.IsSequence() || n.size() != 5) {
                throw KeyError(origin, key, "expected a list of 5 numbers [k1, k2, p1, p2, k3]");
              }
              double c[5];
              for (int i = 0; i < 5; ++i) {
                c[i] = ReadNumber(n[i], origin, key);
                if (!Closed(-10, 10).Contains(c[i])) {
                  throw KeyError(origin, key, "each value must be in [-10, 10] (got " + n[i].Scalar() + ")");
                }
              }
              *v = {c[0], c[1], c[2], c[3], c[4]};
            },
            [=] {
              YAML::Node out(YAML::NodeType::Sequence);
              for (double c : {v->k1, v->k2, v->p1, v->p2, v->k3}) out.push_back(c);
              out.SetStyle(YAML::EmitterStyle::Flow);
              return out;
            }};
  }

  Field RoomSize(double* v, std::string key) const {
    std::string origin = origin_;
    return {[=](const YAML::Node& n) {
              double t[3];
              ReadTriple(n, origin, key, Closed(2.2, 30), t);
              // The main desk stands 2.1 m from the far wall (+x), the camera 2 m in
              // front of it and moves up to 0.3 m: less than 5 m puts it in the wall.
              if (t[0] < 5 || t[1] < 4) {
                throw KeyError(origin, key, "floor must be at least 5 m (x) by 4 m (y)");
              }
              for (int i = 0; i < 3; ++i) v[i] = t[i];
            },
            [=] {
              YAML::Node out(YAML::NodeType::Sequence);
              for (int i = 0; i < 3; ++i) out.push_back(v[i]);
              out.SetStyle(YAML::EmitterStyle::Flow);
              return out;
            }};
  }

  std::string origin_;
  std::map<std::string, Field> fields_;
  std::vector<std::string> order_;
};

const std::vector<std::string> kSections = {"camera", "sensor", "pass2", "city", "office"};

bool IsSection(const std::string& key) {
  for (const std::string& s : kSections) {
    if (s == key) return true;
  }
  return false;
}

// Camera and sensor defaults that depend on the kind: an AirSim-like car camera (90 deg
// horizontal FOV at 4:3, 15 fps) or a TUM-like Kinect (fy = 525 px at 480 rows, 30 fps).
// The Kinect's noise model (sigma 1.5 mm at 1 m growing with depth squared, disparity
// quantisation of a 7.5 cm baseline) would put metres of noise on a street at 30 m; a
// car's depth sensor is a wide-baseline stereo or lidar-assisted unit, so the city keeps
// the quadratic growth with a fifth of the noise and no Kinect quantisation.
void ApplyKindDefaults(const std::string& kind, CameraSpec* c, SensorSpec* sensor) {
  const double kRadToDeg = 180.0 / M_PI;
  if (kind == "office") {
    c->fovy_deg = 2.0 * std::atan(240.0 / 525.0) * kRadToDeg;  // ~49.1 deg
    c->fps = 30.0;
    c->depth_factor = 5000.0;
    c->near_m = 0.05;
    c->far_m = 20.0;
  } else {
    c->fovy_deg = 2.0 * std::atan(0.75) * kRadToDeg;  // ~73.7 deg
    c->fps = 15.0;
    c->depth_factor = 1000.0;
    c->near_m = 0.1;
    c->far_m = 200.0;
    sensor->depth_noise_sigma_at_1m = 0.0003;
    sensor->depth_quantization = 0.0;
  }
}

std::string KeyText(const YAML::Node& key) { return key.IsScalar() ? PrintableText(key.Scalar()) : "?"; }

// The camera the generator renders passes the check of every camera a run or eval reads
// (SequenceCamera::IsValid's parts): a sensible field of view along both axes, and a lens
// whose bend keeps growing over the whole image (the generator bends each render through
// the lens and a run takes the bend out again).
void CheckCamera(const CameraSpec& camera, const std::string& origin) {
  const PinholeCamera pinhole = PinholeCamera::FromVerticalFov(camera.width, camera.height, camera.fovy_deg);
  std::string problem;
  if (!pinhole.IsValid(&problem)) throw KeyError(origin, "camera", problem);
  if (!LensCoversImage(camera.distortion, pinhole, &problem)) throw KeyError(origin, "camera.distortion", problem);
}

// The pass-2 camera of a city rides on the camera car as pass 1's does (city_layout.h),
// moved by pass2.camera_offset_m: it must stay above the road, keep that car within the
// driving lanes (out of the parked cars' lane), and not move it so far along the route
// that it runs into the vehicle it waits behind at a red light (2 m ahead of its bumper;
// movers keep 1 m from it).
void CheckCityCameraOffset(const Scenario& s, const std::string& origin) {
  using namespace city_layout;
  const std::string key = "pass2.camera_offset_m";
  const Eigen::Vector3d& offset = s.pass2.camera_offset_m;
  constexpr double kMinHeightM = 0.3;
  if (s.city.camera_height_m + offset.z() < kMinHeightM) {
    throw KeyError(origin, key,
                   "puts the pass-2 camera " + Num(s.city.camera_height_m + offset.z()) +
                       " m above the road (city.camera_height_m " + Num(s.city.camera_height_m) + " + z " +
                       Num(offset.z()) + "); it must be at least " + Num(kMinHeightM) + " m");
  }
  // Below the 1 m the movers keep, so that a lead is not at the limit of being left out.
  constexpr double kMaxAlongM = 0.8;
  if (std::abs(offset.x()) > kMaxAlongM) {
    throw KeyError(origin, key,
                   "x (along the route) must be in [-" + Num(kMaxAlongM) + ", " + Num(kMaxAlongM) + "] (got " +
                       Num(offset.x()) + "): the camera car stands 2 m behind the vehicle it waits behind at "
                       "a red light, and movers keep 1 m from it");
  }
  // The camera car's centre is lane - y right of the street's centre line; its sides, a
  // half width either side, stay within the driving lanes, `half` either side of that line.
  const double lane = DrivingLaneOffsetM(s.city.road_width_m);
  const double half = DrivingLanesHalfWidthM(s.city.road_width_m);
  const double lo = lane + kCarDims.half_width - half, hi = lane - kCarDims.half_width + half;
  if (offset.y() < lo || offset.y() > hi) {
    throw KeyError(origin, key,
                   "y (to the left) must be in [" + Num(lo) + ", " + Num(hi) + "] for city.road_width_m " +
                       Num(s.city.road_width_m) + " (got " + Num(offset.y()) + "): further, the camera car (" +
                       Num(2 * kCarDims.half_width) + " m wide) leaves the driving lanes for a lane of parked cars");
  }
}

}  // namespace

Scenario ParseScenario(const std::string& yaml_text, const std::string& origin) {
  Scenario s;
  s.source_file = origin;
  s.text = yaml_text;

  // Parse the YAML itself; syntax errors and repeated keys carry line numbers.
  const YAML::Node root = LoadYamlText(yaml_text, origin);
  if (!root.IsMap()) {
    throw Error(origin + ": expected a mapping of keys at the top level");
  }

  FieldTable table(&s, origin);

  // The kind first: it chooses the camera defaults that the file may then override.
  if (root["kind"]) table.Find("kind")->read(root["kind"]);
  ApplyKindDefaults(s.kind, &s.camera, &s.sensor);

  // Every key in document order, refusing unknown ones.
  for (const auto& top : root) {
    const std::string key = KeyText(top.first);
    if (key == "expect") {
      s.expect = YAML::Clone(top.second);
    } else if (key == "bench") {
      s.bench = YAML::Clone(top.second);
    } else if (IsSection(key)) {
      if (top.second.IsNull()) continue;
      if (!top.second.IsMap()) throw KeyError(origin, key, "expected a mapping");
      for (const auto& sub : top.second) {
        const std::string dotted = key + "." + KeyText(sub.first);
        const Field* f = table.Find(dotted);
        if (f == nullptr) throw Error(origin + ": unknown key '" + PrintableText(dotted) + "'");
        f->read(sub.second);
      }
    } else {
      const Field* f = table.Find(key);
      if (f == nullptr) throw Error(origin + ": unknown key '" + PrintableText(key) + "'");
      f->read(top.second);
    }
  }

  // Checks across keys.
  CheckCamera(s.camera, origin);
  if (s.camera.far_m <= s.camera.near_m) {
    throw KeyError(origin, "camera.far_m", "must be > camera.near_m (got " + Num(s.camera.far_m) + ")");
  }
  if (s.sensor.max_depth_m > 0 && s.sensor.min_depth_m >= s.sensor.max_depth_m) {
    throw KeyError(origin, "sensor.max_depth_m",
                   "must be > sensor.min_depth_m (got " + Num(s.sensor.max_depth_m) + " <= " +
                       Num(s.sensor.min_depth_m) + "): no pixel would have depth");
  }
  if (s.pass2.relocated_share + s.pass2.removed_share > 1.0 + 1e-9) {
    throw KeyError(origin, "pass2.removed_share",
                   "relocated_share + removed_share must be <= 1 (got " +
                       Num(s.pass2.relocated_share + s.pass2.removed_share) + ")");
  }
  if (s.kind != "city" && s.pass2.relocated_shift_m > 0) {
    throw KeyError(origin, "pass2.relocated_shift_m",
                   "applies to city scenarios only (this one is '" + s.kind + "'); leave it 0");
  }
  if (s.kind == "city" && s.city.road_width_m + 2 * s.city.sidewalk_width_m + 8 > s.city.block_size_m) {
    throw KeyError(origin, "city.block_size_m",
                   "must leave at least 8 m for buildings after roads and sidewalks (got " +
                       Num(s.city.block_size_m) + ")");
  }
  if (s.kind == "city") CheckCityCameraOffset(s, origin);
  const bool name_from_file = s.name.empty();
  // A scenario built in code (no file) without a name gets a plain one.
  if (name_from_file) s.name = origin == kBuiltInCodeOrigin ? "scenario" : std::filesystem::path(origin).stem().string();
  // The name becomes a folder name (the dataset cache, reports) and goes into JUnit XML.
  const bool name_ok = !s.name.empty() && s.name.size() <= 100 && s.name.front() != '.' &&
                       std::all_of(s.name.begin(), s.name.end(), [](char c) {
                         return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
                       });
  if (!name_ok) {
    throw KeyError(origin, "name",
                   "'" + s.name + "'" + (name_from_file ? " (the file's name)" : "") +
                       " must be 1 to 100 letters, digits, '.', '_' or '-', not starting with '.' (it names "
                       "folders)");
  }
  return s;
}

Scenario LoadScenario(const std::filesystem::path& file) {
  return ParseScenario(ReadFileText(file), file.string());
}

YAML::Node ScenarioToYaml(const Scenario& scenario) {
  Scenario copy = scenario;
  FieldTable table(&copy, scenario.source_file.string());
  YAML::Node root(YAML::NodeType::Map);
  for (const std::string& key : table.Order()) {
    const std::size_t dot = key.find('.');
    if (dot == std::string::npos) {
      root[key] = table.Find(key)->write();
    } else {
      root[key.substr(0, dot)][key.substr(dot + 1)] = table.Find(key)->write();
    }
  }
  if (scenario.expect && !scenario.expect.IsNull()) root["expect"] = YAML::Clone(scenario.expect);
  if (scenario.bench && !scenario.bench.IsNull()) root["bench"] = YAML::Clone(scenario.bench);
  return root;
}

namespace {

std::string OverrideOrigin(const Scenario& scenario) {
  return scenario.source_file.empty() ? std::string(kBuiltInCodeOrigin) : scenario.source_file.string();
}

// The YAML that overrides edit: the file's own text, or the effective configuration.
YAML::Node EditableYaml(const Scenario& scenario, const std::string& origin) {
  YAML::Node root;
  if (!scenario.text.empty()) {
    try {
      root = YAML::Load(scenario.text);
    } catch (const YAML::ParserException& e) {
      throw Error(origin + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
  }
  if (!root.IsMap()) root = ScenarioToYaml(scenario);
  return root;
}

// Sets `dotted_key` in `root` to `value` read as YAML (so lists and numbers keep their
// types), creating mappings on the way.
void SetKey(YAML::Node root, const std::string& origin, const std::string& dotted_key, const std::string& value) {
  YAML::Node parsed;
  try {
    parsed = YAML::Load(value);
  } catch (const YAML::ParserException& e) {
    throw KeyError(origin, dotted_key, "cannot read override value '" + value + "': " + e.msg);
  }
  std::vector<std::string> parts;
  std::stringstream ss(dotted_key);
  for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
  if (parts.empty() || dotted_key.empty()) throw Error(origin + ": empty override key");
  YAML::Node node = root;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node child = node[parts[i]];
    if (!child.IsDefined() || child.IsNull()) {
      node[parts[i]] = YAML::Node(YAML::NodeType::Map);
      child.reset(node[parts[i]]);
    }
    if (!child.IsMap()) throw KeyError(origin, parts[i], "expected a mapping");
    node.reset(child);
  }
  node[parts.back()] = parsed;
}

// Validates the edited YAML as a file would be, and makes it the scenario.
void ReplaceWithEdited(Scenario& scenario, const YAML::Node& root, const std::string& origin) {
  YAML::Emitter out;
  out << root;
  Scenario edited = ParseScenario(std::string(out.c_str()) + "\n", origin);
  edited.source_file = scenario.source_file;
  scenario = std::move(edited);
}

}  // namespace

void ApplyOverride(Scenario& scenario, const std::string& dotted_key, const std::string& value) {
  const std::string origin = OverrideOrigin(scenario);
  YAML::Node root = EditableYaml(scenario, origin);
  SetKey(root, origin, dotted_key, value);
  ReplaceWithEdited(scenario, root, origin);
}

void ApplyOverrides(Scenario& scenario, const std::vector<std::string>& assignments) {
  const std::string origin = OverrideOrigin(scenario);
  YAML::Node root = EditableYaml(scenario, origin);
  for (const std::string& assignment : assignments) {
    const std::size_t equals = assignment.find('=');
    if (equals == std::string::npos || equals == 0) {
      throw Error("'" + assignment + "': expected KEY=VALUE, e.g. city.moving_cars=8");
    }
    SetKey(root, origin, assignment.substr(0, equals), assignment.substr(equals + 1));
  }
  // Validated once all are set: keys checked together (pass2.relocated_share and
  // pass2.removed_share) may come in any order.
  if (!assignments.empty()) ReplaceWithEdited(scenario, root, origin);
}

Scenario StaticTwin(const Scenario& scenario) {
  Scenario twin = scenario;
  std::vector<std::string> changes = {"name=" + scenario.name + "_static_twin"};
  if (scenario.kind == "city") {
    changes.insert(changes.end(), {"city.moving_cars=0", "city.pedestrians=0"});
  } else {
    changes.push_back("office.people_walking=0");
  }
  ApplyOverrides(twin, changes);
  return twin;
}

}  // namespace segslam::scenes
