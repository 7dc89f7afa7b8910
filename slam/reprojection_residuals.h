// Ceres building blocks shared by the pose-only optimizer and local bundle adjustment:
// a pose parameterization with a left-multiplied tangent update, and the reprojection
// residuals of ORB-SLAM2 (monocular pixel, or RGB-D as a virtual stereo triple
// (u, v, u_right) with u_right = u - bf / depth).
//
// Internal to slam/: it includes Ceres, which segslam_slam links privately.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/camera.h"

namespace segslam::slam::internal {

// Pose T_cw stored as 7 doubles: translation (3), then the rotation as a unit
// quaternion in Eigen's coefficient order (x, y, z, w).
constexpr int kPoseAmbientSize = 7;
constexpr int kPoseTangentSize = 6;

void PoseToParameters(const Eigen::Isometry3d& T_cw, double* parameters);
Eigen::Isometry3d PoseFromParameters(const double* parameters);

// Tangent vector delta = (rho, phi), rho a translation and phi a rotation vector.
// Plus(T, delta) = (Exp(phi) * R, Exp(phi) * t + rho): a left update of T_cw, so a point
// in the camera frame moves to p_c' = Exp(phi) * p_c + rho and its derivative at
// delta = 0 is [I, -[p_c]x], independent of the current pose.
//
// The Jacobians are deliberately not the true derivatives with respect to the 7 stored
// numbers: PlusJacobian is [I6; 0] and the cost functions below put the derivative with
// respect to delta in the first 6 of their 7 pose columns (the 7th is 0). Ceres only ever
// uses the product (cost Jacobian) x (PlusJacobian), which is then exactly the tangent
// Jacobian; this saves the 4x3 quaternion chain rule in every residual. The price:
// Ceres's gradient checker (Solver::Options::check_gradients) must not be used on
// problems holding this manifold, since it compares ambient Jacobians.
class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseAmbientSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool RightMultiplyByPlusJacobian(const double* x, int num_rows, const double* ambient_matrix,
                                   double* tangent_matrix) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

struct StereoCameraModel {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double bf = 0;  // fx * baseline, pixel-metres; used by 3-residual (stereo) terms only
  static StereoCameraModel From(const PinholeCamera& camera, double bf) {
    return {camera.fx, camera.fy, camera.cx, camera.cy, bf};
  }
};

// Points closer than this to the image plane cannot be projected stably; a solver step
// that brings an observed point there is rejected.
constexpr double kMinProjectionDepthM = 1e-6;

// Whitened residual sqrt(information) * (measured - projected(p_c)) and, when wanted, its
// derivative with respect to p_c. kResiduals is 2 (u, v) or 3 (u, v, u_right).
// Returns false when p_c is not in front of the camera.
template <int kResiduals>
bool WhitenedReprojectionResidual(const StereoCameraModel& model,
                                  const Eigen::Matrix<double, kResiduals, 1>& measured,
                                  double sqrt_information, const Eigen::Vector3d& p_c,
                                  double* residuals,
                                  Eigen::Matrix<double, kResiduals, 3>* d_residual_d_pc) {
  static_assert(kResiduals == 2 || kResiduals == 3);
  const double z = p_c.z();
  if (!(z > kMinProjectionDepthM)) return false;
  const double inv_z = 1.0 / z;
  const double u = model.fx * p_c.x() * inv_z + model.cx;
  const double v = model.fy * p_c.y() * inv_z + model.cy;
  residuals[0] = sqrt_information * (measured[0] - u);
  residuals[1] = sqrt_information * (measured[1] - v);
  if constexpr (kResiduals == 3) {
    residuals[2] = sqrt_information * (measured[2] - (u - model.bf * inv_z));
  }
  if (d_residual_d_pc != nullptr) {
    const double inv_z2 = inv_z * inv_z;
    // The residual is measured minus projected, hence the minus signs.
    const double s = -sqrt_information;
    auto& J = *d_residual_d_pc;
    J(0, 0) = s * model.fx * inv_z;
    J(0, 1) = 0;
    J(0, 2) = -s * model.fx * p_c.x() * inv_z2;
    J(1, 0) = 0;
    J(1, 1) = s * model.fy * inv_z;
    J(1, 2) = -s * model.fy * p_c.y() * inv_z2;
    if constexpr (kResiduals == 3) {
      J(2, 0) = J(0, 0);
      J(2, 1) = 0;
      J(2, 2) = J(0, 2) + s * model.bf * inv_z2;
    }
  }
  return true;
}

// d p_c / d delta for the left update of PoseManifold: [I, -[p_c]x].
inline Eigen::Matrix<double, 3, 6> PointTangentJacobian(const Eigen::Vector3d& p_c) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() << 0, p_c.z(), -p_c.y(),  //
      -p_c.z(), 0, p_c.x(),                  //
      p_c.y(), -p_c.x(), 0;
  return J;
}

