#include "slam/tracker_option_overrides.h"

#include "core/option_assignment.h"

namespace segslam::slam {

namespace {

constexpr const char* kWhat = "tracker option";

#define SEGSLAM_REAL(field) \
  {#field, [](TrackerOptions* o, const NumericAssignment& a) { o->field = static_cast<decltype(o->field)>(a.value); }}
#define SEGSLAM_INT(field) \
  {#field, [](TrackerOptions* o, const NumericAssignment& a) { o->field = WholeNumberValue(a, kWhat); }}
#define SEGSLAM_BOOL(field) \
  {#field, [](TrackerOptions* o, const NumericAssignment& a) { o->field = ZeroOrOneValue(a, kWhat); }}

// Every overridable field; one table serves both functions.
const NamedOptionTable<TrackerOptions>& Table() {
  static const NamedOptionTable<TrackerOptions> table(kWhat, {
      SEGSLAM_INT(orb.max_features),
      SEGSLAM_REAL(orb.scale_factor),
      SEGSLAM_INT(orb.levels),
      SEGSLAM_INT(orb.initial_fast_threshold),
      SEGSLAM_INT(orb.min_fast_threshold),
      SEGSLAM_INT(orb.cell_size_px),
      SEGSLAM_REAL(orb.min_depth_m),
      SEGSLAM_REAL(orb.max_depth_m),
      SEGSLAM_REAL(depth_sigma_at_1m),
      SEGSLAM_REAL(max_point_depth_m),
      SEGSLAM_INT(max_descriptor_distance),
      SEGSLAM_INT(strict_descriptor_distance),
      SEGSLAM_REAL(projection_ratio),
      SEGSLAM_REAL(relocalization_ratio),
      SEGSLAM_REAL(last_frame_radius_px),
      SEGSLAM_REAL(local_map_radius_px),
      SEGSLAM_INT(min_tracking_inliers),
      SEGSLAM_INT(min_relocalization_inliers),
      SEGSLAM_INT(min_rival_consensus),
      SEGSLAM_REAL(rival_pose_distance_m),
      SEGSLAM_REAL(rival_support_ratio),
      SEGSLAM_INT(relocalization_ransac_iterations),
      SEGSLAM_INT(min_long_term_inliers),
      SEGSLAM_BOOL(relocalize_off_map),
      SEGSLAM_REAL(off_map_relocalization_interval_s),
      SEGSLAM_REAL(relocalization_probation_s),
      SEGSLAM_REAL(relocalization_recheck_margin),
      SEGSLAM_REAL(keyframe_tracked_ratio),
      SEGSLAM_REAL(close_depth_m),
      SEGSLAM_BOOL(local_bundle_adjustment),
      SEGSLAM_INT(local_ba_keyframes),
      SEGSLAM_REAL(moving_distance_m),
      SEGSLAM_REAL(moving_distance_per_m),
      SEGSLAM_REAL(moving_reprojection_px),
      SEGSLAM_REAL(motion_baseline_s),
      SEGSLAM_INT(min_points_to_judge),
      SEGSLAM_INT(instance_margin_px),
      SEGSLAM_REAL(moving_share_threshold),
      SEGSLAM_INT(min_points_to_move_fixed_class),
      SEGSLAM_INT(moving_streak_frames),
      SEGSLAM_REAL(moving_memory_s),
      SEGSLAM_INT(min_points_to_clear_moving),
      SEGSLAM_INT(static_frames_to_trust_young_points),
      SEGSLAM_INT(long_term_min_observations),
      SEGSLAM_INT(min_initial_map_features),
      SEGSLAM_INT(reset_map_keyframes),
      SEGSLAM_REAL(reset_map_after_lost_s),
  });
  return table;
}

#undef SEGSLAM_REAL
#undef SEGSLAM_INT
#undef SEGSLAM_BOOL

}  // namespace

void SetTrackerOption(TrackerOptions* options, const std::string& assignment) { Table().Set(options, assignment); }

std::vector<std::string> TrackerOptionNames() { return Table().Names(); }

}  // namespace segslam::slam
