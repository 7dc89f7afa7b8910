#include "scenes/builder.h"

#include "core/coco.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>

namespace segslam::scenes {

std::uint64_t SubSeed(std::uint64_t seed, const std::string& tag, std::uint64_t index) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (unsigned char c : tag) {
    h ^= c;
    h *= 1099511628211ull;
  }
  std::uint64_t z = seed ^ (h + 0x9e3779b97f4a7c15ull * (index + 1));
  for (int i = 0; i < 2; ++i) {  // splitmix64 finaliser, twice
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
  }
  return z;
}

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  const double u = static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
  return lo + (hi - lo) * u;
}

int UniformInt(std::mt19937_64& rng, int lo, int hi) {
  if (hi <= lo) return lo;
  return lo + static_cast<int>(rng() % static_cast<std::uint64_t>(hi - lo + 1));
}

bool Chance(std::mt19937_64& rng, double p) { return Uniform(rng, 0.0, 1.0) < p; }

int CocoId(const std::string& name) {
  const CocoCategory* category = FindCocoCategoryByName(name);
  if (category == nullptr) throw Error("scenes: no COCO category named '" + name + "'");
  return category->id;
}

bool CocoMoveable(int category_id) { return IsMoveableCategory(category_id); }

Eigen::Isometry3d PoseXYZYaw(const Eigen::Vector3d& t, double yaw_rad) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).matrix();
  T.translation() = t;
  return T;
}

Geom MakeBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half, int material,
             double yaw_rad) {
  Geom g;
  g.shape = Shape::kBox;
  g.size = half;
  g.T_parent_geom = PoseXYZYaw(center, yaw_rad);
  g.material = material;
  return g;
}

Geom MakeShape(Shape shape, const Eigen::Vector3d& center, const Eigen::Vector3d& size,
               int material, const Eigen::Matrix3d& R) {
  Geom g;
  g.shape = shape;
  g.size = size;
  g.T_parent_geom.linear() = R;
  g.T_parent_geom.translation() = center;
  g.material = material;
  return g;
}

Geom MakeRod(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int material) {
  const Eigen::Vector3d d = b - a;
  const Eigen::Matrix3d R =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), d.normalized()).toRotationMatrix();
  return MakeShape(Shape::kCylinder, 0.5 * (a + b), Eigen::Vector3d(radius, 0.5 * d.norm(), 0),
                   material, R);
}

Eigen::Matrix3d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return R;
}

int WorldBuilder::AddTexture(const std::string& name, cv::Mat image_bgr,
                             Eigen::Vector2d tile_size_m) {
  Texture t;
  t.name = name;
  t.image_bgr = std::move(image_bgr);
  t.tile_size_m = tile_size_m;
  world_->textures.push_back(std::move(t));
  return static_cast<int>(world_->textures.size()) - 1;
}

int WorldBuilder::AddMaterial(const std::string& name, int texture, Eigen::Vector4f rgba,
                              float specular, float shininess) {
  Material m;
  m.name = name;
  m.texture = texture;
  m.rgba = rgba;
  m.specular = specular;
  m.shininess = shininess;
  world_->materials.push_back(std::move(m));
  return static_cast<int>(world_->materials.size()) - 1;
}

Object& WorldBuilder::AddObject(const std::string& category_name) {
  Object o;
  o.instance_id = static_cast<std::uint16_t>(world_->objects.size() + 1);
  o.category_name = category_name;
  o.coco_category_id = CocoId(category_name);
  o.moveable = CocoMoveable(o.coco_category_id);
  world_->objects.push_back(std::move(o));
  return world_->objects.back();
}

CameraRoute OffsetRoute(const CameraRoute& route, const Eigen::Vector3d& offset_m, double yaw_deg) {
  CameraRoute out = route;
  const Eigen::Matrix3d R_yaw =
      Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  for (CameraKey& key : out.keys) {
    // The route frame of this key: forward is the optical axis projected on the ground.
    Eigen::Vector3d forward = key.T_wc.linear().col(2);
    forward.z() = 0;
    forward = forward.norm() > 1e-6 ? forward.normalized() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(forward);
    key.T_wc.translation() += offset_m.x() * forward + offset_m.y() * left +
                              offset_m.z() * Eigen::Vector3d::UnitZ();
    key.T_wc.linear() = R_yaw * key.T_wc.linear();
  }
  return out;
}

ChangePlan PlanSecondPass(int candidates, const SecondPassSpec& spec, std::mt19937_64& rng) {
  std::vector<int> order(candidates);
  for (int i = 0; i < candidates; ++i) order[i] = i;
  Shuffle(order, rng);
  const int relocated = std::min<int>(candidates, std::lround(spec.relocated_share * candidates));
  const int removed =
      std::min<int>(candidates - relocated, std::lround(spec.removed_share * candidates));
  ChangePlan plan;
  plan.relocated.assign(order.begin(), order.begin() + relocated);
  plan.removed.assign(order.begin() + relocated, order.begin() + relocated + removed);
  std::sort(plan.relocated.begin(), plan.relocated.end());
  std::sort(plan.removed.begin(), plan.removed.end());
  return plan;
}

