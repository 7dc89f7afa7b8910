#include "slam/tracker.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "slam/bundle_adjustment.h"
#include "slam/pose_optimizer.h"

namespace segslam::slam {

std::string ToString(SlamMode mode) {
  switch (mode) {
    case SlamMode::kPlain: return "plain";
    case SlamMode::kMaskMoveable: return "mask-moveable";
    case SlamMode::kMutual: return "mutual";
  }
  return "?";
}

const std::vector<std::string>& SlamModeNames() {
  static const std::vector<std::string> names = {
      ToString(SlamMode::kPlain), ToString(SlamMode::kMaskMoveable), ToString(SlamMode::kMutual)};
  return names;
}

SlamMode ParseSlamMode(const std::string& name) {
  if (name == "plain") return SlamMode::kPlain;
  if (name == "mask-moveable") return SlamMode::kMaskMoveable;
  if (name == "mutual") return SlamMode::kMutual;
  throw Error("unknown SLAM mode '" + name + "' (expected plain, mask-moveable or mutual)");
}

std::string ToString(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kTracking: return "tracking";
    case TrackingStatus::kRelocalized: return "relocalized";
    case TrackingStatus::kLost: return "lost";
  }
  return "?";
}

std::string ToString(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::kUsed: return "used";
    case FeatureKind::kUnmatched: return "unmatched";
    case FeatureKind::kOutlier: return "outlier";
    case FeatureKind::kDroppedMoving: return "dropped-moving";
    case FeatureKind::kDroppedMoveable: return "dropped-moveable";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Keypoint indices bucketed by position, for searches in a window around a projection.
class FeatureGrid {
 public:
  static constexpr int kCellPx = 16;

  void Build(const std::vector<cv::KeyPoint>& keypoints, int width, int height) {
    cols_ = (width + kCellPx - 1) / kCellPx;
    rows_ = (height + kCellPx - 1) / kCellPx;
    cells_.assign(static_cast<size_t>(cols_ * rows_), {});
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const int c = std::clamp(static_cast<int>(keypoints[i].pt.x) / kCellPx, 0, cols_ - 1);
      const int r = std::clamp(static_cast<int>(keypoints[i].pt.y) / kCellPx, 0, rows_ - 1);
      cells_[static_cast<size_t>(r * cols_ + c)].push_back(static_cast<int>(i));
    }
  }

  // Indices of keypoints within `radius` of (x, y) whose level lies in [min_level, max_level].
  void Query(const std::vector<cv::KeyPoint>& keypoints, double x, double y, double radius,
             int min_level, int max_level, std::vector<int>* out) const {
    out->clear();
    const int c0 = std::max(0, static_cast<int>(std::floor((x - radius) / kCellPx)));
    const int c1 = std::min(cols_ - 1, static_cast<int>(std::floor((x + radius) / kCellPx)));
    const int r0 = std::max(0, static_cast<int>(std::floor((y - radius) / kCellPx)));
    const int r1 = std::min(rows_ - 1, static_cast<int>(std::floor((y + radius) / kCellPx)));
    const double radius2 = radius * radius;
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        for (int index : cells_[static_cast<size_t>(r * cols_ + c)]) {
          const cv::KeyPoint& kp = keypoints[static_cast<size_t>(index)];
          if (kp.octave < min_level || kp.octave > max_level) continue;
          const double dx = kp.pt.x - x;
          const double dy = kp.pt.y - y;
          if (dx * dx + dy * dy <= radius2) out->push_back(index);
        }
      }
    }
  }

 private:
  int cols_ = 0;
  int rows_ = 0;
  std::vector<std::vector<int>> cells_;
};

// ORB-SLAM's rotation consistency check: the orientation changes of correct matches
// agree, so only the matches in the three most populated histogram bins are kept.
class RotationHistogram {
 public:
  static constexpr int kBins = 30;
  void Add(int feature, float angle_from_deg, float angle_to_deg) {
    float change = angle_to_deg - angle_from_deg;
    if (change < 0) change += 360.0f;
    const int bin = std::min(kBins - 1, static_cast<int>(change * kBins / 360.0f));
    bins_[static_cast<size_t>(bin)].push_back(feature);
  }
  // Features outside the three strongest bins (a bin under 10% of the strongest is
  // dropped too, as ORB-SLAM does).
  std::vector<int> Rejected() const {
    std::array<size_t, kBins> order{};
    for (int i = 0; i < kBins; ++i) order[static_cast<size_t>(i)] = static_cast<size_t>(i);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return bins_[a].size() > bins_[b].size(); });
    const size_t strongest = bins_[order[0]].size();
    std::vector<int> rejected;
    for (int rank = 0; rank < kBins; ++rank) {
      const auto& bin = bins_[order[static_cast<size_t>(rank)]];
      const bool keep = rank < 3 && bin.size() * 10 >= strongest;
      if (!keep) rejected.insert(rejected.end(), bin.begin(), bin.end());
    }
    return rejected;
  }

 private:
  std::array<std::vector<int>, kBins> bins_;
};

// What the judgement of later frames needs to know of a past frame: its instance
// features, their descriptors and world positions.
struct InstanceSnapshot {
  int frame_index = 0;
  double stamp_s = 0;
  std::vector<std::uint16_t> instance;          // per stored feature
  std::vector<Eigen::Vector3d> point_w;         // NaN where no depth
  cv::Mat descriptors;                          // rows = stored features
};

// The 3-D displacements measured on one instance. A moving rigid object moves all its
// points the same way; mismatches on a still one scatter. So the object moves only if
// the component-wise median displacement, not just most single points, exceeds the
// threshold.
struct MotionEvidence {
  std::vector<Eigen::Vector3d> displacements;
  std::vector<double> thresholds;

  void Add(const Eigen::Vector3d& displacement, double threshold) {
    displacements.push_back(displacement);
    thresholds.push_back(threshold);
  }

  // True when there are no 3-D measurements (reprojection evidence only) or when the
  // median displacement exceeds the median threshold.
  bool ConsensusMoves() const {
    if (displacements.empty()) return true;
    auto median = [](std::vector<double> values) {
      std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
      return values[values.size() / 2];
    };
    Eigen::Vector3d median_displacement;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> component;
      for (const Eigen::Vector3d& d : displacements) component.push_back(d[axis]);
      median_displacement[axis] = median(component);
    }
    return median_displacement.norm() > median(thresholds);
  }
};

// What the judgement remembers of one instance between frames.
struct InstanceMotionMemory {
  int moving_frames = 0;  // measured moving, frames in a row (none moving_memory_s apart)
  double last_moving_stamp_s = -1e9;
  int static_frames = 0;  // judged static over a full baseline, frames in a row
};

