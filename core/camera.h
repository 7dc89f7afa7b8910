// Pinhole camera intrinsics in OpenCV's pixel convention: pixel centres lie at integer
// coordinates, so the top-left pixel's centre is (0, 0) and the image spans
// [-0.5, W-0.5] x [-0.5, H-0.5]. No distortion model: the renderer's camera is ideal,
// and a real camera's lens distortion is taken out of its images as a sequence is read
// (core/lens_distortion.h), so everything downstream works on pinhole images.
#pragma once

#include <string>

#include <Eigen/Core>
#include <opencv2/core/matx.hpp>

namespace segslam {

struct PinholeCamera {
  int width = 0;    // Image width in pixels, > 0.
  int height = 0;   // Image height in pixels, > 0.
  double fx = 0;    // Focal length in pixels along x, > 0.
  double fy = 0;    // Focal length in pixels along y, > 0.
  double cx = 0;    // Principal point x in pixels (OpenCV convention).
  double cy = 0;    // Principal point y in pixels (OpenCV convention).

  // The camera MuJoCo renders for a vertical field of view `fovy_deg` (0 < fovy < 180):
  // fy = 0.5 * H / tan(fovy / 2), fx = fy (square pixels), cx = (W - 1) / 2,
  // cy = (H - 1) / 2 (the image centre in OpenCV's integer-centred pixel convention).
  static PinholeCamera FromVerticalFov(int width, int height, double fovy_deg);

  // Pixel of a point in the camera optical frame (x right, y down, z forward, metres).
  // The caller makes sure p_cam.z() > 0; for z <= 0 the result is meaningless.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_cam) const;

  // Point in the camera optical frame seen at `pixel` with `depth_m` measured along the
  // optical axis (the z coordinate, as in TUM depth images), not along the ray.
  Eigen::Vector3d BackProject(const Eigen::Vector2d& pixel, double depth_m) const;

  // True if `pixel` lies at least `border_px` inside the image area
  // [-0.5, W-0.5) x [-0.5, H-0.5), i.e. it rounds to a valid pixel index when border 0.
  bool InImage(const Eigen::Vector2d& pixel, double border_px = 0) const;

  // The 3x3 calibration matrix [fx 0 cx; 0 fy cy; 0 0 1].
  Eigen::Matrix3d K() const;
  cv::Matx33d KCv() const;

  // Limits of a camera segslam accepts, wherever one comes from (a scenario, camera.yaml,
  // --camera, a map file): beyond them a run "localizes" every frame with absurd poses.
  static constexpr int kMaxSidePixels = 16384;
  // The field of view along each axis, 2 atan(size / 2 f): a pinhole image wider than this
  // is nearly all periphery, a narrower one a telescope's.
  static constexpr double kMinFieldOfViewDeg = 1;
  static constexpr double kMaxFieldOfViewDeg = 170;
  // fx / fy: pixels at most twice as wide as high, or the reverse.
  static constexpr double kMaxPixelAspect = 2;

  // False (and a reason in *error when given) for a size outside 1..kMaxSidePixels,
  // non-finite values, a focal length whose field of view lies outside
  // [kMinFieldOfViewDeg, kMaxFieldOfViewDeg] or whose fx / fy exceeds kMaxPixelAspect either
  // way, or a principal point outside the image area [-0.5, W-0.5] x [-0.5, H-0.5].
  bool IsValid(std::string* error) const;
};

}  // namespace segslam
