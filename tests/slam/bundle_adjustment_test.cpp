#include "slam/bundle_adjustment.h"

#include <gtest/gtest.h>

#include <algorithm>
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
using testing::TestCamera;

struct Scene {
  std::vector<Eigen::Isometry3d> T_cw_true;
  std::vector<Eigen::Vector3d> points_true;
  std::vector<BaObservation> observations;

  // Points that observations determine: two views, or one with depth. The others are
  // either unobserved (left alone) or free along a single viewing ray.
  std::vector<bool> Determined() const {
    std::vector<int> views(points_true.size(), 0);
    std::vector<bool> has_depth(points_true.size(), false);
    for (const BaObservation& o : observations) {
      ++views[o.point];
      if (std::isfinite(o.right_u)) has_depth[o.point] = true;
    }
    std::vector<bool> determined(points_true.size());
    for (size_t p = 0; p < determined.size(); ++p) determined[p] = views[p] >= 2 || has_depth[p];
    return determined;
  }
};

// A camera moving sideways along x (15 cm steps, yawing slightly) in front of points
// 3-7 m away; every point seen inside the image is observed exactly. Points with an
// even index have depth (virtual stereo), the others are monocular.
Scene MakeScene(int keyframes, int points, unsigned seed) {
  const PinholeCamera camera = TestCamera();
  const double bf = camera.fx * kBaseline;
  Scene scene;
  std::mt19937 rng(seed);
  for (int k = 0; k < keyframes; ++k) {
    const Eigen::Isometry3d T_wc = Eigen::Translation3d(0.15 * k, 0.02 * k, 0.0) *
                                   MakePose({0, 1, 0.1}, 1.5 * k - 4, {0, 0, 0});
    scene.T_cw_true.push_back(T_wc.inverse());
  }
  std::uniform_real_distribution<double> x(-2.5, 3.5), y(-1.8, 1.8), z(3, 7);
  for (int p = 0; p < points; ++p) scene.points_true.emplace_back(x(rng), y(rng), z(rng));
  for (int p = 0; p < points; ++p) {
    for (int k = 0; k < keyframes; ++k) {
      const Eigen::Vector3d p_c = scene.T_cw_true[k] * scene.points_true[p];
      if (p_c.z() <= 0.1) continue;
      const Eigen::Vector2d pixel = camera.Project(p_c);
      if (!camera.InImage(pixel)) continue;
      BaObservation o;
      o.keyframe = k;
      o.point = p;
      o.pixel = pixel;
      if (p % 2 == 0) o.right_u = pixel.x() - bf / p_c.z();
      o.information = 1.0 / std::pow(1.44, (p + k) % 3);
      scene.observations.push_back(o);
    }
  }
  return scene;
}

BundleAdjustmentOptions Options() {
  BundleAdjustmentOptions options;
  options.bf = TestCamera().fx * kBaseline;
  return options;
}

struct Start {
  std::vector<BaKeyframe> keyframes;
  std::vector<Eigen::Vector3d> points;
};

// Keyframes 0 and 1 fixed at the truth; the others moved by about 5 cm and 1 degree;
// every point moved by 5 cm in a random direction.
Start PerturbedStart(const Scene& scene, unsigned seed, int num_fixed = 2) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0, 1);
  Start start;
  for (size_t k = 0; k < scene.T_cw_true.size(); ++k) {
    BaKeyframe kf;
    kf.fixed = static_cast<int>(k) < num_fixed;
    kf.T_cw = scene.T_cw_true[k];
    if (!kf.fixed) {
      const Eigen::Vector3d axis(gauss(rng), gauss(rng), gauss(rng));
      const Eigen::Vector3d shift =
          Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized() * 0.05;
      kf.T_cw = MakePose(axis, 1.0, shift) * kf.T_cw;
    }
    start.keyframes.push_back(kf);
  }
  for (const Eigen::Vector3d& p : scene.points_true) {
    start.points.push_back(p +
                           Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized() * 0.05);
  }
  return start;
}

