#include "slam/pose_optimizer.h"

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <fmt/format.h>

#include <cmath>
#include <string>
#include <utility>

#include "core/error.h"
#include "slam/reprojection_residuals.h"

namespace segslam::slam {
namespace {

using internal::kPoseAmbientSize;
using internal::StereoCameraModel;

// Fewer 2-D constraints than this leave the six pose parameters undetermined.
constexpr int kMinInliersForPose = 3;

void ValidateInput(const Eigen::Isometry3d& T_cw_initial,
                   const std::vector<PoseObservation>& observations, const PinholeCamera& camera,
                   const PoseOptimizerOptions& options) {
  std::string reason;
  if (!camera.IsValid(&reason)) throw Error("OptimizePose: invalid camera: " + reason);
  if (!T_cw_initial.matrix().allFinite()) throw Error("OptimizePose: initial pose is not finite");
  if (options.rounds < 1 || options.iterations_per_round < 1) {
    throw Error(fmt::format("OptimizePose: rounds ({}) and iterations_per_round ({}) must be >= 1",
                            options.rounds, options.iterations_per_round));
  }
  if (!(options.chi2_mono > 0) || !(options.chi2_stereo > 0)) {
    throw Error("OptimizePose: chi2 thresholds must be positive");
  }
  for (size_t i = 0; i < observations.size(); ++i) {
    const PoseObservation& o = observations[i];
    if (!o.point_w.allFinite() || !o.pixel.allFinite() || std::isinf(o.right_u)) {
      throw Error(fmt::format("OptimizePose: observation {} is not finite", i));
    }
    if (!(o.information > 0) || !std::isfinite(o.information)) {
      throw Error(fmt::format("OptimizePose: observation {} has information {} (must be > 0)", i,
                              o.information));
    }
    if (std::isfinite(o.right_u) && !(options.bf > 0)) {
      throw Error(fmt::format(
          "OptimizePose: observation {} is stereo (right_u {}) but options.bf is {} (must be > 0)",
          i, o.right_u, options.bf));
    }
  }
}

bool IsStereo(const PoseObservation& o) { return std::isfinite(o.right_u); }

// chi2 of one observation at pose T_cw, or a negative value when behind the camera.
double ObservationChi2(const StereoCameraModel& model, const Eigen::Isometry3d& T_cw,
                       const PoseObservation& o) {
  const Eigen::Vector3d p_c = T_cw * o.point_w;
  if (IsStereo(o)) {
    return internal::ReprojectionChi2<3>(
        model, Eigen::Vector3d(o.pixel.x(), o.pixel.y(), o.right_u), o.information, p_c);
  }
  return internal::ReprojectionChi2<2>(model, o.pixel, o.information, p_c);
}

int ClassifyObservations(const StereoCameraModel& model, const Eigen::Isometry3d& T_cw,
                         const std::vector<PoseObservation>& observations,
                         const PoseOptimizerOptions& options, std::vector<bool>* inlier) {
  int count = 0;
  for (size_t i = 0; i < observations.size(); ++i) {
    const double chi2 = ObservationChi2(model, T_cw, observations[i]);
    const double threshold = IsStereo(observations[i]) ? options.chi2_stereo : options.chi2_mono;
    (*inlier)[i] = chi2 >= 0 && chi2 <= threshold;
    count += (*inlier)[i] ? 1 : 0;
  }
  return count;
}

}  // namespace

PoseOptimizationResult OptimizePose(const Eigen::Isometry3d& T_cw_initial,
                                    const std::vector<PoseObservation>& observations,
                                    const PinholeCamera& camera,
                                    const PoseOptimizerOptions& options) {
  ValidateInput(T_cw_initial, observations, camera, options);
  const StereoCameraModel model = StereoCameraModel::From(camera, options.bf);

  PoseOptimizationResult result;
  result.T_cw = T_cw_initial;
  result.inlier.assign(observations.size(), false);
  if (observations.empty()) return result;

  ceres::HuberLoss huber_mono(std::sqrt(options.chi2_mono));
  ceres::HuberLoss huber_stereo(std::sqrt(options.chi2_stereo));
  internal::PoseManifold manifold;

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;

  ceres::Solver::Options solver_options;
  // Six unknowns: forming the 6x6 normal equations is cheaper than a QR of the Jacobian.
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.iterations_per_round;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  double pose[kPoseAmbientSize];
  internal::PoseToParameters(T_cw_initial, pose);

  // The first round trusts every observation it can evaluate; the Huber loss tempers the
  // outliers among them.
  std::vector<bool> use(observations.size());
  int num_used = 0;
  for (size_t i = 0; i < observations.size(); ++i) {
    use[i] = (T_cw_initial * observations[i].point_w).z() > internal::kMinProjectionDepthM;
    num_used += use[i] ? 1 : 0;
  }

  bool last_round_converged = false;
  for (int round = 0; round < options.rounds; ++round) {
    if (num_used < kMinInliersForPose) {
      last_round_converged = false;
      break;
    }
    const bool robust = round + 1 < options.rounds;
    const std::vector<bool> optimized_over = use;
    std::vector<internal::PoseOnlyObservationsCost::Observation> terms;
    terms.reserve(num_used);
    for (size_t i = 0; i < observations.size(); ++i) {
      if (!use[i]) continue;
      const PoseObservation& o = observations[i];
      const bool stereo = IsStereo(o);
      const ceres::LossFunction* loss = nullptr;
      if (robust) loss = stereo ? &huber_stereo : &huber_mono;
      const Eigen::Vector3d measured(o.pixel.x(), o.pixel.y(), stereo ? o.right_u : 0.0);
      terms.push_back({o.point_w, measured, stereo, std::sqrt(o.information), loss});
    }
    internal::PoseOnlyObservationsCost cost(model, std::move(terms));
    ceres::Problem problem(problem_options);
    problem.AddParameterBlock(pose, kPoseAmbientSize, &manifold);
    problem.AddResidualBlock(&cost, nullptr, pose);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    ++result.rounds_run;
    last_round_converged = summary.termination_type == ceres::CONVERGENCE;
    num_used = ClassifyObservations(model, internal::PoseFromParameters(pose), observations,
                                    options, &use);
    // The next round would minimise the same sum from the point where this one converged:
    // every observation it would use is within its chi2 threshold here, where the Huber
    // loss equals the squared error, so dropping the loss changes nothing either. Tracking
    // calls this two to four times a frame, and such a round costs a Ceres solve set-up.
    if (last_round_converged && use == optimized_over) break;
  }

  result.T_cw = internal::PoseFromParameters(pose);
  result.num_inliers =
      ClassifyObservations(model, result.T_cw, observations, options, &result.inlier);
  result.converged = last_round_converged && result.num_inliers >= kMinInliersForPose;
  return result;
}

}  // namespace segslam::slam
