// The analytic Jacobians of the shared Ceres terms, checked against central differences
// taken through the manifold's own Plus (the only product Ceres uses), the robust cost of
// the pose-only observations block, and the manifold's Plus/Minus consistency.
#include "slam/reprojection_residuals.h"

#include <ceres/loss_function.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace segslam::slam::internal {
namespace {

StereoCameraModel TestModel() { return {525, 520, 319.5, 239.5, 525 * 0.08}; }

using Pose = std::array<double, kPoseAmbientSize>;

Pose TestPose() {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  T_cw.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, -1, 0.2).normalized()).toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(0.2, -0.1, 0.5);
  Pose pose;
  PoseToParameters(T_cw, pose.data());
  return pose;
}

// The pose moved by +h and by -h along tangent direction j, through the manifold's Plus.
std::pair<Pose, Pose> TangentSteps(const Pose& pose, int j, double h) {
  double delta[6] = {0, 0, 0, 0, 0, 0};
  Pose plus, minus;
  delta[j] = h;
  PoseManifold().Plus(pose.data(), delta, plus.data());
  delta[j] = -h;
  PoseManifold().Plus(pose.data(), delta, minus.data());
  return {plus, minus};
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

// Two stereo and two monocular observations of points in front of TestPose(); the second
// of each kind is far off (well outside a Huber loss of delta 2), the others close.
std::vector<PoseOnlyObservationsCost::Observation> MixedObservations(
    const ceres::LossFunction* loss) {
  const Eigen::Isometry3d T_cw = PoseFromParameters(TestPose().data());
  const StereoCameraModel model = TestModel();
  std::vector<PoseOnlyObservationsCost::Observation> observations;
  const Eigen::Vector3d points_c[] = {
      {0.4, -0.3, 3.0}, {-1.0, 0.5, 5.0}, {0.2, 0.6, 2.0}, {1.1, -0.2, 7.0}};
  const Eigen::Vector3d offsets[] = {{0.7, -0.4, 0.9}, {30, -12, 25}, {-0.5, 0.3, 0}, {-20, 9, 0}};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d& p_c = points_c[i];
    const double u = model.fx * p_c.x() / p_c.z() + model.cx;
    const double v = model.fy * p_c.y() / p_c.z() + model.cy;
    PoseOnlyObservationsCost::Observation o;
    o.point_w = T_cw.inverse() * p_c;
    o.stereo = i < 2;
    o.measured = Eigen::Vector3d(u, v, u - model.bf / p_c.z()) + offsets[i];
    o.sqrt_information = i % 2 == 0 ? 1.0 : 1 / 1.2;
    o.loss = loss;
    observations.push_back(o);
  }
  return observations;
}

// One observation's whitened residual at T_cw (third entry 0 for a monocular one).
Eigen::Vector3d ObservationResidual(const PoseOnlyObservationsCost::Observation& o,
                                    const Eigen::Isometry3d& T_cw) {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  const Eigen::Vector3d p_c = T_cw * o.point_w;
  const bool in_front =
      o.stereo ? WhitenedReprojectionResidual<3>(TestModel(), o.measured, o.sqrt_information,
                                                 p_c, r.data(), nullptr)
               : WhitenedReprojectionResidual<2>(TestModel(), Eigen::Vector2d(o.measured.head<2>()),
                                                 o.sqrt_information, p_c, r.data(), nullptr);
  EXPECT_TRUE(in_front);
  return r;
}

// Half the block's squared norm: the cost Ceres minimises.
double HalfSquaredNorm(const ceres::CostFunction& cost, const double* pose) {
  Eigen::VectorXd r(cost.num_residuals());
  const double* parameters[1] = {pose};
  EXPECT_TRUE(cost.Evaluate(parameters, r.data(), nullptr));
  return 0.5 * r.squaredNorm();
}