struct WorkingFrame {
  int index = -1;
  double stamp_s = 0;
  cv::Mat color_bgr;
  cv::Mat depth_m;
  FrameFeatures features;
  FeatureGrid grid;
  std::vector<MapPoint*> points;        // match per feature (nullptr = none)
  std::vector<bool> outlier;            // match rejected by the last pose optimisation
  std::vector<MapPoint*> rejected;      // outlier matches removed before local-map search
  std::vector<std::uint16_t> instance;  // instance id per feature, 0 = background
  std::vector<bool> excluded;           // moving / unjudged moveable: not for fine pose or map
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
};

Eigen::Isometry3d PoseFromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat rotation;
  cv::Rodrigues(rvec, rotation);
  Eigen::Matrix3d R;
  cv::cv2eigen(rotation, R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  return T;
}

}  // namespace

struct Tracker::Impl {
  Impl(const PinholeCamera& cam, const TrackerOptions& opts, Map* m)
      : camera(cam), options(opts), map(m), extractor(opts.orb) {
    bf = 1.0 / options.depth_sigma_at_1m;
  }

  const PinholeCamera camera;
  const TrackerOptions options;
  Map* map;
  OrbExtractor extractor;
  double bf = 0;
  double close_depth_m = 0;

  WorkingFrame current;
  WorkingFrame last;
  bool have_last = false;
  std::optional<Eigen::Isometry3d> velocity;  // T_cw(t-1) * T_cw(t-2)^-1
  Keyframe* reference_keyframe = nullptr;
  int last_keyframe_frame = -1000;
  int last_relocalization_frame = -1000;
  bool initialized = false;
  bool pending_first_keyframe = false;
  bool last_status_lost = false;
  double lost_since_s = -1;  // stamp of the first frame of the current run of lost frames
  bool reset_map = false;    // drop the map once this frame is done
  bool localization_mode = false;
  std::deque<InstanceSnapshot> history;
  std::map<std::uint16_t, InstanceMotionMemory> motion_memory;  // per instance id
  std::vector<MapPoint*> recent_points;
  int keyframes_since_purge = 0;

  // Per-frame state.
  bool coarse_ok = false;
  bool fine_ok = false;
  bool judged = false;
  FrameResult result;
  Clock::time_point frame_start;
  // Features DropMoveableFeatures() removed from `current` (record_features only).
  std::vector<FeatureRecord> dropped_moveable_records;

  // One record per feature of the frame: those dropped before tracking, then the
  // current features by what the fine pose made of them.
  std::vector<FeatureRecord> FeatureRecords() const {
    std::map<std::uint16_t, bool> moving_of;
    for (const InstanceJudgement& judgement : result.instances) moving_of[judgement.id] = judgement.moving;
    std::vector<FeatureRecord> records = dropped_moveable_records;
    records.reserve(records.size() + current.features.size());
    for (size_t i = 0; i < current.features.size(); ++i) {
      FeatureRecord record;
      record.pixel = current.features.keypoints[i].pt;
      record.instance_id = current.instance[i];
      if (current.excluded[i]) {
        const auto judged = moving_of.find(record.instance_id);
        record.kind = judged != moving_of.end() && judged->second ? FeatureKind::kDroppedMoving
                                                                  : FeatureKind::kDroppedMoveable;
      } else if (current.points[i] != nullptr) {
        record.kind = current.outlier[i] ? FeatureKind::kOutlier : FeatureKind::kUsed;
      } else {
        record.kind = current.rejected[i] != nullptr ? FeatureKind::kOutlier : FeatureKind::kUnmatched;
      }
      records.push_back(record);
    }
    return records;
  }

  bool last_lost() const { return last_status_lost; }

  // ---------------------------------------------------------------- matching helpers

  std::vector<PoseObservation> Observations(const WorkingFrame& frame,
                                            std::vector<int>* feature_of_observation,
                                            bool skip_excluded) const {
    return ObservationsOf(frame, feature_of_observation, [&](size_t i) {
      return frame.points[i] != nullptr && !(skip_excluded && frame.excluded[i]) ? frame.points[i] : nullptr;
    });
  }

  // The observations of the features for which `match(i)` gives a map point.
  template <typename MatchOf>
  std::vector<PoseObservation> ObservationsOf(const WorkingFrame& frame, std::vector<int>* feature_of_observation,
                                              const MatchOf& match) const {
    std::vector<PoseObservation> observations;
    feature_of_observation->clear();
    const auto& inverse_sigma2 = extractor.inverse_level_sigma2();
    for (size_t i = 0; i < frame.points.size(); ++i) {
      const MapPoint* point = match(i);
      if (point == nullptr || point->bad) continue;
      const cv::KeyPoint& kp = frame.features.keypoints[i];
      PoseObservation observation;
      observation.point_w = point->position_w;
      observation.pixel = Eigen::Vector2d(kp.pt.x, kp.pt.y);
      const float depth = frame.features.depth_m[i];
      if (depth > 0) observation.right_u = kp.pt.x - bf / depth;
      observation.information = inverse_sigma2[static_cast<size_t>(kp.octave)];
      observations.push_back(observation);
      feature_of_observation->push_back(static_cast<int>(i));
    }
    return observations;
  }

