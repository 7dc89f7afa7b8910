#include "core/camera.h"

#include <cmath>

namespace segslam {

PinholeCamera PinholeCamera::FromVerticalFov(int width, int height, double fovy_deg) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  const double fovy_rad = fovy_deg * M_PI / 180.0;
  camera.fy = 0.5 * height / std::tan(0.5 * fovy_rad);
  camera.fx = camera.fy;
  // OpenCV puts pixel centres at integers, so the image centre is (W-1)/2, (H-1)/2.
  camera.cx = 0.5 * (width - 1);
  camera.cy = 0.5 * (height - 1);
  return camera;
}

Eigen::Vector2d PinholeCamera::Project(const Eigen::Vector3d& p_cam) const {
  const double inv_z = 1.0 / p_cam.z();
  return {fx * p_cam.x() * inv_z + cx, fy * p_cam.y() * inv_z + cy};
}

Eigen::Vector3d PinholeCamera::BackProject(const Eigen::Vector2d& pixel, double depth_m) const {
  return {(pixel.x() - cx) / fx * depth_m, (pixel.y() - cy) / fy * depth_m, depth_m};
}

bool PinholeCamera::InImage(const Eigen::Vector2d& pixel, double border_px) const {
  return pixel.x() >= -0.5 + border_px && pixel.x() < width - 0.5 - border_px &&
         pixel.y() >= -0.5 + border_px && pixel.y() < height - 0.5 - border_px;
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

cv::Matx33d PinholeCamera::KCv() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }

bool PinholeCamera::IsValid(std::string* error) const {
  auto fail = [error](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (width <= 0 || height <= 0) {
    return fail("image size must be positive, got " + std::to_string(width) + "x" +
                std::to_string(height));
  }
  if (!std::isfinite(fx) || !std::isfinite(fy) || fx <= 0 || fy <= 0) {
    return fail("focal lengths fx, fy must be finite and positive, got " +
                std::to_string(fx) + ", " + std::to_string(fy));
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) {
    return fail("principal point cx, cy must be finite");
  }
  return true;
}

}  // namespace segslam