TEST(ReprojectionResidualsTest, ObservationsBlockWithoutLossStacksTheWhitenedResiduals) {
  const auto observations = MixedObservations(nullptr);
  const PoseOnlyObservationsCost cost(TestModel(), observations);
  ASSERT_EQ(cost.num_residuals(), 3 + 3 + 2 + 2 + 1);
  auto pose = TestPose();
  Eigen::VectorXd r(cost.num_residuals());
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J(cost.num_residuals(), 7);
  const double* parameters[1] = {pose.data()};
  double* jacobians[1] = {J.data()};
  ASSERT_TRUE(cost.Evaluate(parameters, r.data(), jacobians));
  const Eigen::Isometry3d T_cw = PoseFromParameters(pose.data());
  int row = 0;
  for (const auto& o : observations) {
    const Eigen::Vector3d expected = ObservationResidual(o, T_cw);
    const int rows = o.stereo ? 3 : 2;
    for (int k = 0; k < rows; ++k) EXPECT_NEAR(r[row + k], expected[k], 1e-12) << row + k;
    row += rows;
  }
  EXPECT_EQ(r[row], 0.0);  // no loss, no remainder
  EXPECT_EQ(J.row(row).norm(), 0.0);

  // Each row's tangent Jacobian against central differences through the manifold.
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) {
    const auto [plus, minus] = TangentSteps(pose, j, h);
    Eigen::VectorXd r_plus(cost.num_residuals()), r_minus(cost.num_residuals());
    const double* at_plus[1] = {plus.data()};
    const double* at_minus[1] = {minus.data()};
    ASSERT_TRUE(cost.Evaluate(at_plus, r_plus.data(), nullptr));
    ASSERT_TRUE(cost.Evaluate(at_minus, r_minus.data(), nullptr));
    const Eigen::VectorXd numeric = (r_plus - r_minus) / (2 * h);
    EXPECT_LT((numeric - J.col(j)).norm(), 1e-5 * (1 + numeric.norm())) << "column " << j;
  }
  EXPECT_EQ(J.col(6).norm(), 0.0);
}

// With a Huber loss the block must cost what one block per observation with the loss
// would (the sum of rho / 2), and J^T r must be that cost's gradient: the two things the
// solver's steps depend on besides the Gauss-Newton approximation of the Hessian.
TEST(ReprojectionResidualsTest, ObservationsBlockWithHuberLossCostsTheSumOfRobustCosts) {
  const ceres::HuberLoss huber(2.0);
  const auto observations = MixedObservations(&huber);
  const PoseOnlyObservationsCost cost(TestModel(), observations);
  auto pose = TestPose();

  auto robust_cost = [&](const double* at) {
    const Eigen::Isometry3d T_cw = PoseFromParameters(at);
    double total = 0;
    for (const auto& o : observations) {
      const double s = ObservationResidual(o, T_cw).squaredNorm();
      // Huber with delta 2: s inside 4, else 2 * 2 * sqrt(s) - 4.
      total += 0.5 * (s <= 4 ? s : 4 * std::sqrt(s) - 4);
    }
    return total;
  };
  const double expected = robust_cost(pose.data());
  EXPECT_NEAR(HalfSquaredNorm(cost, pose.data()), expected, 1e-9 * expected);

  Eigen::VectorXd r(cost.num_residuals());
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J(cost.num_residuals(), 7);
  const double* parameters[1] = {pose.data()};
  double* jacobians[1] = {J.data()};
  ASSERT_TRUE(cost.Evaluate(parameters, r.data(), jacobians));
  EXPECT_GT(r[cost.num_residuals() - 1], 0.0);  // the far observations leave a remainder
  const Eigen::VectorXd gradient = J.leftCols<6>().transpose() * r;
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) {
    const auto [plus, minus] = TangentSteps(pose, j, h);
    const double numeric = (robust_cost(plus.data()) - robust_cost(minus.data())) / (2 * h);
    EXPECT_NEAR(gradient[j], numeric, 1e-5 * (1 + std::abs(numeric))) << "column " << j;
  }
}

TEST(ReprojectionResidualsTest, ObservationsBlockFailsWhenAPointIsBehindTheCamera) {
  auto observations = MixedObservations(nullptr);
  const Eigen::Isometry3d T_cw = PoseFromParameters(TestPose().data());
  observations[2].point_w = T_cw.inverse() * Eigen::Vector3d(0.1, 0.1, -2.0);
  const PoseOnlyObservationsCost cost(TestModel(), observations);
  const auto pose = TestPose();
  Eigen::VectorXd r(cost.num_residuals());
  const double* parameters[1] = {pose.data()};
  EXPECT_FALSE(cost.Evaluate(parameters, r.data(), nullptr));
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
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) {
    auto [plus, minus] = TangentSteps(pose, j, h);
    const Eigen::Matrix<double, kResiduals, 1> numeric =
        (residual_at(plus.data(), point.data()) - residual_at(minus.data(), point.data())) /
        (2 * h);
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
