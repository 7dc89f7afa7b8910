// ATE and RPE against two kinds of independent facts: the numbers TUM's own scripts print
// for the fr1/xyz RGBDSLAM example (shared/data/tum_fr1_xyz_trajectories/SOURCE.md), and
// hand-made trajectories whose errors follow in closed form.
#include "harness/trajectory_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <unistd.h>

#include "core/error.h"
#include "core/pose.h"

namespace segslam::harness {
namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kTumDir = SEGSLAM_SHARED_DATA_DIR "/tum_fr1_xyz_trajectories";

// The scripts print "%f": six decimals, rounded.
std::string Printed(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%f", value);
  return text;
}

double Degrees(double radians) { return radians * 180.0 / kPi; }

template <typename Substring>
void ExpectErrorContaining(const std::function<void()>& call, const Substring& fragment) {
  try {
    call();
    ADD_FAILURE() << "no segslam::Error; expected one containing '" << fragment << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

// The reference data lives beside the checkout (../shared/data); a clone elsewhere skips.
bool HaveTumReference() { return std::filesystem::exists(kTumDir); }

class TumReferenceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!HaveTumReference()) return;
    ground_truth_ = new std::vector<StampedPose>(ReadTumTrajectory(kTumDir + "/groundtruth.txt"));
    estimate_ = new std::vector<StampedPose>(ReadTumTrajectory(kTumDir + "/rgbdslam_estimate.txt"));
  }
  void SetUp() override {
    if (!HaveTumReference()) GTEST_SKIP() << kTumDir << " not present";
  }
  static void TearDownTestSuite() {
    delete ground_truth_;
    delete estimate_;
  }
  static std::vector<StampedPose>* ground_truth_;
  static std::vector<StampedPose>* estimate_;
};
std::vector<StampedPose>* TumReferenceTest::ground_truth_ = nullptr;
std::vector<StampedPose>* TumReferenceTest::estimate_ = nullptr;

TEST_F(TumReferenceTest, FilesAreTheOnesSourceMdDescribes) {
  EXPECT_EQ(ground_truth_->size(), 3000u);
  EXPECT_EQ(estimate_->size(), 788u);
}

// evaluate_ate.py groundtruth.txt rgbdslam_estimate.txt --verbose
TEST_F(TumReferenceTest, AteMatchesEvaluateAtePy) {
  const AteResult ate = ComputeAte(*ground_truth_, *estimate_);
  EXPECT_EQ(ate.translation_m.count, 786u);
  EXPECT_EQ(ate.pairs.size(), 786u);
  EXPECT_EQ(Printed(ate.translation_m.rmse), "0.013473");
  EXPECT_EQ(Printed(ate.translation_m.mean), "0.012029");
  EXPECT_EQ(Printed(ate.translation_m.median), "0.011176");
  EXPECT_EQ(Printed(ate.translation_m.std), "0.006068");
  EXPECT_EQ(Printed(ate.translation_m.min), "0.000939");
  EXPECT_EQ(Printed(ate.translation_m.max), "0.034727");

  // The transform maps every estimate pose, and the paired ones are the ones measured.
  EXPECT_EQ(ate.aligned_estimate.size(), estimate_->size());
  for (const AtePair& pair : ate.pairs) {
    EXPECT_LT(std::abs(pair.stamp_gt_s - pair.stamp_est_s), 0.02);
  }
  const Eigen::Matrix3d R = ate.T_gt_est.linear();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

// evaluate_rpe.py ... --fixed_delta --delta 1 --delta_unit s --verbose
TEST_F(TumReferenceTest, RpeOneSecondMatchesEvaluateRpePy) {
  const RpeResult rpe = ComputeRpe(*ground_truth_, *estimate_, {1.0, RpeDeltaUnit::kSeconds});
  EXPECT_EQ(rpe.pairs.size(), 753u);
  EXPECT_EQ(Printed(rpe.translation_m.rmse), "0.021217");
  EXPECT_EQ(Printed(rpe.translation_m.mean), "0.019524");
  EXPECT_EQ(Printed(Degrees(rpe.rotation_rad.rmse)), "0.934480");
  EXPECT_EQ(Printed(Degrees(rpe.rotation_rad.mean)), "0.841472");
}

// evaluate_rpe.py ... --fixed_delta --delta 1 --delta_unit f --verbose
TEST_F(TumReferenceTest, RpeOneFrameMatchesEvaluateRpePy) {
  const RpeResult rpe = ComputeRpe(*ground_truth_, *estimate_, {1.0, RpeDeltaUnit::kFrames});
  EXPECT_EQ(rpe.pairs.size(), 783u);
  EXPECT_EQ(Printed(rpe.translation_m.rmse), "0.005763");
  EXPECT_EQ(Printed(Degrees(rpe.rotation_rad.rmse)), "0.352969");
}

TEST_F(TumReferenceTest, FileEvaluationGivesTheSameNumbers) {
  const TrajectoryEvaluation evaluation =
      EvaluateTrajectoryFiles(kTumDir + "/groundtruth.txt", kTumDir + "/rgbdslam_estimate.txt",
                              AteOptions{}, RpeOptions{});
  EXPECT_EQ(Printed(evaluation.ate.translation_m.rmse), "0.013473");
  ASSERT_TRUE(evaluation.rpe.has_value()) << evaluation.rpe_missing_reason;
  EXPECT_EQ(evaluation.rpe->pairs.size(), 753u);
}

TEST(ErrorStatisticsTest, NumpyConventions) {
  const ErrorStatistics s = ComputeErrorStatistics({4, 1, 3, 2});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.median, 2.5);  // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population, not sample (sqrt(5/3))
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 4);
  EXPECT_DOUBLE_EQ(ComputeErrorStatistics({5, 1, 3}).median, 3);
  EXPECT_THROW(ComputeErrorStatistics({}), Error);
}