TEST(BundleAdjustmentTest, ExactObservationsBringPosesAndPointsBackToTruth) {
  const Scene scene = MakeScene(7, 300, 1);
  const Start start = PerturbedStart(scene, 11);
  const BundleAdjustmentResult r = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options());
  ASSERT_EQ(r.T_cw.size(), 7u);
  ASSERT_EQ(r.points_w.size(), 300u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_TRUE(r.T_cw[k].matrix() == start.keyframes[k].T_cw.matrix()) << "fixed keyframe " << k;
  }
  for (int k = 2; k < 7; ++k) {
    EXPECT_LT(CentreError(r.T_cw[k], scene.T_cw_true[k]), 1e-4) << "keyframe " << k;
    EXPECT_LT(RotationErrorDeg(r.T_cw[k], scene.T_cw_true[k]), 1e-3) << "keyframe " << k;
  }
  double worst_point_error = 0;
  const std::vector<bool> determined = scene.Determined();
  EXPECT_GT(std::count(determined.begin(), determined.end(), true), 200);
  for (size_t p = 0; p < scene.points_true.size(); ++p) {
    if (!determined[p]) continue;
    worst_point_error = std::max(worst_point_error, (r.points_w[p] - scene.points_true[p]).norm());
  }
  EXPECT_LT(worst_point_error, 1e-3);
  EXPECT_TRUE(std::all_of(r.observation_inlier.begin(), r.observation_inlier.end(),
                          [](bool in) { return in; }));
  EXPECT_GT(r.initial_cost, 1000.0);  // 5 cm at 3-7 m is ~5-9 px per observation
  EXPECT_LT(r.final_cost, 1e-8);
}

TEST(BundleAdjustmentTest, CorruptedObservationsAreFlaggedAsOutliers) {
  Scene scene = MakeScene(6, 250, 2);
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> offset(12, 40);
  std::vector<bool> corrupted(scene.observations.size(), false);
  for (size_t i = 7; i < scene.observations.size(); i += 20) {  // 5%
    BaObservation& o = scene.observations[i];
    const double du = offset(rng);
    o.pixel += Eigen::Vector2d(du, -offset(rng));
    if (std::isfinite(o.right_u)) o.right_u += du;
    corrupted[i] = true;
  }
  const Start start = PerturbedStart(scene, 12);
  const BundleAdjustmentResult r = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options());
  int flagged = 0, corrupted_count = 0, good_rejected = 0;
  for (size_t i = 0; i < corrupted.size(); ++i) {
    if (corrupted[i]) {
      ++corrupted_count;
      flagged += r.observation_inlier[i] ? 0 : 1;
    } else {
      good_rejected += r.observation_inlier[i] ? 0 : 1;
    }
  }
  EXPECT_EQ(flagged, corrupted_count);
  EXPECT_LE(good_rejected, static_cast<int>(corrupted.size() / 100));
  for (int k = 2; k < 6; ++k) {
    EXPECT_LT(CentreError(r.T_cw[k], scene.T_cw_true[k]), 2e-3) << "keyframe " << k;
    EXPECT_LT(RotationErrorDeg(r.T_cw[k], scene.T_cw_true[k]), 0.02) << "keyframe " << k;
  }
}

TEST(BundleAdjustmentTest, PointBehindACameraIsAnOutlierThere) {
  Scene scene = MakeScene(5, 100, 3);
  Start start = PerturbedStart(scene, 13);
  // Observation 0's point is placed behind its keyframe's camera.
  const BaObservation& first = scene.observations[0];
  const Eigen::Isometry3d T_wc = start.keyframes[first.keyframe].T_cw.inverse();
  start.points[first.point] = T_wc * Eigen::Vector3d(0.1, 0.1, -2.0);
  const BundleAdjustmentResult r = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options());
  EXPECT_FALSE(r.observation_inlier[0]);
  for (int k = 2; k < 5; ++k) EXPECT_LT(CentreError(r.T_cw[k], scene.T_cw_true[k]), 1e-3);
}

TEST(BundleAdjustmentTest, AllKeyframesFixedRefinesPointsOnly) {
  const Scene scene = MakeScene(5, 120, 4);
  const Start start = PerturbedStart(scene, 14, /*num_fixed=*/5);
  const BundleAdjustmentResult r = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options());
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(r.T_cw[k].matrix() == start.keyframes[k].T_cw.matrix());
  const std::vector<bool> determined = scene.Determined();
  for (size_t p = 0; p < scene.points_true.size(); ++p) {
    if (!determined[p]) continue;
    EXPECT_LT((r.points_w[p] - scene.points_true[p]).norm(), 1e-4) << "point " << p;
  }
}

// A loaded map's points held constant anchor keyframes that are all free: the constant
// points come back bit for bit, and the keyframes and the free points come back to the
// truth the constant points were placed at (without them, nothing fixes the gauge).
TEST(BundleAdjustmentTest, ConstantPointsAnchorFreeKeyframesAndStayWhereTheyAre) {
  const Scene scene = MakeScene(6, 240, 7);
  Start start = PerturbedStart(scene, 17, /*num_fixed=*/0);
  std::vector<bool> constant(scene.points_true.size());
  for (size_t p = 0; p < constant.size(); ++p) {
    constant[p] = p % 3 == 0;
    if (constant[p]) start.points[p] = scene.points_true[p];
  }
  const BundleAdjustmentResult r = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options(), constant);
  for (size_t p = 0; p < constant.size(); ++p) {
    if (constant[p]) {
      EXPECT_TRUE(r.points_w[p] == start.points[p]) << "constant point " << p;
    }
  }
  for (int k = 0; k < 6; ++k) {
    EXPECT_LT(CentreError(r.T_cw[k], scene.T_cw_true[k]), 1e-4) << "keyframe " << k;
    EXPECT_LT(RotationErrorDeg(r.T_cw[k], scene.T_cw_true[k]), 1e-3) << "keyframe " << k;
  }
  const std::vector<bool> determined = scene.Determined();
  int free_checked = 0;
  for (size_t p = 0; p < scene.points_true.size(); ++p) {
    if (constant[p] || !determined[p]) continue;
    EXPECT_LT((r.points_w[p] - scene.points_true[p]).norm(), 1e-4) << "free point " << p;
    ++free_checked;
  }
  EXPECT_GT(free_checked, 100);
}

