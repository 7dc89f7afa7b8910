#include "slam/bundle_adjustment.h"

#include <ceres/loss_function.h>
#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "core/error.h"
#include "slam/reprojection_residuals.h"

namespace segslam::slam {
namespace {

using internal::kPoseAmbientSize;
using internal::StereoCameraModel;
using PoseParameters = std::array<double, kPoseAmbientSize>;

// Beyond this many free keyframes the dense reduced camera matrix (6 x 6 per pair of
// keyframes) costs more than a sparse factorization.
constexpr int kMaxFreeKeyframesForDenseSchur = 40;

void ValidateInput(const PinholeCamera& camera, const std::vector<BaKeyframe>& keyframes,
                   const std::vector<Eigen::Vector3d>& points_w,
                   const std::vector<BaObservation>& observations,
                   const BundleAdjustmentOptions& options, const std::vector<bool>& constant_points) {
  std::string reason;
  if (!camera.IsValid(&reason)) throw Error("RunBundleAdjustment: invalid camera: " + reason);
  if (options.first_iterations < 0 || options.second_iterations < 0 || options.threads < 1) {
    throw Error(
        fmt::format("RunBundleAdjustment: iterations ({}, {}) must be >= 0 and threads ({}) >= 1",
                    options.first_iterations, options.second_iterations, options.threads));
  }
  if (!(options.chi2_mono > 0) || !(options.chi2_stereo > 0)) {
    throw Error("RunBundleAdjustment: chi2 thresholds must be positive");
  }
  for (size_t k = 0; k < keyframes.size(); ++k) {
    if (!keyframes[k].T_cw.matrix().allFinite()) {
      throw Error(fmt::format("RunBundleAdjustment: keyframe {} pose is not finite", k));
    }
  }
  if (!constant_points.empty() && constant_points.size() != points_w.size()) {
    throw Error(fmt::format("RunBundleAdjustment: {} constant-point flags for {} points", constant_points.size(),
                            points_w.size()));
  }
  for (size_t p = 0; p < points_w.size(); ++p) {
    if (!points_w[p].allFinite()) {
      throw Error(fmt::format("RunBundleAdjustment: point {} is not finite", p));
    }
  }
  for (size_t i = 0; i < observations.size(); ++i) {
    const BaObservation& o = observations[i];
    if (o.keyframe < 0 || o.keyframe >= static_cast<int>(keyframes.size()) || o.point < 0 ||
        o.point >= static_cast<int>(points_w.size())) {
      throw Error(fmt::format(
          "RunBundleAdjustment: observation {} refers to keyframe {} / point {}, but there are "
          "{} keyframes and {} points",
          i, o.keyframe, o.point, keyframes.size(), points_w.size()));
    }
    if (!o.pixel.allFinite() || std::isinf(o.right_u)) {
      throw Error(fmt::format("RunBundleAdjustment: observation {} is not finite", i));
    }
    if (!(o.information > 0) || !std::isfinite(o.information)) {
      throw Error(
          fmt::format("RunBundleAdjustment: observation {} has information {} (must be > 0)", i,
                      o.information));
    }
    if (std::isfinite(o.right_u) && !(options.bf > 0)) {
      throw Error(fmt::format(
          "RunBundleAdjustment: observation {} is stereo but options.bf is {} (must be > 0)", i,
          options.bf));
    }
  }
}

bool IsStereo(const BaObservation& o) { return std::isfinite(o.right_u); }

class BundleAdjuster {
 public:
  BundleAdjuster(const PinholeCamera& camera, const std::vector<BaKeyframe>& keyframes,
                 const std::vector<Eigen::Vector3d>& points_w,
                 const std::vector<BaObservation>& observations,
                 const BundleAdjustmentOptions& options, const std::vector<bool>& constant_points)
      : model_(StereoCameraModel::From(camera, options.bf)),
        keyframes_(keyframes),
        constant_points_(constant_points),
        observations_(observations),
        options_(options),
        huber_mono_(std::sqrt(options.chi2_mono)),
        huber_stereo_(std::sqrt(options.chi2_stereo)),
        poses_(keyframes.size()),
        points_(points_w) {
    for (size_t k = 0; k < keyframes.size(); ++k) {
      internal::PoseToParameters(keyframes[k].T_cw, poses_[k].data());
    }
    costs_.reserve(observations.size());
    for (const BaObservation& o : observations) {
      if (IsStereo(o)) {
        costs_.push_back(std::make_unique<internal::PosePointReprojectionCost<3>>(
            model_, Eigen::Vector3d(o.pixel.x(), o.pixel.y(), o.right_u), o.information));
      } else {
        costs_.push_back(std::make_unique<internal::PosePointReprojectionCost<2>>(model_, o.pixel,
                                                                                  o.information));
      }
    }
  }

