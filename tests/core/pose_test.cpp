#include "core/pose.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using testing::SharedDataDir;

Eigen::Isometry3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 10.0;
  return T;
}

double RotationErrorRad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.rotation().transpose() * b.rotation()).angle();
}

TEST(TumPoseLine, RoundTripManyRandomPoses) {
  std::mt19937 rng(42);
  // %.9g translation of |t| ~ 10 m and %.9f quaternion components.
  constexpr double kMaxTranslationError_m = 1e-6;
  constexpr double kMaxRotationError_rad = 1e-8;
  for (int i = 0; i < 2000; ++i) {
    StampedPose pose;
    pose.stamp_s = 1305031102.160407 + i * 0.033;
    pose.T_wc = RandomPose(rng);
    const std::string line = FormatTumPoseLine(pose);
    const StampedPose back = ParseTumPoseLine(line, "test");
    EXPECT_NEAR(back.stamp_s, pose.stamp_s, 1e-6) << line;
    EXPECT_LT((back.T_wc.translation() - pose.T_wc.translation()).norm(), kMaxTranslationError_m);
    EXPECT_LT(RotationErrorRad(back.T_wc, pose.T_wc), kMaxRotationError_rad) << line;
    // Written quaternion has qw >= 0.
    double qw = 0;
    std::istringstream(line.substr(line.rfind(' '))) >> qw;
    EXPECT_GE(qw, 0.0) << line;
  }
}

TEST(TumPoseLine, ParseErrors) {
  EXPECT_NE(ErrorMessage([] { ParseTumPoseLine("1 2 3", "f.txt:3"); }).find("f.txt:3"),
            std::string::npos);
  EXPECT_NE(ErrorMessage([] { ParseTumPoseLine("1 0 0 0 0 0 0 abc", "o"); }).find("qw"),
            std::string::npos);
  EXPECT_NE(ErrorMessage([] { ParseTumPoseLine("1 0 0 0 0 0 0 2", "o"); }).find("norm"),
            std::string::npos);
  EXPECT_NE(ErrorMessage([] { ParseTumPoseLine("1 0 nan 0 0 0 0 1", "o"); }).find("ty"),
            std::string::npos);
  // A few printed digits give norms slightly off 1; that is accepted and normalized.
  const StampedPose pose = ParseTumPoseLine("1 0 0 0 0.7071 0 0 0.7071", "o");
  EXPECT_NEAR(Eigen::Quaterniond(pose.T_wc.rotation()).norm(), 1.0, 1e-12);
}

// Lines as TUM's scripts read them: commas and tabs separate fields too; numbers as
// Python's float() reads them (tiny values yes, hexadecimal no).
TEST(TumPoseLine, ReadsWhatTheTumScriptsRead) {
  const StampedPose commas = ParseTumPoseLine("1.5,0.25,\t0,0, 0,0,0,1", "o");
  EXPECT_EQ(commas.stamp_s, 1.5);
  EXPECT_EQ(commas.T_wc.translation().x(), 0.25);
  EXPECT_EQ(ParseTumPoseLine("1 1e-310 0 0 0 0 0 1", "o").T_wc.translation().x(), 1e-310);
  EXPECT_NE(ErrorMessage([] { ParseTumPoseLine("1 0x1p3 0 0 0 0 0 1", "o"); }).find("tx"), std::string::npos);
  EXPECT_NE(ErrorMessage([] { ParseTumPoseLine("1 1e999 0 0 0 0 0 1", "o"); }).find("tx"), std::string::npos);
  EXPECT_EQ(SplitTumFields(" a,b\t c  d,,e "), (std::vector<std::string>{"a", "b", "c", "d", "e"}));
}

class TumTrajectoryTest : public testing::TempDirTest {
 protected:
  std::filesystem::path WriteText(const std::string& text) {
    const auto path = dir() / "traj.txt";
    std::ofstream(path) << text;
    return path;
  }
};

TEST_F(TumTrajectoryTest, WriteReadRoundTrip) {
  std::mt19937 rng(3);
  std::vector<StampedPose> poses;
  for (int i = 0; i < 50; ++i) poses.push_back({0.1 * i, RandomPose(rng)});
  const auto path = dir() / "out.txt";
  WriteTumTrajectory(path, poses, "a header\nsecond line");
  const auto back = ReadTumTrajectory(path);
  ASSERT_EQ(back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_NEAR(back[i].stamp_s, poses[i].stamp_s, 1e-6);
    EXPECT_LT((back[i].T_wc.translation() - poses[i].T_wc.translation()).norm(), 1e-6);
    EXPECT_LT(RotationErrorRad(back[i].T_wc, poses[i].T_wc), 1e-8);
  }
  std::ifstream file(path);
  std::string first;
  std::getline(file, first);
  EXPECT_EQ(first, "# a header");
}

