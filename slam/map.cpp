#include "slam/map.h"

#include <algorithm>
#include <cmath>

namespace segslam::slam {

bool KeyframeIdLess::operator()(const Keyframe* a, const Keyframe* b) const {
  return a->id < b->id;
}

int MapPoint::PredictLevel(double distance_m, const OrbExtractor& extractor) const {
  const int levels = extractor.options().levels;
  if (max_distance_m <= 0 || distance_m <= 0) return 0;
  const double ratio = max_distance_m / distance_m;
  const int level = static_cast<int>(
      std::ceil(std::log(ratio) / std::log(double(extractor.options().scale_factor))));
  return std::clamp(level, 0, levels - 1);
}

Keyframe* Map::AddKeyframe(std::unique_ptr<Keyframe> keyframe) {
  keyframes_.push_back(std::move(keyframe));
  return keyframes_.back().get();
}

MapPoint* Map::AddPoint(std::unique_ptr<MapPoint> point) {
  points_.push_back(std::move(point));
  return points_.back().get();
}

void Map::AddObservation(MapPoint* point, Keyframe* keyframe, int index) {
  point->observations[keyframe] = index;
  keyframe->points[index] = point;
}

void Map::MarkBad(MapPoint* point) {
  if (point->fixed) return;  // the long-term map is read-only in a localization run
  for (auto& [keyframe, index] : point->observations) {
    if (keyframe->points[index] == point) keyframe->points[index] = nullptr;
  }
  point->observations.clear();
  point->bad = true;
}

void Map::UpdatePointStatistics(MapPoint* point, const OrbExtractor& extractor) {
  if (point->observations.empty()) return;
  std::vector<const std::uint8_t*> descriptors;
  Eigen::Vector3d direction_sum = Eigen::Vector3d::Zero();
  for (const auto& [keyframe, index] : point->observations) {
    descriptors.push_back(keyframe->features.descriptors.ptr<std::uint8_t>(index));
    const Eigen::Vector3d ray = point->position_w - keyframe->Center();
    if (ray.norm() > 0) direction_sum += ray.normalized();
  }
  if (direction_sum.norm() > 0) point->viewing_direction_w = direction_sum.normalized();

  // The descriptor closest (least median Hamming distance) to all others represents the
  // point best across viewpoints.
  const size_t n = descriptors.size();
  int best_median = 1 << 30;
  size_t best = 0;
  std::vector<int> distances(n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) distances[j] = DescriptorDistance(descriptors[i], descriptors[j]);
    std::nth_element(distances.begin(), distances.begin() + (n - 1) / 2, distances.end());
    const int median = distances[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  std::copy(descriptors[best], descriptors[best] + kOrbDescriptorBytes, point->descriptor.begin());

  // Scale-invariance range from the first observation, as ORB-SLAM: the distance at
  // which this keypoint's level would move to level 0 (max) or the last level (min).
  const auto& [reference, index] = *point->observations.begin();
  const double distance = (point->position_w - reference->Center()).norm();
  const int level = reference->features.keypoints[index].octave;
  const auto& scales = extractor.scale_factors();
  point->max_distance_m = static_cast<float>(distance * scales[level]);
  point->min_distance_m = static_cast<float>(point->max_distance_m / scales.back());
}

void Map::PurgeBadPoints() {
  points_.erase(std::remove_if(points_.begin(), points_.end(),
                               [](const std::unique_ptr<MapPoint>& p) { return p->bad; }),
                points_.end());
}

void Map::LoadFixedPoints(const LongTermMapData& data) {
  for (const StoredMapPoint& stored : data.points) {
    auto point = std::make_unique<MapPoint>();
    point->id = NextPointId();
    point->position_w = stored.position_w;
    point->descriptor = stored.descriptor;
    point->viewing_direction_w = stored.viewing_direction.cast<double>();
    point->min_distance_m = stored.min_distance_m;
    point->max_distance_m = stored.max_distance_m;
    point->color_rgb = stored.color_rgb;
    point->fixed = true;
    point->num_loaded_observations = static_cast<int>(stored.num_observations);
    AddPoint(std::move(point));
  }
}

LongTermMapData Map::ToLongTermMap(const PinholeCamera& camera, bool include_instances, int min_observations,
                                   bool keep_fixed_instances) const {
  LongTermMapData data;
  data.camera = camera;
  for (const auto& keyframe : keyframes_) {
    if (keyframe->bad) continue;
    data.keyframes.push_back({keyframe->id, keyframe->stamp_s, keyframe->T_wc()});
  }
  for (const auto& point : points_) {
    if (point->bad) continue;
    const bool on_instances = keep_fixed_instances
                                  ? point->made_on_moveable || point->SeenMostlyOnMoveableInstances()
                                  : point->instance_id != 0 || point->SeenMostlyOnInstances();
    if (!include_instances && on_instances) continue;
    if (point->NumObservations() < min_observations) continue;
    StoredMapPoint stored;
    stored.id = point->id;
    stored.position_w = point->position_w;
    stored.viewing_direction = point->viewing_direction_w.cast<float>();
    stored.min_distance_m = point->min_distance_m;
    stored.max_distance_m = point->max_distance_m;
    stored.descriptor = point->descriptor;
    stored.num_observations = static_cast<std::uint32_t>(point->NumObservations());
    stored.color_rgb = point->color_rgb;
    data.points.push_back(stored);
  }
  return data;
}

size_t Map::NumGoodPoints() const {
  return static_cast<size_t>(std::count_if(points_.begin(), points_.end(),
                                           [](const auto& p) { return !p->bad; }));
}

}  // namespace segslam::slam
