// ORB features as ORB-SLAM2 extracts them: FAST corners on an image pyramid, found per
// grid cell (with a lower threshold where a cell has none), thinned per level to a budget
// by a quadtree that keeps the strongest corner of each region so features spread over
// the image, oriented by the intensity centroid, described by rotated BRIEF (cv::ORB's
// learned 256-bit pattern on the Gaussian-blurred level image).
#pragma once

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

#include "core/camera.h"

namespace segslam::slam {

struct OrbExtractorOptions {
  int max_features = 1000;
  float scale_factor = 1.2f;
  int levels = 8;
  int initial_fast_threshold = 20;
  int min_fast_threshold = 7;  // retried in grid cells where the initial one finds nothing
  int cell_size_px = 30;
  float min_depth_m = 0.1f;  // depth outside [min, max] counts as missing
  float max_depth_m = 40.0f;
};

struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;  // level-0 pixel coordinates; octave = level
  cv::Mat descriptors;                  // N x 32 CV_8U
  std::vector<float> depth_m;           // per keypoint; 0 = no valid depth
  std::vector<Eigen::Vector3d>
      points_cam;  // BackProject(keypoint, depth) where depth_m > 0, else (0,0,0)
  size_t size() const { return keypoints.size(); }
  bool HasDepth(size_t i) const { return depth_m[i] > 0; }
};

class OrbExtractor {
 public:
  // Throws segslam::Error for options out of range (max_features < 1, scale_factor <= 1,
  // levels < 1, thresholds outside 1..254 or min > initial, cell_size_px < 8, or an
  // empty depth range).
  explicit OrbExtractor(const OrbExtractorOptions& options = {});

  // gray: CV_8U, one channel, the camera's size; depth_m: CV_32F metres of the same size,
  // or empty (then no keypoint has depth). Keypoints come level by level; within a level
  // no keypoint lies closer than kBorderPx (in that level's pixels) to the image border,
  // where the oriented descriptor pattern would leave the image. `size` is the 31-pixel
  // patch diameter scaled to level 0, `angle` in degrees [0, 360), `response` the FAST
  // score. Throws segslam::Error on wrong types or sizes. Thread-safe (const, no state).
  FrameFeatures Extract(const cv::Mat& gray, const cv::Mat& depth_m,
                        const PinholeCamera& camera) const;

  const OrbExtractorOptions& options() const { return options_; }
  const std::vector<float>& scale_factors() const { return scale_factors_; }  // level 0 = 1
  const std::vector<float>& level_sigma2() const { return level_sigma2_; }    // scale^(2*level)
  const std::vector<float>& inverse_level_sigma2() const { return inverse_level_sigma2_; }
  // Feature budget of each level, a geometric series in 1/scale_factor summing to
  // max_features (levels with fewer corners than their budget return fewer).
  const std::vector<int>& features_per_level() const { return features_per_level_; }

  // Keypoints keep this distance (level pixels) from the border: the rotated BRIEF
  // pattern reaches 13 * sqrt(2) ~ 18.4 px from the centre.
  static constexpr int kBorderPx = 19;
  static constexpr int kPatchSizePx = 31;

 private:
  // The keypoints of one pyramid level, in that level's pixels: corners detected per
  // cell, kept by the quadtree up to the level's budget, each with its orientation.
  std::vector<cv::KeyPoint> DetectLevel(const cv::Mat& level_image, int level) const;

  OrbExtractorOptions options_;
  std::vector<float> scale_factors_;
  std::vector<float> level_sigma2_;
  std::vector<float> inverse_level_sigma2_;
  std::vector<int> features_per_level_;
  std::vector<int> circle_half_widths_;  // orientation patch: half width of each row
};

}  // namespace segslam::slam
