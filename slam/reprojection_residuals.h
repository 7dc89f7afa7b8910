// Ceres building blocks shared by the pose-only optimizer and local bundle adjustment:
// a pose parameterization with a left-multiplied tangent update, and the reprojection
// residuals of ORB-SLAM2 (monocular pixel, or RGB-D as a virtual stereo triple
// (u, v, u_right) with u_right = u - bf / depth).
//
// Internal to slam/: it includes Ceres, which segslam_slam links privately.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

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

// Residual of one observation of a fixed world point; parameter block: the pose.
template <int kResiduals>
class PoseOnlyReprojectionCost final
    : public ceres::SizedCostFunction<kResiduals, kPoseAmbientSize> {
 public:
  PoseOnlyReprojectionCost(const StereoCameraModel& model,
                           const Eigen::Matrix<double, kResiduals, 1>& measured, double information,
                           const Eigen::Vector3d& point_w)
      : model_(model),
        measured_(measured),
        sqrt_information_(std::sqrt(information)),
        point_w_(point_w) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0] + 3);
    const Eigen::Vector3d p_c = q * point_w_ + t;
    if (jacobians == nullptr || jacobians[0] == nullptr) {
      return WhitenedReprojectionResidual<kResiduals>(model_, measured_, sqrt_information_, p_c,
                                                      residuals, nullptr);
    }
    Eigen::Matrix<double, kResiduals, 3> d_r_d_pc;
    if (!WhitenedReprojectionResidual<kResiduals>(model_, measured_, sqrt_information_, p_c,
                                                  residuals, &d_r_d_pc)) {
      return false;
    }
    Eigen::Map<Eigen::Matrix<double, kResiduals, kPoseAmbientSize, Eigen::RowMajor>> J(
        jacobians[0]);
    J.template leftCols<kPoseTangentSize>() = d_r_d_pc * PointTangentJacobian(p_c);
    J.col(kPoseTangentSize).setZero();
    return true;
  }

 private:
  StereoCameraModel model_;
  Eigen::Matrix<double, kResiduals, 1> measured_;
  double sqrt_information_;
  Eigen::Vector3d point_w_;
};

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
