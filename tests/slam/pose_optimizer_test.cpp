#include "slam/pose_optimizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.h"
#include "tests/slam/pose_test_util.h"

namespace segslam::slam {
namespace {

using testing::CentreError;
using testing::kBaseline;
using testing::MakePose;
using testing::RotationErrorDeg;

// fy differs from fx so that a mix-up of the two shows.
PinholeCamera TestCamera() { return testing::TestCamera(/*fy=*/520); }

enum class Kind { kMono, kStereo, kMixed };

struct Scene {
  Eigen::Isometry3d T_cw_true;
  std::vector<PoseObservation> observations;
};

// Points seen at uniformly random pixels, 1-8 m deep, by a camera at T_cw_true;
// observations are exact projections plus Gaussian pixel noise of `noise_px`.
Scene MakeScene(int count, Kind kind, double noise_px, unsigned seed) {
  const PinholeCamera camera = TestCamera();
  Scene scene;
  scene.T_cw_true = MakePose({0.2, 1, 0.1}, 25, {0.4, -0.3, 1.2});
  const Eigen::Isometry3d T_wc = scene.T_cw_true.inverse();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(20, 620), v(20, 460), depth(1, 8);
  std::normal_distribution<double> noise(0, 1);
  const double bf = camera.fx * kBaseline;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d pixel(u(rng), v(rng));
    const double z = depth(rng);
    PoseObservation o;
    o.point_w = T_wc * camera.BackProject(pixel, z);
    o.pixel = pixel + noise_px * Eigen::Vector2d(noise(rng), noise(rng));
    const bool stereo = kind == Kind::kStereo || (kind == Kind::kMixed && i % 2 == 0);
    if (stereo) o.right_u = pixel.x() - bf / z + noise_px * noise(rng);
    o.information = 1.0 / std::pow(1.44, i % 3);  // levels 0-2
    scene.observations.push_back(o);
  }
  return scene;
}

PoseOptimizerOptions Options() {
  PoseOptimizerOptions options;
  options.bf = TestCamera().fx * kBaseline;
  return options;
}

Eigen::Isometry3d Perturbed(const Eigen::Isometry3d& T_cw) {
  // 10 cm and 5 degrees.
  return MakePose({1, -2, 0.5}, 5, Eigen::Vector3d(0.06, 0.08, 0.0)) * T_cw;
}

TEST(PoseOptimizerTest, RecoversExactPoseFromPerturbedStart) {
  for (Kind kind : {Kind::kMixed, Kind::kMono, Kind::kStereo}) {
    const Scene scene = MakeScene(200, kind, 0.0, 1);
    const PoseOptimizationResult r =
        OptimizePose(Perturbed(scene.T_cw_true), scene.observations, TestCamera(), Options());
    EXPECT_TRUE(r.converged);
    EXPECT_LT(CentreError(r.T_cw, scene.T_cw_true), 1e-3) << static_cast<int>(kind);
    EXPECT_LT(RotationErrorDeg(r.T_cw, scene.T_cw_true), 0.01) << static_cast<int>(kind);
    EXPECT_EQ(r.num_inliers, 200);
    ASSERT_EQ(r.inlier.size(), 200u);
    for (bool in : r.inlier) EXPECT_TRUE(in);
  }
}

TEST(PoseOptimizerTest, NoisyObservationsGiveAccuratePose) {
  const Scene scene = MakeScene(300, Kind::kMixed, 0.7, 2);
  const PoseOptimizationResult r =
      OptimizePose(Perturbed(scene.T_cw_true), scene.observations, TestCamera(), Options());
  EXPECT_TRUE(r.converged);
  EXPECT_LT(CentreError(r.T_cw, scene.T_cw_true), 0.01);
  EXPECT_LT(RotationErrorDeg(r.T_cw, scene.T_cw_true), 0.1);
  // Most of the noise is well inside the 95% chi2 gates.
  EXPECT_GT(r.num_inliers, 270);
}

TEST(PoseOptimizerTest, GrossOutliersAreFlaggedAndDoNotBiasThePose) {
  Scene scene = MakeScene(400, Kind::kMixed, 0.3, 3);
  std::mt19937 rng(33);
  std::uniform_real_distribution<double> offset(15, 80);
  std::vector<bool> corrupted(scene.observations.size(), false);
  for (size_t i = 0; i < scene.observations.size(); i += 10) {
    for (size_t j : {i, i + 3, i + 7}) {  // 30%
      PoseObservation& o = scene.observations[j];
      const double du = offset(rng) * (j % 2 ? 1 : -1);
      o.pixel += Eigen::Vector2d(du, offset(rng));
      if (std::isfinite(o.right_u)) o.right_u += du;
      corrupted[j] = true;
    }
  }
  const PoseOptimizationResult r =
      OptimizePose(Perturbed(scene.T_cw_true), scene.observations, TestCamera(), Options());
  EXPECT_TRUE(r.converged);
  EXPECT_LT(CentreError(r.T_cw, scene.T_cw_true), 0.01);
  EXPECT_LT(RotationErrorDeg(r.T_cw, scene.T_cw_true), 0.1);
  int outliers_flagged = 0, good_kept = 0, good = 0;
  for (size_t i = 0; i < corrupted.size(); ++i) {
    if (corrupted[i]) {
      outliers_flagged += r.inlier[i] ? 0 : 1;
    } else {
      ++good;
      good_kept += r.inlier[i] ? 1 : 0;
    }
  }
  EXPECT_EQ(outliers_flagged, 120);
  EXPECT_GE(good_kept, good * 95 / 100);
  EXPECT_EQ(r.num_inliers, good_kept);
}

// A round that converges and keeps every observation it used ends the optimisation; one
// that changes the set is followed by another on the new set.
TEST(PoseOptimizerTest, StopsOnceARoundKeepsTheObservationsItUsed) {
  const Scene clean = MakeScene(200, Kind::kMixed, 0.0, 4);
  const PoseOptimizationResult r =
      OptimizePose(Perturbed(clean.T_cw_true), clean.observations, TestCamera(), Options());
  EXPECT_EQ(r.rounds_run, 1);
  EXPECT_EQ(r.num_inliers, 200);
  EXPECT_LT(CentreError(r.T_cw, clean.T_cw_true), 1e-3);

  Scene corrupted = MakeScene(200, Kind::kMixed, 0.3, 4);
  for (size_t i = 0; i < corrupted.observations.size(); i += 5) {
    corrupted.observations[i].pixel += Eigen::Vector2d(40, -30);
  }
  const PoseOptimizationResult o =
      OptimizePose(Perturbed(corrupted.T_cw_true), corrupted.observations, TestCamera(), Options());
  EXPECT_GE(o.rounds_run, 2);  // the first round uses the outliers, the second does not
  EXPECT_LE(o.rounds_run, Options().rounds);
  EXPECT_LE(o.num_inliers, 160);
  EXPECT_LT(CentreError(o.T_cw, corrupted.T_cw_true), 0.01);
}

TEST(PoseOptimizerTest, InformationScalesTheChi2Gate) {
  // A 2-pixel error gives chi2 4 at information 1 (inside 5.991) but 8 at information 2.
  for (double information : {1.0, 2.0}) {
    Scene scene = MakeScene(300, Kind::kMono, 0.0, 4);
    scene.observations[0].pixel.x() += 2.0;
    scene.observations[0].information = information;
    const PoseOptimizationResult r =
        OptimizePose(scene.T_cw_true, scene.observations, TestCamera(), Options());
    EXPECT_EQ(r.inlier[0], information == 1.0) << information;
  }
}

TEST(PoseOptimizerTest, PointsBehindTheCameraAreOutliers) {
  Scene scene = MakeScene(100, Kind::kMixed, 0.0, 5);
  const Eigen::Isometry3d T_wc = scene.T_cw_true.inverse();
  scene.observations[5].point_w = T_wc * Eigen::Vector3d(0.1, 0.2, -3.0);
  scene.observations[6].point_w = T_wc * Eigen::Vector3d(-0.4, 0.0, -0.5);
  const PoseOptimizationResult r =
      OptimizePose(Perturbed(scene.T_cw_true), scene.observations, TestCamera(), Options());
  EXPECT_FALSE(r.inlier[5]);
  EXPECT_FALSE(r.inlier[6]);
  EXPECT_EQ(r.num_inliers, 98);
  EXPECT_LT(CentreError(r.T_cw, scene.T_cw_true), 1e-3);
}

TEST(PoseOptimizerTest, EmptyOrTooFewObservationsReturnTheInitialPose) {
  const Eigen::Isometry3d initial = MakePose({0, 0, 1}, 10, {1, 2, 3});
  const PoseOptimizationResult empty = OptimizePose(initial, {}, TestCamera(), Options());
  EXPECT_TRUE(empty.T_cw.isApprox(initial));
  EXPECT_EQ(empty.num_inliers, 0);
  EXPECT_TRUE(empty.inlier.empty());
  EXPECT_FALSE(empty.converged);

  Scene scene = MakeScene(2, Kind::kMono, 0.0, 6);
  const PoseOptimizationResult two =
      OptimizePose(scene.T_cw_true, scene.observations, TestCamera(), Options());
  EXPECT_FALSE(two.converged);
  EXPECT_TRUE(two.T_cw.isApprox(scene.T_cw_true));
}

TEST(PoseOptimizerTest, RejectsInvalidInput) {
  Scene scene = MakeScene(10, Kind::kStereo, 0.0, 7);
  PoseOptimizerOptions no_bf = Options();
  no_bf.bf = 0;
  EXPECT_THROW(OptimizePose(scene.T_cw_true, scene.observations, TestCamera(), no_bf), Error);
  EXPECT_THROW(OptimizePose(scene.T_cw_true, scene.observations, PinholeCamera{}, Options()),
               Error);
  scene.observations[3].information = 0;
  EXPECT_THROW(OptimizePose(scene.T_cw_true, scene.observations, TestCamera(), Options()), Error);
  scene.observations[3].information = 1;
  scene.observations[4].point_w.x() = std::nan("");
  EXPECT_THROW(OptimizePose(scene.T_cw_true, scene.observations, TestCamera(), Options()), Error);
}

}  // namespace
}  // namespace segslam::slam