// What ReadTumTrajectory refuses is not written: each case names the file and the pose.
TEST_F(TumTrajectoryTest, WriteRefusesNonFinitePosesAndStampsThatDoNotIncrease) {
  const auto path = dir() / "out.txt";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto poses_with = [](int index, StampedPose bad) {
    std::vector<StampedPose> poses;
    for (int i = 0; i < 3; ++i) poses.push_back({1.0 + i, Eigen::Isometry3d::Identity()});
    poses[index] = bad;
    return poses;
  };
  StampedPose nan_translation{2.0, Eigen::Isometry3d::Identity()};
  nan_translation.T_wc.translation().x() = nan;
  StampedPose nan_rotation{2.0, Eigen::Isometry3d::Identity()};
  nan_rotation.T_wc.linear()(0, 0) = nan;
  const std::vector<std::pair<std::vector<StampedPose>, std::string>> cases = {
      {poses_with(1, nan_translation), "pose 1 (stamp 2): not finite"},
      {poses_with(1, nan_rotation), "pose 1 (stamp 2): not finite"},
      {poses_with(2, {nan, Eigen::Isometry3d::Identity()}), "pose 2 (stamp nan): not finite"},
      {poses_with(2, {2.0, Eigen::Isometry3d::Identity()}), "pose 2: timestamp 2.000000 does not increase"},
      // Apart by less than the written microsecond: the file would hold the same stamp twice.
      {poses_with(2, {2.0000004, Eigen::Isometry3d::Identity()}), "pose 2: timestamp 2.000000 does not increase"},
  };
  for (const auto& [poses, expected] : cases) {
    SCOPED_TRACE(expected);
    const std::string message = ErrorMessage([&] { WriteTumTrajectory(path, poses); });
    EXPECT_NE(message.find(path.string() + ": refusing to write " + expected), std::string::npos) << message;
    EXPECT_FALSE(std::filesystem::exists(path));
  }
}

TEST_F(TumTrajectoryTest, SkipsCommentsAndBlankLines) {
  const auto poses = ReadTumTrajectory(WriteText("# c\n\n1 0 0 0 0 0 0 1\n  # x\n2 1 2 3 0 0 0 1\n"));
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].T_wc.translation(), Eigen::Vector3d(1, 2, 3));
}

TEST_F(TumTrajectoryTest, BadFieldCountNamesFileAndLine) {
  const auto path = WriteText("# header\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n");
  const std::string message = ErrorMessage([&] { ReadTumTrajectory(path); });
  EXPECT_NE(message.find(path.string() + ":3"), std::string::npos) << message;
  EXPECT_NE(message.find("8 fields"), std::string::npos) << message;
}

TEST_F(TumTrajectoryTest, NanNamesFileAndLine) {
  const auto path = WriteText("1 0 0 0 0 0 0 1\n2 0 NaN 0 0 0 0 1\n");
  const std::string message = ErrorMessage([&] { ReadTumTrajectory(path); });
  EXPECT_NE(message.find(path.string() + ":2"), std::string::npos) << message;
  EXPECT_NE(message.find("not a finite number"), std::string::npos) << message;
}

TEST_F(TumTrajectoryTest, NonMonotonicNamesFileAndLine) {
  const auto path = WriteText("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n");
  const std::string message = ErrorMessage([&] { ReadTumTrajectory(path); });
  EXPECT_NE(message.find(path.string() + ":3"), std::string::npos) << message;
  EXPECT_NE(message.find("does not increase"), std::string::npos) << message;
}

TEST_F(TumTrajectoryTest, MissingFile) {
  const std::string message = ErrorMessage([&] { ReadTumTrajectory(dir() / "none.txt"); });
  EXPECT_NE(message.find("none.txt"), std::string::npos);
  EXPECT_NE(message.find("does not exist"), std::string::npos);
}

TEST(InterpolatePose, EndpointsAndMidpoint) {
  std::mt19937 rng(5);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Isometry3d a = RandomPose(rng), b = RandomPose(rng);
    EXPECT_LT((InterpolatePose(a, b, 0).matrix() - a.matrix()).norm(), 1e-9);
    EXPECT_LT((InterpolatePose(a, b, 1).matrix() - b.matrix()).norm(), 1e-9);
    const Eigen::Isometry3d mid = InterpolatePose(a, b, 0.5);
    EXPECT_LT((mid.translation() - 0.5 * (a.translation() + b.translation())).norm(), 1e-9);
    // Slerp's midpoint is equally far (in angle) from both ends.
    EXPECT_NEAR(RotationErrorRad(a, mid), RotationErrorRad(mid, b), 1e-9);
    EXPECT_NEAR(RotationErrorRad(a, mid) * 2, RotationErrorRad(a, b), 1e-9);
  }
}

TEST(TumTrajectoryRealData, Freiburg1XyzFiles) {
  const auto dir = SharedDataDir() / "tum_fr1_xyz_trajectories";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not present";
  const auto gt = ReadTumTrajectory(dir / "groundtruth.txt");
  EXPECT_EQ(gt.size(), 3000u);
  EXPECT_NEAR(gt.front().stamp_s, 1305031098.6659, 1e-4);
  EXPECT_NEAR(gt.back().stamp_s, 1305031128.7555, 1e-4);
  const auto estimate = ReadTumTrajectory(dir / "rgbdslam_estimate.txt");
  ASSERT_EQ(estimate.size(), 788u);
  EXPECT_NEAR(estimate.front().stamp_s, 1305031102.160407, 1e-6);
  EXPECT_NEAR(estimate.front().T_wc.translation().x(), 1.344379, 1e-9);
}

}  // namespace
}  // namespace segslam
