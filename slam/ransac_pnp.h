// RANSAC PnP: the pose of a frame from 2D-3D matches of which most may be wrong, as in a
// relocalization against a whole map (slam/tracker.h, relocalization_ransac_iterations).
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/types.hpp>

#include "core/camera.h"

namespace segslam::slam {

struct PnpConsensus {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;  // indices into the matches
};

// Draws minimal samples of four matches (AP3P), at most `max_samples` of them, and stops
// sooner once it is 99 % sure of its best consensus; a match agrees with a pose within
// `max_error_px`. The pose is then re-estimated on its consensus (OpenCV's
// solvePnPRansac). Empty when no pose has `min_consensus` (>= 4) matches agreeing.
std::optional<PnpConsensus> SolveRansacPnp(const std::vector<cv::Point3f>& points_w,
                                           const std::vector<cv::Point2f>& pixels, const PinholeCamera& camera,
                                           int max_samples, int min_consensus, float max_error_px = 4.0f);

}  // namespace segslam::slam