// Every point constant: each keyframe is a pose fitted to fixed points, as localization's.
TEST(BundleAdjustmentTest, AllPointsConstantRefinesKeyframesOnly) {
  const Scene scene = MakeScene(4, 150, 8);
  const Start start = PerturbedStart(scene, 18, /*num_fixed=*/0);
  const std::vector<bool> constant(scene.points_true.size(), true);
  const BundleAdjustmentResult r = RunBundleAdjustment(TestCamera(), start.keyframes, scene.points_true,
                                                       scene.observations, Options(), constant);
  for (size_t p = 0; p < scene.points_true.size(); ++p) EXPECT_TRUE(r.points_w[p] == scene.points_true[p]);
  for (int k = 0; k < 4; ++k) {
    EXPECT_LT(CentreError(r.T_cw[k], scene.T_cw_true[k]), 1e-4) << "keyframe " << k;
    EXPECT_LT(RotationErrorDeg(r.T_cw[k], scene.T_cw_true[k]), 1e-3) << "keyframe " << k;
  }
}

TEST(BundleAdjustmentTest, IsDeterministicAndKeepsUnobservedPoints) {
  const Scene scene = MakeScene(6, 150, 5);
  Start start = PerturbedStart(scene, 15);
  start.points.emplace_back(9, 9, 9);  // observed by nobody
  const BundleAdjustmentResult a = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options());
  const BundleAdjustmentResult b = RunBundleAdjustment(TestCamera(), start.keyframes, start.points,
                                                       scene.observations, Options());
  for (size_t k = 0; k < a.T_cw.size(); ++k) EXPECT_TRUE(a.T_cw[k].matrix() == b.T_cw[k].matrix());
  for (size_t p = 0; p < a.points_w.size(); ++p) EXPECT_TRUE(a.points_w[p] == b.points_w[p]);
  EXPECT_EQ(a.points_w.back(), Eigen::Vector3d(9, 9, 9));
  EXPECT_EQ(a.final_cost, b.final_cost);
}

TEST(BundleAdjustmentTest, EmptyProblemReturnsTheInput) {
  const std::vector<BaKeyframe> keyframes{{MakePose({0, 0, 1}, 5, {1, 0, 0}), false}};
  const std::vector<Eigen::Vector3d> points{{0, 0, 4}};
  const BundleAdjustmentResult r =
      RunBundleAdjustment(TestCamera(), keyframes, points, {}, Options());
  EXPECT_TRUE(r.T_cw[0].isApprox(keyframes[0].T_cw, 1e-12));
  EXPECT_EQ(r.points_w[0], points[0]);
  EXPECT_TRUE(r.observation_inlier.empty());
}

TEST(BundleAdjustmentTest, RejectsInvalidInput) {
  const Scene scene = MakeScene(3, 20, 6);
  const Start start = PerturbedStart(scene, 16);
  std::vector<BaObservation> bad = scene.observations;
  bad[0].point = 20;
  EXPECT_THROW(RunBundleAdjustment(TestCamera(), start.keyframes, start.points, bad, Options()),
               Error);
  bad = scene.observations;
  bad[0].keyframe = -1;
  EXPECT_THROW(RunBundleAdjustment(TestCamera(), start.keyframes, start.points, bad, Options()),
               Error);
  BundleAdjustmentOptions no_bf = Options();
  no_bf.bf = 0;
  EXPECT_THROW(
      RunBundleAdjustment(TestCamera(), start.keyframes, start.points, scene.observations, no_bf),
      Error);
  bad = scene.observations;
  bad[1].information = -1;
  EXPECT_THROW(RunBundleAdjustment(TestCamera(), start.keyframes, start.points, bad, Options()),
               Error);
  const std::vector<bool> too_few_flags(start.points.size() - 1, true);
  EXPECT_THROW(RunBundleAdjustment(TestCamera(), start.keyframes, start.points, scene.observations, Options(),
                                   too_few_flags),
               Error);
}

}  // namespace
}  // namespace segslam::slam
