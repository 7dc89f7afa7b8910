// Tracking a frame against the map (see slam/tracker.h): projection matching from the last
// frame (constant velocity) and from the local map, descriptor matching against the
// reference keyframe, relocalization against every map point, and the robust pose
// optimisation that follows each.
#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>

#include "slam/ransac_pnp.h"
#include "slam/tracker_internal.h"

namespace segslam::slam {

std::vector<PoseObservation> Tracker::Impl::Observations(const WorkingFrame& frame,
                                                         std::vector<int>* feature_of_observation,
                                                         bool skip_excluded) const {
  return ObservationsOf(frame, feature_of_observation, [&](size_t i) {
    return frame.points[i] != nullptr && !(skip_excluded && frame.excluded[i]) ? frame.points[i] : nullptr;
  });
}

// Optimises current.T_cw from its matches; flags outliers; returns the inlier count.
// `discard_outliers` drops outlier matches (remembering them for the judgement).
int Tracker::Impl::OptimizeCurrentPose(bool skip_excluded, bool discard_outliers) {
  std::vector<int> feature_of;
  const std::vector<PoseObservation> observations = Observations(current, &feature_of, skip_excluded);
  if (observations.size() < 3) return 0;
  PoseOptimizerOptions pose_options = options.pose_optimizer;
  pose_options.bf = bf;
  const PoseOptimizationResult optimized = OptimizePose(current.T_cw, observations, camera, pose_options);
  current.T_cw = optimized.T_cw;
  int inliers = 0;
  for (size_t k = 0; k < feature_of.size(); ++k) {
    const size_t i = static_cast<size_t>(feature_of[k]);
    current.outlier[i] = !optimized.inlier[k];
    if (optimized.inlier[k]) {
      ++inliers;
    } else if (discard_outliers) {
      current.rejected[i] = current.points[i];
      current.points[i] = nullptr;
      current.outlier[i] = false;
    }
  }
  return inliers;
}

// The map point feature i was matched to, kept or rejected as an outlier.
MapPoint* Tracker::Impl::MatchedPoint(size_t i) const {
  return current.points[i] != nullptr ? current.points[i] : current.rejected[i];
}

// Best feature of the current frame for `descriptor` among `candidates` that have no
// match yet; returns -1 if none passes the distance limit and the ratio test.
int Tracker::Impl::BestCandidate(const OrbDescriptor& descriptor, const std::vector<int>& candidates, int max_distance,
                                 float ratio) const {
  NearestTwo nearest;
  for (int index : candidates) {
    if (current.points[static_cast<size_t>(index)] != nullptr) continue;
    nearest.Offer(index, DescriptorDistance(descriptor.data(), current.features.descriptors.ptr<std::uint8_t>(index)));
  }
  if (nearest.best < 0 || nearest.best_distance > max_distance) return -1;
  const auto level = [&](int index) { return current.features.keypoints[static_cast<size_t>(index)].octave; };
  // The ratio test compares like with like: a second match on another pyramid level is
  // another scale of the same corner, not a rival.
  if (ratio < 1.0f && nearest.second >= 0 && level(nearest.best) == level(nearest.second) &&
      nearest.best_distance > ratio * nearest.second_distance) {
    return -1;
  }
  return nearest.best;
}

// Projects the matched points of the last frame into the current one (ORB-SLAM's
// SearchByProjection for the motion model); returns the number of matches.
int Tracker::Impl::SearchLastFrame(double radius_px) {
  int matches = 0;
  RotationHistogram histogram;
  std::vector<int> candidates;
  const auto& scales = extractor.scale_factors();
  const int levels = extractor.options().levels;
  for (size_t j = 0; j < last.points.size(); ++j) {
    MapPoint* point = last.points[j];
    if (point == nullptr || point->bad || last.outlier[j]) continue;
    if (point->last_matched_frame == current.index) continue;
    const Eigen::Vector3d p_c = current.T_cw * point->position_w;
    if (p_c.z() <= 0) continue;
    const Eigen::Vector2d uv = camera.Project(p_c);
    if (!camera.InImage(uv)) continue;
    const int level = last.features.keypoints[j].octave;
    const double radius = radius_px * scales[static_cast<size_t>(level)];
    current.grid.Query(current.features.keypoints, uv.x(), uv.y(), radius, std::max(0, level - 1),
                       std::min(levels - 1, level + 1), &candidates);
    const int best = BestCandidate(point->descriptor, candidates, options.max_descriptor_distance, 1.0f);
    if (best < 0) continue;
    current.points[static_cast<size_t>(best)] = point;
    point->last_matched_frame = current.index;
    histogram.Add(best, last.features.keypoints[j].angle, current.features.keypoints[static_cast<size_t>(best)].angle);
    ++matches;
  }
  for (int rejected : histogram.Rejected()) {
    current.points[static_cast<size_t>(rejected)]->last_matched_frame = -1;
    current.points[static_cast<size_t>(rejected)] = nullptr;
    --matches;
  }
  return matches;
}

bool Tracker::Impl::IsOccluded(const Eigen::Vector2d& uv, double z) const {
  if (current.depth_m.empty()) return false;
  const int x = static_cast<int>(std::lround(uv.x()));
  const int y = static_cast<int>(std::lround(uv.y()));
  const float measured = current.depth_m.at<float>(y, x);
  // Something measurably in front of the point hides it (moving objects included);
  // the margin absorbs depth noise and edges.
  return std::isfinite(measured) && measured > 0 && measured < 0.85 * z - 0.1;
}

// Matches every map point that the current frame should see (frustum, scale range,
// viewing angle, depth occlusion) by projection: ORB-SLAM's SearchLocalPoints, over
// the whole map (a brute-force frustum test costs well under a millisecond per 10^5
// points, and needs no covisibility graph). Returns the number of new matches.
int Tracker::Impl::SearchLocalMap(double radius_factor) {
  // The points already matched are in view too: counted, or FoundRatio() would read high
  // for every point the earlier stages match and the culling would keep spurious ones.
  for (MapPoint* point : current.points) {
    if (point != nullptr && !point->bad && point->last_visible_frame != current.index) {
      point->last_visible_frame = current.index;
      ++point->visible_count;
    }
  }
  int matches = 0;
  const Eigen::Isometry3d T_wc = current.T_cw.inverse();
  const Eigen::Vector3d center = T_wc.translation();
  const auto& scales = extractor.scale_factors();
  std::vector<int> candidates;
  for (const auto& owned : map->points()) {
    MapPoint* point = owned.get();
    if (point->bad || point->last_matched_frame == current.index) continue;
    const Eigen::Vector3d p_c = current.T_cw * point->position_w;
    if (p_c.z() <= 0.05) continue;
    const Eigen::Vector2d uv = camera.Project(p_c);
    if (!camera.InImage(uv, 1)) continue;
    const Eigen::Vector3d ray = point->position_w - center;
    const double distance = ray.norm();
    if (point->max_distance_m > 0 &&
        (distance < 0.8 * point->min_distance_m || distance > 1.2 * point->max_distance_m)) {
      continue;
    }
    const double view_cos = ray.dot(point->viewing_direction_w) / distance;
    if (view_cos < 0.5) continue;
    if (IsOccluded(uv, p_c.z())) continue;
    if (point->last_visible_frame != current.index) {
      point->last_visible_frame = current.index;
      ++point->visible_count;
    }
    const int level = point->PredictLevel(distance, extractor);
    const double radius = radius_factor * (view_cos > 0.998 ? 2.5 : 4.0) * scales[static_cast<size_t>(level)];
    current.grid.Query(current.features.keypoints, uv.x(), uv.y(), radius, std::max(0, level - 1), level, &candidates);
    const int best =
        BestCandidate(point->descriptor, candidates, options.max_descriptor_distance, options.projection_ratio);
    if (best < 0) continue;
    current.points[static_cast<size_t>(best)] = point;
    current.outlier[static_cast<size_t>(best)] = false;
    point->last_matched_frame = current.index;
    ++matches;
  }
  return matches;
}

// Forgets the matches of an attempt that failed, so the next attempt may match the same
// points again.
void Tracker::Impl::ClearMatches() {
  for (const std::vector<MapPoint*>* matches : {&current.points, &current.rejected}) {
    for (MapPoint* point : *matches) {
      if (point != nullptr && point->last_matched_frame == current.index) point->last_matched_frame = -1;
    }
  }
  std::fill(current.points.begin(), current.points.end(), nullptr);
  std::fill(current.outlier.begin(), current.outlier.end(), false);
  std::fill(current.rejected.begin(), current.rejected.end(), nullptr);
}

void Tracker::Impl::MarkCurrentMatched() {
  for (MapPoint* point : current.points) {
    if (point != nullptr) point->last_matched_frame = current.index;
  }
}

Tracker::Impl::SavedMatches Tracker::Impl::SaveMatches() const {
  return {current.T_cw, current.points, current.rejected, current.outlier};
}

// Undoes the searches since SaveMatches(): their matches are cleared, and the saved
// points, kept and rejected, are marked matched by this frame again, as they were.
void Tracker::Impl::RestoreMatches(const SavedMatches& saved) {
  ClearMatches();
  current.T_cw = saved.T_cw;
  current.points = saved.points;
  current.rejected = saved.rejected;
  current.outlier = saved.outlier;
  for (const std::vector<MapPoint*>* matches : {&current.points, &current.rejected}) {
    for (MapPoint* point : *matches) {
      if (point != nullptr) point->last_matched_frame = current.index;
    }
  }
}

bool Tracker::Impl::TrackWithMotionModel() {
  ClearMatches();
  const bool have_velocity = velocity.has_value();
  current.T_cw = have_velocity ? Eigen::Isometry3d(*velocity * last.T_cw) : last.T_cw;
  double radius = options.last_frame_radius_px * (have_velocity ? 1.0 : 2.0);
  int matches = SearchLastFrame(radius);
  if (matches < 20) {
    ClearMatches();
    matches = SearchLastFrame(2 * radius);
  }
  if (matches < 20) return false;
  return OptimizeCurrentPose(/*skip_excluded=*/false, /*discard_outliers=*/true) >= 10;
}

// No velocity is known on the frame after the map's first, and the window search around
// the last pose favours whatever moved with the camera: a camera that starts at speed
// among traffic finds the car ahead where it was, and too few of the near background's
// features, which left their windows, to say otherwise. So the reference keyframe's
// descriptors are also matched anywhere in the image, and the pose that more matches
// agree with is kept. At rest or slow that is mostly the window's, and the frame is
// tracked exactly as it would be without the second search.
bool Tracker::Impl::TrackWithoutVelocity() {
  // Outliers were discarded: the matches left are the inliers.
  const auto inliers = [this] {
    return static_cast<int>(std::count_if(current.points.begin(), current.points.end(),
                                          [](const MapPoint* point) { return point != nullptr; }));
  };
  const bool by_window = TrackWithMotionModel();
  const int window_inliers = by_window ? inliers() : 0;
  const SavedMatches window = SaveMatches();
  if (TrackReferenceKeyframe() && inliers() > window_inliers) return true;
  RestoreMatches(window);
  return by_window;
}

bool Tracker::Impl::TrackReferenceKeyframe() {
  if (reference_keyframe == nullptr) return false;
  ClearMatches();
  std::vector<int> reference_features;
  for (size_t i = 0; i < reference_keyframe->points.size(); ++i) {
    const MapPoint* point = reference_keyframe->points[i];
    if (point != nullptr && !point->bad) reference_features.push_back(static_cast<int>(i));
  }
  if (reference_features.size() < 15 || current.features.size() == 0) return false;
  cv::Mat reference_descriptors(static_cast<int>(reference_features.size()), kOrbDescriptorBytes, CV_8U);
  for (size_t k = 0; k < reference_features.size(); ++k) {
    reference_keyframe->features.descriptors.row(reference_features[k])
        .copyTo(reference_descriptors.row(static_cast<int>(k)));
  }
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(current.features.descriptors, reference_descriptors, knn, 2);
  int matches = 0;
  for (const auto& pair : knn) {
    if (pair.empty() || pair[0].distance > options.strict_descriptor_distance) continue;
    if (pair.size() > 1 && pair[0].distance > 0.7f * pair[1].distance) continue;
    MapPoint* point =
        reference_keyframe->points[static_cast<size_t>(reference_features[static_cast<size_t>(pair[0].trainIdx)])];
    if (point->last_matched_frame == current.index) continue;
    current.points[static_cast<size_t>(pair[0].queryIdx)] = point;
    point->last_matched_frame = current.index;
    ++matches;
  }
  if (matches < 15) return false;
  current.T_cw = last.T_cw;
  return OptimizeCurrentPose(false, true) >= 10;
}

// The local-map stage after a successful first stage; true if the frame is tracked.
bool Tracker::Impl::TrackLocalMap(int min_inliers, double radius_factor) {
  SearchLocalMap(radius_factor);
  const int inliers = OptimizeCurrentPose(false, false);
  result.num_coarse_inliers = inliers;
  return inliers >= min_inliers;
}

// Puts the first frame at options.initial_T_wc and fixes the close-point depth; the
// keyframe follows in UpdateMaps(). False while the frame has too few features with depth.
bool Tracker::Impl::InitializeMap() {
  // Counted on the features left after DropMoveableFeatures(), not the frame's.
  std::vector<float> depths;
  for (float d : current.features.depth_m) {
    if (d > 0) depths.push_back(d);
  }
  if (depths.empty() || static_cast<int>(depths.size()) < options.min_initial_map_features) return false;
  current.T_cw = options.initial_T_wc.inverse();
  initialized = true;
  pending_first_keyframe = true;
  if (options.close_depth_m > 0) {
    close_depth_m = options.close_depth_m;
  } else {
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
    close_depth_m = std::clamp(double(depths[depths.size() / 2]), 3.0, 25.0);
  }
  return true;
}

namespace {

// The descriptor index of the map's points that `keep` accepts, which it lists in
// `points` (row k of the index is points[k]).
template <typename Keep>
std::unique_ptr<DescriptorIndex> IndexPoints(const Map& map, Keep keep, std::vector<MapPoint*>* points) {
  points->clear();
  cv::Mat descriptors;
  for (const auto& owned : map.points()) {
    if (!keep(*owned)) continue;
    points->push_back(owned.get());
    descriptors.push_back(cv::Mat(1, kOrbDescriptorBytes, CV_8U, owned->descriptor.data()));
  }
  return std::make_unique<DescriptorIndex>(descriptors);
}

}  // namespace

// The run's own points (not the loaded map's, not bad) and their descriptor index,
// rebuilt only when points were made or purged since: points never change their
// descriptor, and one marked bad since is skipped where it is matched.
const DescriptorIndex& Tracker::Impl::OwnPointIndex() {
  const std::uint64_t upcoming_point_id = map->UpcomingPointId();
  const size_t map_size = map->points().size();
  if (own_index != nullptr && own_index_upcoming_point_id == upcoming_point_id && own_index_map_size == map_size) {
    return *own_index;
  }
  own_index = IndexPoints(*map, [](const MapPoint& point) { return !point.bad && !point.fixed; }, &own_points);
  own_index_upcoming_point_id = upcoming_point_id;
  own_index_map_size = map_size;
  return *own_index;
}

// Relocalization against every map point: nearest-neighbour descriptor search with a
// ratio test, RANSAC PnP (up to two rival poses), pose optimisation, then a local-map
// search. Two poses that both hold up on the local map leave the frame lost: it says
// nothing certain of where it is (TrackerOptions::rival_support_ratio); a re-check
// (kTakeStronger) takes the stronger, to weigh it against the pose tracked. The search goes
// through descriptor indexes (by brute force a relocalization on city_boulevard's map
// took 0.6 s, and a lost run pays it every frame): the loaded map's, built once, and
// the run's own points', rebuilt when they changed.
bool Tracker::Impl::Relocalize(bool long_term_only, RivalPolicy rival_policy) {
  ClearMatches();
  if (current.features.size() < 20) return false;
  if (localization_mode && long_term_index == nullptr) {
    long_term_index = IndexPoints(*map, [](const MapPoint& point) { return point.fixed; }, &long_term_points);
  }
  // Rows: the long-term points first, then the run's own.
  std::vector<MapPoint*> searched = localization_mode ? long_term_points : std::vector<MapPoint*>();
  std::vector<NearestTwo> nearest(current.features.size());
  if (localization_mode) nearest = long_term_index->Search(current.features.descriptors);
  if (!long_term_only) {
    const DescriptorIndex& own = OwnPointIndex();
    const int offset = static_cast<int>(searched.size());
    searched.insert(searched.end(), own_points.begin(), own_points.end());
    const std::vector<NearestTwo> own_nearest = own.Search(current.features.descriptors);
    for (size_t i = 0; i < nearest.size(); ++i) {
      const NearestTwo& found = own_nearest[i];
      if (found.best >= 0) nearest[i].Offer(offset + found.best, found.best_distance);
      if (found.second >= 0) nearest[i].Offer(offset + found.second, found.second_distance);
    }
  }
  if (searched.size() < 20) return false;
  std::vector<cv::Point3f> object_points;
  std::vector<cv::Point2f> image_points;
  std::vector<std::pair<int, MapPoint*>> matched;
  for (size_t i = 0; i < nearest.size(); ++i) {
    const NearestTwo& found = nearest[i];
    if (found.best < 0 || found.best_distance > 64) continue;
    if (found.best_distance > options.relocalization_ratio * found.second_distance) continue;
    MapPoint* point = searched[static_cast<size_t>(found.best)];
    if (point->bad) continue;
    const Eigen::Vector3d& p = point->position_w;
    object_points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    image_points.push_back(current.features.keypoints[i].pt);
    matched.emplace_back(static_cast<int>(i), point);
  }
  if (matched.size() < 15) return false;
  const std::vector<RelocalizationHypothesis> hypotheses = RivalPoses(matched, object_points, image_points);
  if (hypotheses.empty()) return false;
  if (hypotheses.size() == 2) {
    // The rival first, so that the frame is left in the first pose's state, which wins
    // far more often; the rival is tracked again only when it wins.
    const int support_second = TrackFromHypothesis(hypotheses[1], matched);
    const Eigen::Vector3d center_second = current.T_cw.inverse().translation();
    const int support_first = TrackFromHypothesis(hypotheses[0], matched);
    const Eigen::Vector3d center_first = current.T_cw.inverse().translation();
    const bool apart = (center_first - center_second).norm() > options.rival_pose_distance_m;
    const bool ambiguous = apart && std::min(support_first, support_second) >=
                                        options.rival_support_ratio * std::max(support_first, support_second);
    if (ambiguous && rival_policy == RivalPolicy::kStayLostWhenAmbiguous) {
      ClearMatches();
      return false;
    }
    if (support_second > support_first) TrackFromHypothesis(hypotheses[1], matched);
  } else {
    TrackFromHypothesis(hypotheses[0], matched);
  }
  return result.num_coarse_inliers >= options.min_relocalization_inliers;
}

// RANSAC PnP on the relocalization's matches, then again on the matches its consensus
// left out: a street of repeated façades matches two places at once, and the larger
// consensus may be the wrong one. The second pose is kept when at least
// min_rival_consensus matches agree on it.
std::vector<Tracker::Impl::RelocalizationHypothesis> Tracker::Impl::RivalPoses(
    const std::vector<std::pair<int, MapPoint*>>& matched, const std::vector<cv::Point3f>& object_points,
    const std::vector<cv::Point2f>& image_points) const {
  std::vector<RelocalizationHypothesis> hypotheses;
  std::vector<bool> taken(matched.size(), false);
  for (size_t round = 0; round < 2; ++round) {
    const size_t min_consensus = round == 0 ? 15 : static_cast<size_t>(options.min_rival_consensus);
    std::vector<cv::Point3f> round_object_points;
    std::vector<cv::Point2f> round_image_points;
    std::vector<int> round_matches;
    for (size_t k = 0; k < matched.size(); ++k) {
      if (taken[k]) continue;
      round_object_points.push_back(object_points[k]);
      round_image_points.push_back(image_points[k]);
      round_matches.push_back(static_cast<int>(k));
    }
    if (round_matches.size() < min_consensus) break;
    const std::optional<PnpConsensus> consensus =
        SolveRansacPnp(round_object_points, round_image_points, camera, options.relocalization_ransac_iterations,
                       static_cast<int>(min_consensus));
    if (!consensus) break;
    RelocalizationHypothesis hypothesis;
    hypothesis.T_cw = consensus->T_cw;
    for (int k : consensus->inliers) {
      const int match = round_matches[static_cast<size_t>(k)];
      taken[static_cast<size_t>(match)] = true;
      hypothesis.matches.push_back(match);
    }
    hypotheses.push_back(std::move(hypothesis));
  }
  return hypotheses;
}

// Tracks the current frame from a relocalization pose and its consensus: pose
// optimisation, then a search of the local map. Leaves current.T_cw, the matches and
// result.num_coarse_inliers as they come out, and returns the local-map inliers (0 when
// the consensus does not survive the optimisation). The map points a losing pose looked
// at keep that look in their visible count; it happens only on relocalization frames.
int Tracker::Impl::TrackFromHypothesis(const RelocalizationHypothesis& hypothesis,
                                       const std::vector<std::pair<int, MapPoint*>>& matched) {
  ClearMatches();
  current.T_cw = hypothesis.T_cw;
  for (int k : hypothesis.matches) {
    const auto& [feature, point] = matched[static_cast<size_t>(k)];
    if (point->last_matched_frame == current.index) continue;
    current.points[static_cast<size_t>(feature)] = point;
    point->last_matched_frame = current.index;
  }
  result.num_coarse_inliers = 0;
  if (OptimizeCurrentPose(false, true) < 10) return 0;
  TrackLocalMap(options.min_relocalization_inliers, 5.0);
  return result.num_coarse_inliers;
}

// ORB-SLAM2's localization mode: a frame tracked only on the points the run made itself
// may be in the frame of a relocalization at a look-alike place (repeated facades) or
// drifting; a relocalization on the long-term map says where it is. The points and
// keyframes made since the run left the map are in the frame just found wrong: dropped,
// so they neither match nor pull later poses.
bool Tracker::Impl::RelocalizeOffMap() {
  last_off_map_relocalization_s = current.stamp_s;
  if (!Relocalize(true)) return false;
  // Decided on what stays: a pose held up by the points about to be dropped is no pose.
  if (LongTermInliers() < options.min_long_term_inliers ||
      InliersKeptWhenDroppingFrom(first_point_off_map) < options.min_relocalization_inliers) {
    return false;
  }
  DropWorkSince(first_point_off_map, off_map_since_frame);
  return true;
}

int Tracker::Impl::InliersKeptWhenDroppingFrom(std::uint64_t first_dropped_point) const {
  int inliers = 0;
  for (size_t i = 0; i < current.points.size(); ++i) {
    const MapPoint* point = current.points[i];
    if (point != nullptr && !current.outlier[i]) inliers += point->fixed || point->id < first_dropped_point;
  }
  return inliers;
}

void Tracker::Impl::DropWorkSince(std::uint64_t first_point, int since_frame) {
  for (const auto& owned : map->points()) {
    if (!owned->fixed && owned->id >= first_point) Map::MarkBad(owned.get());
  }
  for (const auto& keyframe : map->keyframes()) {
    if (keyframe->frame_index >= since_frame) keyframe->bad = true;
  }
  if (reference_keyframe != nullptr && reference_keyframe->bad) reference_keyframe = nullptr;
  for (size_t i = 0; i < current.points.size(); ++i) {
    if (current.points[i] != nullptr && current.points[i]->bad) {
      current.points[i] = nullptr;
      current.outlier[i] = false;
    }
  }
  result.num_coarse_inliers = OptimizeCurrentPose(false, false);
  // The instance snapshots were taken in the frame just left: against them everything
  // would seem to move.
  history.clear();
}

void Tracker::Impl::BeginProbation() {
  if (!localization_mode) return;
  probation_until_s = current.stamp_s + options.relocalization_probation_s;
  probation_first_point = map->UpcomingPointId();
  last_probation_check_s = current.stamp_s;
}

// A relocalization is taken on one frame's evidence, and along repeated façades that
// evidence can point to a look-alike with no rival left to doubt it; tracking then
// carries on there, on the map. Searching the whole map again on later frames, while the
// camera shows more of where it is, gives the place a second chance: the frame's own
// place explains the façades and what differs from the look-alike (parked cars, trees,
// street furniture). The tracked pose is compared on the long-term map's inliers only:
// the points the run made since were made in the pose under test and agree with it.
bool Tracker::Impl::RecheckRelocalization() {
  if (!localization_mode || current.stamp_s > probation_until_s + 1e-9 ||
      current.stamp_s - last_probation_check_s < options.off_map_relocalization_interval_s - 1e-9) {
    return false;
  }
  last_probation_check_s = current.stamp_s;
  const int tracked_support = LongTermInliers();
  const SavedMatches tracked = SaveMatches();
  const int tracked_coarse_inliers = result.num_coarse_inliers;
  const Eigen::Vector3d tracked_center = tracked.T_cw.inverse().translation();
  bool replace = Relocalize(true, RivalPolicy::kTakeStronger);
  if (replace) {
    const double moved_m = (current.T_cw.inverse().translation() - tracked_center).norm();
    replace = moved_m > options.rival_pose_distance_m &&
              InliersKeptWhenDroppingFrom(probation_first_point) >= options.min_relocalization_inliers &&
              LongTermInliers() >= options.relocalization_recheck_margin * std::max(tracked_support, 1);
  }
  if (!replace) {
    // The map points the search looked at keep that look in their visible count, as a
    // losing rival's do.
    RestoreMatches(tracked);
    result.num_coarse_inliers = tracked_coarse_inliers;
    return false;
  }
  DropWorkSince(probation_first_point, last_relocalization_frame);
  return true;
}

void Tracker::Impl::NoteLongTermMapMatches() {
  const int inliers = fine_ok ? LongTermInliers() : 0;
  result.num_long_term_inliers = inliers;
  result.on_long_term_map = fine_ok && inliers >= options.min_long_term_inliers;
  if (!fine_ok) return;  // a lost frame says nothing of where the run is
  if (result.on_long_term_map) {
    off_long_term_map = false;
  } else if (!off_long_term_map) {
    // The try clock is not restarted here: a run that drifts hovers about the threshold
    // (on a boulevard 5 to 12 map inliers a frame for 2 s, then 294 after relocalizing),
    // and each return to the map would put the next try off.
    off_long_term_map = true;
    off_map_since_frame = current.index;
    first_point_off_map = map->UpcomingPointId();
  }
}

}  // namespace segslam::slam
