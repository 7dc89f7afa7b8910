// Helpers shared by the scenes tests: scenario paths, a hash of a whole world, and
// conservative world-space bounding boxes of geoms.
#pragma once

#include "scenes/scenario.h"
#include "scenes/world.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <cstring>
#include <string>

namespace segslam::scenes::testing {

inline std::string ScenarioPath(const std::string& relative) {
  return std::string(SEGSLAM_SOURCE_DIR) + "/scenarios/" + relative;
}

// FNV-1a over every number of the world, including texture bytes.
class Hasher {
 public:
  void Bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 1099511628211ull;
  }
  void Double(double v) { Bytes(&v, sizeof v); }
  void Int(long long v) { Bytes(&v, sizeof v); }
  void Pose(const Eigen::Isometry3d& T) {
    for (int i = 0; i < 16; ++i) Double(T.matrix().data()[i]);
  }
  void Path(const PathMotion& p) {
    for (const auto& w : p.waypoints) Bytes(w.data(), sizeof(double) * 3);
    Double(p.speed_mps);
    Double(p.start_offset_m);
    Int(p.closed);
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ull;
};

inline std::uint64_t HashWorld(const World& w) {
  Hasher h;
  for (const Texture& t : w.textures) {
    h.Int(t.image_bgr.rows);
    h.Int(t.image_bgr.cols);
    for (int r = 0; r < t.image_bgr.rows; ++r) h.Bytes(t.image_bgr.ptr(r), t.image_bgr.cols * 3);
    h.Double(t.tile_size_m.x());
    h.Double(t.tile_size_m.y());
  }
  for (const Material& m : w.materials) {
    h.Int(m.texture);
    h.Bytes(m.rgba.data(), sizeof(float) * 4);
  }
  auto geom = [&](const Geom& g) {
    h.Int(static_cast<int>(g.shape));
    h.Bytes(g.size.data(), sizeof(double) * 3);
    h.Pose(g.T_parent_geom);
    h.Int(g.material);
  };
  for (const Geom& g : w.static_geoms) geom(g);
  for (const Object& o : w.objects) {
    h.Int(o.instance_id);
    h.Int(o.coco_category_id);
    h.Double(o.gait_phase_offset);
    h.Double(o.body_scale);
    for (const Part& p : o.parts) {
      for (const Geom& g : p.geoms) geom(g);
    }
    for (const Placement& p : o.placement) {
      h.Int(p.present);
      h.Int(p.moving);
      h.Pose(p.T_world_object);
      h.Path(p.path);
    }
  }
  for (const CameraRoute& r : w.camera_route) {
    for (const CameraKey& k : r.keys) {
      h.Double(k.stamp_s);
      h.Pose(k.T_wc);
    }
  }
  h.Int(w.frames_per_pass[0]);
  h.Int(w.frames_per_pass[1]);
  return h.value();
}

// Conservative axis-aligned box of a geom placed at T_world_geom (planes: none).
inline bool GeomBox(const Geom& g, const Eigen::Isometry3d& T_world_geom, Eigen::Vector3d* lo,
                    Eigen::Vector3d* hi) {
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  switch (g.shape) {
    case Shape::kPlane:
      return false;
    case Shape::kBox:
    case Shape::kEllipsoid:
      half = g.size;
      break;
    case Shape::kSphere:
      half = Eigen::Vector3d::Constant(g.size.x());
      break;
    case Shape::kCylinder:
      half = Eigen::Vector3d(g.size.x(), g.size.x(), g.size.y());
      break;
    case Shape::kCapsule:
      half = Eigen::Vector3d(g.size.x(), g.size.x(), g.size.y() + g.size.x());
      break;
  }
  const Eigen::Vector3d extent = T_world_geom.linear().cwiseAbs() * half;
  *lo = T_world_geom.translation() - extent;
  *hi = T_world_geom.translation() + extent;
  return true;
}

// Whether `p` lies inside the box of any geom of the world (static and objects) at
// time t of `pass`, with `margin_m` added to each box. Names the first hit.
inline bool InsideAnyGeom(const World& w, Pass pass, double t, const Eigen::Vector3d& p,
                          double margin_m, std::string* what) {
  auto test = [&](const Geom& g, const Eigen::Isometry3d& T_world_parent, const std::string& name) {
    Eigen::Vector3d lo, hi;
    if (!GeomBox(g, T_world_parent * g.T_parent_geom, &lo, &hi)) return false;
    lo.array() -= margin_m;
    hi.array() += margin_m;
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) {
      *what = name;
      return true;
    }
    return false;
  };
  for (std::size_t i = 0; i < w.static_geoms.size(); ++i) {
    if (test(w.static_geoms[i], Eigen::Isometry3d::Identity(), "static geom " + std::to_string(i))) return true;
  }
  for (const Object& o : w.objects) {
    const auto poses = PartPosesAt(o, pass, t);
    for (std::size_t k = 0; k < poses.size(); ++k) {
      for (const Geom& g : o.parts[k].geoms) {
        if (test(g, poses[k], o.category_name + " " + std::to_string(o.instance_id))) return true;
      }
    }
  }
  return false;
}

}  // namespace segslam::scenes::testing
