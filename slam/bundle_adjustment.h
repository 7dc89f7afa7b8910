// Local bundle adjustment of keyframe poses and map points (ORB-SLAM2's
// Optimizer::LocalBundleAdjustment, in Ceres): a short robust solve, removal of the
// observations that fail the chi2 test, then a longer solve without robust loss.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "core/camera.h"

namespace segslam::slam {

struct BaKeyframe {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  bool fixed = false;  // held constant (ORB-SLAM2's covisible-but-not-local keyframes)
};

struct BaObservation {
  int keyframe = 0;  // index into the keyframes
  int point = 0;     // index into the points
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  // u - bf / depth (virtual stereo; may be negative with a long virtual baseline);
  // NaN: monocular observation (no depth).
  double right_u = std::numeric_limits<double>::quiet_NaN();
  double information = 1;  // inverse sigma^2 of the keypoint's pyramid level, > 0
};

struct BundleAdjustmentOptions {
  int first_iterations = 5;    // robust stage
  int second_iterations = 10;  // after outlier removal, no robust loss; 0 skips it
  double chi2_mono = 5.991;
  double chi2_stereo = 7.815;
  double bf = 0;  // fx * virtual baseline in pixel-metres; must be > 0 when any right_u is not NaN
  int threads = 1;
};

struct BundleAdjustmentResult {
  std::vector<Eigen::Isometry3d> T_cw;    // per keyframe (fixed ones unchanged)
  std::vector<Eigen::Vector3d> points_w;  // per point (unobserved ones unchanged)
  std::vector<bool> observation_inlier;   // per observation, judged at the result
  // Ceres costs (1/2 sum of squared whitened residuals): initial_cost at the input under
  // the Huber loss over the observations whose point lay in front of their camera;
  // final_cost at the result over the second stage's observations without loss (or the
  // first stage's robust cost when there is no second stage).
  double initial_cost = 0, final_cost = 0;
};

// Huber deltas are sqrt(chi2_mono) and sqrt(chi2_stereo). An observation is an outlier
// when its point is behind the camera or its information-weighted squared error exceeds
// the chi2 threshold of its kind. Uses a Schur-complement solver with points eliminated
// first. Bit-for-bit deterministic with threads = 1 (Ceres's multi-threaded Schur
// elimination may sum in a different order from run to run). Throws segslam::Error for an invalid
// camera, out-of-range indices, non-finite input, information <= 0, negative iteration
// counts, threads < 1, stereo observations with bf <= 0, or constant_points of another
// size than points_w.
// constant_points: per point, true holds it where it is (a loaded long-term map's point:
// it anchors the keyframes and is returned bit for bit); empty: every point is free.
BundleAdjustmentResult RunBundleAdjustment(const PinholeCamera& camera,
                                           const std::vector<BaKeyframe>& keyframes,
                                           const std::vector<Eigen::Vector3d>& points_w,
                                           const std::vector<BaObservation>& observations,
                                           const BundleAdjustmentOptions& options = {},
                                           const std::vector<bool>& constant_points = {});

}  // namespace segslam::slam