TEST(AssociateStampsTest, GreedyByDifferenceStrictRadiusSortedByFirst) {
  // 1.03 is closest to 1.04 (0.01); 1.00's only candidate, 1.015, is then still free.
  const std::vector<StampAssociation> matches =
      AssociateStamps({1.00, 1.03, 2.00}, {1.015, 1.04, 2.02}, 0.02);
  ASSERT_EQ(matches.size(), 2u);  // |2.00 - 2.02| = 0.02 is not < 0.02
  EXPECT_EQ(matches[0].first_index, 0u);
  EXPECT_EQ(matches[0].second_index, 0u);
  EXPECT_EQ(matches[1].first_index, 1u);
  EXPECT_EQ(matches[1].second_index, 1u);

  // One second stamp claimed by two first stamps goes to the closer one.
  const std::vector<StampAssociation> contested = AssociateStamps({1.000, 1.012}, {1.010}, 0.02);
  ASSERT_EQ(contested.size(), 1u);
  EXPECT_EQ(contested[0].first_index, 1u);
}

// Ground truth at the 8 corners of a box, centred on c. The estimate is those corners
// plus offsets d_i, seen from another frame: est_i = T_est_gt (p_i + d_i). The offsets'
// components are the box's "product" sign patterns (sx*sy, sy*sz, sx*sz, sx*sy*sz),
// orthogonal to a constant and to each coordinate, so sum_i d_i = 0 and
// sum_i d_i (p_i - c)^T = 0. Then the cross-covariance is T_est_gt's rotation times a
// positive definite matrix, the best alignment is exactly T_est_gt^-1, and the aligned
// errors are exactly |d_i|.
struct BoxTrajectories {
  std::vector<StampedPose> ground_truth, estimate;
  std::vector<Eigen::Vector3d> offsets;
  Eigen::Isometry3d T_est_gt = Eigen::Isometry3d::Identity();
};

BoxTrajectories MakeBoxTrajectories() {
  BoxTrajectories box;
  box.T_est_gt = Eigen::Translation3d(3.0, -1.5, 0.7) *
                 Eigen::AngleAxisd(2.1, Eigen::Vector3d(1, -2, 0.5).normalized());
  const Eigen::Vector3d centre(0.4, 1.1, -0.2);
  int k = 0;
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      for (int sz : {-1, 1}) {
        const Eigen::Vector3d p = centre + Eigen::Vector3d(0.8 * sx, 0.5 * sy, 0.3 * sz);
        const Eigen::Vector3d d(0.03 * sx * sy + 0.01 * sx * sy * sz, 0.02 * sy * sz,
                                -0.015 * sx * sz + 0.005 * sx * sy);
        StampedPose gt;
        gt.stamp_s = 100.0 + 0.1 * k;
        gt.T_wc = Eigen::Translation3d(p) * Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d::UnitZ());
        StampedPose est;
        est.stamp_s = gt.stamp_s + 0.004;  // within the 0.02 s association radius
        est.T_wc = box.T_est_gt * Eigen::Translation3d(d) * gt.T_wc;
        box.ground_truth.push_back(gt);
        box.estimate.push_back(est);
        box.offsets.push_back(d);
        ++k;
      }
    }
  }
  return box;
}

