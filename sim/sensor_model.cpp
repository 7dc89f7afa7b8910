#include "sim/sensor_model.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace segslam::sim {
namespace {

// SplitMix64 finaliser: a well-mixed 64-bit key from the frame's identity.
std::uint64_t Mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// One independent generator per (seed, pass, frame, stream); cv::RNG is deterministic
// across platforms and OpenCV builds.
cv::RNG StreamRng(std::uint64_t seed, int pass_index, int frame_index, int stream) {
  std::uint64_t key = Mix(seed);
  key = Mix(key ^ static_cast<std::uint64_t>(pass_index));
  key = Mix(key ^ static_cast<std::uint64_t>(static_cast<std::uint32_t>(frame_index)));
  key = Mix(key ^ static_cast<std::uint64_t>(stream));
  return cv::RNG(key == 0 ? 1 : key);
}

enum Stream { kDepthNoise = 1, kEdgeDropout = 2, kRgbNoise = 3 };

// Linear motion blur of `image` along `motion_px` (pixels travelled while the shutter
// is open): the mean of the image shifted along the segment.
void MotionBlur(const Eigen::Vector2d& motion_px, cv::Mat* image) {
  const double length = motion_px.norm();
  if (length < 1.0) return;
  const int size = 2 * static_cast<int>(std::ceil(length / 2)) + 1;
  cv::Mat kernel = cv::Mat::zeros(size, size, CV_32F);
  const Eigen::Vector2d dir = motion_px / length;
  const int samples = std::max(2, static_cast<int>(std::ceil(length)) * 2);
  const double c = (size - 1) / 2.0;
  for (int i = 0; i < samples; ++i) {
    const double t = (i / static_cast<double>(samples - 1) - 0.5) * length;
    const int x = static_cast<int>(std::lround(c + t * dir.x()));
    const int y = static_cast<int>(std::lround(c + t * dir.y()));
    kernel.at<float>(std::clamp(y, 0, size - 1), std::clamp(x, 0, size - 1)) += 1.0f;
  }
  kernel /= cv::sum(kernel)[0];
  cv::filter2D(*image, *image, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
}

}  // namespace

SensorModel::SensorModel(const scenes::SensorSpec& spec, const PinholeCamera& camera,
                         double kind_default_max_depth_m, double fps)
    : spec_(spec),
      camera_(camera),
      max_depth_m_(spec.max_depth_m > 0 ? spec.max_depth_m : kind_default_max_depth_m),
      fps_(fps) {}

void SensorModel::Apply(std::uint64_t seed, int pass_index, int frame_index,
                        const Eigen::Isometry3d& T_wc_prev, const Eigen::Isometry3d& T_wc,
                        RenderedFrame* frame) const {
  if (!spec_.enabled || frame == nullptr) return;
  cv::Mat& depth = frame->depth_m;
  cv::Mat& color = frame->color_bgr;

  // Motion blur of the colour image along the image motion of the scene centre: the
  // centre pixel's point (at its depth, or 3 m where none) seen from the previous pose,
  // re-projected with the current pose, scaled by the exposure's share of the frame
  // interval.
  if (spec_.motion_blur && !color.empty() && spec_.exposure_s > 0 && fps_ > 0) {
    const Eigen::Vector2d centre(camera_.cx, camera_.cy);
    double z = 3.0;
    if (!depth.empty()) {
      const float zc = depth.at<float>(static_cast<int>(std::lround(camera_.cy)),
                                       static_cast<int>(std::lround(camera_.cx)));
      if (zc > 0) z = zc;
    }
    const Eigen::Vector3d p_w = T_wc_prev * camera_.BackProject(centre, z);
    const Eigen::Vector3d p_c = T_wc.inverse() * p_w;
    if (p_c.z() > 1e-3) {
      const Eigen::Vector2d motion = camera_.Project(p_c) - centre;
      MotionBlur(motion * std::min(1.0, spec_.exposure_s * fps_), &color);
    }
  }

  // RGB noise: Gaussian per channel, 8-bit levels.
  if (!color.empty() && spec_.rgb_noise_sigma > 0) {
    cv::RNG rng = StreamRng(seed, pass_index, frame_index, kRgbNoise);
    cv::Mat noise(color.size(), CV_32FC3);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, spec_.rgb_noise_sigma);
    cv::Mat sum;
    color.convertTo(sum, CV_32FC3);
    sum += noise;
    sum.convertTo(color, CV_8UC3);  // rounds and saturates
  }

  if (depth.empty()) return;
  CV_Assert(depth.type() == CV_32F);
  const cv::Mat clean = depth.clone();

  // Depth edges, found on the clean depth: 3x3 range above a share of the depth.
  cv::Mat local_max, local_min;
  cv::dilate(clean, local_max, cv::Mat());
  cv::erode(clean, local_min, cv::Mat());
  cv::RNG edge_rng = StreamRng(seed, pass_index, frame_index, kEdgeDropout);
  cv::RNG noise_rng = StreamRng(seed, pass_index, frame_index, kDepthNoise);
  const double fb = camera_.fx * kBaselineM;
  const bool quantize = spec_.depth_quantization > 0;
  const double step = kDisparityStepPx * (quantize ? spec_.depth_quantization : 1.0);
  for (int r = 0; r < depth.rows; ++r) {
    float* z_row = depth.ptr<float>(r);
    const float* max_row = local_max.ptr<float>(r);
    const float* min_row = local_min.ptr<float>(r);
    for (int c = 0; c < depth.cols; ++c) {
      const double z = z_row[c];
      // Every pixel draws the same number of variates, so one pixel's outcome never
      // shifts the noise of the next.
      const double u = edge_rng.uniform(0.0, 1.0);
      const double g = noise_rng.gaussian(1.0);
      if (z <= 0) continue;
      if (max_row[c] - min_row[c] > kEdgeRelativeRange * z && u < spec_.edge_dropout) {
        z_row[c] = 0;
        continue;
      }
      double noisy = z + g * spec_.depth_noise_sigma_at_1m * z * z;
      if (quantize && noisy > 0) {
        const double disparity = std::round(fb / noisy / step) * step;
        noisy = disparity > 0 ? fb / disparity : 0;
      }
      z_row[c] = (noisy < spec_.min_depth_m || noisy > max_depth_m_)
                     ? 0.0f
                     : static_cast<float>(noisy);
    }
  }
}

}  // namespace segslam::sim
