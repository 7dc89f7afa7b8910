#include "slam/ransac_pnp.h"

#include <algorithm>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace segslam::slam {

std::optional<PnpConsensus> SolveRansacPnp(const std::vector<cv::Point3f>& points_w,
                                           const std::vector<cv::Point2f>& pixels, const PinholeCamera& camera,
                                           int max_samples, int min_consensus, float max_error_px) {
  if (points_w.size() != pixels.size() || points_w.size() < static_cast<size_t>(std::max(min_consensus, 4))) {
    return std::nullopt;
  }
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (!cv::solvePnPRansac(points_w, pixels, cv::Mat(camera.KCv()), cv::noArray(), rvec, tvec, false, max_samples,
                          max_error_px, 0.99, inliers, cv::SOLVEPNP_AP3P) ||
      inliers.size() < static_cast<size_t>(min_consensus)) {
    return std::nullopt;
  }
  cv::Mat rotation;
  cv::Rodrigues(rvec, rotation);
  Eigen::Matrix3d R;
  cv::cv2eigen(rotation, R);
  PnpConsensus consensus;
  consensus.T_cw.linear() = R;
  consensus.T_cw.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  consensus.inliers = std::move(inliers);
  return consensus;
}

}  // namespace segslam::slam
