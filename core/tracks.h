// Per-object ground-truth motion, written by the generator next to the masks
// ("tracks.json") so that evaluation knows which instance moved when.
//
// JSON layout:
//   {"tracks": [{"instance_id": 3, "samples": [
//       {"frame": 0, "stamp_s": 0.0, "present": true, "moving": false,
//        "t": [x, y, z], "q": [qx, qy, qz, qw], "visible_pixels": 1234}, ...]}, ...]}
// Numbers are printed with the shortest round-trip representation (nlohmann's), so the
// same tracks always give the same bytes. Quaternions are normalized with qw >= 0.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace segslam {

struct TrackSample {
  int frame = 0;         // Frame index in the sequence.
  double stamp_s = 0;    // Frame timestamp, seconds.
  bool present = true;   // The object exists in the scene at this frame.
  bool moving = false;   // The object (root or limbs) moved since the previous frame.
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // Object-to-world.
  int visible_pixels = 0;  // Pixels of this instance in the frame's mask, >= 0.
};

struct ObjectTrack {
  std::uint16_t instance_id = 0;     // Instance id as in the masks, 1..65535.
  std::vector<TrackSample> samples;  // Ordered by strictly increasing frame.
};

nlohmann::json TracksToJson(const std::vector<ObjectTrack>& tracks);

// Throws segslam::Error starting with `origin` on malformed JSON content: missing keys,
// wrong types, non-finite numbers, bad quaternions, instance id outside 1..65535,
// duplicate instance ids, non-increasing frames, negative visible_pixels.
std::vector<ObjectTrack> TracksFromJson(const nlohmann::json& json, const std::string& origin);

// Reads a tracks file; errors name the file.
std::vector<ObjectTrack> ReadTracks(const std::filesystem::path& path);

// Writes a tracks file atomically (2-space indented JSON).
void WriteTracks(const std::filesystem::path& path, const std::vector<ObjectTrack>& tracks);

}  // namespace segslam