  // Optimises current.T_cw from its matches; flags outliers; returns the inlier count.
  // `discard_outliers` drops outlier matches (remembering them for the judgement).
  int OptimizeCurrentPose(bool skip_excluded, bool discard_outliers) {
    std::vector<int> feature_of;
    const std::vector<PoseObservation> observations = Observations(current, &feature_of, skip_excluded);
    if (observations.size() < 3) return 0;
    PoseOptimizerOptions pose_options;
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
  MapPoint* MatchedPoint(size_t i) const {
    return current.points[i] != nullptr ? current.points[i] : current.rejected[i];
  }

  // The pose of the background alone: re-estimated from the coarse pose's matches (its
  // rejected ones too) of the features on no instance of a moveable class. Empty when
  // fewer than min_tracking_inliers of them fit.
  std::optional<Eigen::Isometry3d> BackgroundPose(const std::unordered_set<std::uint16_t>& moveable_ids) const {
    std::vector<int> feature_of;
    const std::vector<PoseObservation> observations = ObservationsOf(current, &feature_of, [&](size_t i) {
      const std::uint16_t id = current.instance[i];
      return id != 0 && moveable_ids.count(id) > 0 ? nullptr : MatchedPoint(i);
    });
    if (static_cast<int>(observations.size()) < options.min_tracking_inliers) return std::nullopt;
    PoseOptimizerOptions pose_options;
    pose_options.bf = bf;
    const PoseOptimizationResult optimized = OptimizePose(current.T_cw, observations, camera, pose_options);
    const auto inliers = std::count(optimized.inlier.begin(), optimized.inlier.end(), true);
    if (inliers < options.min_tracking_inliers) return std::nullopt;
    return optimized.T_cw;
  }

  // Best feature of the current frame for `descriptor` among `candidates` that have no
  // match yet; returns -1 if none passes the distance limit and the ratio test.
  int BestCandidate(const OrbDescriptor& descriptor, const std::vector<int>& candidates,
                    int max_distance, float ratio) const {
    int best = 256, second = 256, best_index = -1, best_level = -1, second_level = -1;
    for (int index : candidates) {
      if (current.points[static_cast<size_t>(index)] != nullptr) continue;
      const int d = DescriptorDistance(descriptor.data(),
                                       current.features.descriptors.ptr<std::uint8_t>(index));
      const int level = current.features.keypoints[static_cast<size_t>(index)].octave;
      if (d < best) {
        second = best;
        second_level = best_level;
        best = d;
        best_index = index;
        best_level = level;
      } else if (d < second) {
        second = d;
        second_level = level;
      }
    }
    if (best_index < 0 || best > max_distance) return -1;
    if (ratio < 1.0f && best_level == second_level && best > ratio * second) return -1;
    return best_index;
  }

  // Projects the matched points of the last frame into the current one (ORB-SLAM's
  // SearchByProjection for the motion model); returns the number of matches.
  int SearchLastFrame(double radius_px) {
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
      histogram.Add(best, last.features.keypoints[j].angle,
                    current.features.keypoints[static_cast<size_t>(best)].angle);
      ++matches;
    }
    for (int rejected : histogram.Rejected()) {
      current.points[static_cast<size_t>(rejected)]->last_matched_frame = -1;
      current.points[static_cast<size_t>(rejected)] = nullptr;
      --matches;
    }
    return matches;
  }

  bool IsOccluded(const Eigen::Vector2d& uv, double z) const {
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
  int SearchLocalMap(double radius_factor) {
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
      const double radius =
          radius_factor * (view_cos > 0.998 ? 2.5 : 4.0) * scales[static_cast<size_t>(level)];
      current.grid.Query(current.features.keypoints, uv.x(), uv.y(), radius, std::max(0, level - 1),
                         level, &candidates);
      const int best = BestCandidate(point->descriptor, candidates, options.max_descriptor_distance,
                                     options.projection_ratio);
      if (best < 0) continue;
      current.points[static_cast<size_t>(best)] = point;
      current.outlier[static_cast<size_t>(best)] = false;
      point->last_matched_frame = current.index;
      ++matches;
    }
    return matches;
  }

  void ClearMatches() {
    std::fill(current.points.begin(), current.points.end(), nullptr);
    std::fill(current.outlier.begin(), current.outlier.end(), false);
    std::fill(current.rejected.begin(), current.rejected.end(), nullptr);
  }

  void MarkCurrentMatched() {
    for (MapPoint* point : current.points) {
      if (point != nullptr) point->last_matched_frame = current.index;
    }
  }

  // ---------------------------------------------------------------- tracking stages

  bool TrackWithMotionModel() {
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

  bool TrackReferenceKeyframe() {
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
      MapPoint* point = reference_keyframe->points[static_cast<size_t>(reference_features[static_cast<size_t>(pair[0].trainIdx)])];
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
  bool TrackLocalMap(int min_inliers, double radius_factor) {
    SearchLocalMap(radius_factor);
    const int inliers = OptimizeCurrentPose(false, false);
    result.num_coarse_inliers = inliers;
    return inliers >= min_inliers;
  }

  // Puts the first frame at options.initial_T_wc and fixes the close-point depth; the
  // keyframe follows in UpdateMaps(). False while the frame has too few features with depth.
  bool InitializeMap() {
    if (result.num_features_with_depth < options.min_initial_map_features) return false;
    current.T_cw = options.initial_T_wc.inverse();
    initialized = true;
    pending_first_keyframe = true;
    if (options.close_depth_m > 0) {
      close_depth_m = options.close_depth_m;
    } else {
      std::vector<float> depths;
      for (float d : current.features.depth_m) if (d > 0) depths.push_back(d);
      std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
      close_depth_m = std::clamp(double(depths[depths.size() / 2]), 3.0, 25.0);
    }
    return true;
  }

  // Relocalization against every map point: nearest-neighbour descriptor search with a
  // ratio test, RANSAC PnP, pose optimisation, then a local-map search.
  bool Relocalize() {
    ClearMatches();
    std::vector<MapPoint*> candidates;
    for (const auto& owned : map->points()) {
      if (!owned->bad) candidates.push_back(owned.get());
    }
    if (candidates.size() < 20 || current.features.size() < 20) return false;
    cv::Mat map_descriptors(static_cast<int>(candidates.size()), kOrbDescriptorBytes, CV_8U);
    for (size_t k = 0; k < candidates.size(); ++k) {
      std::copy(candidates[k]->descriptor.begin(), candidates[k]->descriptor.end(),
                map_descriptors.ptr<std::uint8_t>(static_cast<int>(k)));
    }
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(current.features.descriptors, map_descriptors, knn, 2);
    std::vector<cv::Point3f> object_points;
    std::vector<cv::Point2f> image_points;
    std::vector<std::pair<int, MapPoint*>> matched;
    for (const auto& pair : knn) {
      if (pair.empty() || pair[0].distance > 64) continue;
      if (pair.size() > 1 && pair[0].distance > options.relocalization_ratio * pair[1].distance) continue;
      MapPoint* point = candidates[static_cast<size_t>(pair[0].trainIdx)];
      const Eigen::Vector3d& p = point->position_w;
      object_points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
      image_points.push_back(current.features.keypoints[static_cast<size_t>(pair[0].queryIdx)].pt);
      matched.emplace_back(pair[0].queryIdx, point);
    }
    if (matched.size() < 15) return false;
    cv::Mat rvec, tvec;
    std::vector<int> inliers;
    const bool solved = cv::solvePnPRansac(object_points, image_points, cv::Mat(camera.KCv()), cv::noArray(),
                                           rvec, tvec, false, 300, 4.0f, 0.99, inliers, cv::SOLVEPNP_EPNP);
    if (!solved || inliers.size() < 15) return false;
    current.T_cw = PoseFromRvecTvec(rvec, tvec);
    for (int k : inliers) {
      const auto& [feature, point] = matched[static_cast<size_t>(k)];
      if (point->last_matched_frame == current.index) continue;
      current.points[static_cast<size_t>(feature)] = point;
      point->last_matched_frame = current.index;
    }
    if (OptimizeCurrentPose(false, true) < 10) return false;
    return TrackLocalMap(options.min_relocalization_inliers, 5.0);
  }

  // ---------------------------------------------------------------- judgement helpers

  // A keypoint on an object's silhouette reads its depth from either side of the edge,
  // so its 3-D position jumps between frames although nothing moved: such features
  // give no motion evidence.
  bool OnDepthEdge(size_t i) const {
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
        if (!(d > 0) || std::abs(d - depth) > 0.05f * depth + 0.02f) return true;
      }
    }
    return false;
  }