TEST(AteTest, HandMadeBoxHasAnalyticErrors) {
  const BoxTrajectories box = MakeBoxTrajectories();
  const AteResult ate = ComputeAte(box.ground_truth, box.estimate);

  // Components are orthogonal patterns of +-1 over the 8 corners, so the mean of |d|^2 is
  // the sum of their squared amplitudes.
  const double expected_rmse = std::sqrt(0.03 * 0.03 + 0.01 * 0.01 + 0.02 * 0.02 +
                                         0.015 * 0.015 + 0.005 * 0.005);
  EXPECT_NEAR(ate.translation_m.rmse, expected_rmse, 1e-9);
  ASSERT_EQ(ate.pairs.size(), box.offsets.size());
  for (std::size_t i = 0; i < box.offsets.size(); ++i) {
    EXPECT_NEAR(ate.pairs[i].error_m, box.offsets[i].norm(), 1e-9) << i;
  }
  EXPECT_TRUE(ate.T_gt_est.isApprox(box.T_est_gt.inverse(), 1e-9))
      << ate.T_gt_est.matrix() << "\nvs\n" << box.T_est_gt.inverse().matrix();
  // The aligned estimate carries the rotation too.
  EXPECT_TRUE(ate.aligned_estimate[3].T_wc.isApprox(
      Eigen::Translation3d(box.offsets[3]) * box.ground_truth[3].T_wc, 1e-9));
}

TEST(AteTest, WithoutAlignmentErrorsAreRawDistances) {
  BoxTrajectories box = MakeBoxTrajectories();
  AteOptions options;
  options.align = false;
  const AteResult ate = ComputeAte(box.ground_truth, box.estimate, options);
  EXPECT_TRUE(ate.T_gt_est.isApprox(Eigen::Isometry3d::Identity()));
  for (std::size_t i = 0; i < box.ground_truth.size(); ++i) {
    const double raw = (box.estimate[i].T_wc.translation() -
                        box.ground_truth[i].T_wc.translation()).norm();
    EXPECT_NEAR(ate.pairs[i].error_m, raw, 1e-12);
  }
  // One pair is enough when nothing is estimated from the pairs.
  box.ground_truth.resize(1);
  EXPECT_EQ(ComputeAte(box.ground_truth, box.estimate, options).translation_m.count, 1u);
}

TEST(PositionErrorPerFrameTest, OneValuePerGroundTruthPoseNanWhereNothingAssociates) {
  std::vector<StampedPose> ground_truth;
  for (int i = 0; i < 5; ++i) {
    StampedPose pose;
    pose.stamp_s = 0.1 * i;
    pose.T_wc.translation() = Eigen::Vector3d(i, 0, 0);
    ground_truth.push_back(pose);
  }
  // Estimates at frames 0, 1 (5 ms late) and 3 (30 ms late: beyond the 0.02 s radius), off
  // by known vectors; frames 2 and 4 have none.
  std::vector<StampedPose> estimate(3);
  estimate[0].stamp_s = 0.0;
  estimate[0].T_wc.translation() = Eigen::Vector3d(0, 0.03, 0.04);
  estimate[1].stamp_s = 0.105;
  estimate[1].T_wc.translation() = Eigen::Vector3d(1.01, 0, 0);
  estimate[2].stamp_s = 0.33;
  estimate[2].T_wc.translation() = Eigen::Vector3d(3, 0, 0);

  const std::vector<double> errors = PositionErrorPerFrame(ground_truth, estimate);
  ASSERT_EQ(errors.size(), 5u);
  EXPECT_NEAR(errors[0], 0.05, 1e-12);
  EXPECT_NEAR(errors[1], 0.01, 1e-12);
  for (const int missing : {2, 3, 4}) EXPECT_TRUE(std::isnan(errors[static_cast<size_t>(missing)])) << missing;
  // Where frames associate, the same errors as the ATE's pairs.
  AteOptions in_place;
  in_place.align = false;
  const AteResult ate = ComputeAte(ground_truth, estimate, in_place);
  ASSERT_EQ(ate.pairs.size(), 2u);
  EXPECT_DOUBLE_EQ(ate.pairs[1].error_m, errors[1]);

  for (const double error : PositionErrorPerFrame(ground_truth, {})) EXPECT_TRUE(std::isnan(error));
}

