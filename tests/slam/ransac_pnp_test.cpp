// RANSAC PnP on synthetic matches with a known pose: points in front of the camera,
// projected exactly with a little pixel noise, and a share of the matches re-drawn at
// random so that they are wrong.
#include "slam/ransac_pnp.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "tests/slam/pose_test_util.h"

namespace segslam::slam {
namespace {

using testing::CentreError;
using testing::MakePose;
using testing::RotationErrorDeg;
using testing::TestCamera;

struct Matches {
  std::vector<cv::Point3f> points_w;
  std::vector<cv::Point2f> pixels;
  std::set<int> right;  // the matches that are not re-drawn
};

// `count` points 2 to 12 m in front of the camera at T_cw; every match but one in
// `right_every` gets a random pixel.
Matches SyntheticMatches(const Eigen::Isometry3d& T_cw, int count, int right_every, std::uint32_t seed) {
  const PinholeCamera camera = TestCamera();
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> u(0, camera.width), v(0, camera.height), depth(2, 12);
  std::normal_distribution<double> noise(0, 0.5);
  Matches matches;
  for (int k = 0; k < count; ++k) {
    const double z = depth(random);
    const double pu = u(random), pv = v(random);
    const Eigen::Vector3d p_c((pu - camera.cx) / camera.fx * z, (pv - camera.cy) / camera.fy * z, z);
    const Eigen::Vector3d p_w = T_cw.inverse() * p_c;
    matches.points_w.emplace_back(static_cast<float>(p_w.x()), static_cast<float>(p_w.y()), static_cast<float>(p_w.z()));
    if (k % right_every == 0) {
      matches.right.insert(k);
      matches.pixels.emplace_back(static_cast<float>(pu + noise(random)), static_cast<float>(pv + noise(random)));
    } else {
      matches.pixels.emplace_back(static_cast<float>(u(random)), static_cast<float>(v(random)));
    }
  }
  return matches;
}

const Eigen::Isometry3d kTruth = MakePose(Eigen::Vector3d(0.2, 1, 0.1), 35, Eigen::Vector3d(-3, 0.5, 40));

TEST(RansacPnpTest, FindsThePoseWhenFourMatchesInFiveAreWrong) {
  // As many matches as a relocalization on a city map keeps after its ratio test.
  for (std::uint32_t seed = 1; seed <= 10; ++seed) {
    const Matches matches = SyntheticMatches(kTruth, 100, 5, seed);
    const auto consensus = SolveRansacPnp(matches.points_w, matches.pixels, TestCamera(), 2000, 15);
    ASSERT_TRUE(consensus.has_value()) << "seed " << seed;
    EXPECT_LT(CentreError(consensus->T_cw, kTruth), 0.05) << "seed " << seed;
    EXPECT_LT(RotationErrorDeg(consensus->T_cw, kTruth), 0.3) << "seed " << seed;
    int right_in_consensus = 0;
    for (int k : consensus->inliers) right_in_consensus += matches.right.count(k) > 0;
    EXPECT_GE(right_in_consensus, 18) << "seed " << seed;  // of 20 right matches
    // A wrong match lands within 4 px of the true pose's projection by chance only.
    EXPECT_LE(consensus->inliers.size() - right_in_consensus, 2u) << "seed " << seed;
  }
}

TEST(RansacPnpTest, NoPoseWhenTooFewMatchesAgree) {
  const Matches matches = SyntheticMatches(kTruth, 30, 3, 3);  // 10 right matches
  EXPECT_FALSE(SolveRansacPnp(matches.points_w, matches.pixels, TestCamera(), 2000, 15).has_value());
  EXPECT_TRUE(SolveRansacPnp(matches.points_w, matches.pixels, TestCamera(), 2000, 8).has_value());
}

TEST(RansacPnpTest, TooFewOrMismatchedMatchesGiveNoPose) {
  const Matches matches = SyntheticMatches(kTruth, 3, 1, 4);
  EXPECT_FALSE(SolveRansacPnp(matches.points_w, matches.pixels, TestCamera(), 2000, 3).has_value());
  Matches more = SyntheticMatches(kTruth, 30, 1, 5);
  more.pixels.pop_back();
  EXPECT_FALSE(SolveRansacPnp(more.points_w, more.pixels, TestCamera(), 2000, 15).has_value());
}

}  // namespace
}  // namespace segslam::slam