  double MovingDistanceThreshold(double depth) const {
    return options.moving_distance_m + options.moving_distance_per_m * depth;
  }

  // +1 moving, 0 static, -1 no measurement, for feature i against map point `point`.
  int MotionAgainstPoint(size_t i, const MapPoint* point, const Eigen::Isometry3d& T_wc,
                         MotionEvidence* evidence) const {
    const float depth = current.features.depth_m[i];
    if (depth > 0) {
      if (OnDepthEdge(i)) return -1;
      const Eigen::Vector3d displacement = T_wc * current.features.points_cam[i] - point->position_w;
      evidence->Add(displacement, MovingDistanceThreshold(depth));
      return displacement.norm() > MovingDistanceThreshold(depth) ? 1 : 0;
    }
    const Eigen::Vector3d p_c = T_wc.inverse() * point->position_w;
    if (p_c.z() <= 0) return 1;
    const cv::KeyPoint& kp = current.features.keypoints[i];
    const double error = (camera.Project(p_c) - Eigen::Vector2d(kp.pt.x, kp.pt.y)).norm();
    const double scale = extractor.scale_factors()[static_cast<size_t>(kp.octave)];
    return error > options.moving_reprojection_px * scale ? 1 : 0;
  }

  InstanceSnapshot Snapshot() const {
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
    return snapshot;
  }

  struct HistoryMeasurement {
    // A remembered frame held at least min_points_to_judge of the instance's features
    // with depth: the instance was there to be followed.
    bool found_instance = false;
    // That frame was a full baseline back. A "static" verdict needs it: over one frame a
    // walker moves less than the depth noise.
    bool full_baseline = false;
  };

