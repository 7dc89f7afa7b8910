#include "core/camera.h"

#include <cmath>

#include <fmt/format.h>

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
  if (width <= 0 || height <= 0 || width > kMaxSidePixels || height > kMaxSidePixels) {
    return fail(fmt::format("image size must be 1 to {} pixels a side, got {}x{}", kMaxSidePixels, width, height));
  }
  if (!std::isfinite(fx) || !std::isfinite(fy) || fx <= 0 || fy <= 0) {
    return fail(fmt::format("focal lengths fx, fy must be finite and positive, got {:g}, {:g}", fx, fy));
  }
  // Each axis's field of view, and the focal lengths that bound it.
  const auto check_focal = [&](const char* name, double focal, int size, const char* axis) {
    const double fov_deg = 2 * std::atan(0.5 * size / focal) * 180 / M_PI;
    if (fov_deg >= kMinFieldOfViewDeg && fov_deg <= kMaxFieldOfViewDeg) return true;
    const auto focal_for = [&](double fov) { return 0.5 * size / std::tan(0.5 * fov * M_PI / 180); };
    return fail(fmt::format("{} {:g} px gives a {} field of view of {:.4g} deg across {} px; it must be {} to {} "
                            "deg ({} from {:.4g} to {:.4g} px)",
                            name, focal, axis, fov_deg, size, kMinFieldOfViewDeg, kMaxFieldOfViewDeg, name,
                            focal_for(kMaxFieldOfViewDeg), focal_for(kMinFieldOfViewDeg)));
  };
  if (!check_focal("fx", fx, width, "horizontal") || !check_focal("fy", fy, height, "vertical")) return false;
  if (fx > kMaxPixelAspect * fy || fy > kMaxPixelAspect * fx) {
    return fail(fmt::format("fx {:g} and fy {:g} differ more than {:g} times (pixels that much wider than high, or "
                            "the reverse)",
                            fx, fy, kMaxPixelAspect));
  }
  // Inside the image area, the pixel centres' span widened by half a pixel.
  const auto check_centre = [&](const char* name, double centre, int size) {
    if (centre >= -0.5 && centre <= size - 0.5) return true;
    return fail(fmt::format("principal point {} {:g} lies outside the image (-0.5 to {:g} for {} px)", name, centre,
                            size - 0.5, size));
  };
  if (!std::isfinite(cx) || !std::isfinite(cy)) {
    return fail("principal point cx, cy must be finite");
  }
  return check_centre("cx", cx, width) && check_centre("cy", cy, height);
}

}  // namespace segslam