void RecordSecondPassChanges(World* world, int candidates) {
  SecondPassChanges& c = world->pass2_changes;
  c = SecondPassChanges();
  c.candidates = candidates;
  for (const Object& o : world->objects) {
    const Placement& p1 = o.placement[0];
    const Placement& p2 = o.placement[1];
    // Movers are traffic, not changes of what stays put (a city's pass 2 has its own).
    if (p1.moving || p2.moving) continue;
    if (p1.present && !p2.present) c.removed.push_back(o.instance_id);
    if (!p1.present && p2.present) c.added.push_back(o.instance_id);
    if (p1.present && p2.present && !p1.moving && !p2.moving &&
        !p1.T_world_object.isApprox(p2.T_world_object, 1e-9)) {
      c.relocated.push_back(o.instance_id);
    }
  }
}

namespace {
Eigen::Vector2d Horizontal(const Eigen::Vector3d& v) { return v.head<2>(); }
}  // namespace

double MinDistanceToCamera(const World& world, const Object& object, double step_s) {
  double best = 1e18;
  for (Pass pass : kBothPasses) {
    if (!object.placement[PassIndex(pass)].present) continue;
    const double duration = world.frames_per_pass[PassIndex(pass)] / world.camera.fps;
    for (double t = 0; t <= duration + 1e-9; t += step_s) {
      const double d = (Horizontal(ObjectPoseAt(object, pass, t).translation()) -
                        Horizontal(CameraPoseAt(world, pass, t).translation()))
                           .norm();
      best = std::min(best, d);
    }
  }
  return best;
}

double MinDistanceToObjects(const World& world, const Object& object,
                            const std::vector<const Object*>& others, double step_s) {
  double best = 1e18;
  for (Pass pass : kBothPasses) {
    if (!object.placement[PassIndex(pass)].present) continue;
    const double duration = world.frames_per_pass[PassIndex(pass)] / world.camera.fps;
    for (double t = 0; t <= duration + 1e-9; t += step_s) {
      const Eigen::Vector2d p = Horizontal(ObjectPoseAt(object, pass, t).translation());
      for (const Object* other : others) {
        if (!other->placement[PassIndex(pass)].present) continue;
        best = std::min(best, (p - Horizontal(ObjectPoseAt(*other, pass, t).translation())).norm());
      }
    }
  }
  return best;
}

void PlaceOnPaths(World* world, std::mt19937_64& rng, int index,
                  const std::vector<PathMotion>& candidates, const std::vector<int>& others,
                  double min_camera_m, double min_other_m, double step_s) {
  // Sample times of both passes, with the camera's and the other objects' positions
  // there computed once.
  struct Sample {
    Pass pass;
    double t;
    Eigen::Vector2d camera;
    std::vector<Eigen::Vector2d> others;
  };
  std::vector<Sample> samples;
  for (Pass pass : kBothPasses) {
    const double duration = world->frames_per_pass[PassIndex(pass)] / world->camera.fps;
    for (double t = 0; t <= duration + 1e-9; t += step_s) {
      Sample s{pass, t, Horizontal(CameraPoseAt(*world, pass, t).translation()), {}};
      for (int i : others) {
        const Object& other = world->objects[i];
        if (other.placement[PassIndex(pass)].present) {
          s.others.push_back(Horizontal(ObjectPoseAt(other, pass, t).translation()));
        }
      }
      samples.push_back(std::move(s));
    }
  }

  // Try candidates and start offsets; a try stops as soon as it cannot beat the best.
  Object& o = world->objects[index];
  double best_score = -1;
  std::array<Placement, 2> best = o.placement;
  for (int attempt = 0; attempt < 40 && !candidates.empty(); ++attempt) {
    const PathMotion& base = candidates[attempt % candidates.size()];
    for (Placement& p : o.placement) {
      p.present = true;
      p.moving = true;
      p.path = base;
      p.path.start_offset_m = Uniform(rng, 0, 1000);
    }
    double score = 1e9;
    for (const Sample& s : samples) {
      const Eigen::Vector2d p = Horizontal(ObjectPoseAt(o, s.pass, s.t).translation());
      score = std::min(score, (p - s.camera).norm() / min_camera_m);
      for (const Eigen::Vector2d& q : s.others) score = std::min(score, (p - q).norm() / min_other_m);
      if (score <= best_score) break;
    }
    if (score > best_score) {
      best_score = score;
      best = o.placement;
    }
    if (score >= 1.0) break;
  }
  o.placement = best;
}

double SmoothNoise::Eval(double t) const {
  double v = 0;
  for (int i = 0; i < 3; ++i) v += std::sin(2 * M_PI * freq_hz[i] * t + phase[i]) / 1.7;
  return v;
}

SmoothNoise SmoothNoise::Make(std::mt19937_64& rng, double base_hz) {
  SmoothNoise n;
  for (int i = 0; i < 3; ++i) {
    n.freq_hz[i] = base_hz * Uniform(rng, 0.7, 1.3) * (1 << i) * 0.9;
    n.phase[i] = Uniform(rng, 0, 2 * M_PI);
  }
  return n;
}

World BuildWorld(const Scenario& scenario) {
  return scenario.kind == "office" ? BuildOffice(scenario) : BuildCity(scenario);
}

}  // namespace segslam::scenes
