#include "slam/tracker.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "slam/tracker_internal.h"
#include "slam/tracker_options.h"

namespace segslam::slam {

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


// One record per feature of the frame: those dropped before tracking, then the
// current features by what the fine pose made of them.
std::vector<FeatureRecord> Tracker::Impl::FeatureRecords() const {
  std::map<std::uint16_t, bool> moving_of;
  for (const InstanceJudgement& judgement : result.instances) moving_of[judgement.id] = judgement.moving;
  std::vector<FeatureRecord> records = dropped_moveable_records;
  records.reserve(records.size() + current.features.size());
  for (size_t i = 0; i < current.features.size(); ++i) {
    FeatureRecord record;
    record.pixel = current.features.keypoints[i].pt;
    record.level = current.features.keypoints[i].octave;
    record.instance_id = current.instance[i];
    if (current.excluded[i] && record.instance_id == 0) record.instance_id = current.near_instance[i];
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

namespace {

// Every option within its range (slam/tracker_options.h), refused up front by name
// rather than turning into a crash or nonsense deep inside a run.
void CheckTrackerOptions(const TrackerOptions& options) {
  if (const std::string problem = TrackerOptionRegistry().Check(options); !problem.empty()) throw Error(problem);
}

}  // namespace

Tracker::Tracker(const PinholeCamera& camera, const TrackerOptions& options)
    : camera_(camera), options_(options), map_(std::make_unique<Map>()) {
  std::string error;
  if (!camera.IsValid(&error)) throw Error("tracker: invalid camera: " + error);
  CheckTrackerOptions(options_);
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
  if (std::isnan(s.first_frame_stamp_s)) s.first_frame_stamp_s = frame.stamp_s;
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
  s.current.near_instance.assign(n, 0);
  s.current.excluded.assign(n, false);
  s.current.on_moveable.assign(n, false);
  s.coarse_ok = s.fine_ok = s.judged = s.pose_jumped = false;
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
    // The mask itself, no margin: a parked car's outline does not move, and around each
    // of a row of them the margin would leave the baseline little to track.
    const cv::Point pixel(static_cast<int>(std::lround(all.keypoints[i].pt.x)),
                          static_cast<int>(std::lround(all.keypoints[i].pt.y)));
    const std::uint16_t id = instances.ids.at<std::uint16_t>(std::clamp(pixel.y, 0, camera_.height - 1),
                                                            std::clamp(pixel.x, 0, camera_.width - 1));
    if (id != 0 && instances.moveable_ids.count(id) > 0) {
      if (options_.record_features) {
        s.dropped_moveable_records.push_back(
            {all.keypoints[i].pt, id, FeatureKind::kDroppedMoveable, all.keypoints[i].octave});
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
  s.current.near_instance.assign(n, 0);
  s.current.excluded.assign(n, false);
  s.current.on_moveable.assign(n, false);
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
    if (s.localization_mode && options_.relocalize_off_map && s.off_long_term_map &&
        s.current.stamp_s - s.last_off_map_relocalization_s >= options_.off_map_relocalization_interval_s - 1e-9) {
      relocalized = s.pose_jumped = tracked = s.RelocalizeOffMap();
    }
    if (!relocalized) {
      const bool after_first_frame = !s.velocity.has_value() && map_->keyframes().size() == 1;
      tracked = after_first_frame ? s.TrackWithoutVelocity() : s.TrackWithMotionModel() || s.TrackReferenceKeyframe();
      if (tracked) {
        s.MarkCurrentMatched();
        const bool recently_relocalized = s.current.index - s.last_relocalization_frame < 30;
        tracked = s.TrackLocalMap(
            recently_relocalized ? options_.min_relocalization_inliers : options_.min_tracking_inliers,
            options_.local_map_radius_px);
      }
      if (tracked && !s.off_long_term_map) relocalized = s.pose_jumped = s.RecheckRelocalization();
    }
    if (relocalized) {
      s.last_relocalization_frame = s.current.index;
      s.BeginProbation();
    }
  }
  if (!tracked && !s.pending_first_keyframe) {
    relocalized = s.Relocalize(false);
    tracked = relocalized;
    if (relocalized) {
      s.initialized = true;
      s.last_relocalization_frame = s.current.index;
      s.BeginProbation();
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

bool Tracker::CoarsePoseRelocalized() const { return impl_->result.status == TrackingStatus::kRelocalized; }

void Tracker::PresetStartVerdicts(std::unordered_map<std::uint16_t, bool> moving_by_id, double until_stamp_s) {
  impl_->preset_moving = std::move(moving_by_id);
  impl_->preset_until_s = until_stamp_s;
}

std::vector<InstanceJudgement> Tracker::JudgeInstances(const FrameInstances& instances,
                                                       const std::unordered_set<std::uint16_t>* given_moving_ids) {
  Impl& s = *impl_;
  const Clock::time_point start = Clock::now();
  if (instances.ids.type() != CV_16U || instances.ids.size() != cv::Size(camera_.width, camera_.height)) {
    throw Error("frame " + std::to_string(s.current.index) + ": instance ids must be CV_16U of the camera's size");
  }
  const std::map<std::uint16_t, std::vector<int>> features_of = s.LabelFeatures(instances.ids);
  s.ForgetSnapshotsBefore(s.current.stamp_s);
  // Motion is measured against the background's pose where it can be had. The coarse
  // pose comes from every feature, and instances that fill the view pull it along: then
  // their own points agree with it whether they move or not (three walkers in front of
  // the camera were cleared that way, and entered the fine pose).
  const std::optional<Eigen::Isometry3d> background_T_cw =
      s.coarse_ok ? s.BackgroundPose(instances.moveable_ids) : std::nullopt;
  const Eigen::Isometry3d T_wc = background_T_cw.value_or(s.current.T_cw).inverse();
  // The judgement from depth measures against the remembered frame a baseline back (or
  // the oldest there is, which can show motion but not stillness).
  const bool by_depth = s.JudgesByDepth();
  if (by_depth && s.coarse_ok) s.SampleInstanceDepth(instances.ids);
  const InstanceSnapshot* past =
      by_depth && !s.history.empty() && !s.history.front().depth_m.empty() ? &s.history.front() : nullptr;
  const bool depth_full_baseline =
      past != nullptr && s.current.stamp_s - past->stamp_s >= options_.motion_baseline_s - 1e-6;
  const bool margin_around_unjudged = options_.instance_margin_around_unjudged &&
                                      (options_.instance_margin_around_unjudged_at_start || !s.AtMapStart());
  std::vector<InstanceJudgement> judgements;
  for (const auto& [id, features] : features_of) {
    InstanceJudgement judgement;
    judgement.id = id;
    judgement.moveable_class = instances.moveable_ids.count(id) > 0;
    for (const int f : features) s.current.on_moveable[static_cast<size_t>(f)] = judgement.moveable_class;
    judgement.num_features = static_cast<int>(features.size());
    InstanceMotionMemory& memory = s.motion_memory[id];
    if (s.coarse_ok && by_depth) {
      DepthVotes votes;
      if (past != nullptr) votes = s.MeasureDepthMotion(id, T_wc, *past, &judgement);
      // Depth sees an object come, go or cross the view; the sparse features see what
      // depth cannot, a flat textured surface sliding within its own plane (a torso
      // walking across the view at arm's length). Either one seeing motion is motion, so
      // the features are asked only where depth did not see it.
      const bool depth_moving = s.DepthSeesMotion(votes, judgement);
      bool sparse_moving = false;
      if (options_.depth_judgement.sparse_features && !depth_moving) {
        InstanceJudgement sparse;
        sparse.id = id;
        sparse.moveable_class = judgement.moveable_class;
        sparse.num_features = judgement.num_features;
        MotionEvidence evidence;
        const bool trust_young_points = memory.static_frames >= options_.static_frames_to_trust_young_points;
        const bool sparse_full_baseline =
            s.MeasureInstanceMotion(id, features, T_wc, trust_young_points, &sparse, &evidence);
        s.DecideMotion(sparse_full_baseline, evidence, &sparse);
        // Depth cannot see a slide within a surface, but it can refute one that did
        // not happen (DepthRefutesSparseMotion).
        sparse_moving = sparse.moving &&
                        !(past != nullptr && s.DepthRefutesSparseMotion(id, T_wc, *past, evidence, votes));
      }
      if (given_moving_ids != nullptr) {
        judgement.judged = true;
        judgement.moving = given_moving_ids->count(id) > 0;
      } else {
        s.DecideFromDepth(votes, depth_full_baseline, depth_moving || sparse_moving, &judgement, &memory);
      }
    } else if (s.coarse_ok) {
      // Once an instance has been seen still over a full baseline, its young points serve
      // again (a parked car stays parked); until then, or once it moves, they do not.
      const bool trust_young_points = memory.static_frames >= options_.static_frames_to_trust_young_points;
      MotionEvidence evidence;
      const bool full_baseline =
          s.MeasureInstanceMotion(id, features, T_wc, trust_young_points, &judgement, &evidence);
      if (given_moving_ids != nullptr) {
        judgement.judged = true;
        judgement.moving = given_moving_ids->count(id) > 0;
      } else {
        s.DecideMotion(full_baseline, evidence, &judgement);
        s.ApplyMotionMemory(full_baseline, &judgement, &memory);
      }
    }
    if (!judgement.judged && s.current.stamp_s < s.preset_until_s) {
      if (const auto preset = s.preset_moving.find(id); preset != s.preset_moving.end()) {
        judgement.judged = true;
        judgement.moving = preset->second;
      }
    }
    s.KeepOutOfPoseAndMap(judgement, features);
    if (s.current.excluded[static_cast<size_t>(features.front())] &&
        (judgement.moving || margin_around_unjudged)) {
      s.KeepOutNearbyBackground(id);
    }
    judgements.push_back(judgement);
  }
  // A background point made on the outline of an instance not judged yet stays out of
  // the fine pose and the map until the verdict.
  s.SettleWaitingOutlines(judgements);
  // What the verdict compared began at the remembered frame a baseline back.
  const double evidence_since_s = past != nullptr ? past->stamp_s : s.current.stamp_s - options_.motion_baseline_s;
  if (options_.map_instances_on_verdict) s.MapInstancesOnTheirVerdict(judgements, evidence_since_s);
  for (size_t i = 0; i < s.current.points.size(); ++i) {
    const MapPoint* point = s.current.points[i];
    if (point != nullptr && !point->bad && s.current.instance[i] == 0 && point->bordered_unjudged_instance != 0) {
      s.current.excluded[i] = true;
      s.current.near_instance[i] = point->bordered_unjudged_instance;
    }
  }
  // Every match of a tracked frame counts, inlier of the coarse pose or not: a point made
  // on an object its mask missed moves with the object, and its later matches are the
  // coarse pose's outliers. A lost frame's matches were made at a wrong pose.
  for (size_t i = 0; s.coarse_ok && i < s.current.points.size(); ++i) {
    MapPoint* point = s.current.points[i];
    if (point == nullptr || point->bad || point->fixed) continue;
    ++point->labelled_sightings;
    point->instance_sightings += s.current.instance[i] != 0;
    point->moveable_sightings += s.current.on_moveable[i];
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
  if (s.localization_mode) s.NoteLongTermMapMatches();
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
    // A pose that jumped (Impl::RelocalizeOffMap) gives no velocity.
    const bool continuous = s.have_last && !s.last_lost() && !s.pose_jumped;
    s.velocity = continuous ? std::optional<Eigen::Isometry3d>(s.current.T_cw * s.last.T_cw.inverse()) : std::nullopt;
    s.history.push_back(s.Snapshot());
    // What the next frame needs is kept: it is later than this one.
    s.ForgetSnapshotsBefore(s.current.stamp_s);
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

LongTermMapData Tracker::ExportLongTermMap(bool include_instances) const {
  if (loaded_map_.has_value()) return *loaded_map_;
  return map_->ToLongTermMap(camera_, include_instances, options_.long_term_min_observations,
                             options_.long_term_map_keeps_fixed_instances);
}

}  // namespace segslam::slam
