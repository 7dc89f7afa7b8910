// Pose-only optimisation of one frame against known world points (ORB-SLAM2's
// Optimizer::PoseOptimization, in Ceres): a few rounds of robust least squares, each
// followed by a chi2 test that decides which observations the next round uses.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "core/camera.h"

namespace segslam::slam {

struct PoseObservation {
  Eigen::Vector3d point_w = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  // u - bf / depth (virtual stereo; may be negative with a long virtual baseline);
  // NaN: monocular observation (no depth).
  double right_u = std::numeric_limits<double>::quiet_NaN();
  double information = 1;  // inverse sigma^2 of the keypoint's pyramid level, > 0
};

struct PoseOptimizerOptions {
  int rounds = 4;
  int iterations_per_round = 10;
  double chi2_mono = 5.991;    // 95% of chi2 with 2 degrees of freedom
  double chi2_stereo = 7.815;  // 95% of chi2 with 3 degrees of freedom
  double bf = 0;  // fx * virtual baseline in pixel-metres; must be > 0 when any right_u is not NaN
};

struct PoseOptimizationResult {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  std::vector<bool> inlier;  // per observation, judged at the final pose
  int num_inliers = 0;
  // True when the last round's solver converged with at least 3 inliers in it (fewer
  // do not determine a pose).
  bool converged = false;
  int rounds_run = 0;  // at most options.rounds; fewer after an early stop (below)
};

// Every round but the last uses a Huber loss (delta = sqrt of the chi2 threshold). The
// first round uses every observation whose point lies in front of the camera; after each
// round every observation is judged afresh at the new pose (so an outlier can come back):
// inlier when its point lies in front of the camera and its information-weighted squared
// error is within chi2_mono (2-D) or chi2_stereo (3-D). The next round uses the inliers
// only; rounds stop early when fewer than 3 remain, or when a round converged and the
// judgement at its result keeps exactly the observations it used (the next round would
// start at its own optimum: Huber and squared loss agree within the thresholds).
// Single-threaded, deterministic.
// Throws segslam::Error for an invalid camera, non-finite input, information <= 0,
// rounds or iterations < 1, or stereo observations with bf <= 0.
PoseOptimizationResult OptimizePose(const Eigen::Isometry3d& T_cw_initial,
                                    const std::vector<PoseObservation>& observations,
                                    const PinholeCamera& camera,
                                    const PoseOptimizerOptions& options = {});

}  // namespace segslam::slam
