// The judgement of each instance as moving or static (the paper's step 3, DESIGN.md "The
// core"), measured against the background's pose: 3-D displacement of the instance's
// features against its map points or against its own features a baseline back, a verdict
// on their consensus, a memory of recent verdicts, and what a verdict keeps out of the
// pose and the map. Tracker::JudgeInstances() runs these steps per instance.
#include <cmath>
#include <limits>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "slam/tracker_internal.h"

namespace segslam::slam {

// The pose of the background alone: re-estimated from the coarse pose's matches (its
// rejected ones too) of the features on no instance of a moveable class. Empty when
// fewer than min_tracking_inliers of them fit.
std::optional<Eigen::Isometry3d> Tracker::Impl::BackgroundPose(
    const std::unordered_set<std::uint16_t>& moveable_ids) const {
  std::vector<int> feature_of;
  const std::vector<PoseObservation> observations = ObservationsOf(current, &feature_of, [&](size_t i) {
    const std::uint16_t id = current.instance[i];
    return id != 0 && moveable_ids.count(id) > 0 ? nullptr : MatchedPoint(i);
  });
  if (static_cast<int>(observations.size()) < options.min_tracking_inliers) return std::nullopt;
  PoseOptimizerOptions pose_options = options.pose_optimizer;
  pose_options.bf = bf;
  const PoseOptimizationResult optimized = OptimizePose(current.T_cw, observations, camera, pose_options);
  const auto inliers = std::count(optimized.inlier.begin(), optimized.inlier.end(), true);
  if (inliers < options.min_tracking_inliers) return std::nullopt;
  return optimized.T_cw;
}

// A keypoint on an object's silhouette reads its depth from either side of the edge,
// so its 3-D position jumps between frames although nothing moved: such features
// give no motion evidence.
bool Tracker::Impl::OnDepthEdge(size_t i) const {
  const cv::KeyPoint& kp = current.features.keypoints[i];
  const int x = static_cast<int>(std::lround(kp.pt.x));
  const int y = static_cast<int>(std::lround(kp.pt.y));
  const float depth = current.features.depth_m[i];
  const int r = 1;
  if (x < r || y < r || x >= current.depth_m.cols - r || y >= current.depth_m.rows - r) return true;
  for (int dy = -r; dy <= r; ++dy) {
    const float* row = current.depth_m.ptr<float>(y + dy);
    for (int dx = -r; dx <= r; ++dx) {
      const float d = row[x + dx];
      if (!OnSameSurface(d, depth)) return true;
    }
  }
  return false;
}

double Tracker::Impl::MovingDistanceThreshold(double depth) const {
  return options.moving_distance_m + options.moving_distance_per_m * depth;
}

// +1 moving, 0 static, -1 no measurement, for feature i against map point `point`.
int Tracker::Impl::MotionAgainstPoint(size_t i, const MapPoint* point, const Eigen::Isometry3d& T_wc,
                                      MotionEvidence* evidence) const {
  const float depth = current.features.depth_m[i];
  if (depth > 0) {
    if (OnDepthEdge(i)) return -1;
    const Eigen::Vector3d displacement = T_wc * current.features.points_cam[i] - point->position_w;
    evidence->Add(displacement, MovingDistanceThreshold(depth), current.stamp_s - point->first_stamp_s);
    return displacement.norm() > MovingDistanceThreshold(depth) ? 1 : 0;
  }
  const Eigen::Vector3d p_c = T_wc.inverse() * point->position_w;
  if (p_c.z() <= 0) return 1;
  const cv::KeyPoint& kp = current.features.keypoints[i];
  const double error = (camera.Project(p_c) - Eigen::Vector2d(kp.pt.x, kp.pt.y)).norm();
  const double scale = extractor.scale_factors()[static_cast<size_t>(kp.octave)];
  return error > options.moving_reprojection_px * scale ? 1 : 0;
}

InstanceSnapshot Tracker::Impl::Snapshot() const {
  InstanceSnapshot snapshot;
  snapshot.frame_index = current.index;
  snapshot.stamp_s = current.stamp_s;
  const Eigen::Isometry3d T_wc = current.T_cw.inverse();
  std::vector<int> rows;
  for (size_t i = 0; i < current.instance.size(); ++i) {
    if (current.instance[i] == 0) continue;
    rows.push_back(static_cast<int>(i));
    snapshot.instance.push_back(current.instance[i]);
    snapshot.point_w.push_back(current.features.depth_m[i] > 0 && !OnDepthEdge(i)
                                   ? Eigen::Vector3d(T_wc * current.features.points_cam[i])
                                   : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  snapshot.descriptors.create(static_cast<int>(rows.size()), kOrbDescriptorBytes, CV_8U);
  for (size_t k = 0; k < rows.size(); ++k) {
    current.features.descriptors.row(rows[k]).copyTo(snapshot.descriptors.row(static_cast<int>(k)));
  }
  if (judged && JudgesByDepth()) {
    snapshot.T_wc = T_wc;
    snapshot.depth_m = current.depth_m.clone();  // the caller may reuse the frame's buffers
    for (const auto& [id, samples_c] : current.depth_samples_c) {
      std::vector<Eigen::Vector3d>& samples_w = snapshot.depth_samples_w[id];
      samples_w.reserve(samples_c.size());
      for (const Eigen::Vector3d& p_c : samples_c) samples_w.push_back(T_wc * p_c);
    }
  }
  return snapshot;
}

void Tracker::Impl::ForgetSnapshotsBefore(double stamp_s) {
  while (history.size() > 1 && stamp_s - history[1].stamp_s >= options.motion_baseline_s - 1e-6) {
    history.pop_front();
  }
}

// Frame-to-frame evidence for features of `id` that have no map point of their own:
// match them to the same instance's features in the oldest remembered frame, the newest
// a full baseline back where there is one (a longer baseline makes slow walkers
// measurable), and compare their world positions.
bool Tracker::Impl::MotionAgainstHistory(std::uint16_t id, const std::vector<int>& features,
                                         const Eigen::Isometry3d& T_wc, InstanceJudgement* judgement,
                                         MotionEvidence* evidence) const {
  std::vector<int> query_features;
  for (int i : features) {
    if (current.features.depth_m[static_cast<size_t>(i)] > 0 && !OnDepthEdge(static_cast<size_t>(i))) {
      query_features.push_back(i);
    }
  }
  if (query_features.empty()) return false;
  for (const InstanceSnapshot& snapshot : history) {  // oldest first
    std::vector<int> rows;
    for (size_t k = 0; k < snapshot.instance.size(); ++k) {
      if (snapshot.instance[k] == id && std::isfinite(snapshot.point_w[k].x())) rows.push_back(static_cast<int>(k));
    }
    if (static_cast<int>(rows.size()) < options.min_points_to_judge) continue;
    cv::Mat past(static_cast<int>(rows.size()), kOrbDescriptorBytes, CV_8U);
    for (size_t k = 0; k < rows.size(); ++k) snapshot.descriptors.row(rows[k]).copyTo(past.row(static_cast<int>(k)));
    cv::Mat query(static_cast<int>(query_features.size()), kOrbDescriptorBytes, CV_8U);
    for (size_t k = 0; k < query_features.size(); ++k) {
      current.features.descriptors.row(query_features[k]).copyTo(query.row(static_cast<int>(k)));
    }
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(query, past, knn, 2);
    for (const auto& pair : knn) {
      if (pair.empty() || pair[0].distance > 64) continue;
      if (pair.size() > 1 && pair[0].distance > 0.8f * pair[1].distance) continue;
      const size_t i = static_cast<size_t>(query_features[static_cast<size_t>(pair[0].queryIdx)]);
      const Eigen::Vector3d x_w = T_wc * current.features.points_cam[i];
      const Eigen::Vector3d& past_w =
          snapshot.point_w[static_cast<size_t>(rows[static_cast<size_t>(pair[0].trainIdx)])];
      ++judgement->num_points;
      const double threshold = MovingDistanceThreshold(current.features.depth_m[i]);
      evidence->Add(x_w - past_w, threshold, current.stamp_s - snapshot.stamp_s);
      if ((x_w - past_w).norm() > threshold) ++judgement->num_moving_points;
    }
    return current.stamp_s - snapshot.stamp_s >= options.motion_baseline_s - 1e-6;
  }
  return false;
}

std::uint16_t Tracker::Impl::InstanceNear(const cv::Mat& ids, const cv::Mat& instance_pixels_integral, int x, int y,
                                         int margin) const {
  // The instance pixels in the square of half-width r around (x, y), in four reads.
  const cv::Mat& sum = instance_pixels_integral;
  const auto any_within = [&](int r) {
    const int u0 = std::max(0, x - r), u1 = std::min(camera.width - 1, x + r);
    const int v0 = std::max(0, y - r), v1 = std::min(camera.height - 1, y + r);
    return sum.at<int>(v1 + 1, u1 + 1) - sum.at<int>(v0, u1 + 1) - sum.at<int>(v1 + 1, u0) + sum.at<int>(v0, u0) != 0;
  };
  // Most background features have no instance pixel within the margin (a city frame's
  // instances are a small share of it). Where one has, the smallest square holding one
  // (half-width r) bounds the nearest pixel's distance by r * sqrt(2), so only that
  // square is scanned, not the whole margin's (up to 109 x 109 pixels at a coarse level).
  if (!any_within(margin)) return 0;
  int lo = 0, hi = margin;  // any_within(hi) holds; any_within(lo) does not (the feature's own pixel is background)
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    (any_within(mid) ? hi : lo) = mid;
  }
  const int reach = std::min(margin, static_cast<int>(std::floor(hi * std::sqrt(2.0))));
  // The nearest instance pixel within the margin (the first in row order among equals,
  // so the answer depends on nothing but the mask).
  std::uint16_t nearest = 0;
  int nearest_d2 = margin * margin + 1;
  for (int v = std::max(0, y - reach); v <= std::min(camera.height - 1, y + reach); ++v) {
    const std::uint16_t* row = ids.ptr<std::uint16_t>(v);
    for (int u = std::max(0, x - reach); u <= std::min(camera.width - 1, x + reach); ++u) {
      const int d2 = (u - x) * (u - x) + (v - y) * (v - y);
      if (row[u] != 0 && d2 < nearest_d2) {
        nearest = row[u];
        nearest_d2 = d2;
      }
    }
  }
  return nearest;
}

// The instance under each feature (into current.instance; for background features the
// nearest one within the margin into current.near_instance), and each instance's features.
std::map<std::uint16_t, std::vector<int>> Tracker::Impl::LabelFeatures(const cv::Mat& ids) {
  cv::Mat instance_pixels_integral;
  if (options.instance_margin_px > 0) {
    const cv::Mat instance_pixels = ids != 0;  // 255 on instances, 0 elsewhere
    cv::integral(instance_pixels, instance_pixels_integral, CV_32S);
  }
  std::map<std::uint16_t, std::vector<int>> features_of;
  for (size_t i = 0; i < current.features.size(); ++i) {
    const cv::KeyPoint& kp = current.features.keypoints[i];
    const int x = std::clamp(static_cast<int>(std::lround(kp.pt.x)), 0, camera.width - 1);
    const int y = std::clamp(static_cast<int>(std::lround(kp.pt.y)), 0, camera.height - 1);
    const std::uint16_t id = ids.at<std::uint16_t>(y, x);
    int margin_px = options.instance_margin_px;
    if (options.instance_margin_scales_with_level) {
      margin_px = static_cast<int>(std::lround(margin_px * extractor.scale_factors()[static_cast<size_t>(kp.octave)]));
    }
    current.near_instance[i] =
        id == 0 && margin_px > 0 ? InstanceNear(ids, instance_pixels_integral, x, y, margin_px) : 0;
    current.instance[i] = id;
    if (id != 0) features_of[id].push_back(static_cast<int>(i));
  }
  return features_of;
}

// Counts into judgement->num_points and num_moving_points how many of instance `id`'s
// `features` measure its motion, seen from T_wc, and how many of them moved; their
// displacements go to *evidence. Returns whether the measurement spans a full baseline.
bool Tracker::Impl::MeasureInstanceMotion(std::uint16_t id, const std::vector<int>& features,
                                          const Eigen::Isometry3d& T_wc, bool trust_young_points,
                                          InstanceJudgement* judgement, MotionEvidence* evidence) const {
  std::vector<int> unmatched;
  for (int f : features) {
    const MapPoint* point = MatchedPoint(static_cast<size_t>(f));
    // A point made less than a baseline ago has not seen the object move far enough
    // to tell (a walker covers 1-2 cm per frame, under the threshold): the instance's
    // own features a baseline back measure it instead, or older points.
    const bool too_young = !trust_young_points && point != nullptr && !point->fixed &&
                           current.stamp_s - point->first_stamp_s < options.motion_baseline_s - 1e-6;
    if (point == nullptr || point->bad || too_young) {
      unmatched.push_back(f);
      continue;
    }
    // A match to another object's point is an accidental descriptor match, not a
    // measurement of this instance: a parked car, added or relocated since the map
    // was made, matches the façade it now hides, and would be judged moving for as
    // long as it stays there. Its own features measure it instead.
    if (point->instance_id != id) {
      unmatched.push_back(f);
      continue;
    }
    const int motion = MotionAgainstPoint(static_cast<size_t>(f), point, T_wc, evidence);
    if (motion < 0) continue;
    ++judgement->num_points;
    judgement->num_moving_points += motion;
  }
  if (judgement->num_points >= options.min_points_to_judge) return true;
  return MotionAgainstHistory(id, unmatched, T_wc, judgement, evidence);
}

// The verdict on this frame's measurement alone: moving needs enough points, a share of
// them moving and, where they give 3-D displacements, a median displacement over the
// threshold; a static verdict also needs the measurement to span a full baseline.
void Tracker::Impl::DecideMotion(bool full_baseline, const MotionEvidence& evidence,
                                 InstanceJudgement* judgement) const {
  judgement->moving_share =
      judgement->num_points > 0 ? double(judgement->num_moving_points) / judgement->num_points : 0;
  const bool measured = judgement->num_points >= options.min_points_to_judge;
  const bool evidence_enough_to_move =
      judgement->moveable_class || judgement->num_points >= options.min_points_to_move_fixed_class;
  judgement->moving = measured && evidence_enough_to_move &&
                      judgement->moving_share >= options.moving_share_threshold && evidence.ConsensusMoves();
  judgement->judged = measured && (judgement->moving || full_baseline);
}

// What the instance's recent frames add: an instance seen moving in enough frames in a
// row stays moving until a frame shows enough of it still. The frames it is judged still
// since it last moved are counted (they decide trust_young_points in JudgeInstances()).
void Tracker::Impl::ApplyMotionMemory(bool full_baseline, InstanceJudgement* judgement,
                                      InstanceMotionMemory* memory) const {
  if (judgement->moving) {
    const bool in_a_row = current.stamp_s - memory->last_moving_stamp_s <= options.moving_memory_s + 1e-9;
    memory->moving_frames = in_a_row ? memory->moving_frames + 1 : 1;
    memory->last_moving_stamp_s = current.stamp_s;
  }
  const bool known_mover = memory->moving_frames >= options.moving_streak_frames &&
                           current.stamp_s - memory->last_moving_stamp_s <= options.moving_memory_s + 1e-9;
  // A small object cannot show min_points_to_clear_moving points: an eighth of its
  // features is enough there.
  const int points_to_clear =
      std::min(options.min_points_to_clear_moving, std::max(options.min_points_to_judge, judgement->num_features / 8));
  if (known_mover && !judgement->moving) {
    if (judgement->num_points < points_to_clear) {
      judgement->moving = true;
      judgement->judged = true;
    } else if (judgement->judged) {
      memory->moving_frames = 0;  // cleared: it has stopped
    }
  }
  if (judgement->moving) {
    memory->static_frames = 0;
  } else if (judgement->judged && full_baseline) {
    ++memory->static_frames;
  }
}

// A moveable object that cannot be judged yet is kept out of the pose and the map
// until it can: mapping a walking person because it was not measured is the error the
// paper exists to avoid. Judged from depth, that is one frame a baseline after it
// appears (most often while it is far and small, where its features weigh little), or
// never for one beyond the sensor's depth range, where a car crossing 50 m away would
// turn the view by a degree a frame. What it costs with nothing moving: docs/results.md.
void Tracker::Impl::KeepOutOfPoseAndMap(const InstanceJudgement& judgement, const std::vector<int>& features) {
  const bool exclude = judgement.moving || (judgement.moveable_class && !judgement.judged);
  for (int f : features) current.excluded[static_cast<size_t>(f)] = exclude;
  if (exclude) current.kept_out.insert(judgement.id);
  if (!judgement.moving) return;
  // Whatever the map holds of a moving object is now in the wrong place.
  for (const auto& owned : map->points()) {
    if (owned->instance_id == judgement.id && !owned->bad && !owned->fixed) Map::MarkBad(owned.get());
  }
  for (int f : features) {
    MapPoint* point = current.points[static_cast<size_t>(f)];
    if (point != nullptr && !point->fixed && point->instance_id == judgement.id) Map::MarkBad(point);
  }
}

// Background features on the outline of an instance kept out go with it: a corner there
// is made by the object against what lies behind it and moves with the object, yet its
// keypoint often falls just outside the mask.
void Tracker::Impl::KeepOutNearbyBackground(std::uint16_t id) {
  for (size_t i = 0; i < current.features.size(); ++i) {
    if (current.instance[i] == 0 && current.near_instance[i] == id) current.excluded[i] = true;
  }
}

}  // namespace segslam::slam
