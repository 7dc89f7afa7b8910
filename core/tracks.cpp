#include "core/tracks.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <set>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/json_file.h"
#include "core/error.h"

namespace segslam {
namespace {

// WriteTracks stores quaternions with round-trip digits (norm 1 to ~1e-16); the slack
// admits hand-written test files with a few digits, a larger error means a corrupt file.
constexpr double kMaxQuaternionNormError = 1e-3;

const nlohmann::json& Require(const nlohmann::json& object, const char* key,
                              const std::string& where) {
  if (!object.contains(key)) throw Error(fmt::format("{}: missing key \"{}\"", where, key));
  return object[key];
}

double RequireFinite(const nlohmann::json& value, const std::string& where) {
  if (!value.is_number()) throw Error(where + ": expected a number");
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw Error(where + ": number is not finite");
  return v;
}

std::int64_t RequireInt(const nlohmann::json& value, const std::string& where) {
  if (!value.is_number_integer()) throw Error(where + ": expected an integer");
  return value.get<std::int64_t>();
}

bool RequireBool(const nlohmann::json& value, const std::string& where) {
  if (!value.is_boolean()) throw Error(where + ": expected true or false");
  return value.get<bool>();
}

void CheckKeys(const nlohmann::json& object, std::initializer_list<const char*> allowed,
               const std::string& where) {
  if (!object.is_object()) throw Error(where + ": expected an object");
  for (const auto& item : object.items()) {
    bool ok = false;
    for (const char* key : allowed) ok = ok || item.key() == key;
    if (!ok) throw Error(fmt::format("{}: unknown key \"{}\"", where, item.key()));
  }
}

}  // namespace

nlohmann::json TracksToJson(const std::vector<ObjectTrack>& tracks) {
  nlohmann::json list = nlohmann::json::array();
  for (const ObjectTrack& track : tracks) {
    nlohmann::json samples = nlohmann::json::array();
    for (const TrackSample& s : track.samples) {
      Eigen::Quaterniond q(s.T_world_object.rotation());
      q.normalize();
      if (q.w() < 0) q.coeffs() *= -1.0;  // One of q, -q, so output is unique.
      const Eigen::Vector3d t = s.T_world_object.translation();
      samples.push_back({{"frame", s.frame},
                         {"stamp_s", s.stamp_s},
                         {"present", s.present},
                         {"moving", s.moving},
                         {"t", {t.x(), t.y(), t.z()}},
                         {"q", {q.x(), q.y(), q.z(), q.w()}},
                         {"visible_pixels", s.visible_pixels}});
    }
    list.push_back({{"instance_id", track.instance_id}, {"samples", samples}});
  }
  return nlohmann::json{{"tracks", list}};
}

std::vector<ObjectTrack> TracksFromJson(const nlohmann::json& json, const std::string& origin) {
  CheckKeys(json, {"tracks"}, origin);
  const nlohmann::json& list = Require(json, "tracks", origin);
  if (!list.is_array()) throw Error(origin + ": \"tracks\" must be an array");
  std::vector<ObjectTrack> tracks;
  std::set<std::int64_t> seen_ids;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string where = fmt::format("{}: tracks[{}]", origin, i);
    CheckKeys(list[i], {"instance_id", "samples"}, where);
    ObjectTrack track;
    const std::int64_t id = RequireInt(Require(list[i], "instance_id", where), where + ".instance_id");
    if (id < 1 || id > 65535) {
      throw Error(fmt::format("{}: instance_id {} is outside 1..65535", where, id));
    }
    if (!seen_ids.insert(id).second) {
      throw Error(fmt::format("{}: duplicate instance_id {}", where, id));
    }
    track.instance_id = static_cast<std::uint16_t>(id);
    const nlohmann::json& samples = Require(list[i], "samples", where);
    if (!samples.is_array()) throw Error(where + ": \"samples\" must be an array");
    for (size_t j = 0; j < samples.size(); ++j) {
      const std::string at = fmt::format("{}.samples[{}]", where, j);
      const nlohmann::json& js = samples[j];
      CheckKeys(js, {"frame", "stamp_s", "present", "moving", "t", "q", "visible_pixels"}, at);
      TrackSample s;
      const std::int64_t frame = RequireInt(Require(js, "frame", at), at + ".frame");
      if (frame < 0 || frame > std::numeric_limits<int>::max()) {
        throw Error(fmt::format("{}: frame {} is out of range", at, frame));
      }
      s.frame = static_cast<int>(frame);
      if (!track.samples.empty() && s.frame <= track.samples.back().frame) {
        throw Error(fmt::format("{}: frame {} does not increase (previous {})", at, s.frame,
                                track.samples.back().frame));
      }
      s.stamp_s = RequireFinite(Require(js, "stamp_s", at), at + ".stamp_s");
      s.present = RequireBool(Require(js, "present", at), at + ".present");
      s.moving = RequireBool(Require(js, "moving", at), at + ".moving");
      const nlohmann::json& jt = Require(js, "t", at);
      const nlohmann::json& jq = Require(js, "q", at);
      if (!jt.is_array() || jt.size() != 3) throw Error(at + ": \"t\" must be [x, y, z]");
      if (!jq.is_array() || jq.size() != 4) throw Error(at + ": \"q\" must be [qx, qy, qz, qw]");
      Eigen::Vector3d t;
      for (int k = 0; k < 3; ++k) t[k] = RequireFinite(jt[k], at + ".t");
      double q[4];
      for (int k = 0; k < 4; ++k) q[k] = RequireFinite(jq[k], at + ".q");
      Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
      if (std::abs(quat.norm() - 1.0) > kMaxQuaternionNormError) {
        throw Error(fmt::format("{}: quaternion norm {:.9g} is not 1", at, quat.norm()));
      }
      quat.normalize();
      s.T_world_object = Eigen::Isometry3d::Identity();
      s.T_world_object.linear() = quat.toRotationMatrix();
      s.T_world_object.translation() = t;
      const std::int64_t pixels =
          RequireInt(Require(js, "visible_pixels", at), at + ".visible_pixels");
      if (pixels < 0 || pixels > std::numeric_limits<int>::max()) {
        throw Error(fmt::format("{}: visible_pixels {} is out of range", at, pixels));
      }
      s.visible_pixels = static_cast<int>(pixels);
      track.samples.push_back(s);
    }
    tracks.push_back(std::move(track));
  }
  return tracks;
}

std::vector<ObjectTrack> ReadTracks(const std::filesystem::path& path) {
  return TracksFromJson(ReadJsonFile(path), path.string());
}

void WriteTracks(const std::filesystem::path& path, const std::vector<ObjectTrack>& tracks) {
  WriteFileAtomically(path, TracksToJson(tracks).dump(2) + "\n");
}

}  // namespace segslam
