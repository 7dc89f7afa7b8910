// A procedural world as plain data: geometry, materials, textures, objects with their
// motion in each pass, and the camera route of each pass. Nothing here renders; sim/
// turns a World into a MuJoCo model and asks the query functions below where every
// part and the camera are at a given time.
//
// Frames: world z up, metres. Poses are rigid transforms named `T_<to>_<from>`:
// `T_world_object` maps points of the object's frame into the world frame. Camera poses
// are `T_wc`, camera-to-world, with the camera in the optical convention (x right,
// y down, z forward), exactly as written to groundtruth.txt.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/lens_distortion.h"

namespace segslam::scenes {

// Which of the two passes over the same place: pass 1 builds the map, pass 2 revisits
// it with relocated objects and an offset camera route.
enum class Pass { kFirst = 0, kSecond = 1 };
constexpr std::array<Pass, 2> kBothPasses = {Pass::kFirst, Pass::kSecond};
inline int PassIndex(Pass pass) { return static_cast<int>(pass); }
inline const char* PassName(Pass pass) { return pass == Pass::kFirst ? "pass1" : "pass2"; }

// A procedurally generated RGB texture. `image_bgr` is CV_8UC3 in OpenCV's BGR order;
// row 0 is the top of the picture (the +z end on vertical faces).
struct Texture {
  std::string name;
  cv::Mat image_bgr;
  // Physical size one copy of the image covers on a surface, metres (u, v).
  Eigen::Vector2d tile_size_m{1.0, 1.0};
};

struct Material {
  std::string name;
  int texture = -1;                        // index into World::textures, -1 = untextured
  // Textured boxes: where the texture starts on every face, in copies of the texture
  // ((0, 0) = its top-left corner), and the metres one copy covers there (zero: the
  // texture's own tile_size_m). A texture that packs many pictures (one per facade,
  // street, plate) gives each picture's material the window of its own picture.
  Eigen::Vector2d texture_origin = Eigen::Vector2d::Zero();
  Eigen::Vector2d texture_tile_m = Eigen::Vector2d::Zero();
  Eigen::Vector4f rgba{1.f, 1.f, 1.f, 1.f};  // multiplies the texture colour
  float specular = 0.1f;                   // MuJoCo's material specular, [0, 1]
  float shininess = 0.2f;                  // MuJoCo's material shininess, [0, 1]
};

enum class Shape { kBox, kCylinder, kCapsule, kSphere, kEllipsoid, kPlane };

// One primitive. `size` follows MuJoCo's semantics:
//   box: half extents (x, y, z); cylinder and capsule: (radius, half length, -);
//   sphere: (radius, -, -); ellipsoid: semi-axes; plane: (half x, half y, -), normal +z.
// A textured box or plane maps its material's texture with tile_size_m in world units
// on every face: u along the face's horizontal edge, v downward along its vertical edge
// (for a horizontal face, u along x and v along -y of the geom frame).
struct Geom {
  Shape shape = Shape::kBox;
  Eigen::Vector3d size = Eigen::Vector3d::Constant(0.5);
  Eigen::Isometry3d T_parent_geom = Eigen::Isometry3d::Identity();  // in world or part frame
  int material = 0;  // index into World::materials
};

// A rigid piece of an object that moves as one: a car's body, a person's forearm.
struct Part {
  std::string name;
  std::vector<Geom> geoms;  // poses relative to the part frame
};

// How a person's limbs move; rigid objects use kRigid.
enum class Articulation { kRigid, kWalker, kSitter };

// A stop on the way, as a car makes at a red light: the mover brakes at a constant
// deceleration to stand still where it has travelled `at_m`, waits `wait_s`, and pulls
// away with the same acceleration back to its cruising speed.
struct Halt {
  double at_m = 0.0;  // distance travelled (start offset included) where it stands
  double wait_s = 0.0;
};

// Distance travelled at time t by a mover that starts at `start_m`, cruises at speed_mps
// and makes `halts` (sorted by at_m), braking and accelerating at accel_mps2. A halt at
// start_m itself is a standing start (it stands there from t = 0 for wait_s); one it would
// have had to start braking for before start_m otherwise is ignored. Each halt delays the
// rest of the trip by wait_s + speed / accel against cruising straight through, but for
// one nearer than speed^2 / accel after the halt before: from there the mover speeds up
// over half the way and brakes over the other half, never reaching cruising speed (and
// loses less time). Continuous and non-decreasing in t.
double DistanceWithHalts(double start_m, double speed_mps, const std::vector<Halt>& halts, double accel_mps2,
                         double t);

// A polyline the object follows at constant speed (but for its halts), heading along
// the path (object +x forward, z up). Closed paths loop; open paths ping-pong (turn
// around at the ends).
struct PathMotion {
  std::vector<Eigen::Vector3d> waypoints;
  double speed_mps = 0.0;
  double start_offset_m = 0.0;  // arc length at t = 0
  bool closed = true;
  std::vector<Halt> halts;  // by distance travelled, start offset included
  double accel_mps2 = 2.0;  // braking and pulling away at halts
};

// Distance the mover has travelled along `path` at time t (start offset included).
double PathDistanceAt(const PathMotion& path, double t);

// Arc length of `path`'s waypoints (closed: with the segment back to the first); an open
// path's mover stands still at its ends outside [0, PathLength].
double PathLength(const PathMotion& path);

// Where an object is in one pass. Exactly one of: absent, static at T_world_object,
// or moving along `path` (then T_world_object is ignored).
struct Placement {
  bool present = true;
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();
  bool moving = false;
  PathMotion path;  // used when moving
  // Sitters: boxes (in the object frame) their arms keep out of in this pass: the desk
  // and what stands on it, their chair; see KeepArmsClear() in scenes/person.h.
  std::vector<Geom> arm_obstacles;
};

// An instance in the masks: a thing a segmenter should find (car, person, chair, tv...).
struct Object {
  std::uint16_t instance_id = 0;  // >= 1, unique in the world, same in both passes
  int coco_category_id = 0;       // COCO category id (1..90 with gaps)
  std::string category_name;      // COCO name, e.g. "car"
  bool moveable = false;          // on the moveable shortlist (core/coco.h)
  Articulation articulation = Articulation::kRigid;
  double gait_phase_offset = 0.0;  // walkers/sitters: phase at t = 0, [0, 1)
  double body_scale = 1.0;         // walkers/sitters: 1 = a 1.75 m tall person
  bool animated = true;            // sitters: sway torso, head and arms; false = still
  std::vector<Part> parts;         // kRigid: one or more parts, posed together
  std::array<Placement, 2> placement;  // indexed by PassIndex()
};

// Camera route of one pass: key poses at times, interpolated (position piecewise
// cubic or linear as built, rotation by slerp) by CameraPoseAt().
struct CameraKey {
  double stamp_s = 0.0;
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
};
struct CameraRoute {
  std::vector<CameraKey> keys;  // strictly increasing stamps, covering [0, duration]
};

struct Light {
  Eigen::Vector3d position{0, 0, 10};
  Eigen::Vector3d direction{0, 0, -1};
  bool directional = true;
  Eigen::Vector3f diffuse{0.7f, 0.7f, 0.7f};
  Eigen::Vector3f ambient{0.2f, 0.2f, 0.2f};
  Eigen::Vector3f specular{0.1f, 0.1f, 0.1f};
};

struct CameraSpec {
  int width = 640;
  int height = 480;
  double fovy_deg = 57.0;     // vertical field of view
  double fps = 15.0;
  double depth_factor = 1000;  // stored PNG value per metre
  double near_m = 0.05;       // clipping planes of the renderer
  double far_m = 200.0;
  // The lens's distortion of the stored images (none by default); the renderer's camera
  // is ideal and the generator bends its images through this lens.
  LensDistortion distortion;
};

// What pass 2 changed of the objects that do not move, by instance id (sorted), and how
// many objects could change (parked cars in a city; moveable rigid objects not under a
// sitter in an office). Moving cars and people are left out: they are traffic.
struct SecondPassChanges {
  int candidates = 0;
  std::vector<std::uint16_t> relocated;  // present in both passes, elsewhere in pass 2
  std::vector<std::uint16_t> removed;    // present in pass 1 only
  std::vector<std::uint16_t> added;      // present in pass 2 only
};

struct World {
  std::string name;  // scenario name
  std::string kind;  // "city" or "office"
  std::uint64_t seed = 0;
  CameraSpec camera;
  std::array<int, 2> frames_per_pass{0, 0};
  Eigen::Vector3f sky_rgb{0.6f, 0.7f, 0.85f};  // background colour where nothing is hit
  std::vector<Texture> textures;
  std::vector<Material> materials;
  std::vector<Geom> static_geoms;  // scenery that is not an instance: ground, buildings, walls
  std::vector<Object> objects;
  std::vector<Light> lights;
  std::array<CameraRoute, 2> camera_route;  // indexed by PassIndex()
  SecondPassChanges pass2_changes;
  // Moving cars and pedestrians of the scenario (and vehicles the camera car would wait
  // behind at red lights) left out because no path tried kept their bodies clear of the
  // others and of the camera car's (a city denser than its streets hold).
  int movers_left_out = 0;
  // Red lights of the scenario (city.red_lights) left out: the route has too few
  // intersections, or those it has are too near the start or the light before for the
  // camera car to brake at its speed and be back at it before the next.
  int red_lights_left_out = 0;
};

// Time of frame `index` of a pass, seconds from the start of that pass.
inline double FrameStamp(const World& world, int index) { return index / world.camera.fps; }

// Camera-to-world pose (optical frame) at time `stamp_s` of `pass`.
Eigen::Isometry3d CameraPoseAt(const World& world, Pass pass, double stamp_s);

// World pose of every part of `object` at time `stamp_s` of `pass`, in the order of
// object.parts. For an object absent from the pass the result is empty.
std::vector<Eigen::Isometry3d> PartPosesAt(const Object& object, Pass pass, double stamp_s);

// Pose of the object's root frame (not of its parts) at time `stamp_s` of `pass`.
Eigen::Isometry3d ObjectPoseAt(const Object& object, Pass pass, double stamp_s);
// ObjectPoseAt at each of `stamps_s`, the same poses bit for bit; the path's arc-length
// table is built once rather than once per stamp.
std::vector<Eigen::Isometry3d> ObjectPosesAt(const Object& object, Pass pass, const std::vector<double>& stamps_s);

// Whether the object's root moves between stamp_s and stamp_s + dt_s (rigid motion or
// gait), i.e. whether it is a moving object in that frame.
bool ObjectMovesAt(const Object& object, Pass pass, double stamp_s, double dt_s);

}  // namespace segslam::scenes