  // Frame-to-frame evidence for features of `id` that have no map point of their own:
  // match them to the same instance's features in the oldest remembered frame (a longer
  // baseline makes slow walkers measurable) and compare their world positions.
  HistoryMeasurement MotionAgainstHistory(std::uint16_t id, const std::vector<int>& features,
                                          const Eigen::Isometry3d& T_wc, InstanceJudgement* judgement,
                                          MotionEvidence* evidence) const {
    HistoryMeasurement measurement;
    for (const InstanceSnapshot& snapshot : history) {  // oldest first
      measurement.full_baseline = current.stamp_s - snapshot.stamp_s >= options.motion_baseline_s - 1e-6;
      std::vector<int> rows;
      for (size_t k = 0; k < snapshot.instance.size(); ++k) {
        if (snapshot.instance[k] == id && std::isfinite(snapshot.point_w[k].x())) rows.push_back(static_cast<int>(k));
      }
      if (static_cast<int>(rows.size()) < options.min_points_to_judge) continue;
      measurement.found_instance = true;
      cv::Mat past(static_cast<int>(rows.size()), kOrbDescriptorBytes, CV_8U);
      for (size_t k = 0; k < rows.size(); ++k) snapshot.descriptors.row(rows[k]).copyTo(past.row(static_cast<int>(k)));
      std::vector<int> query_features;
      for (int i : features) {
        if (current.features.depth_m[static_cast<size_t>(i)] > 0 && !OnDepthEdge(static_cast<size_t>(i))) {
          query_features.push_back(i);
        }
      }
      if (query_features.empty()) {
        measurement.full_baseline = false;
        return measurement;
      }
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
        const Eigen::Vector3d& past_w = snapshot.point_w[static_cast<size_t>(rows[static_cast<size_t>(pair[0].trainIdx)])];
        ++judgement->num_points;
        const double threshold = MovingDistanceThreshold(current.features.depth_m[i]);
        evidence->Add(x_w - past_w, threshold);
        if ((x_w - past_w).norm() > threshold) ++judgement->num_moving_points;
      }
      return measurement;
    }
    measurement.full_baseline = false;
    return measurement;
  }

  // ---------------------------------------------------------------- judgement
  // JudgeInstances() in steps: which features lie on which instance; what this frame
  // measures of each instance's motion; the verdict on that measurement; what the
  // instance's recent frames add to it; and what a verdict keeps out of the pose and map.

  // The instance id under each feature (into current.instance), and each instance's
  // features.
  std::map<std::uint16_t, std::vector<int>> LabelFeatures(const cv::Mat& ids) {
    std::map<std::uint16_t, std::vector<int>> features_of;
    for (size_t i = 0; i < current.features.size(); ++i) {
      const cv::KeyPoint& kp = current.features.keypoints[i];
      const int x = std::clamp(static_cast<int>(std::lround(kp.pt.x)), 0, camera.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(kp.pt.y)), 0, camera.height - 1);
      const std::uint16_t id = ids.at<std::uint16_t>(y, x);
      current.instance[i] = id;
      if (id != 0) features_of[id].push_back(static_cast<int>(i));
    }
    return features_of;
  }

  // Counts into judgement->num_points and num_moving_points how many of instance `id`'s
  // `features` measure its motion, seen from T_wc, and how many of them moved; their
  // displacements go to *evidence. Returns whether the measurement spans a full baseline.
  bool MeasureInstanceMotion(std::uint16_t id, const std::vector<int>& features,
                             const Eigen::Isometry3d& T_wc, bool trust_young_points,
                             InstanceJudgement* judgement, MotionEvidence* evidence) const {
    std::vector<int> unmatched;
    std::vector<int> on_other_objects;  // matched to a point of another instance or background
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
      // long as it stays there. Such matches are kept as a last resort (below).
      if (point->instance_id != id) {
        unmatched.push_back(f);
        on_other_objects.push_back(f);
        continue;
      }
      const int motion = MotionAgainstPoint(static_cast<size_t>(f), point, T_wc, evidence);
      if (motion < 0) continue;
      ++judgement->num_points;
      judgement->num_moving_points += motion;
    }
    if (judgement->num_points >= options.min_points_to_judge) return true;
    const HistoryMeasurement history = MotionAgainstHistory(id, unmatched, T_wc, judgement, evidence);
    bool full_baseline = history.full_baseline;
    // The last resort: the instance was there a moment ago with enough features, yet
    // none of them can be found again and none of its own map points measures it. A
    // walker does that (limbs and folds change their look within a baseline); a rigid
    // car seen again is measured by its history. Then the matches to other objects
    // decide. Without it, walking_xyz with ground-truth masks finds its walkers moving
    // in 23 % of the frames they are seen in instead of 45 % (coverage, segslam eval).
    if (judgement->num_points == 0 && history.found_instance) {
      for (int f : on_other_objects) {
        const size_t i = static_cast<size_t>(f);
        const int motion = MotionAgainstPoint(i, MatchedPoint(i), T_wc, evidence);
        if (motion < 0) continue;
        ++judgement->num_points;
        judgement->num_moving_points += motion;
        full_baseline = true;  // the points are at least a baseline old
      }
    }
    return full_baseline;
  }

  // The verdict on this frame's measurement alone: moving needs enough points, a share of
  // them moving and, where they give 3-D displacements, a median displacement over the
  // threshold; a static verdict also needs the measurement to span a full baseline.
  void DecideMotion(bool full_baseline, const MotionEvidence& evidence, InstanceJudgement* judgement) const {
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
  void ApplyMotionMemory(bool full_baseline, InstanceJudgement* judgement, InstanceMotionMemory* memory) const {
    if (judgement->moving) {
      const bool in_a_row = current.stamp_s - memory->last_moving_stamp_s <= options.moving_memory_s + 1e-9;
      memory->moving_frames = in_a_row ? memory->moving_frames + 1 : 1;
      memory->last_moving_stamp_s = current.stamp_s;
    }
    const bool known_mover = memory->moving_frames >= options.moving_streak_frames &&
                             current.stamp_s - memory->last_moving_stamp_s <= options.moving_memory_s + 1e-9;
    // A small object cannot show min_points_to_clear_moving points: an eighth of its
    // features is enough there.
    const int points_to_clear = std::min(options.min_points_to_clear_moving,
                                         std::max(options.min_points_to_judge, judgement->num_features / 8));
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
  // paper exists to avoid.
  void KeepOutOfPoseAndMap(const InstanceJudgement& judgement, const std::vector<int>& features) {
    const bool exclude = judgement.moving || (judgement.moveable_class && !judgement.judged);
    for (int f : features) current.excluded[static_cast<size_t>(f)] = exclude;
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

  // ---------------------------------------------------------------- mapping

  bool NeedNewKeyframe() const {
    if (reference_keyframe == nullptr) return true;
    int inliers = 0, tracked_close = 0, untracked_close = 0;
    for (size_t i = 0; i < current.points.size(); ++i) {
      const bool tracked = current.points[i] != nullptr && !current.outlier[i];
      if (tracked) ++inliers;
      const float depth = current.features.depth_m[i];
      if (depth > 0 && depth < close_depth_m && !current.excluded[i]) {
        if (tracked) ++tracked_close; else ++untracked_close;
      }
    }
    // ORB-SLAM counts an RGB-D observation twice (it is a stereo pair) and asks for 2
    // observations while the map has at most two keyframes, 3 later: here that is one
    // keyframe, then two.
    const int min_observations = map->keyframes().size() <= 2 ? 1 : 2;
    int reference_points = 0;
    for (const MapPoint* point : reference_keyframe->points) {
      if (point != nullptr && !point->bad && point->NumObservations() >= min_observations) ++reference_points;
    }
    const bool need_close = tracked_close < 100 && untracked_close > 70;
    const bool few_tracked = inliers < options.keyframe_tracked_ratio * reference_points;
    const bool long_ago = current.index - last_keyframe_frame >= options.max_frames_between_keyframes;
    return ((few_tracked || need_close) && inliers > 15) || (long_ago && inliers > 15 && few_tracked);
  }

  void CreateKeyframe() {
    auto owned = std::make_unique<Keyframe>();
    owned->id = map->NextKeyframeId();
    owned->frame_index = current.index;
    owned->stamp_s = current.stamp_s;
    owned->T_cw = current.T_cw;
    owned->features = current.features;
    owned->points.assign(current.features.size(), nullptr);
    Keyframe* keyframe = map->AddKeyframe(std::move(owned));

    for (size_t i = 0; i < current.points.size(); ++i) {
      MapPoint* point = current.points[i];
      if (point == nullptr || point->bad || current.outlier[i] || current.excluded[i]) continue;
      Map::AddObservation(point, keyframe, static_cast<int>(i));
      if (!point->fixed) Map::UpdatePointStatistics(point, extractor);
    }
    const Eigen::Isometry3d T_wc = current.T_cw.inverse();
    for (size_t i = 0; i < current.features.size(); ++i) {
      if (keyframe->points[i] != nullptr || current.excluded[i]) continue;
      if (current.points[i] != nullptr && !current.outlier[i]) continue;
      const float depth = current.features.depth_m[i];
      if (!(depth > 0) || depth > options.max_point_depth_m) continue;
      auto point = std::make_unique<MapPoint>();
      point->id = map->NextPointId();
      point->position_w = T_wc * current.features.points_cam[i];
      point->instance_id = current.instance[i];
      point->first_keyframe_id = keyframe->id;
      point->first_stamp_s = current.stamp_s;
      point->last_matched_frame = current.index;
      point->last_visible_frame = current.index;
      const cv::KeyPoint& kp = current.features.keypoints[i];
      const cv::Vec3b bgr = current.color_bgr.at<cv::Vec3b>(static_cast<int>(std::lround(kp.pt.y)),
                                                             static_cast<int>(std::lround(kp.pt.x)));
      point->color_rgb = {bgr[2], bgr[1], bgr[0]};
      MapPoint* added = map->AddPoint(std::move(point));
      Map::AddObservation(added, keyframe, static_cast<int>(i));
      Map::UpdatePointStatistics(added, extractor);
      current.points[i] = added;
      current.outlier[i] = false;
      recent_points.push_back(added);
    }
    reference_keyframe = keyframe;
    last_keyframe_frame = current.index;
    result.keyframe = true;

    if (!localization_mode) {
      CullRecentPoints(keyframe);
      if (options.local_bundle_adjustment) {
        const Clock::time_point start = Clock::now();
        LocalBundleAdjustment();
        result.timings.bundle_adjustment_ms = MsSince(start);
      }
    }
    if (++keyframes_since_purge >= 5) PurgeBadPoints();
  }

  // ORB-SLAM's culling of recently created points: those the tracker rarely finds where
  // they should be visible, or that no later keyframe confirmed, are spurious.
  void CullRecentPoints(const Keyframe* keyframe) {
    std::vector<MapPoint*> kept;
    for (MapPoint* point : recent_points) {
      if (point->bad) continue;
      const std::uint64_t age = keyframe->id - point->first_keyframe_id;
      if (point->FoundRatio() < 0.25) {
        Map::MarkBad(point);
      } else if (age >= 2 && point->NumObservations() < 2) {
        Map::MarkBad(point);
      } else if (age < 3) {
        kept.push_back(point);
      }
    }
    recent_points = std::move(kept);
  }

  // The newest good keyframes, newest first: local bundle adjustment's free poses.
  std::vector<Keyframe*> LocalWindow() const {
    std::vector<Keyframe*> window;
    const auto& keyframes = map->keyframes();
    for (auto it = keyframes.rbegin(); it != keyframes.rend() && static_cast<int>(window.size()) < options.local_ba_keyframes; ++it) {
      if (!(*it)->bad) window.push_back(it->get());
    }
    return window;
  }

  // Local bundle adjustment's problem over a window: its keyframes and the good points
  // they see are free; the other keyframes that see those points hold the window in
  // place, and so does the map's first keyframe.
  struct LocalBaProblem {
    std::map<Keyframe*, int, KeyframeIdLess> keyframe_index;  // into `keyframes`
    std::vector<BaKeyframe> keyframes;
    std::vector<MapPoint*> points;  // ascending id
    std::vector<Eigen::Vector3d> positions;  // of `points`
    std::vector<BaObservation> observations;
    std::vector<std::pair<MapPoint*, Keyframe*>> observation_owner;  // of `observations`
  };

  LocalBaProblem MakeLocalBaProblem(const std::vector<Keyframe*>& window) const {
    LocalBaProblem problem;
    for (Keyframe* keyframe : window) problem.keyframe_index[keyframe] = -1;
    std::set<std::uint64_t> seen;
    for (Keyframe* keyframe : window) {
      for (MapPoint* point : keyframe->points) {
        if (point == nullptr || point->bad || point->fixed || !seen.insert(point->id).second) continue;
        problem.points.push_back(point);
      }
    }
    std::sort(problem.points.begin(), problem.points.end(),
              [](const MapPoint* a, const MapPoint* b) { return a->id < b->id; });
    for (MapPoint* point : problem.points) {
      for (const auto& observation : point->observations) problem.keyframe_index.emplace(observation.first, -1);
    }
    const std::uint64_t first_keyframe_id = map->keyframes().front()->id;
    bool any_fixed = false;
    for (auto& [keyframe, index] : problem.keyframe_index) {
      const bool in_window = std::find(window.begin(), window.end(), keyframe) != window.end();
      const bool fixed = !in_window || keyframe->id == first_keyframe_id;
      any_fixed = any_fixed || fixed;
      index = static_cast<int>(problem.keyframes.size());
      problem.keyframes.push_back({keyframe->T_cw, fixed});
    }
    if (!any_fixed) problem.keyframes.front().fixed = true;  // the oldest fixes the gauge

    const auto& inverse_sigma2 = extractor.inverse_level_sigma2();
    for (size_t p = 0; p < problem.points.size(); ++p) {
      MapPoint* point = problem.points[p];
      problem.positions.push_back(point->position_w);
      for (const auto& [keyframe, feature] : point->observations) {
        const cv::KeyPoint& kp = keyframe->features.keypoints[static_cast<size_t>(feature)];
        BaObservation observation;
        observation.keyframe = problem.keyframe_index.at(keyframe);
        observation.point = static_cast<int>(p);
        observation.pixel = Eigen::Vector2d(kp.pt.x, kp.pt.y);
        const float depth = keyframe->features.depth_m[static_cast<size_t>(feature)];
        if (depth > 0) observation.right_u = kp.pt.x - bf / depth;
        observation.information = inverse_sigma2[static_cast<size_t>(kp.octave)];
        problem.observations.push_back(observation);
        problem.observation_owner.emplace_back(point, keyframe);
      }
    }
    return problem;
  }

  // Moves the free keyframes and the points to the adjusted values and unlinks the
  // observations the adjustment found to be outliers (a point left unobserved is bad).
  void ApplyLocalBa(const LocalBaProblem& problem, const BundleAdjustmentResult& adjusted) {
    for (const auto& [keyframe, index] : problem.keyframe_index) {
      if (!problem.keyframes[static_cast<size_t>(index)].fixed) keyframe->T_cw = adjusted.T_cw[static_cast<size_t>(index)];
    }
    for (size_t p = 0; p < problem.points.size(); ++p) problem.points[p]->position_w = adjusted.points_w[p];
    for (size_t k = 0; k < problem.observations.size(); ++k) {
      if (adjusted.observation_inlier[k]) continue;
      auto [point, keyframe] = problem.observation_owner[k];
      const auto found = point->observations.find(keyframe);
      if (found == point->observations.end()) continue;
      if (keyframe->points[static_cast<size_t>(found->second)] == point) {
        keyframe->points[static_cast<size_t>(found->second)] = nullptr;
      }
      point->observations.erase(found);
      if (point->observations.empty()) Map::MarkBad(point);
    }
    for (MapPoint* point : problem.points) {
      if (!point->bad) Map::UpdatePointStatistics(point, extractor);
    }
  }

  void LocalBundleAdjustment() {
    const std::vector<Keyframe*> window = LocalWindow();
    if (window.size() < 2) return;
    const LocalBaProblem problem = MakeLocalBaProblem(window);
    if (problem.observations.empty()) return;
    BundleAdjustmentOptions ba_options;
    ba_options.bf = bf;
    ApplyLocalBa(problem, RunBundleAdjustment(camera, problem.keyframes, problem.positions, problem.observations,
                                              ba_options));
    // The current frame's pose moves with its keyframe.
    current.T_cw = reference_keyframe->T_cw;
  }

  void PurgeBadPoints() {
    for (WorkingFrame* frame : {&current, &last}) {
      for (MapPoint*& point : frame->points) {
        if (point != nullptr && point->bad) point = nullptr;
      }
      for (MapPoint*& point : frame->rejected) {
        if (point != nullptr && point->bad) point = nullptr;
      }
    }
    recent_points.erase(std::remove_if(recent_points.begin(), recent_points.end(),
                                       [](const MapPoint* p) { return p->bad; }),
                        recent_points.end());
    if (reference_keyframe != nullptr) {
      for (MapPoint*& point : reference_keyframe->points) {
        if (point != nullptr && point->bad) point = nullptr;
      }
    }
    map->PurgeBadPoints();
    keyframes_since_purge = 0;
  }
};

Tracker::Tracker(const PinholeCamera& camera, const TrackerOptions& options)
    : camera_(camera), options_(options), map_(std::make_unique<Map>()) {
  std::string error;
  if (!camera.IsValid(&error)) throw Error("tracker: invalid camera: " + error);
  impl_ = std::make_unique<Impl>(camera_, options_, map_.get());
}

Tracker::~Tracker() = default;

void Tracker::LoadLongTermMap(const LongTermMapData& map, const std::string& origin) {
  CheckMapCamera(map, camera_, origin);
  if (!map_->points().empty()) throw Error(origin + ": a long-term map must be loaded before the first frame");
  map_->LoadFixedPoints(map);
  localization_mode_ = true;
  impl_->localization_mode = true;
  loaded_map_ = map;
}

void Tracker::BeginFrame(const RgbdFrame& frame) {
  Impl& s = *impl_;
  s.frame_start = Clock::now();
  const cv::Size size(camera_.width, camera_.height);
  if (frame.color_bgr.type() != CV_8UC3 || frame.color_bgr.size() != size) {
    throw Error("frame " + std::to_string(frame.index) + ": colour image must be CV_8UC3 of the camera's size");
  }
  if (!frame.depth_m.empty() && (frame.depth_m.type() != CV_32F || frame.depth_m.size() != size)) {
    throw Error("frame " + std::to_string(frame.index) + ": depth must be CV_32F metres of the camera's size");
  }
  s.current = WorkingFrame();
  s.current.index = frame.index;
  s.current.stamp_s = frame.stamp_s;
  s.current.color_bgr = frame.color_bgr;
  s.current.depth_m = frame.depth_m;
  cv::Mat gray;
  cv::cvtColor(frame.color_bgr, gray, cv::COLOR_BGR2GRAY);
  s.current.features = s.extractor.Extract(gray, frame.depth_m, camera_);
  const size_t n = s.current.features.size();
  s.current.grid.Build(s.current.features.keypoints, camera_.width, camera_.height);
  s.current.points.assign(n, nullptr);
  s.current.outlier.assign(n, false);
  s.current.rejected.assign(n, nullptr);
  s.current.instance.assign(n, 0);
  s.current.excluded.assign(n, false);
  s.coarse_ok = s.fine_ok = s.judged = false;
  s.dropped_moveable_records.clear();
  s.result = FrameResult();
  s.result.frame_index = frame.index;
  s.result.stamp_s = frame.stamp_s;
  s.result.num_features = static_cast<int>(n);
  s.result.num_features_with_depth = static_cast<int>(
      std::count_if(s.current.features.depth_m.begin(), s.current.features.depth_m.end(), [](float d) { return d > 0; }));
  s.result.timings.features_ms = MsSince(s.frame_start);
}

void Tracker::DropMoveableFeatures(const FrameInstances& instances) {
  Impl& s = *impl_;
  if (instances.ids.type() != CV_16U || instances.ids.size() != cv::Size(camera_.width, camera_.height)) {
    throw Error("frame " + std::to_string(s.current.index) + ": instance ids must be CV_16U of the camera's size");
  }
  FrameFeatures kept;
  std::vector<int> rows;
  const FrameFeatures& all = s.current.features;
  for (size_t i = 0; i < all.size(); ++i) {
    const cv::Point pixel(static_cast<int>(std::lround(all.keypoints[i].pt.x)),
                          static_cast<int>(std::lround(all.keypoints[i].pt.y)));
    const std::uint16_t id = instances.ids.at<std::uint16_t>(std::clamp(pixel.y, 0, camera_.height - 1),
                                                            std::clamp(pixel.x, 0, camera_.width - 1));
    if (id != 0 && instances.moveable_ids.count(id) > 0) {
      if (options_.record_features) {
        s.dropped_moveable_records.push_back({all.keypoints[i].pt, id, FeatureKind::kDroppedMoveable});
      }
      continue;
    }
    rows.push_back(static_cast<int>(i));
    kept.keypoints.push_back(all.keypoints[i]);
    kept.depth_m.push_back(all.depth_m[i]);
    kept.points_cam.push_back(all.points_cam[i]);
  }
  kept.descriptors.create(static_cast<int>(rows.size()), kOrbDescriptorBytes, CV_8U);
  for (size_t k = 0; k < rows.size(); ++k) all.descriptors.row(rows[k]).copyTo(kept.descriptors.row(static_cast<int>(k)));
  s.current.features = std::move(kept);
  const size_t n = s.current.features.size();
  s.current.grid.Build(s.current.features.keypoints, camera_.width, camera_.height);
  s.current.points.assign(n, nullptr);
  s.current.outlier.assign(n, false);
  s.current.rejected.assign(n, nullptr);
  s.current.instance.assign(n, 0);
  s.current.excluded.assign(n, false);
}

std::optional<Eigen::Isometry3d> Tracker::EstimateCoarsePose() {
  Impl& s = *impl_;
  const Clock::time_point start = Clock::now();
  bool tracked = false;
  bool relocalized = false;
  if (!s.initialized && !s.localization_mode) {
    // The first frame defines the map; it needs enough features with depth (checked
    // again in UpdateMaps() on those that may enter the map).
    tracked = s.InitializeMap();
  } else if (s.have_last && !s.last_lost()) {
    tracked = s.TrackWithMotionModel() || s.TrackReferenceKeyframe();
    if (tracked) {
      s.MarkCurrentMatched();
      const bool recently_relocalized = s.current.index - s.last_relocalization_frame < 30;
      tracked = s.TrackLocalMap(recently_relocalized ? options_.min_relocalization_inliers : options_.min_tracking_inliers,
                                options_.local_map_radius_px);
    }
  }
  if (!tracked && !s.pending_first_keyframe) {
    relocalized = s.Relocalize();
    tracked = relocalized;
    if (relocalized) {
      s.initialized = true;
      s.last_relocalization_frame = s.current.index;
      if (s.close_depth_m <= 0) s.close_depth_m = options_.close_depth_m > 0 ? options_.close_depth_m : 10.0;
    }
  }
  if (tracked) {
    s.lost_since_s = -1;
  } else if (s.initialized && !s.localization_mode) {
    if (s.lost_since_s < 0) s.lost_since_s = s.current.stamp_s;
    const int keyframes = static_cast<int>(map_->keyframes().size());
    s.reset_map = keyframes <= options_.reset_map_keyframes &&
                  s.current.stamp_s - s.lost_since_s >= options_.reset_map_after_lost_s - 1e-9;
  }
  s.coarse_ok = tracked;
  s.result.status = !tracked ? TrackingStatus::kLost
                   : relocalized ? TrackingStatus::kRelocalized : TrackingStatus::kTracking;
  s.result.timings.coarse_ms = MsSince(start);
  if (!tracked) return std::nullopt;
  s.result.T_wc_coarse = s.current.T_cw.inverse();
  return s.result.T_wc_coarse;
}

std::vector<InstanceJudgement> Tracker::JudgeInstances(const FrameInstances& instances) {
  Impl& s = *impl_;
  const Clock::time_point start = Clock::now();
  if (instances.ids.type() != CV_16U || instances.ids.size() != cv::Size(camera_.width, camera_.height)) {
    throw Error("frame " + std::to_string(s.current.index) + ": instance ids must be CV_16U of the camera's size");
  }
  const std::map<std::uint16_t, std::vector<int>> features_of = s.LabelFeatures(instances.ids);
  // Motion is measured against the background's pose where it can be had. The coarse
  // pose comes from every feature, and instances that fill the view pull it along: then
  // their own points agree with it whether they move or not (three walkers in front of
  // the camera were cleared that way, and entered the fine pose).
  const std::optional<Eigen::Isometry3d> background_T_cw =
      s.coarse_ok ? s.BackgroundPose(instances.moveable_ids) : std::nullopt;
  const Eigen::Isometry3d T_wc = background_T_cw.value_or(s.current.T_cw).inverse();
  std::vector<InstanceJudgement> judgements;
  for (const auto& [id, features] : features_of) {
    InstanceJudgement judgement;
    judgement.id = id;
    judgement.moveable_class = instances.moveable_ids.count(id) > 0;
    judgement.num_features = static_cast<int>(features.size());
    InstanceMotionMemory& memory = s.motion_memory[id];
    if (s.coarse_ok) {
      // Once an instance has been seen still over a full baseline, its young points serve
      // again (a parked car stays parked); until then, or once it moves, they do not.
      const bool trust_young_points = memory.static_frames >= options_.static_frames_to_trust_young_points;
      MotionEvidence evidence;
      const bool full_baseline =
          s.MeasureInstanceMotion(id, features, T_wc, trust_young_points, &judgement, &evidence);
      s.DecideMotion(full_baseline, evidence, &judgement);
      s.ApplyMotionMemory(full_baseline, &judgement, &memory);
    }
    s.KeepOutOfPoseAndMap(judgement, features);
    judgements.push_back(judgement);
  }
  s.judged = true;
  s.result.instances = judgements;
  s.result.timings.judge_ms = MsSince(start);
  return judgements;
}

std::optional<Eigen::Isometry3d> Tracker::EstimateFinePose() {
  Impl& s = *impl_;
  const Clock::time_point start = Clock::now();
  s.fine_ok = s.coarse_ok;
  if (s.coarse_ok && s.judged && !s.pending_first_keyframe) {
    bool any_excluded_match = false;
    for (size_t i = 0; i < s.current.points.size(); ++i) {
      if (s.current.points[i] != nullptr && (s.current.excluded[i] || s.current.points[i]->bad)) {
        any_excluded_match = true;
        break;
      }
    }
    if (any_excluded_match) {
      for (size_t i = 0; i < s.current.points.size(); ++i) {
        if (s.current.points[i] != nullptr && (s.current.excluded[i] || s.current.points[i]->bad)) {
          s.current.points[i] = nullptr;
          s.current.outlier[i] = false;
        }
      }
      const Eigen::Isometry3d coarse = s.current.T_cw;
      const int inliers = s.OptimizeCurrentPose(true, false);
      if (inliers < 10) {
        s.current.T_cw = coarse;
        s.fine_ok = false;
      }
    }
  }
  int inliers = 0;
  for (size_t i = 0; i < s.current.points.size(); ++i) {
    if (s.current.points[i] != nullptr && !s.current.outlier[i]) ++inliers;
  }
  s.result.num_fine_inliers = inliers;
  if (s.coarse_ok && !s.fine_ok) s.result.status = TrackingStatus::kLost;
  if (options_.record_features) s.result.feature_records = s.FeatureRecords();
  s.result.timings.fine_ms = MsSince(start);
  if (!s.fine_ok) return std::nullopt;
  s.result.T_wc = s.current.T_cw.inverse();
  return s.result.T_wc;
}

FrameResult Tracker::UpdateMaps() {
  Impl& s = *impl_;
  const Clock::time_point start = Clock::now();
  if (s.fine_ok && s.pending_first_keyframe) {
    int mappable = 0;
    for (size_t i = 0; i < s.current.features.size(); ++i) {
      mappable += s.current.features.depth_m[i] > 0 && !s.current.excluded[i];
    }
    if (mappable < options_.min_initial_map_features) {
      // Mostly unjudged moveable objects: no map on this frame, wait for a better view.
      s.pending_first_keyframe = false;
      s.initialized = false;
      s.fine_ok = false;
      s.result.status = TrackingStatus::kLost;
    }
  }
  if (s.fine_ok) {
    for (size_t i = 0; i < s.current.points.size(); ++i) {
      MapPoint* point = s.current.points[i];
      if (point != nullptr && !s.current.outlier[i]) ++point->found_count;
    }
    if (s.pending_first_keyframe) {
      s.CreateKeyframe();
      s.pending_first_keyframe = false;
    } else if (s.NeedNewKeyframe()) {
      s.CreateKeyframe();
    }
    s.result.T_wc = s.current.T_cw.inverse();
    s.velocity = s.have_last && !s.last_lost() ? std::optional<Eigen::Isometry3d>(s.current.T_cw * s.last.T_cw.inverse())
                                                : std::nullopt;
    s.history.push_back(s.Snapshot());
    // Keep the newest snapshot at least one baseline old, and everything younger.
    while (s.history.size() > 1 && s.current.stamp_s - s.history[1].stamp_s >= options_.motion_baseline_s - 1e-6) {
      s.history.pop_front();
    }
  } else {
    s.velocity.reset();
    s.history.clear();
  }
  s.last = std::move(s.current);
  s.last_status_lost = !s.fine_ok;
  s.have_last = true;
  s.current = WorkingFrame();
  s.result.timings.map_update_ms = MsSince(start) - s.result.timings.bundle_adjustment_ms;
  if (!s.reset_map) return s.result;
  FrameResult result = std::move(s.result);
  result.map_reset = true;
  // A fresh map and tracker state; what is known of the instances' motion is not tied
  // to the map and stays.
  std::map<std::uint16_t, InstanceMotionMemory> motion_memory = std::move(s.motion_memory);
  map_ = std::make_unique<Map>();
  impl_ = std::make_unique<Impl>(camera_, options_, map_.get());
  impl_->motion_memory = std::move(motion_memory);
  return result;
}

FrameResult Tracker::Track(const RgbdFrame& frame, const FrameInstances* instances, SlamMode mode) {
  if (mode != SlamMode::kPlain && instances == nullptr) {
    throw Error("frame " + std::to_string(frame.index) + ": mode " + ToString(mode) + " needs instance masks");
  }
  BeginFrame(frame);
  if (mode == SlamMode::kMaskMoveable) DropMoveableFeatures(*instances);
  EstimateCoarsePose();
  if (mode == SlamMode::kMutual) JudgeInstances(*instances);
  EstimateFinePose();
  return UpdateMaps();
}

LongTermMapData Tracker::ExportLongTermMap(bool include_instances) const {
  if (loaded_map_.has_value()) return *loaded_map_;
  return map_->ToLongTermMap(camera_, include_instances, options_.long_term_min_observations);
}

}  // namespace segslam::slam
