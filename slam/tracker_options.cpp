#include "slam/tracker_options.h"

namespace segslam::slam {

#define REAL(FIELD, RANGE, UNIT, HELP) SEGSLAM_OPTION_REAL(TrackerOptions, FIELD, RANGE, UNIT, HELP)
#define WHOLE(FIELD, RANGE, UNIT, HELP) SEGSLAM_OPTION_WHOLE(TrackerOptions, FIELD, RANGE, UNIT, HELP)
#define SWITCH(FIELD, HELP) SEGSLAM_OPTION_SWITCH(TrackerOptions, FIELD, HELP)

const OptionRegistry<TrackerOptions>& TrackerOptionRegistry() {
  static const OptionRegistry<TrackerOptions> registry("tracker option", {
      // ORB features.
      WHOLE(orb.max_features, AtLeast(1), "", "ORB features extracted per frame"),
      REAL(orb.scale_factor, OpenClosed(1, 4), "", "scale between two levels of the image pyramid"),
      WHOLE(orb.levels, Closed(1, 16), "", "levels of the image pyramid"),
      WHOLE(orb.initial_fast_threshold, Closed(1, 254), "", "FAST threshold tried first in each grid cell"),
      WHOLE(orb.min_fast_threshold, Closed(1, 254), "", "FAST threshold retried where the first finds nothing"),
      WHOLE(orb.cell_size_px, AtLeast(8), "px", "grid cell over which features are spread"),
      REAL(orb.min_depth_m, AtLeast(0), "m", "depth below this counts as missing"),
      REAL(orb.max_depth_m, Above(0), "m", "depth above this counts as missing"),
      // Depth, matching and tracking.
      REAL(depth_sigma_at_1m, Above(0), "m", "depth noise at 1 m (grows with depth squared); weighs depth in poses"),
      REAL(max_point_depth_m, Above(0), "m", "map points are made only up to this depth"),
      WHOLE(max_descriptor_distance, Closed(0, 256), "bits", "largest Hamming distance of a match"),
      WHOLE(strict_descriptor_distance, Closed(0, 256), "bits", "largest Hamming distance of a strict match"),
      REAL(projection_ratio, OpenClosed(0, 1), "", "nearest/second-nearest ratio of projection matching"),
      REAL(relocalization_ratio, OpenClosed(0, 1), "", "nearest/second-nearest ratio of relocalization matching"),
      REAL(last_frame_radius_px, Above(0), "px", "search radius for the last frame's points (pyramid level 0)"),
      REAL(local_map_radius_px, Above(0), "px", "search radius for the local map's points (pyramid level 0)"),
      WHOLE(min_tracking_inliers, AtLeast(1), "", "inliers a tracked frame needs after local-map tracking"),
      WHOLE(min_relocalization_inliers, AtLeast(1), "", "inliers a frame needs right after a relocalization"),
      // Relocalization and its look-alike guards.
      WHOLE(min_rival_consensus, AtLeast(4), "", "matches that must agree on a rival pose (a huge value: no rival check)"),
      REAL(rival_pose_distance_m, AtLeast(0), "m", "a rival pose this far from the best is another place"),
      REAL(rival_support_ratio, Above(0), "", "a rival this strong (share of the best's inliers) keeps the frame lost"),
      WHOLE(relocalization_ransac_iterations, AtLeast(1), "", "most RANSAC PnP samples of one relocalization"),
      WHOLE(min_long_term_inliers, AtLeast(1), "", "localization: fewer long-term-map inliers than this is off the map"),
      SWITCH(relocalize_off_map, "localization: off the map, search the whole map again for the pose"),
      REAL(off_map_relocalization_interval_s, AtLeast(0), "s", "localization: at most one whole-map search per this time"),
      REAL(relocalization_probation_s, AtLeast(0), "s", "localization: a relocalization is re-checked this long (0: never)"),
      REAL(relocalization_recheck_margin, AtLeast(1), "", "a re-check's pose needs this many times the tracked pose's inliers"),
      // Keyframes and the local map.
      REAL(keyframe_tracked_ratio, OpenClosed(0, 1), "", "new keyframe below this share of the reference keyframe's points"),
      REAL(close_depth_m, AtLeast(0), "m", "depth of a close point in keyframe decisions (0: from the first frame)"),
      SWITCH(local_bundle_adjustment, "local bundle adjustment after each keyframe"),
      WHOLE(local_ba_keyframes, AtLeast(1), "", "keyframes the local bundle adjustment moves"),
      SWITCH(localization_bundle_adjustment, "localization: local bundle adjustment too, the loaded map's points held fixed"),
      // The moving/static judgement (the paper's step 3).
      REAL(moving_distance_m, AtLeast(0), "m", "a feature moves when its 3-D position is off by more than this (plus per-metre part)"),
      REAL(moving_distance_per_m, AtLeast(0), "m/m", "a feature moves when off by moving_distance_m plus this times its depth"),
      REAL(moving_reprojection_px, Above(0), "px", "without depth, a feature moves when it reprojects this far off"),
      REAL(motion_baseline_s, AtLeast(0), "s", "motion is measured against the instance's points of this long ago"),
      WHOLE(min_points_to_judge, AtLeast(1), "", "measured features an instance needs to be judged"),
      WHOLE(instance_margin_px, AtLeast(0), "px", "background features this near a kept-out instance are kept out too"),
      SWITCH(instance_margin_scales_with_level, "instance_margin_px is in pixels of the feature's pyramid level"),
      SWITCH(instance_margin_around_unjudged, "the margin also goes around instances kept out as not judged yet"),
      SWITCH(instance_margin_around_unjudged_at_start, "that margin also in a run's first motion_baseline_s, when none can be judged"),
      SWITCH(map_instances_on_verdict, "an instance judged still is mapped in a map's first keyframes that kept it out unjudged"),
      SWITCH(retrack_map_start, "a pass's first motion_baseline_s is tracked again with the verdicts at its end (mutual pipeline)"),
      REAL(moving_share_threshold, Closed(0, 1), "", "an instance moves when this share of its measured features does"),
      WHOLE(min_points_to_move_fixed_class, AtLeast(1), "", "measured points a class that does not move needs to be moving"),
      WHOLE(moving_streak_frames, AtLeast(1), "", "frames in a row measured moving after which an instance stays moving"),
      REAL(moving_memory_s, AtLeast(0), "s", "most time between two frames of a moving streak"),
      WHOLE(min_points_to_clear_moving, AtLeast(1), "", "measured features that clear an instance kept moving"),
      WHOLE(static_frames_to_trust_young_points, AtLeast(0), "", "frames judged static after which young points judge too"),
      SWITCH(judge_by_depth, "judge instances from their depth pixels (0: from re-found sparse features, the paper's)"),
      WHOLE(depth_judgement.samples_per_instance, AtLeast(1), "", "depth judgement: interior pixels sampled per instance and frame"),
      WHOLE(depth_judgement.interior_margin_px, Closed(0, 20), "px", "depth judgement: mask and depth agree this far around a sample"),
      WHOLE(depth_judgement.min_samples, AtLeast(1), "", "depth judgement: measured samples a frame needs to see an instance"),
      REAL(depth_judgement.max_depth_m, Above(0), "m", "depth judgement: samples are taken and compared only up to this depth"),
      SWITCH(depth_judgement.sparse_features, "depth judgement: also ask the sparse features where depth saw no motion"),
      REAL(depth_judgement.moving_share, OpenClosed(0, 1), "", "depth judgement: share of samples contradicted that shows motion"),
      REAL(depth_judgement.moving_log_odds, Above(0), "", "depth judgement: log-odds of moving added by a frame that sees motion"),
      REAL(depth_judgement.static_log_odds, Above(0), "", "depth judgement: log-odds taken by a frame that sees it still"),
      REAL(depth_judgement.max_log_odds, Above(0), "", "depth judgement: bound of the log-odds either way"),
      // Maps.
      WHOLE(long_term_min_observations, AtLeast(1), "", "keyframes that must see a point for the long-term map"),
      SWITCH(long_term_map_keeps_fixed_instances, "long-term map of the judging modes: keep points on fixed-class instances"),
      WHOLE(min_initial_map_features, AtLeast(1), "", "features with depth the first keyframe needs"),
      WHOLE(reset_map_keyframes, AtLeast(0), "", "a lost map of at most this many keyframes is begun anew (0: never)"),
      REAL(reset_map_after_lost_s, AtLeast(0), "s", "how long a young map stays lost before it is dropped"),
      // The robust pose optimisation and the local bundle adjustment.
      WHOLE(pose_optimizer.rounds, Closed(1, 20), "", "rounds of the pose optimisation, outliers judged afresh after each"),
      WHOLE(pose_optimizer.iterations_per_round, AtLeast(1), "", "solver iterations per round of the pose optimisation"),
      REAL(pose_optimizer.chi2_mono, Above(0), "", "outlier threshold of an observation without depth (chi2, 2 dof)"),
      REAL(pose_optimizer.chi2_stereo, Above(0), "", "outlier threshold of an observation with depth (chi2, 3 dof)"),
      WHOLE(bundle_adjustment.first_iterations, AtLeast(1), "", "local bundle adjustment: iterations of its robust stage"),
      WHOLE(bundle_adjustment.second_iterations, AtLeast(0), "", "local bundle adjustment: iterations once outliers are removed (0: none)"),
      REAL(bundle_adjustment.chi2_mono, Above(0), "", "local bundle adjustment: outlier threshold without depth (chi2, 2 dof)"),
      REAL(bundle_adjustment.chi2_stereo, Above(0), "", "local bundle adjustment: outlier threshold with depth (chi2, 3 dof)"),
  });
  return registry;
}

#undef REAL
#undef WHOLE
#undef SWITCH

void SetTrackerOption(TrackerOptions* options, const std::string& assignment) {
  TrackerOptionRegistry().Set(options, assignment);
}

std::vector<std::string> TrackerOptionNames() { return TrackerOptionRegistry().Names(); }

}  // namespace segslam::slam
