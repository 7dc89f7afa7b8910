#include "slam/reprojection_residuals.h"

#include <algorithm>

namespace segslam::slam::internal {
namespace {

Eigen::Quaterniond QuaternionFromRotationVector(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  // Below this angle sin(a/2)/a = 1/2 to double precision, and dividing by the angle
  // would amplify rounding.
  if (angle < 1e-10) {
    return Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

}  // namespace

void PoseToParameters(const Eigen::Isometry3d& T_cw, double* parameters) {
  Eigen::Map<Eigen::Vector3d> t(parameters);
  Eigen::Map<Eigen::Quaterniond> q(parameters + 3);
  t = T_cw.translation();
  q = Eigen::Quaterniond(T_cw.rotation()).normalized();
}

Eigen::Isometry3d PoseFromParameters(const double* parameters) {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  T_cw.linear() =
      Eigen::Map<const Eigen::Quaterniond>(parameters + 3).normalized().toRotationMatrix();
  T_cw.translation() = Eigen::Map<const Eigen::Vector3d>(parameters);
  return T_cw;
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Vector3d> t(x);
  const Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  const Eigen::Map<const Eigen::Vector3d> rho(delta);
  const Eigen::Quaterniond dq =
      QuaternionFromRotationVector(Eigen::Map<const Eigen::Vector3d>(delta + 3));
  Eigen::Map<Eigen::Vector3d> t_out(x_plus_delta);
  Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta + 3);
  t_out = dq * t + rho;
  q_out = (dq * q).normalized();
  return true;
}

bool PoseManifold::PlusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, kPoseAmbientSize, kPoseTangentSize, Eigen::RowMajor>> J(
      jacobian);
  J.setZero();
  J.topRows<kPoseTangentSize>().setIdentity();
  return true;
}

bool PoseManifold::RightMultiplyByPlusJacobian(const double* /*x*/, int num_rows,
                                               const double* ambient_matrix,
                                               double* tangent_matrix) const {
  for (int row = 0; row < num_rows; ++row) {
    std::copy_n(ambient_matrix + row * kPoseAmbientSize, kPoseTangentSize,
                tangent_matrix + row * kPoseTangentSize);
  }
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::Map<const Eigen::Vector3d> t_x(x);
  const Eigen::Map<const Eigen::Quaterniond> q_x(x + 3);
  const Eigen::Map<const Eigen::Vector3d> t_y(y);
  const Eigen::Map<const Eigen::Quaterniond> q_y(y + 3);
  Eigen::Quaterniond dq = (q_y * q_x.conjugate()).normalized();
  // q and -q are the same rotation; w >= 0 picks the rotation vector of angle <= pi.
  if (dq.w() < 0) dq.coeffs() = -dq.coeffs();
  const Eigen::AngleAxisd angle_axis(dq);
  const Eigen::Vector3d phi = angle_axis.angle() * angle_axis.axis();
  Eigen::Map<Eigen::Vector3d> rho(y_minus_x);
  Eigen::Map<Eigen::Vector3d> phi_out(y_minus_x + 3);
  rho = t_y - dq * t_x;
  phi_out = phi;
  return true;
}

bool PoseManifold::MinusJacobian(const double* /*x*/, double* jacobian) const {
  // The left inverse of PlusJacobian, in the same tangent-column convention.
  Eigen::Map<Eigen::Matrix<double, kPoseTangentSize, kPoseAmbientSize, Eigen::RowMajor>> J(
      jacobian);
  J.setZero();
  J.leftCols<kPoseTangentSize>().setIdentity();
  return true;
}

}  // namespace segslam::slam::internal
