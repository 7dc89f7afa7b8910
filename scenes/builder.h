// Internal helpers shared by the city and office builders: seeds, COCO ids, geoms,
// materials, camera routes and the pass-2 bookkeeping. Not part of the public API.
#pragma once

#include "scenes/scenario.h"
#include "scenes/world.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace segslam::scenes {

// A seed for one component, derived from the world seed and a tag (splitmix64 of the
// seed mixed with an FNV-1a hash of the tag and an index), so adding a component never
// changes the random numbers of another.
std::uint64_t SubSeed(std::uint64_t seed, const std::string& tag, std::uint64_t index = 0);

// Uniform and Gaussian draws from a std::mt19937_64 (portable, unlike std distributions
// whose algorithms differ between standard libraries).
double Uniform(std::mt19937_64& rng, double lo, double hi);
int UniformInt(std::mt19937_64& rng, int lo, int hi);  // inclusive
bool Chance(std::mt19937_64& rng, double p);
// A portable Fisher-Yates shuffle.
template <typename T>
void Shuffle(std::vector<T>& v, std::mt19937_64& rng) {
  for (int i = static_cast<int>(v.size()) - 1; i > 0; --i) {
    std::swap(v[i], v[UniformInt(rng, 0, i)]);
  }
}

// COCO category id for a name (person, car, chair, ...) from core/coco.h; throws
// segslam::Error for names that are not COCO categories.
int CocoId(const std::string& name);
bool CocoMoveable(int category_id);

// Poses and geoms.
Eigen::Isometry3d PoseXYZYaw(const Eigen::Vector3d& t, double yaw_rad);
Geom MakeBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half, int material,
             double yaw_rad = 0.0);
Geom MakeShape(Shape shape, const Eigen::Vector3d& center, const Eigen::Vector3d& size,
               int material, const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity());
// A cylinder between two points.
Geom MakeRod(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int material);

// Camera optical frame at `eye` looking at `target`, with world z up (x right, y down).
Eigen::Matrix3d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

// Adds textures, materials and objects to a world and keeps the instance ids.
class WorldBuilder {
 public:
  explicit WorldBuilder(World* world) : world_(world) {}
  int AddTexture(const std::string& name, cv::Mat image_bgr, Eigen::Vector2d tile_size_m);
  int AddMaterial(const std::string& name, int texture, Eigen::Vector4f rgba,
                  float specular = 0.1f, float shininess = 0.2f);
  // A new object with the next instance id, present and static in both passes.
  Object& AddObject(const std::string& category_name);
  World& world() { return *world_; }

 private:
  World* world_;
};

// Pass 2 of `route` (copied from pass 1): every key shifted by offset_m in its own
// route frame (x along the horizontal viewing direction, y left, z up) and turned by
// yaw_deg about world z.
CameraRoute OffsetRoute(const CameraRoute& route, const Eigen::Vector3d& offset_m, double yaw_deg);

// Which candidates pass 2 relocates, removes (disjoint) and how many it adds, as
// indices into the candidates: relocated = round(share * n), removed = round(share * n)
// capped by what is left.
struct ChangePlan {
  std::vector<int> relocated;
  std::vector<int> removed;
};
ChangePlan PlanSecondPass(int candidates, const SecondPassSpec& spec, std::mt19937_64& rng);

// Fills world.pass2_changes from the objects' placements.
void RecordSecondPassChanges(World* world, int candidates);

// Smallest horizontal distance between the object's root and the camera, and between
// the object's root and the roots of `others`, over the frames of both passes sampled
// every `step_s`.
double MinDistanceToCamera(const World& world, const Object& object, double step_s);
double MinDistanceToObjects(const World& world, const Object& object,
                            const std::vector<const Object*>& others, double step_s);

// Puts object `index` on one of `candidates` (both passes, independent random start
// offsets), trying until it keeps `min_camera_m` from the camera and `min_other_m` from
// the objects `others` (indices) at every `step_s`; keeps the best try if none is clear.
void PlaceOnPaths(World* world, std::mt19937_64& rng, int index,
                  const std::vector<PathMotion>& candidates, const std::vector<int>& others,
                  double min_camera_m, double min_other_m, double step_s);

// Cheap smooth noise: sum of sinusoids with seeded phases, amplitude ~1, for hand shake.
struct SmoothNoise {
  double freq_hz[3];
  double phase[3];
  double Eval(double t) const;
  static SmoothNoise Make(std::mt19937_64& rng, double base_hz);
};

// World builders per kind (city.cpp, office.cpp).
World BuildCity(const Scenario& scenario);
World BuildOffice(const Scenario& scenario);

}  // namespace segslam::scenes