// Every observation of one pose-only problem (a frame against fixed world points) as a
// single residual block; parameter block: the pose.
//
// One block, because for 2- and 3-row blocks Ceres's per-block bookkeeping (scratch
// space, validity checks, the loss corrector) costs several times the residual itself,
// and tracking solves this problem two to four times a frame.
//
// Ceres applies a loss to a whole block, so each observation's loss is applied here, the
// way Ceres would apply it to a block of its own (see ApplyConcaveLoss). The block's last
// residual carries what that leaves out of the cost, so that the block's cost is the sum
// of the observations' robust costs and the solver takes the same steps as with one block
// per observation.
class PoseOnlyObservationsCost final : public ceres::CostFunction {
 public:
  struct Observation {
    Eigen::Vector3d point_w = Eigen::Vector3d::Zero();
    Eigen::Vector3d measured = Eigen::Vector3d::Zero();  // (u, v, u_right)
    bool stereo = false;  // 3 residuals (u, v, u_right); else 2 (u, v)
    double sqrt_information = 1;
    // Not owned; nullptr: the squared error. Must be concave (rho'' <= 0), as Ceres's
    // robust losses are.
    const ceres::LossFunction* loss = nullptr;
  };

  PoseOnlyObservationsCost(const StereoCameraModel& model, std::vector<Observation> observations);

  // Rows: 2 or 3 per observation in order, then the cost remainder (see above), whose
  // Jacobian row is zero. Fails (Ceres then rejects the step) when any point is not in
  // front of the camera.
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  StereoCameraModel model_;
  std::vector<Observation> observations_;
};

// A residual r and its Jacobian J as Ceres's corrector turns them for a concave loss
// (rho'' <= 0, where Ceres drops the curvature term of Triggs et al.'s correction): both
// scaled by sqrt(rho'(s)), s = |r|^2. Then J^T r is the gradient of rho(s) / 2 and J^T J
// the Gauss-Newton approximation Ceres uses. Returns rho(s) - |scaled r|^2
// (= rho - rho' s >= 0 for a concave loss), the part of the robust cost the scaled
// residual no longer carries. A null loss changes nothing and returns 0. J may have 0
// columns (residual only).
template <int kResiduals, int kColumns>
double ApplyConcaveLoss(const ceres::LossFunction* loss, Eigen::Matrix<double, kResiduals, 1>* r,
                        Eigen::Matrix<double, kResiduals, kColumns>* J) {
  if (loss == nullptr) return 0;
  const double s = r->squaredNorm();
  double rho[3];
  loss->Evaluate(s, rho);
  const double scale = std::sqrt(rho[1]);
  *r *= scale;
  *J *= scale;
  return std::max(0.0, rho[0] - rho[1] * s);
}

// Residual of one observation; parameter blocks: the pose, then the world point.
template <int kResiduals>
class PosePointReprojectionCost final
    : public ceres::SizedCostFunction<kResiduals, kPoseAmbientSize, 3> {
 public:
  PosePointReprojectionCost(const StereoCameraModel& model,
                            const Eigen::Matrix<double, kResiduals, 1>& measured,
                            double information)
      : model_(model), measured_(measured), sqrt_information_(std::sqrt(information)) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0] + 3);
    const Eigen::Map<const Eigen::Vector3d> point_w(parameters[1]);
    const Eigen::Vector3d p_c = q * point_w + t;
    const bool want_jacobians =
        jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
    Eigen::Matrix<double, kResiduals, 3> d_r_d_pc;
    if (!WhitenedReprojectionResidual<kResiduals>(model_, measured_, sqrt_information_, p_c,
                                                  residuals,
                                                  want_jacobians ? &d_r_d_pc : nullptr)) {
      return false;
    }
    if (!want_jacobians) return true;
    if (jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, kResiduals, kPoseAmbientSize, Eigen::RowMajor>> J(
          jacobians[0]);
      J.template leftCols<kPoseTangentSize>() = d_r_d_pc * PointTangentJacobian(p_c);
      J.col(kPoseTangentSize).setZero();
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor>> J(jacobians[1]);
      J = d_r_d_pc * q.toRotationMatrix();
    }
    return true;
  }

 private:
  StereoCameraModel model_;
  Eigen::Matrix<double, kResiduals, 1> measured_;
  double sqrt_information_;
};

// Information-weighted squared reprojection error (the chi2 statistic ORB-SLAM2 tests
// against 5.991 / 7.815), or a negative value when p_c is not in front of the camera.
template <int kResiduals>
double ReprojectionChi2(const StereoCameraModel& model,
                        const Eigen::Matrix<double, kResiduals, 1>& measured, double information,
                        const Eigen::Vector3d& p_c) {
  double residuals[kResiduals];
  if (!WhitenedReprojectionResidual<kResiduals>(model, measured, std::sqrt(information), p_c,
                                                residuals, nullptr)) {
    return -1;
  }
  double chi2 = 0;
  for (double r : residuals) chi2 += r * r;
  return chi2;
}

}  // namespace segslam::slam::internal
