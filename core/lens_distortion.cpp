#include "core/lens_distortion.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace segslam {
namespace {

// A stored pixel whose inverse does not re-distort to within this distance of itself lies
// where the model folds over (outside the calibrated field); it gets no pinhole source.
constexpr double kInverseToleranceNormalised = 1e-5;
// A map entry far outside any image: the pixel has no source (0, or the border colour).
constexpr float kNoSource = -1e6f;

}  // namespace

bool LensDistortion::IsValid(std::string* error) const {
  for (double value : {k1, k2, p1, p2, k3}) {
    if (!std::isfinite(value)) {
      if (error != nullptr) *error = "distortion coefficients k1, k2, p1, p2, k3 must be finite";
      return false;
    }
  }
  return true;
}

cv::Vec2d LensDistortion::Distort(const cv::Vec2d& undistorted) const {
  const double x = undistorted[0], y = undistorted[1];
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

double LensDistortion::DistortRadius(double r) const {
  const double r2 = r * r;
  return r * (1 + r2 * (k1 + r2 * (k2 + r2 * k3)));
}

double LensDistortion::GrowingRadius(double limit) const {
  // d r_d / d r = 1 + 3 k1 r^2 + 5 k2 r^4 + 7 k3 r^6, sampled finely enough for the
  // polynomials of real lenses (a few sign changes at most).
  constexpr int kSteps = 4096;
  for (int i = 1; i <= kSteps; ++i) {
    const double r = limit * i / kSteps;
    const double r2 = r * r;
    if (1 + r2 * (3 * k1 + r2 * (5 * k2 + r2 * 7 * k3)) <= 0) return limit * (i - 1) / kSteps;
  }
  return limit;
}

double CornerRadius(const PinholeCamera& camera) {
  return std::hypot(std::max(camera.cx, camera.width - 1 - camera.cx) / camera.fx,
                    std::max(camera.cy, camera.height - 1 - camera.cy) / camera.fy);
}

bool LensCoversImage(const LensDistortion& distortion, const PinholeCamera& camera, std::string* error) {
  if (distortion.IsZero()) return true;
  const double corner = CornerRadius(camera);
  // Searched past the corners: a barrel lens's stored corners see points beyond them.
  const double growing = distortion.GrowingRadius(4 * corner);
  if (growing < corner || distortion.DistortRadius(growing) < corner) {
    if (error != nullptr) {
      *error = fmt::format("the lens (k1 {:g}, k2 {:g}, k3 {:g}) folds the image: its radial distortion stops growing "
                           "at normalised radius {:.4g}, and the image's corners lie at {:.4g} (a polynomial fitted "
                           "to a narrower field of view?)",
                           distortion.k1, distortion.k2, distortion.k3, growing, corner);
    }
    return false;
  }
  return true;
}

ImageUndistorter::ImageUndistorter(const PinholeCamera& camera, const LensDistortion& distortion)
    : camera_(camera) {
  std::string error;
  if (!camera.IsValid(&error)) throw Error("lens undistortion: invalid camera: " + error);
  if (!distortion.IsValid(&error)) throw Error("lens undistortion: " + error);
  const cv::Size size(camera.width, camera.height);

  // Pinhole pixel -> stored pixel: the model itself, where it still bends outwards (a
  // polynomial fitted to a narrower field may fold back beyond that).
  const double corner = CornerRadius(camera);
  // Searched past the corners: a barrel lens's stored corners see points beyond them.
  const double growing = distortion.GrowingRadius(4 * corner);
  undistort_map_x_.create(size, CV_32F);
  undistort_map_y_.create(size, CV_32F);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      const cv::Vec2d x((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy);
      const bool modelled = std::hypot(x[0], x[1]) <= growing;
      const cv::Vec2d d = distortion.Distort(x);
      undistort_map_x_.at<float>(v, u) = modelled ? static_cast<float>(camera.fx * d[0] + camera.cx) : kNoSource;
      undistort_map_y_.at<float>(v, u) = modelled ? static_cast<float>(camera.fy * d[1] + camera.cy) : kNoSource;
    }
  }

  // Stored pixel -> pinhole pixel: OpenCV's iterative inversion, checked by re-distorting
  // (and by where the model holds: a folded lens has a second, false preimage).
  std::vector<cv::Point2d> stored;
  stored.reserve(static_cast<size_t>(size.area()));
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) stored.emplace_back(u, v);
  }
  std::vector<cv::Point2d> normalised;
  const cv::Matx33d K = camera.KCv();
  cv::undistortPoints(stored, normalised, K, distortion.Coefficients(), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-6));
  distort_map_x_.create(size, CV_32F);
  distort_map_y_.create(size, CV_32F);
  for (int v = 0, k = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u, ++k) {
      const cv::Vec2d x(normalised[k].x, normalised[k].y);
      const cv::Vec2d back = distortion.Distort(x);
      const bool inverted = std::hypot(x[0], x[1]) <= growing &&
                            std::hypot(back[0] - (u - camera.cx) / camera.fx, back[1] - (v - camera.cy) / camera.fy) <
                                kInverseToleranceNormalised;
      distort_map_x_.at<float>(v, u) = inverted ? static_cast<float>(camera.fx * x[0] + camera.cx) : kNoSource;
      distort_map_y_.at<float>(v, u) = inverted ? static_cast<float>(camera.fy * x[1] + camera.cy) : kNoSource;
    }
  }
}

cv::Mat ImageUndistorter::Remap(const cv::Mat& image, const cv::Mat& map_x, const cv::Mat& map_y,
                                Resampling resampling) const {
  if (image.cols != camera_.width || image.rows != camera_.height) {
    throw Error(fmt::format("lens undistortion: image is {}x{}, the camera's is {}x{}", image.cols, image.rows,
                            camera_.width, camera_.height));
  }
  cv::Mat out;
  if (resampling == Resampling::kSmooth) {
    cv::remap(image, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  } else {
    cv::remap(image, out, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  }
  return out;
}

cv::Mat ImageUndistorter::UndistortColour(const cv::Mat& image) const {
  return Remap(image, undistort_map_x_, undistort_map_y_, Resampling::kSmooth);
}
cv::Mat ImageUndistorter::UndistortDepth(const cv::Mat& depth) const {
  return Remap(depth, undistort_map_x_, undistort_map_y_, Resampling::kNearest);
}
cv::Mat ImageUndistorter::UndistortIds(const cv::Mat& ids) const {
  return Remap(ids, undistort_map_x_, undistort_map_y_, Resampling::kNearest);
}
cv::Mat ImageUndistorter::DistortColour(const cv::Mat& image) const {
  return Remap(image, distort_map_x_, distort_map_y_, Resampling::kSmooth);
}
cv::Mat ImageUndistorter::DistortDepth(const cv::Mat& depth) const {
  return Remap(depth, distort_map_x_, distort_map_y_, Resampling::kNearest);
}
cv::Mat ImageUndistorter::DistortIds(const cv::Mat& ids) const {
  return Remap(ids, distort_map_x_, distort_map_y_, Resampling::kNearest);
}

}  // namespace segslam
