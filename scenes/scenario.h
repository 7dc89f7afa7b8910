// A scenario file (YAML) fully determines a world, its two passes and the sensor.
// Every key has a default here; a file sets only what differs. Unknown keys and
// out-of-range values are refused with an error naming the key and the file.
#pragma once

#include "scenes/world.h"

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace segslam::scenes {

// Sensor model applied after rendering (sim/sensor_model.h implements it).
struct SensorSpec {
  bool enabled = true;                 // false: perfect RGB and depth
  double depth_noise_sigma_at_1m = 0.0015;  // metres; sigma grows with depth squared
                                       // (city default: 0.0003, see scenario.cpp)
  double depth_quantization = 1.0;     // 1 = quantize to the disparity steps of a
                                       // Kinect-like sensor, 0 = off
  double max_depth_m = 0.0;            // beyond this depth is missing; 0 = kind default
  double min_depth_m = 0.3;            // nearer than this is missing
  double edge_dropout = 0.3;           // probability to drop depth on depth edges, [0, 1]
  double rgb_noise_sigma = 2.0;        // 8-bit levels, Gaussian per channel
  bool motion_blur = false;            // blur along the image motion of the camera
  double exposure_s = 0.01;            // exposure time used for the blur
};

// The changes of pass 2 relative to pass 1.
struct SecondPassSpec {
  double relocated_share = 0.3;  // share of parked cars / moveable objects moved, [0, 1]
  // City only. 0: a relocated car is parked again in a free stall elsewhere. > 0: moved
  // along the curb by 0.5 to 1 times this, either way, as far as the vehicles around it
  // allow (into an empty neighbouring stall only as far as still leaves room for a car):
  // a resident's car back in front of the house, the case where its old map points still
  // match, [0, 2.5] m. One with less room than half this (a truck, or a car between
  // trucks) is parked in a free stall elsewhere.
  double relocated_shift_m = 0.0;
  double removed_share = 0.1;    // share removed, [0, 1]
  int added = 2;                 // new parked / moveable objects
  // Offset of the route, route frame (x forward, y left, z up), each in [-5, 5]. In a
  // city the camera rides on a car and the offset moves the car: x in [-1, 1] (it stands
  // 2 m behind the vehicle it waits behind at a red light), y keeps the car within the
  // driving lanes ([-0.38, 4.28] on a 12 m road), and the camera at least 0.3 m high.
  Eigen::Vector3d camera_offset_m{0.0, 0.0, 0.0};
  double camera_yaw_offset_deg = 0.0;              // heading offset of the camera
};

struct CitySpec {
  double route_length_m = 200.0;  // 160 to 400 in the paper
  double camera_speed_mps = 6.0;
  double camera_height_m = 1.5;
  double block_size_m = 40.0;     // distance between street centre lines
  double road_width_m = 12.0;     // curb to curb: parking and a driving lane each way
  double sidewalk_width_m = 3.0;
  int parked_cars = 20;
  int moving_cars = 6;
  double moving_car_speed_mps = 6.0;  // (0, 30]
  int pedestrians = 10;
  double pedestrian_speed_mps = 1.3;  // (0, 3]
  double crossing_share = 0.3;  // share of pedestrians that cross streets
  // Intersections of the route where the camera car waits at a red light (at most one
  // per intersection, spread over the route). While it waits, cross traffic (the
  // crossing share of moving cars) passes and the crossing pedestrians walk over the
  // crosswalk in front of it. At the first light and every other one after it, it waits
  // behind a vehicle (one more, not counted in moving_cars) that pulls away first when
  // the light turns green; at the others it is first in line. An intersection nearer to
  // the start than the camera car's braking distance at camera_speed_mps (v^2 / 2a, with
  // a = 2 m/s^2), or nearer to the light before than v^2 / a, is passed over for the next
  // one; lights that find none are left out (World::red_lights_left_out).
  int red_lights = 0;
  double red_light_s = 12.0;  // standing time at each light
  // The vehicle the camera car waits behind at those lights: random (a car, truck or
  // bus, as traffic comes), car, truck or bus. A bus standing 2 m ahead fills most of
  // the image and then pulls away, the classic case where visual odometry takes the
  // motion of the view for its own.
  std::string red_light_lead = "random";
  // true: pass 2 has traffic of its own (other moving cars, lead vehicles and
  // pedestrians, on other paths at other times), as a revisit on another day and the
  // paper's second passes ("different ... moveable objects"); false: the same movers do
  // the same things in both passes.
  bool pass2_new_traffic = true;
};

struct OfficeSpec {
  std::string camera_motion = "xyz";  // xyz | static | rpy | halfsphere
  int frames = 300;
  double room_size_m[3] = {7.0, 6.0, 2.8};
  int desks = 2;
  int moveable_objects = 12;  // cups, bottles, books, laptops, chairs...
  int people_walking = 2;
  int people_sitting = 0;
  double walking_speed_mps = 0.8;
  // around_desk: each walker on a route of its own, loops around the main desk or a line
  // behind it. in_front: the walkers go one behind the other round a narrow loop between
  // the camera and the desk, in view most of the time and filling much of the image, as
  // the pair in TUM's fr3/walking sequences does (what makes plain ORB-SLAM2 fail there).
  std::string walker_route = "around_desk";
  // Leg of the walkers' loop nearest to the camera's base pose, ahead of it.
  double walker_front_distance_m = 1.15;
  // in_front: gap along the loop from one walker to the next.
  double walker_spacing_m = 0.6;
};

struct Scenario {
  std::filesystem::path source_file;  // where it was read from ("" if built in code)
  std::string name;
  std::string kind = "city";  // city | office
  std::uint64_t seed = 1;
  CameraSpec camera;
  SensorSpec sensor;
  SecondPassSpec pass2;
  CitySpec city;
  OfficeSpec office;
  // Blocks that later layers read, kept verbatim so scenes/ need not know their schema
  // and no part of the world depends on them: `expect:` (thresholds that `segslam
  // scenario run` checks) and `bench:` (its modes, repeats, segmenter and seed).
  YAML::Node expect;
  YAML::Node bench;
  std::string text;  // the file's bytes, copied into datasets as provenance
};

// Reads and validates a scenario; throws segslam::Error naming the file and the key.
Scenario LoadScenario(const std::filesystem::path& file);
// Same, from text; `origin` names the source in error messages and becomes
// source_file of the result.
Scenario ParseScenario(const std::string& yaml_text, const std::string& origin);

// Sets one key for sweeps and CLI overrides, e.g. ("city.moving_cars", "8") or
// ("pass2.camera_offset_m", "[0, 1, 0]"). `value` is read as YAML. The key is written
// into the scenario's YAML (its `text`, or ScenarioToYaml() when text is empty) and the
// result re-parsed with the same validation, so a bad key or value throws the same
// errors as a file would. On success `scenario.text` holds the edited YAML.
void ApplyOverride(Scenario& scenario, const std::string& dotted_key, const std::string& value);
// Sets each "KEY=VALUE" as ApplyOverride does, e.g. "city.moving_cars=8" (what `--set`
// and the `set:` lists of suite and sweep files hold), a later one winning over an
// earlier one of the same key, and validates once all are set, so keys checked
// together (pass2.relocated_share + pass2.removed_share <= 1) may be set in any order.
// Throws on text without a key and an '=' with an error that quotes it; callers add
// where it came from.
void ApplyOverrides(Scenario& scenario, const std::vector<std::string>& assignments);

// The scenario's static twin: the same world, routes and sensor with what moves through
// it taken away (city: moving cars and pedestrians; office: the walkers), named
// NAME_static_twin. Every other part of a world draws from a random stream of its own
// (named by what it builds), so the streets, parked vehicles, rooms and camera paths stay
// exactly as they were. Kept: a city's red-light lead vehicles (the camera's stops are
// placed behind them) and an office's sitters (their chairs are part of the room).
Scenario StaticTwin(const Scenario& scenario);

// The full effective configuration (every key, defaults included, plus `expect` and
// `bench`), for reports that echo what ran. ParseScenario(Dump(ScenarioToYaml(s))) reproduces s.
YAML::Node ScenarioToYaml(const Scenario& scenario);

// Builds the world the scenario describes. Deterministic in scenario.seed.
World BuildWorld(const Scenario& scenario);

}  // namespace segslam::scenes
