// Lens distortion of a real camera, and the resampling between its images and the ideal
// pinhole images that the rest of segslam works on.
//
// TUM publishes radial-tangential distortion for its freiburg1 and freiburg2 colour
// cameras (their images are stored as taken; depth is registered to the colour image as
// taken), and none for freiburg3 (stored already undistorted). A sequence with distortion
// is undistorted as it is read, into a pinhole camera with the same fx, fy, cx, cy, so
// that tracking, the mask refinement's projections and every picture use one model; what
// a run writes beside the sequence (refined masks) is distorted back, so it lies on the
// stored images as the input masks do.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "core/camera.h"

namespace segslam {

// OpenCV's (and TUM's d0..d4) five-coefficient model: for normalised pinhole coordinates
// (x, y), r^2 = x^2 + y^2, the stored image shows the point at
//   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
// All zero: no distortion.
struct LensDistortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  bool IsZero() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
  // Every coefficient finite.
  bool IsValid(std::string* error) const;
  // (k1, k2, p1, p2, k3), the order of OpenCV's distortion vectors.
  cv::Vec<double, 5> Coefficients() const { return {k1, k2, p1, p2, k3}; }

  // Where a point at normalised pinhole coordinates `undistorted` appears in the stored
  // image, in normalised coordinates (the formula above).
  cv::Vec2d Distort(const cv::Vec2d& undistorted) const;

  // The radial part alone: r_d = r (1 + k1 r^2 + k2 r^4 + k3 r^6), normalised radii.
  double DistortRadius(double r) const;
  // The largest radius up to which DistortRadius keeps growing, searched up to `limit`
  // (returned when it grows on the whole of [0, limit]). Beyond it the lens would fold
  // the image back onto itself: a polynomial fitted to a smaller field.
  double GrowingRadius(double limit) const;
};

// Normalised radius of the image corner (pixel centre) farthest from the principal point:
// how far out a lens model must hold for this camera.
double CornerRadius(const PinholeCamera& camera);

// Whether `distortion` holds over the whole of `camera`'s image: its radial distortion
// keeps growing out to the image's corners in the pinhole image, and until it reaches them
// in the stored one. A generated dataset is bent through the lens and a run takes the bend
// out again; beyond where the polynomial stops growing (a fit to a narrower field) the
// lens folds the image onto itself. False with the reason in *error (when given); true for
// no distortion. `camera` must be valid.
bool LensCoversImage(const LensDistortion& distortion, const PinholeCamera& camera, std::string* error);

// Resamples whole images between a distorted camera's stored geometry and the pinhole
// geometry with the same intrinsics. Each direction's pixel map is built once (a few tens
// of milliseconds at 640x480); a call then costs one cv::remap. Immutable after
// construction, so one instance may be shared between threads.
//
// Colour is interpolated bilinearly and the border replicated (no artificial edge for the
// feature detector); depth and instance ids are taken from the nearest pixel (no blend of
// two surfaces or two ids) and are 0 (no depth, background) where the source image has no
// pixel. Where the lens's radial bend stops growing (LensDistortion::GrowingRadius: its
// polynomial was fitted to a narrower field), the model does not hold and pixels beyond
// get no source either.
class ImageUndistorter {
 public:
  // `camera` must be valid (PinholeCamera::IsValid) and `distortion` valid; throws
  // segslam::Error otherwise.
  ImageUndistorter(const PinholeCamera& camera, const LensDistortion& distortion);

  // Stored (distorted) image -> pinhole image. Each takes an image of the camera's size
  // and throws segslam::Error on another size; the type is kept.
  cv::Mat UndistortColour(const cv::Mat& image) const;
  cv::Mat UndistortDepth(const cv::Mat& depth) const;
  cv::Mat UndistortIds(const cv::Mat& ids) const;

  // Pinhole image -> stored (distorted) geometry, the inverse resampling.
  cv::Mat DistortColour(const cv::Mat& image) const;
  cv::Mat DistortDepth(const cv::Mat& depth) const;
  cv::Mat DistortIds(const cv::Mat& ids) const;

 private:
  enum class Resampling { kSmooth, kNearest };
  cv::Mat Remap(const cv::Mat& image, const cv::Mat& map_x, const cv::Mat& map_y,
                Resampling resampling) const;

  PinholeCamera camera_;
  // For each pinhole pixel, the stored image's coordinates it samples (CV_32F each).
  cv::Mat undistort_map_x_, undistort_map_y_;
  // For each stored pixel, the pinhole image's coordinates it samples (CV_32F each).
  cv::Mat distort_map_x_, distort_map_y_;
};

}  // namespace segslam
