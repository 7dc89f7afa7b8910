#include "core/camera.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace segslam {
namespace {

TEST(PinholeCamera, FromVerticalFovMatchesMujocoFormula) {
  // fovy 45 deg, 640x480: fy = 240 / tan(22.5 deg).
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 45.0);
  EXPECT_NEAR(camera.fy, 579.4112549695428, 1e-9);
  EXPECT_DOUBLE_EQ(camera.fx, camera.fy);
  EXPECT_DOUBLE_EQ(camera.cx, 319.5);
  EXPECT_DOUBLE_EQ(camera.cy, 239.5);
  EXPECT_EQ(camera.width, 640);
  EXPECT_EQ(camera.height, 480);
  // fovy 90 deg: fy = H / 2.
  EXPECT_NEAR(PinholeCamera::FromVerticalFov(100, 200, 90.0).fy, 100.0, 1e-12);
}

TEST(PinholeCamera, ProjectBackProjectRoundTrip) {
  const PinholeCamera camera{640, 480, 525.0, 520.0, 319.5, 239.5};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 639.5), v(-0.5, 479.5), z(0.1, 20.0);
  constexpr double kMaxPixelError = 1e-9;
  constexpr double kMaxPointError_m = 1e-9;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d pixel(u(rng), v(rng));
    const double depth_m = z(rng);
    const Eigen::Vector3d p = camera.BackProject(pixel, depth_m);
    EXPECT_DOUBLE_EQ(p.z(), depth_m);  // Depth is along the optical axis, not the ray.
    EXPECT_LT((camera.Project(p) - pixel).norm(), kMaxPixelError);
    EXPECT_LT((camera.BackProject(camera.Project(p), p.z()) - p).norm(), kMaxPointError_m);
  }
  // The principal point sees the optical axis.
  EXPECT_LT((camera.Project({0, 0, 3}) - Eigen::Vector2d(319.5, 239.5)).norm(), 1e-12);
}

TEST(PinholeCamera, KMatricesAgree) {
  const PinholeCamera camera{640, 480, 525.0, 520.0, 319.5, 239.5};
  const Eigen::Matrix3d k = camera.K();
  const cv::Matx33d k_cv = camera.KCv();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(k(r, c), k_cv(r, c));
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const Eigen::Vector3d h = k * p;
  EXPECT_LT((h.hnormalized() - camera.Project(p)).norm(), 1e-12);
}

TEST(PinholeCamera, InImage) {
  const PinholeCamera camera{640, 480, 500, 500, 319.5, 239.5};
  EXPECT_TRUE(camera.InImage({0, 0}));
  EXPECT_TRUE(camera.InImage({-0.49, 479.49}));
  EXPECT_FALSE(camera.InImage({-0.51, 10}));
  EXPECT_FALSE(camera.InImage({639.5, 10}));
  EXPECT_FALSE(camera.InImage({10, 480}));
  EXPECT_TRUE(camera.InImage({10, 10}, 5));
  EXPECT_FALSE(camera.InImage({4, 10}, 5));
  EXPECT_FALSE(camera.InImage({636, 10}, 5));
}

TEST(PinholeCamera, IsValid) {
  std::string error;
  EXPECT_TRUE((PinholeCamera{640, 480, 500, 500, 320, 240}.IsValid(&error)));
  EXPECT_FALSE(PinholeCamera{}.IsValid(&error));
  EXPECT_NE(error.find("size"), std::string::npos);
  EXPECT_FALSE((PinholeCamera{640, 480, -1, 500, 320, 240}.IsValid(&error)));
  EXPECT_NE(error.find("focal"), std::string::npos);
  EXPECT_FALSE((PinholeCamera{640, 480, 500, 500, NAN, 240}.IsValid(nullptr)));
}

// Finite and positive is not enough: a focal length of 1e-9 px "localized" every frame of
// a run with an ATE of 4e8 m. The limits hold for a real Kinect and the generator's cameras.
TEST(PinholeCamera, IsValidRefusesAbsurdFocalLengthsAndPrincipalPoints) {
  std::string error;
  EXPECT_TRUE((PinholeCamera{640, 480, 517.3, 516.5, 318.6, 255.3}.IsValid(&error))) << error;  // TUM fr1
  EXPECT_TRUE(PinholeCamera::FromVerticalFov(640, 480, 160).IsValid(&error)) << error;
  EXPECT_TRUE(PinholeCamera::FromVerticalFov(640, 480, 10).IsValid(&error)) << error;

  EXPECT_FALSE((PinholeCamera{640, 480, 1e-9, 525, 319.5, 239.5}.IsValid(&error)));
  EXPECT_NE(error.find("fx 1e-09 px gives a horizontal field of view of 180 deg across 640 px"), std::string::npos)
      << error;
  EXPECT_FALSE((PinholeCamera{640, 480, 525, 1e7, 319.5, 239.5}.IsValid(&error)));
  EXPECT_NE(error.find("fy 1e+07 px gives a vertical field of view"), std::string::npos) << error;
  EXPECT_FALSE((PinholeCamera{640, 480, 525, 200, 319.5, 239.5}.IsValid(&error)));
  EXPECT_NE(error.find("differ more than 2 times"), std::string::npos) << error;
  EXPECT_FALSE((PinholeCamera{640, 480, 525, 525, 99999, 239.5}.IsValid(&error)));
  EXPECT_NE(error.find("principal point cx 99999 lies outside the image (-0.5 to 639.5 for 640 px)"),
            std::string::npos)
      << error;
  EXPECT_FALSE((PinholeCamera{640, 480, 525, 525, 319.5, -1}.IsValid(&error)));
  EXPECT_NE(error.find("principal point cy -1"), std::string::npos) << error;
  EXPECT_TRUE((PinholeCamera{640, 480, 525, 525, -0.5, 479.5}.IsValid(&error))) << error;  // on the edge
  EXPECT_FALSE((PinholeCamera{100000, 480, 525, 525, 319.5, 239.5}.IsValid(&error)));
  EXPECT_NE(error.find("1 to 16384 pixels a side"), std::string::npos) << error;
}

}  // namespace
}  // namespace segslam
