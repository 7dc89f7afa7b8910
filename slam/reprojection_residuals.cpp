#include "slam/reprojection_residuals.h"

#include <algorithm>
#include <utility>

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

PoseOnlyObservationsCost::PoseOnlyObservationsCost(const StereoCameraModel& model,
                                                   std::vector<Observation> observations)
    : model_(model), observations_(std::move(observations)) {
  int residuals = 1;  // the cost remainder
  for (const Observation& o : observations_) residuals += o.stereo ? 3 : 2;
  set_num_residuals(residuals);
  mutable_parameter_block_sizes()->push_back(kPoseAmbientSize);
}

namespace {

// One observation's rows of PoseOnlyObservationsCost: its residuals at `residuals` and,
// when `jacobian` is not null, its Jacobian rows (row-major, kPoseAmbientSize columns).
// Adds the loss's cost remainder to *remainder. False when p_c is not in front.
template <int kResiduals>
bool EvaluateObservation(const StereoCameraModel& model,
                         const PoseOnlyObservationsCost::Observation& o,
                         const Eigen::Vector3d& p_c, double* residuals, double* jacobian,
                         double* remainder) {
  const Eigen::Matrix<double, kResiduals, 1> measured = o.measured.head<kResiduals>();
  Eigen::Matrix<double, kResiduals, 1> r;
  Eigen::Matrix<double, kResiduals, 3> d_r_d_pc;
  Eigen::Matrix<double, kResiduals, 3>* const wanted = jacobian != nullptr ? &d_r_d_pc : nullptr;
  if (!WhitenedReprojectionResidual<kResiduals>(model, measured, o.sqrt_information, p_c,
                                                r.data(), wanted)) {
    return false;
  }
  if (jacobian == nullptr) {
    Eigen::Matrix<double, kResiduals, 0> no_columns;
    *remainder += ApplyConcaveLoss(o.loss, &r, &no_columns);
    std::copy_n(r.data(), kResiduals, residuals);
    return true;
  }
  Eigen::Matrix<double, kResiduals, kPoseTangentSize> J = d_r_d_pc * PointTangentJacobian(p_c);
  *remainder += ApplyConcaveLoss(o.loss, &r, &J);
  std::copy_n(r.data(), kResiduals, residuals);
  // See PoseManifold: the tangent derivative in the first six ambient columns.
  Eigen::Map<Eigen::Matrix<double, kResiduals, kPoseAmbientSize, Eigen::RowMajor>> J_ambient(
      jacobian);
  J_ambient.template leftCols<kPoseTangentSize>() = J;
  J_ambient.col(kPoseTangentSize).setZero();
  return true;
}

}  // namespace

bool PoseOnlyObservationsCost::Evaluate(double const* const* parameters, double* residuals,
                                        double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
  const Eigen::Matrix3d R =
      Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).toRotationMatrix();
  double* jacobian = jacobians != nullptr ? jacobians[0] : nullptr;
  double remainder = 0;
  for (const Observation& o : observations_) {
    const Eigen::Vector3d p_c = R * o.point_w + t;
    const bool ok =
        o.stereo ? EvaluateObservation<3>(model_, o, p_c, residuals, jacobian, &remainder)
                 : EvaluateObservation<2>(model_, o, p_c, residuals, jacobian, &remainder);
    if (!ok) return false;
    const int rows = o.stereo ? 3 : 2;
    residuals += rows;
    if (jacobian != nullptr) jacobian += rows * kPoseAmbientSize;
  }
  // A zero Jacobian row on purpose: Ceres's corrector models a block's robust cost within
  // a step as |r' + J' delta|^2 / 2 with the scaled r' and J', which misses this same
  // remainder as a constant; only the model's change over a step matters to the solver.
  *residuals = std::sqrt(remainder);
  if (jacobian != nullptr) std::fill_n(jacobian, kPoseAmbientSize, 0.0);
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
