// A ray-cast RGB-D scene for SLAM tests that need exact answers without the simulator:
// textured rectangles (walls, boxes) seen by a pinhole camera at a known pose give the
// colour, the exact depth along the optical axis and instance ids per pixel.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/camera.h"
#include "core/frame.h"

namespace segslam::slam::testing {

// A seeded texture with plenty of corners: rectangles, discs and lines of random grey
// levels and colours over a noisy background.
inline cv::Mat CornerRichTexture(int size, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat texture(size, size, CV_8UC3);
  rng.fill(texture, cv::RNG::UNIFORM, cv::Scalar::all(60), cv::Scalar::all(200));
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 2.0);
  for (int k = 0; k < size / 3; ++k) {
    const cv::Point a(rng.uniform(0, size), rng.uniform(0, size));
    const cv::Point b = a + cv::Point(rng.uniform(6, size / 8), rng.uniform(6, size / 8));
    const cv::Scalar color(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
    switch (k % 3) {
      case 0: cv::rectangle(texture, a, b, color, cv::FILLED); break;
      case 1: cv::circle(texture, a, rng.uniform(3, size / 16), color, cv::FILLED); break;
      default: cv::line(texture, a, b, color, rng.uniform(1, 4)); break;
    }
  }
  // Features a few texels wide, so they span several pixels at the test's distances.
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.2);
  return texture;
}

// A textured rectangle: corner `origin`, edges `u` and `v` (world frame, metres).
struct TexturedQuad {
  Eigen::Vector3d origin;
  Eigen::Vector3d u;
  Eigen::Vector3d v;
  cv::Mat texture;  // CV_8UC3; (0,0) at origin, columns along u, rows along v
  std::uint16_t instance_id = 0;
};

// Six quads of an axis-aligned box with one texture per face.
inline std::vector<TexturedQuad> BoxQuads(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                                          std::uint64_t seed, std::uint16_t instance_id, int texture_px = 256) {
  const Eigen::Vector3d s = max - min;
  const Eigen::Vector3d x(s.x(), 0, 0), y(0, s.y(), 0), z(0, 0, s.z());
  std::vector<TexturedQuad> quads = {
      {min, x, z, {}, instance_id},          {min + y, x, z, {}, instance_id},
      {min, y, z, {}, instance_id},          {min + x, y, z, {}, instance_id},
      {min, x, y, {}, instance_id},          {min + z, x, y, {}, instance_id},
  };
  for (size_t k = 0; k < quads.size(); ++k) quads[k].texture = CornerRichTexture(texture_px, seed * 31 + k);
  return quads;
}

struct RenderedFrame {
  RgbdFrame frame;
  cv::Mat instance_ids;  // CV_16U
};

inline RenderedFrame RenderQuads(const std::vector<TexturedQuad>& quads, const PinholeCamera& camera,
                                 const Eigen::Isometry3d& T_wc, int index, double stamp_s) {
  RenderedFrame out;
  out.frame.index = index;
  out.frame.stamp_s = stamp_s;
  out.frame.color_bgr = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar::all(0));
  out.frame.depth_m = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0));
  out.instance_ids = cv::Mat(camera.height, camera.width, CV_16U, cv::Scalar(0));
  const Eigen::Matrix3d R = T_wc.linear();
  const Eigen::Vector3d c = T_wc.translation();
  struct Prepared {
    Eigen::Vector3d normal;
    double u2, v2;
  };
  std::vector<Prepared> prepared;
  for (const TexturedQuad& q : quads) prepared.push_back({q.u.cross(q.v).normalized(), q.u.squaredNorm(), q.v.squaredNorm()});
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      // Ray with unit z in the camera: its parameter t is the depth along the optical axis.
      const Eigen::Vector3d ray_c((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1.0);
      const Eigen::Vector3d ray_w = R * ray_c;
      double best_t = std::numeric_limits<double>::infinity();
      int best = -1;
      double best_a = 0, best_b = 0;
      for (size_t k = 0; k < quads.size(); ++k) {
        const double denominator = ray_w.dot(prepared[k].normal);
        if (std::abs(denominator) < 1e-12) continue;
        const double t = (quads[k].origin - c).dot(prepared[k].normal) / denominator;
        if (t <= 0.05 || t >= best_t) continue;
        const Eigen::Vector3d p = c + t * ray_w - quads[k].origin;
        const double a = p.dot(quads[k].u) / prepared[k].u2;
        const double b = p.dot(quads[k].v) / prepared[k].v2;
        if (a < 0 || a > 1 || b < 0 || b > 1) continue;
        best_t = t;
        best = static_cast<int>(k);
        best_a = a;
        best_b = b;
      }
      if (best < 0) continue;
      // Bilinear lookup in a smooth texture: point-sampling a sharp one aliases, and
      // the moire biases keypoint positions coherently over the image (a few mm of
      // pose error for no fault of the tracker).
      const cv::Mat& texture = quads[static_cast<size_t>(best)].texture;
      const double tx = std::clamp(best_a * texture.cols - 0.5, 0.0, texture.cols - 1.001);
      const double ty = std::clamp(best_b * texture.rows - 0.5, 0.0, texture.rows - 1.001);
      const int x0 = static_cast<int>(tx), y0 = static_cast<int>(ty);
      const double fx = tx - x0, fy = ty - y0;
      const cv::Vec3b& c00 = texture.at<cv::Vec3b>(y0, x0);
      const cv::Vec3b& c01 = texture.at<cv::Vec3b>(y0, x0 + 1);
      const cv::Vec3b& c10 = texture.at<cv::Vec3b>(y0 + 1, x0);
      const cv::Vec3b& c11 = texture.at<cv::Vec3b>(y0 + 1, x0 + 1);
      cv::Vec3b& pixel = out.frame.color_bgr.at<cv::Vec3b>(y, x);
      for (int ch = 0; ch < 3; ++ch) {
        const double value = (1 - fy) * ((1 - fx) * c00[ch] + fx * c01[ch]) + fy * ((1 - fx) * c10[ch] + fx * c11[ch]);
        pixel[ch] = static_cast<std::uint8_t>(std::lround(value));
      }
      out.frame.depth_m.at<float>(y, x) = static_cast<float>(best_t);
      out.instance_ids.at<std::uint16_t>(y, x) = quads[static_cast<size_t>(best)].instance_id;
    }
  }
  return out;
}

// The inside of a 8 x 6 x 3 m room centred on the origin (z up), walls, floor and ceiling textured.
inline std::vector<TexturedQuad> RoomQuads(std::uint64_t seed) {
  const Eigen::Vector3d min(-4, -3, 0), max(4, 3, 3);
  return BoxQuads(min, max, seed, 0, 768);
}

// A camera pose looking along world +x from `position` (optical z = world x, optical
// y = world -z), turned by `yaw_rad` about world z.
inline Eigen::Isometry3d LookingAlongX(const Eigen::Vector3d& position, double yaw_rad) {
  Eigen::Matrix3d R_base;
  R_base << 0, 0, 1,   //
      -1, 0, 0,        //
      0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_base;
  T.translation() = position;
  return T;
}

// A smooth hand-held-like path at 30 frames a second: forward and sideways drift and a
// slow yaw oscillation, in the room of RoomQuads().
inline Eigen::Isometry3d HandHeldPathPose(int frame) {
  const double t = frame / 30.0;
  return LookingAlongX(Eigen::Vector3d(-2.0 + 0.25 * t, 0.3 * std::sin(1.3 * t), 1.4 + 0.05 * std::sin(2 * t)),
                       0.25 * std::sin(0.9 * t));
}

}  // namespace segslam::slam::testing