TEST(AteTest, NoOverlapAndTooFewPairsAreClearErrors) {
  BoxTrajectories box = MakeBoxTrajectories();
  std::vector<StampedPose> later = box.estimate;
  for (StampedPose& pose : later) pose.stamp_s += 1000;
  ExpectErrorContaining([&] { ComputeAte(box.ground_truth, later); },
                        "no estimate stamp lies within 0.02 s");
  ExpectErrorContaining([&] { ComputeRpe(box.ground_truth, later); }, "barely overlap");

  std::vector<StampedPose> two = box.estimate;
  two.resize(2);
  ExpectErrorContaining([&] { ComputeAte(box.ground_truth, two); },
                        "only 2 pose pair(s) associate");

  std::vector<StampedPose> unordered = box.estimate;
  std::swap(unordered[2], unordered[3]);
  ExpectErrorContaining([&] { ComputeAte(box.ground_truth, unordered); },
                        "estimate stamps do not strictly increase at pose 3");
}

// Ground truth moves along x in steps of v, without rotating; the estimate has the same
// positions but yaws by w more each frame. For poses i and j = i + k the script's error
// (est_i^-1 est_j)(gt_i^-1 gt_j)^-1 has rotation Rz(k w) and translation
// Rz(-i w) k v - Rz(k w) k v, of length 2 k |v| sin((i + k) w / 2).
struct YawDriftTrajectories {
  std::vector<StampedPose> ground_truth, estimate;
  static constexpr double kStep = 0.05, kYawPerFrame = 0.01, kInterval = 0.1;
  static constexpr int kPoses = 20;
};