  BundleAdjustmentResult Run() {
    BundleAdjustmentResult result;
    // Residuals cannot be evaluated for points behind a camera, so the robust stage starts
    // without them; they stay outliers unless the optimised state brings them in front.
    std::vector<bool> use(observations_.size());
    for (size_t i = 0; i < observations_.size(); ++i)
      use[i] = PointDepth(i) > internal::kMinProjectionDepthM;

    ceres::Solver::Summary first = Solve(use, /*robust=*/true, options_.first_iterations);
    result.initial_cost = first.initial_cost;
    result.final_cost = first.final_cost;
    Classify(&use);
    if (options_.second_iterations > 0) {
      ceres::Solver::Summary second = Solve(use, /*robust=*/false, options_.second_iterations);
      result.final_cost = second.final_cost;
      Classify(&use);
    }

    result.observation_inlier = use;
    result.T_cw.resize(keyframes_.size());
    for (size_t k = 0; k < keyframes_.size(); ++k) {
      // Fixed keyframes are returned bit for bit, not through a quaternion round trip.
      result.T_cw[k] =
          keyframes_[k].fixed ? keyframes_[k].T_cw : internal::PoseFromParameters(poses_[k].data());
    }
    result.points_w = points_;
    return result;
  }

 private:
  Eigen::Vector3d PointInCamera(size_t observation) const {
    const BaObservation& o = observations_[observation];
    const double* pose = poses_[o.keyframe].data();
    return Eigen::Map<const Eigen::Quaterniond>(pose + 3) * points_[o.point] +
           Eigen::Map<const Eigen::Vector3d>(pose);
  }
  double PointDepth(size_t observation) const { return PointInCamera(observation).z(); }

  void Classify(std::vector<bool>* inlier) const {
    for (size_t i = 0; i < observations_.size(); ++i) {
      const BaObservation& o = observations_[i];
      const Eigen::Vector3d p_c = PointInCamera(i);
      double chi2 = 0;
      double threshold = 0;
      if (IsStereo(o)) {
        chi2 = internal::ReprojectionChi2<3>(
            model_, Eigen::Vector3d(o.pixel.x(), o.pixel.y(), o.right_u), o.information, p_c);
        threshold = options_.chi2_stereo;
      } else {
        chi2 = internal::ReprojectionChi2<2>(model_, o.pixel, o.information, p_c);
        threshold = options_.chi2_mono;
      }
      (*inlier)[i] = chi2 >= 0 && chi2 <= threshold;
    }
  }

  ceres::Solver::Summary Solve(const std::vector<bool>& use, bool robust, int iterations) {
    ceres::Problem::Options problem_options;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);

    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    std::vector<bool> pose_added(keyframes_.size(), false);
    std::vector<bool> point_added(points_.size(), false);
    int free_keyframes = 0;
    for (size_t i = 0; i < observations_.size(); ++i) {
      if (!use[i]) continue;
      const BaObservation& o = observations_[i];
      double* pose = poses_[o.keyframe].data();
      double* point = points_[o.point].data();
      if (!pose_added[o.keyframe]) {
        pose_added[o.keyframe] = true;
        problem.AddParameterBlock(pose, kPoseAmbientSize, &manifold_);
        if (keyframes_[o.keyframe].fixed) {
          problem.SetParameterBlockConstant(pose);
        } else {
          ++free_keyframes;
        }
        ordering->AddElementToGroup(pose, 1);
      }
      if (!point_added[o.point]) {
        point_added[o.point] = true;
        problem.AddParameterBlock(point, 3);
        if (!constant_points_.empty() && constant_points_[o.point]) problem.SetParameterBlockConstant(point);
        // Points first: the Schur complement eliminates them, leaving the small pose system.
        ordering->AddElementToGroup(point, 0);
      }
      ceres::LossFunction* loss = nullptr;
      if (robust) loss = IsStereo(o) ? &huber_stereo_ : &huber_mono_;
      problem.AddResidualBlock(costs_[i].get(), loss, pose, point);
    }

    ceres::Solver::Summary summary;
    if (problem.NumResidualBlocks() == 0) return summary;
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type =
        free_keyframes <= kMaxFreeKeyframesForDenseSchur ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
    solver_options.linear_solver_ordering = ordering;
    solver_options.max_num_iterations = iterations;
    solver_options.num_threads = options_.threads;
    solver_options.logging_type = ceres::SILENT;
    solver_options.minimizer_progress_to_stdout = false;
    ceres::Solve(solver_options, &problem, &summary);
    return summary;
  }

  const StereoCameraModel model_;
  const std::vector<BaKeyframe>& keyframes_;
  const std::vector<bool>& constant_points_;  // empty: none
  const std::vector<BaObservation>& observations_;
  const BundleAdjustmentOptions& options_;
  ceres::HuberLoss huber_mono_;
  ceres::HuberLoss huber_stereo_;
  internal::PoseManifold manifold_;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs_;
  std::vector<PoseParameters> poses_;
  std::vector<Eigen::Vector3d> points_;
};

}  // namespace

BundleAdjustmentResult RunBundleAdjustment(const PinholeCamera& camera,
                                           const std::vector<BaKeyframe>& keyframes,
                                           const std::vector<Eigen::Vector3d>& points_w,
                                           const std::vector<BaObservation>& observations,
                                           const BundleAdjustmentOptions& options,
                                           const std::vector<bool>& constant_points) {
  ValidateInput(camera, keyframes, points_w, observations, options, constant_points);
  return BundleAdjuster(camera, keyframes, points_w, observations, options, constant_points).Run();
}

}  // namespace segslam::slam
