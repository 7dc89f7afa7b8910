// The map-relative relocalization error of pass 2: how far each pass-2 pose is from where
// pass 1's estimate says that place is, rather than from the ground truth.
//
// Why: pass 2 relocalizes on pass 1's long-term map, so its estimate lives in the map's
// frame, and the ATE of pass 2 in that frame (the paper's Table III) adds pass 1's own
// error at that place to the relocalization error. A pass 2 that relocalizes perfectly
// on a map that pass 1 built 0.5 m off reads 0.5 m there. This score compares pass 2
// with pass 1's estimate at the same place, so an error common to both (the map's) drops
// out and what is left is the relocalization's.
//
// For each pass-2 frame i with ground truth T2_i (T_wc):
// - Its place j is the pass-1 frame whose ground-truth camera position is nearest to
//   T2_i's, among the pass-1 frames that have an estimate (a frame pass 1 lost has no
//   pose to compare with). Position only, no orientation: the error carried over from
//   pass 1 at j grows with the lever arm |p2_i - p1_j| (a rotation error of pass 1 at j
//   moves i by angle x distance), so the nearest position is the place where pass 1's
//   error at j stands for pass 1's error at i best; weighing in orientation would need
//   an arbitrary metres-per-radian factor and could pick a farther frame.
// - Beyond `max_place_distance_m` from every such pass-1 position the frame has no map
//   place (pass 1 never estimated a pose near there, e.g. it was lost along that stretch,
//   or pass 2 left pass 1's route); it is excluded and counted (frames_without_place).
// - The error, with T̂ the estimates and T the ground truth (both T_wc):
//     E = (T̂1_j^-1 T̂2_i)^-1 (T1_j^-1 T2_i)
//   i.e. the estimated pose of camera i in camera j's frame against the true one;
//   translation error |translation(E)| in metres, rotation error angle(rotation(E)) in
//   degrees. Any rigid error A common to both estimates (T̂1_j = A T1_j, T̂2_i = A T2_i)
//   cancels: E = identity.
// - A frame with a place but no pass-2 estimate counts as not within and has no error
//   (it is not in the RMSE: the RMSE says how good the poses given are, the within share
//   how many frames have a good one).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "harness/trajectory_metrics.h"

namespace segslam::harness {

struct MapRelativeOptions {
  // Stamps of a frame and of its pose (ground truth or estimate) agree to within this [s];
  // evaluate_ate.py's association radius, as ComputeAte uses. > 0.
  double max_difference_s = 0.02;
  // A pass-2 frame further than this from every estimated pass-1 ground-truth position
  // has no map place [m]. The shipped scenarios drive pass 2 0.2 to 0.5 m beside pass 1;
  // within 2 m a 1 degree rotation error of pass 1 at the place moves it by 3.5 cm at
  // most, small against the within bound. > 0.
  double max_place_distance_m = 2.0;
  // A frame is within when both errors are at most these [m], [deg]. > 0.
  double within_translation_m = 0.1;
  double within_rotation_deg = 1.0;

  // Empty when valid, else what is wrong.
  std::string Check() const;
};

// One pass-2 frame.
struct MapRelativeFrame {
  double stamp_s = 0;                 // the pass-2 frame's
  bool has_ground_truth = false;      // a ground-truth pose within max_difference_s
  bool has_place = false;             // a pass-1 place within max_place_distance_m
  std::size_t place_index = 0;        // index into pass 1's estimate (j), when has_place
  double place_distance_m = 0;        // |p2_i - p1_j| of the ground truth, when has_place
  bool has_estimate = false;          // the run estimated a pose for this frame
  double translation_error_m = 0;     // |translation(E)|, when has_place and has_estimate
  double rotation_error_deg = 0;      // angle(rotation(E)), when has_place and has_estimate
  bool within = false;                // estimated, and both errors within the bounds
};

struct MapRelativeResult {
  MapRelativeOptions options;            // what it was computed with
  std::vector<MapRelativeFrame> frames;  // one per pass-2 frame, in the order given
  int frames_without_ground_truth = 0;   // excluded: no ground-truth pose to find a place by
  int frames_without_place = 0;          // excluded: no estimated pass-1 place near
  int frames_with_place = 0;             // scored: the within share's denominator
  int frames_unestimated = 0;            // of those, without a pass-2 pose (not within)
  int frames_within = 0;                 // of those, within both bounds
  // Over the frames with a place and an estimate; absent when there is none.
  std::optional<ErrorStatistics> translation_m;
  std::optional<ErrorStatistics> rotation_deg;
  // frames_within / frames_with_place; NaN when no frame has a place.
  double WithinShare() const;
};

// Scores pass 2 against pass 1 as the comment at the top says. `pass2_frame_stamps_s`
// are the pass-2 frames the run processed (its frame log); the trajectories are T_wc
// with strictly increasing stamps, the estimates in the map's frame (as `segslam run`
// writes them, frames it lost left out). Throws segslam::Error for invalid options.
MapRelativeResult ComputeMapRelativeError(const std::vector<StampedPose>& pass1_ground_truth,
                                          const std::vector<StampedPose>& pass1_estimate,
                                          const std::vector<double>& pass2_frame_stamps_s,
                                          const std::vector<StampedPose>& pass2_ground_truth,
                                          const std::vector<StampedPose>& pass2_estimate,
                                          const MapRelativeOptions& options = {});

}  // namespace segslam::harness
