// The mapping side of the tracker: when a frame becomes a keyframe, the points it adds,
// the culling of spurious new points, and local bundle adjustment over the newest
// keyframes (run in line, so results are deterministic).
#include <cmath>
#include <set>

#include "slam/tracker_internal.h"

namespace segslam::slam {

bool Tracker::Impl::NeedNewKeyframe() const {
  if (reference_keyframe == nullptr) return true;
  int inliers = 0, tracked_close = 0, untracked_close = 0;
  for (size_t i = 0; i < current.points.size(); ++i) {
    const bool tracked = current.points[i] != nullptr && !current.outlier[i];
    if (tracked) ++inliers;
    const float depth = current.features.depth_m[i];
    if (depth > 0 && depth < close_depth_m && !current.excluded[i]) {
      if (tracked)
        ++tracked_close;
      else
        ++untracked_close;
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
  return (few_tracked || need_close) && inliers > 15;
}

std::array<std::uint8_t, 3> Tracker::Impl::ColorAt(const cv::KeyPoint& keypoint) const {
  const cv::Vec3b bgr = current.color_bgr.at<cv::Vec3b>(static_cast<int>(std::lround(keypoint.pt.y)),
                                                        static_cast<int>(std::lround(keypoint.pt.x)));
  return {bgr[2], bgr[1], bgr[0]};
}

void Tracker::Impl::CreateKeyframe() {
  auto owned = std::make_unique<Keyframe>();
  owned->id = map->NextKeyframeId();
  owned->frame_index = current.index;
  owned->stamp_s = current.stamp_s;
  owned->T_cw = current.T_cw;
  owned->features = current.features;
  owned->points.assign(current.features.size(), nullptr);
  // A map's founding keyframes, made while no instance can be judged yet (its first
  // motion_baseline_s), keep every moveable instance in view out; they remember what they
  // kept out, to map it on its verdict (TrackerOptions::map_instances_on_verdict).
  if (options.map_instances_on_verdict && AtMapStart() && !current.kept_out.empty()) {
    owned->instance = current.instance;
    owned->color_rgb.reserve(current.features.size());
    for (const cv::KeyPoint& kp : current.features.keypoints) owned->color_rgb.push_back(ColorAt(kp));
  }
  Keyframe* keyframe = map->AddKeyframe(std::move(owned));
  if (!keyframe->instance.empty()) {
    for (const InstanceJudgement& judgement : result.instances) {
      if (KeptOutUnjudged(judgement) && current.kept_out.count(judgement.id) > 0) {
        keyframes_before_verdict[judgement.id].push_back(keyframe);
      }
    }
  }

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
    if (current.instance[i] == 0 && current.kept_out.count(current.near_instance[i]) > 0) {
      point->bordered_unjudged_instance = current.near_instance[i];
    }
    point->labelled_sightings = judged ? 1 : 0;
    point->instance_sightings = judged && current.instance[i] != 0 ? 1 : 0;
    point->made_on_moveable = current.on_moveable[i];
    point->moveable_sightings = judged && current.on_moveable[i] ? 1 : 0;
    point->first_keyframe_id = keyframe->id;
    point->first_stamp_s = current.stamp_s;
    point->last_matched_frame = current.index;
    point->last_visible_frame = current.index;
    point->color_rgb = ColorAt(current.features.keypoints[i]);
    MapPoint* added = map->AddPoint(std::move(point));
    Map::AddObservation(added, keyframe, static_cast<int>(i));
    Map::UpdatePointStatistics(added, extractor);
    current.points[i] = added;
    current.outlier[i] = false;
    // An outline waits for its instance's verdict before the culling looks at it: held
    // out of every keyframe meanwhile, it would be culled for want of observations.
    if (added->bordered_unjudged_instance != 0) {
      waiting_outlines[added->bordered_unjudged_instance].push_back(added);
    } else {
      recent_points.push_back(added);
    }
  }
  reference_keyframe = keyframe;
  last_keyframe_frame = current.index;
  result.keyframe = true;

  // Culling runs in localization too: the loaded map's points are fixed and never
  // culled, and the tracking map's new points need it as much as a mapping run's.
  CullRecentPoints(keyframe);
  if (!localization_mode || options.localization_bundle_adjustment) {
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
void Tracker::Impl::CullRecentPoints(const Keyframe* keyframe) {
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
std::vector<Keyframe*> Tracker::Impl::LocalWindow() const {
  std::vector<Keyframe*> window;
  const auto& keyframes = map->keyframes();
  for (auto it = keyframes.rbegin();
       it != keyframes.rend() && static_cast<int>(window.size()) < options.local_ba_keyframes; ++it) {
    if (!(*it)->bad) window.push_back(it->get());
  }
  return window;
}

Tracker::Impl::LocalBaProblem Tracker::Impl::MakeLocalBaProblem(const std::vector<Keyframe*>& window) const {
  LocalBaProblem problem;
  for (Keyframe* keyframe : window) problem.keyframe_index[keyframe] = -1;
  std::set<std::uint64_t> seen;
  for (Keyframe* keyframe : window) {
    for (MapPoint* point : keyframe->points) {
      // A loaded map's points take part only in localization, held where they are: they
      // anchor the window to the map they were loaded from.
      if (point == nullptr || point->bad || !seen.insert(point->id).second) continue;
      if (point->fixed && !localization_mode) continue;
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
    problem.constant.push_back(point->fixed);
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

// Moves the free keyframes and points to the adjusted values and unlinks the
// observations the adjustment found to be outliers (a point left unobserved is bad).
void Tracker::Impl::ApplyLocalBa(const LocalBaProblem& problem, const BundleAdjustmentResult& adjusted) {
  for (const auto& [keyframe, index] : problem.keyframe_index) {
    if (!problem.keyframes[static_cast<size_t>(index)].fixed)
      keyframe->T_cw = adjusted.T_cw[static_cast<size_t>(index)];
  }
  for (size_t p = 0; p < problem.points.size(); ++p) {
    if (!problem.constant[p]) problem.points[p]->position_w = adjusted.points_w[p];
  }
  for (size_t k = 0; k < problem.observations.size(); ++k) {
    if (adjusted.observation_inlier[k]) continue;
    auto [point, keyframe] = problem.observation_owner[k];
    const auto found = point->observations.find(keyframe);
    if (found == point->observations.end()) continue;
    if (keyframe->points[static_cast<size_t>(found->second)] == point) {
      keyframe->points[static_cast<size_t>(found->second)] = nullptr;
    }
    point->observations.erase(found);
    // A loaded point is never culled: its observations are in the map it came from.
    if (point->observations.empty() && !point->fixed) Map::MarkBad(point);
  }
  for (MapPoint* point : problem.points) {
    if (!point->bad && !point->fixed) Map::UpdatePointStatistics(point, extractor);
  }
}

void Tracker::Impl::LocalBundleAdjustment() {
  const std::vector<Keyframe*> window = LocalWindow();
  if (window.size() < 2) return;
  const LocalBaProblem problem = MakeLocalBaProblem(window);
  if (problem.observations.empty()) return;
  BundleAdjustmentOptions ba_options = options.bundle_adjustment;
  ba_options.bf = bf;
  ba_options.threads = 1;
  ApplyLocalBa(problem,
               RunBundleAdjustment(camera, problem.keyframes, problem.positions, problem.observations, ba_options,
                                       problem.constant));
  // The current frame's pose moves with its keyframe.
  current.T_cw = reference_keyframe->T_cw;
}

void Tracker::Impl::SettleWaitingOutlines(const std::vector<InstanceJudgement>& judgements) {
  for (const InstanceJudgement& judgement : judgements) {
    const auto waiting = waiting_outlines.find(judgement.id);
    if (waiting == waiting_outlines.end() || KeptOutUnjudged(judgement)) continue;
    for (MapPoint* point : waiting->second) {
      if (point->bad) continue;
      if (judgement.moving) {
        Map::MarkBad(point);
        continue;
      }
      // Judged still: from now on a point like any other, culled by how it does from here.
      point->bordered_unjudged_instance = 0;
      point->first_keyframe_id = map->keyframes().back()->id;
      point->visible_count = point->found_count = 1;
      recent_points.push_back(point);
    }
    waiting_outlines.erase(waiting);
  }
}

std::vector<int> Tracker::Impl::MatchByProjection(const std::vector<MapPoint*>& points, const Eigen::Isometry3d& T_cw,
                                                  const FrameFeatures& features,
                                                  const std::vector<int>& candidates) const {
  const auto& inverse_sigma2 = extractor.inverse_level_sigma2();
  std::vector<int> match(points.size(), -1);
  std::vector<bool> taken(features.size(), false);
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d p_cam = T_cw * points[k]->position_w;
    if (p_cam.z() <= 0) continue;
    const Eigen::Vector2d uv = camera.Project(p_cam);
    const double right_u = uv.x() - bf / p_cam.z();
    int best = -1;
    int best_distance = options.strict_descriptor_distance + 1;
    for (const int i : candidates) {
      const size_t f = static_cast<size_t>(i);
      if (taken[f] || !(features.depth_m[f] > 0)) continue;
      const cv::KeyPoint& kp = features.keypoints[f];
      const double du = kp.pt.x - uv.x(), dv = kp.pt.y - uv.y();
      const double dr = kp.pt.x - bf / features.depth_m[f] - right_u;
      if ((du * du + dv * dv + dr * dr) * inverse_sigma2[static_cast<size_t>(kp.octave)] >
          options.bundle_adjustment.chi2_stereo) {
        continue;
      }
      const int distance = DescriptorDistance(points[k]->descriptor.data(), features.descriptors.ptr(i));
      if (distance < best_distance) {
        best_distance = distance;
        best = i;
      }
    }
    if (best < 0) continue;
    taken[static_cast<size_t>(best)] = true;
    match[k] = best;
  }
  return match;
}

void Tracker::Impl::MapInstancesOnTheirVerdict(const std::vector<InstanceJudgement>& judgements,
                                               double evidence_since_s) {
  for (const InstanceJudgement& judgement : judgements) {
    const auto found = keyframes_before_verdict.find(judgement.id);
    if (found == keyframes_before_verdict.end() || KeptOutUnjudged(judgement)) continue;
    const std::vector<Keyframe*> keyframes = std::move(found->second);
    keyframes_before_verdict.erase(found);
    // Judged moving, what those keyframes saw of it has moved since. Keyframes older than
    // what the verdict compared may have seen it elsewhere.
    if (judgement.moving) continue;
    // As the keyframes would have mapped it, oldest first: each matches the points the
    // older ones made on it, by projection, and makes points of the rest.
    std::vector<MapPoint*> made;
    for (Keyframe* keyframe : keyframes) {
      if (keyframe->bad || keyframe->stamp_s < evidence_since_s - 1e-6) continue;
      std::vector<int> unmapped;
      for (size_t i = 0; i < keyframe->features.size(); ++i) {
        const float depth = keyframe->features.depth_m[i];
        if (keyframe->instance[i] == judgement.id && keyframe->points[i] == nullptr && depth > 0 &&
            depth <= options.max_point_depth_m) {
          unmapped.push_back(static_cast<int>(i));
        }
      }
      const std::vector<int> match = MatchByProjection(made, keyframe->T_cw, keyframe->features, unmapped);
      for (size_t k = 0; k < made.size(); ++k) {
        if (match[k] >= 0) Map::AddObservation(made[k], keyframe, match[k]);
      }
      for (const int i : unmapped) {
        if (keyframe->points[static_cast<size_t>(i)] != nullptr) continue;
        auto point = std::make_unique<MapPoint>();
        point->id = map->NextPointId();
        point->position_w = keyframe->T_wc() * keyframe->features.points_cam[static_cast<size_t>(i)];
        point->instance_id = judgement.id;
        point->labelled_sightings = point->instance_sightings = 1;
        point->made_on_moveable = judgement.moveable_class;
        point->moveable_sightings = judgement.moveable_class ? 1 : 0;
        // Young, as a keyframe at the verdict would have made it: a point judges its
        // instance only once made a baseline before (TrackerOptions::motion_baseline_s),
        // and the verdict that let it in must not be judged again on its own evidence.
        point->first_stamp_s = current.stamp_s;
        point->color_rgb = keyframe->color_rgb[static_cast<size_t>(i)];
        MapPoint* added = map->AddPoint(std::move(point));
        Map::AddObservation(added, keyframe, i);
        Map::UpdatePointStatistics(added, extractor);
        made.push_back(added);
      }
    }
    if (made.empty()) continue;
    // The current frame matches them too, as tracking would have: else the keyframe test
    // sees the reference keyframe gain points this frame does not track, and makes a
    // keyframe that maps the instance a second time.
    std::vector<int> unmatched;
    for (size_t i = 0; i < current.features.size(); ++i) {
      if (current.instance[i] == judgement.id && current.points[i] == nullptr) unmatched.push_back(static_cast<int>(i));
    }
    for (MapPoint* point : made) Map::UpdatePointStatistics(point, extractor);
    const std::vector<int> match = MatchByProjection(made, current.T_cw, current.features, unmatched);
    for (size_t k = 0; k < made.size(); ++k) {
      MapPoint* point = made[k];
      // From now on points like any other, culled by how they do from the newest keyframe.
      point->first_keyframe_id = map->keyframes().back()->id;
      recent_points.push_back(point);
      if (match[k] < 0) continue;
      const size_t i = static_cast<size_t>(match[k]);
      current.points[i] = point;
      current.outlier[i] = false;
      point->last_matched_frame = point->last_visible_frame = current.index;
    }
  }
}

void Tracker::Impl::PurgeBadPoints() {
  for (WorkingFrame* frame : {&current, &last}) {
    for (MapPoint*& point : frame->points) {
      if (point != nullptr && point->bad) point = nullptr;
    }
    for (MapPoint*& point : frame->rejected) {
      if (point != nullptr && point->bad) point = nullptr;
    }
  }
  const auto is_bad = [](const MapPoint* p) { return p->bad; };
  recent_points.erase(std::remove_if(recent_points.begin(), recent_points.end(), is_bad), recent_points.end());
  for (auto& [id, outline] : waiting_outlines) {
    outline.erase(std::remove_if(outline.begin(), outline.end(), is_bad), outline.end());
  }
  if (reference_keyframe != nullptr) {
    for (MapPoint*& point : reference_keyframe->points) {
      if (point != nullptr && point->bad) point = nullptr;
    }
  }
  map->PurgeBadPoints();
  keyframes_since_purge = 0;
}

}  // namespace segslam::slam