YawDriftTrajectories MakeYawDrift() {
  YawDriftTrajectories t;
  for (int i = 0; i < YawDriftTrajectories::kPoses; ++i) {
    StampedPose gt;
    gt.stamp_s = 50.0 + YawDriftTrajectories::kInterval * i;
    gt.T_wc = Eigen::Translation3d(YawDriftTrajectories::kStep * i, 0, 0) *
              Eigen::AngleAxisd::Identity();
    StampedPose est = gt;
    est.T_wc.linear() =
        Eigen::AngleAxisd(YawDriftTrajectories::kYawPerFrame * i, Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    t.ground_truth.push_back(gt);
    t.estimate.push_back(est);
  }
  return t;
}

void ExpectYawDriftErrors(const RpeResult& rpe, int k) {
  const int expected_pairs = YawDriftTrajectories::kPoses - 1 - k;  // j = last pose dropped
  ASSERT_EQ(rpe.pairs.size(), static_cast<std::size_t>(expected_pairs));
  for (int i = 0; i < expected_pairs; ++i) {
    const RpePair& pair = rpe.pairs[i];
    EXPECT_DOUBLE_EQ(pair.stamp_est_1_s - pair.stamp_est_0_s,
                     (50.0 + 0.1 * (i + k)) - (50.0 + 0.1 * i));
    EXPECT_NEAR(pair.rotation_error_rad, k * YawDriftTrajectories::kYawPerFrame, 1e-9);
    EXPECT_NEAR(pair.translation_error_m,
                2 * k * YawDriftTrajectories::kStep *
                    std::sin((i + k) * YawDriftTrajectories::kYawPerFrame / 2),
                1e-12)
        << i;
  }
}

TEST(RpeTest, FrameDeltaFollowsTheScriptsErrorDefinition) {
  const YawDriftTrajectories t = MakeYawDrift();
  ExpectYawDriftErrors(ComputeRpe(t.ground_truth, t.estimate, {1, RpeDeltaUnit::kFrames}), 1);
  ExpectYawDriftErrors(ComputeRpe(t.ground_truth, t.estimate, {3, RpeDeltaUnit::kFrames}), 3);
}

TEST(RpeTest, SecondsDeltaPicksThePoseClosestToStampPlusDelta) {
  const YawDriftTrajectories t = MakeYawDrift();
  // 0.29 s is closest to 3 intervals of 0.1 s.
  ExpectYawDriftErrors(ComputeRpe(t.ground_truth, t.estimate, {0.29, RpeDeltaUnit::kSeconds}), 3);
}

TEST(RpeTest, PairsWithoutNearbyGroundTruthAreSkipped) {
  YawDriftTrajectories t = MakeYawDrift();
  // Estimate stamps 0.03 s after the ground truth's, and ground truth 3..8 removed. The
  // median ground-truth interval stays 0.1 s, so a pose more than 0.2 s from every
  // ground-truth stamp cannot be used: estimate poses 4, 5 and 6 (0.23, 0.33 and 0.27 s
  // away). Of the 18 pairs (i, i + 1), the 4 that touch them go.
  for (StampedPose& pose : t.estimate) pose.stamp_s += 0.03;
  std::vector<StampedPose> gappy;
  for (int i = 0; i < YawDriftTrajectories::kPoses; ++i) {
    if (i < 3 || i > 8) gappy.push_back(t.ground_truth[i]);
  }
  const RpeResult rpe = ComputeRpe(gappy, t.estimate, {1, RpeDeltaUnit::kFrames});
  EXPECT_EQ(rpe.pairs.size(), 14u);
  for (const RpePair& pair : rpe.pairs) {
    EXPECT_LE(std::abs(pair.stamp_gt_0_s - pair.stamp_est_0_s), 0.2);
    EXPECT_LE(std::abs(pair.stamp_gt_1_s - pair.stamp_est_1_s), 0.2);
  }
}

TEST(RpeTest, RigidlyMovedEstimateHasNoError) {
  const BoxTrajectories box = MakeBoxTrajectories();
  std::vector<StampedPose> moved = box.ground_truth;
  for (StampedPose& pose : moved) pose.T_wc = box.T_est_gt * pose.T_wc;
  const RpeResult rpe = ComputeRpe(box.ground_truth, moved, {1, RpeDeltaUnit::kFrames});
  EXPECT_LT(rpe.translation_m.max, 1e-12);
  EXPECT_LT(rpe.rotation_rad.max, 1e-6);  // acos near 1 amplifies rounding: ~sqrt(eps)
}

TEST(TrajectoryFilesTest, PairErrorsNameBothFiles) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("segslam_trajectory_files_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string ground_truth = (dir / "groundtruth.txt").string();
  const std::string missing = (dir / "nowhere.txt").string();
  WriteTumTrajectory(ground_truth, MakeBoxTrajectories().ground_truth, "");
  ExpectErrorContaining([&] { EvaluateTrajectoryFiles(ground_truth, missing, AteOptions{}, RpeOptions{}); },
                        missing);
  ExpectErrorContaining([&] { EvaluateTrajectoryFiles(missing, ground_truth, AteOptions{}, RpeOptions{}); },
                        missing);
  std::filesystem::remove_all(dir);
}

// The box's 8 poses span 0.7 s: an ATE, and no pose pair 1 s apart for the RPE. The ATE
// is given and the RPE's absence explained, rather than the whole evaluation failing.
TEST(TrajectoryFilesTest, SequenceShorterThanTheRpeDeltaGivesAteWithoutRpe) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("segslam_trajectory_short_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const BoxTrajectories box = MakeBoxTrajectories();
  WriteTumTrajectory(dir / "groundtruth.txt", box.ground_truth, "");
  WriteTumTrajectory(dir / "estimate.txt", box.estimate, "");
  const TrajectoryEvaluation evaluation =
      EvaluateTrajectoryFiles(dir / "groundtruth.txt", dir / "estimate.txt", AteOptions{}, RpeOptions{});
  EXPECT_EQ(evaluation.ate.translation_m.count, 8u);
  EXPECT_FALSE(evaluation.rpe.has_value());
  EXPECT_NE(evaluation.rpe_missing_reason.find("RPE needs poses at least the delta of 1 s apart; the estimate spans "
                                               "0.700 s"),
            std::string::npos)
      << evaluation.rpe_missing_reason;
  std::filesystem::remove_all(dir);
}

// Translations near 1e200 m square to infinity: refused by name, not scored as inf or NaN.
TEST(TrajectoryMetricsTest, PositionsFarBeyondEarthAreRefusedNotScoredAsInfinity) {
  BoxTrajectories box = MakeBoxTrajectories();
  box.estimate[3].T_wc.translation() = Eigen::Vector3d(1e200, -1e200, 3);
  ExpectErrorContaining([&] { ComputeAte(box.ground_truth, box.estimate); },
                        "estimate pose 3 (stamp 100.304000) lies 1.41e+200 m from the origin; positions beyond "
                        "1e+07 m (10,000 km) are refused");
  ExpectErrorContaining([&] { ComputeRpe(box.estimate, box.ground_truth); }, "ground-truth pose 3");
}

}  // namespace
}  // namespace segslam::harness
