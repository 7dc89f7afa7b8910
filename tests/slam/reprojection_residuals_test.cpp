// The analytic Jacobians of the shared Ceres terms, checked against central differences
// taken through the manifold's own Plus (the only product Ceres uses), and the manifold's
// Plus/Minus consistency.
#include "slam/reprojection_residuals.h"

#include <gtest/gtest.h>

namespace segslam::slam::internal {
namespace {

StereoCameraModel TestModel() { return {525, 520, 319.5, 239.5, 525 * 0.08}; }

std::array<double, kPoseAmbientSize> TestPose() {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  T_cw.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, -1, 0.2).normalized()).toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(0.2, -0.1, 0.5);
  std::array<double, kPoseAmbientSize> pose;
  PoseToParameters(T_cw, pose.data());
  return pose;
}

TEST(ReprojectionResidualsTest, MinusInvertsPlus) {
  const PoseManifold manifold;
  const auto x = TestPose();
  const double delta[6] = {0.03, -0.02, 0.05, 0.1, -0.05, 0.02};
  double y[7], recovered[6];
  ASSERT_TRUE(manifold.Plus(x.data(), delta, y));
  ASSERT_TRUE(manifold.Minus(y, x.data(), recovered));
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(recovered[i], delta[i], 1e-12) << i;
  // Plus moves a camera-frame point p_c to Exp(phi) p_c + rho.
  const Eigen::Vector3d point_w(1, 2, 4);
  const Eigen::Vector3d p_c = PoseFromParameters(x.data()) * point_w;
  const Eigen::Vector3d phi(delta[3], delta[4], delta[5]);
  const Eigen::Vector3d expected = Eigen::AngleAxisd(phi.norm(), phi.normalized()) * p_c +
                                   Eigen::Vector3d(delta[0], delta[1], delta[2]);
  EXPECT_LT((PoseFromParameters(y) * point_w - expected).norm(), 1e-12);
}

// Tangent Jacobian as Ceres forms it: the cost's ambient Jacobian times PlusJacobian.
template <int kResiduals>
Eigen::Matrix<double, kResiduals, 6> TangentJacobian(const ceres::CostFunction& cost, double* pose,
                                                     double* point) {
  double residuals[kResiduals];
  Eigen::Matrix<double, kResiduals, 7, Eigen::RowMajor> ambient;
  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> d_point;
  double* parameters[2] = {pose, point};
  double* jacobians[2] = {ambient.data(), d_point.data()};
  EXPECT_TRUE(cost.Evaluate(parameters, residuals, jacobians));
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jacobian;
  PoseManifold().PlusJacobian(pose, plus_jacobian.data());
  return ambient * plus_jacobian;
}

template <int kResiduals>
void ExpectPosePointJacobiansMatchDifferences(
    const Eigen::Matrix<double, kResiduals, 1>& measured) {
  const PosePointReprojectionCost<kResiduals> cost(TestModel(), measured, 1.7);
  auto pose = TestPose();
  Eigen::Vector3d point(0.4, -0.3, 3.0);
  const Eigen::Matrix<double, kResiduals, 6> analytic =
      TangentJacobian<kResiduals>(cost, pose.data(), point.data());

  auto residual_at = [&cost](double* p, double* q) {
    Eigen::Matrix<double, kResiduals, 1> r;
    double* parameters[2] = {p, q};
    EXPECT_TRUE(cost.Evaluate(parameters, r.data(), nullptr));
    return r;
  };
  const PoseManifold manifold;
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) {
    double delta[6] = {0, 0, 0, 0, 0, 0};
    double plus[7], minus[7];
    delta[j] = h;
    manifold.Plus(pose.data(), delta, plus);
    delta[j] = -h;
    manifold.Plus(pose.data(), delta, minus);
    const Eigen::Matrix<double, kResiduals, 1> numeric =
        (residual_at(plus, point.data()) - residual_at(minus, point.data())) / (2 * h);
    EXPECT_LT((numeric - analytic.col(j)).norm(), 1e-5 * (1 + numeric.norm()))
        << "pose column " << j;
  }

  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> d_point;
  Eigen::Matrix<double, kResiduals, 7, Eigen::RowMajor> ignored;
  double residuals[kResiduals];
  double* parameters[2] = {pose.data(), point.data()};
  double* jacobians[2] = {ignored.data(), d_point.data()};
  ASSERT_TRUE(cost.Evaluate(parameters, residuals, jacobians));
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d plus = point, minus = point;
    plus[j] += h;
    minus[j] -= h;
    const Eigen::Matrix<double, kResiduals, 1> numeric =
        (residual_at(pose.data(), plus.data()) - residual_at(pose.data(), minus.data())) / (2 * h);
    EXPECT_LT((numeric - d_point.col(j)).norm(), 1e-5 * (1 + numeric.norm()))
        << "point column " << j;
  }
}

TEST(ReprojectionResidualsTest, MonoJacobiansMatchCentralDifferences) {
  ExpectPosePointJacobiansMatchDifferences<2>(Eigen::Vector2d(300, 200));
}

TEST(ReprojectionResidualsTest, StereoJacobiansMatchCentralDifferences) {
  ExpectPosePointJacobiansMatchDifferences<3>(Eigen::Vector3d(300, 200, 290));
}

TEST(ReprojectionResidualsTest, ResidualIsWhitenedMeasuredMinusProjected) {
  const StereoCameraModel model = TestModel();
  const Eigen::Vector3d p_c(0.5, -0.25, 2.0);
  // u = 525 * 0.25 + 319.5 = 450.75, v = 520 * -0.125 + 239.5 = 174.5, u_r = u - 42 / 2.
  const Eigen::Vector3d measured(451.75, 172.5, 429.75 + 3.0);
  double r[3];
  ASSERT_TRUE(WhitenedReprojectionResidual<3>(model, measured, 2.0, p_c, r, nullptr));
  EXPECT_NEAR(r[0], 2.0, 1e-9);
  EXPECT_NEAR(r[1], -4.0, 1e-9);
  EXPECT_NEAR(r[2], 6.0, 1e-9);
  EXPECT_NEAR(ReprojectionChi2<3>(model, measured, 4.0, p_c), 4 + 16 + 36, 1e-9);
  EXPECT_LT(ReprojectionChi2<2>(model, Eigen::Vector2d(1, 1), 1.0, Eigen::Vector3d(0, 0, -1)), 0);
}

}  // namespace
}  // namespace segslam::slam::internal
