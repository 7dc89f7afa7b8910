// The long-term map file: what one run leaves behind so that a later run can relocalize
// and track in the same map without remapping (paper section III.C, DESIGN.md "The core"
// step 5), plus a PLY export of its points for point-cloud viewers.
//
// File layout (all numbers little-endian):
//   12 bytes  magic "SEGSLAM-MAP\0"
//   u32       format version (kMapFormatVersion)
//   u64       payload size in bytes
//   payload   camera, description, keyframes, points (see map_file.cpp)
//   32 bytes  SHA-256 of the payload
// The checksum makes a flipped bit or a half-copied file an error instead of a map with
// silently wrong points.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/camera.h"
#include "slam/orb_descriptor.h"

namespace segslam::slam {

// The version this build writes and the only one it reads. Bump it whenever the payload
// layout changes; old files are then refused with a message naming both versions.
constexpr std::uint32_t kMapFormatVersion = 1;

struct StoredMapPoint {
  std::uint64_t id = 0;
  Eigen::Vector3d position_w = Eigen::Vector3d::Zero();
  Eigen::Vector3f viewing_direction = Eigen::Vector3f::Zero();  // mean unit normal, world frame
  float min_distance_m = 0, max_distance_m = 0;  // scale-invariance range (ORB-SLAM)
  OrbDescriptor descriptor{};
  std::uint32_t num_observations = 0;
  std::array<std::uint8_t, 3> color_rgb{};
};

struct StoredKeyframe {
  std::uint64_t id = 0;
  double stamp_s = 0;
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
};

struct LongTermMapData {
  PinholeCamera camera;     // the camera the map was built with
  std::string description;  // free text: source sequence, mode, code version
  std::vector<StoredKeyframe> keyframes;
  std::vector<StoredMapPoint> points;
};

// Writes `map` atomically. Throws segslam::Error naming `path` if the map holds a value
// that LoadLongTermMap would refuse (invalid camera, non-finite numbers, a keyframe
// rotation that is not a rotation, a negative or inverted distance range), so that a
// file once written can always be read back, or if writing fails.
void SaveLongTermMap(const std::filesystem::path& path, const LongTermMapData& map);

// Reads a map written by SaveLongTermMap. Throws segslam::Error "<file>: ..." for a
// missing or unreadable file, wrong magic ("not a segslam map"), an unsupported version
// (naming it and the supported one), a truncated file (expected vs actual size), a
// checksum mismatch ("corrupt"), non-finite or otherwise invalid values, an invalid
// camera, and counts or lengths that exceed the payload.
LongTermMapData LoadLongTermMap(const std::filesystem::path& path);

// Throws segslam::Error starting with `map_origin` if `camera` differs from map.camera
// in size, or in fx, fy, cx or cy by more than 1e-6 relative, naming both cameras: a map
// from another camera cannot be used for relocalization.
void CheckMapCamera(const LongTermMapData& map, const PinholeCamera& camera,
                    const std::string& map_origin);

// Writes the map points as a PLY point cloud (format binary_little_endian 1.0; vertex
// properties x y z as float, red green blue as uchar; the description as comment lines),
// atomically. Readable by MeshLab, CloudCompare and Open3D. Throws segslam::Error naming
// `path` if writing fails.
void ExportPly(const std::filesystem::path& path, const LongTermMapData& map);

}  // namespace segslam::slam
