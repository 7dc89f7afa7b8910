#include "sim/world_renderer.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <set>

#include "core/error.h"
#include "tests/sim/test_world.h"

namespace segslam::sim {
namespace {

using testing::BoxPoses;
using testing::CameraPose;
using testing::kBoxCentre;
using testing::kBoxHalf;
using testing::kBoxInstance;
using testing::kWallX;
using testing::MakeTestWorld;

class WorldRendererTest : public testing::MujocoWarningGuard,
                          public ::testing::WithParamInterface<GlBackend> {};

RenderedFrame RenderTestFrame(WorldRenderer* renderer, bool box_present = true) {
  renderer->SetPartPoses(BoxPoses(box_present));
  return renderer->RenderFrom(CameraPose());
}

TEST_P(WorldRendererTest, ImagesHaveTheContractTypesAndSize) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame f = RenderTestFrame(&renderer);
  EXPECT_EQ(f.color_bgr.type(), CV_8UC3);
  EXPECT_EQ(f.depth_m.type(), CV_32F);
  EXPECT_EQ(f.instance_ids.type(), CV_16U);
  EXPECT_EQ(f.color_bgr.size(), cv::Size(160, 120));
  EXPECT_EQ(f.depth_m.size(), cv::Size(160, 120));
  EXPECT_EQ(f.instance_ids.size(), cv::Size(160, 120));
  EXPECT_FALSE(renderer.gl_renderer().empty());
  EXPECT_EQ(renderer.geom_count(), 3);
  const PinholeCamera cam = renderer.intrinsics();
  EXPECT_DOUBLE_EQ(cam.cx, 79.5);
  EXPECT_DOUBLE_EQ(cam.cy, 59.5);
}

TEST_P(WorldRendererTest, DepthAtTheCentreIsTheDistanceToTheWall) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame f = RenderTestFrame(&renderer);
  const double max_error_m = 0.002;
  EXPECT_NEAR(f.depth_m.at<float>(60, 80), kWallX, max_error_m);
  EXPECT_NEAR(f.depth_m.at<float>(59, 79), kWallX, max_error_m);
}

TEST_P(WorldRendererTest, BackProjectedPixelsLandOnTheWallAndTheFloor) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame f = RenderTestFrame(&renderer);
  const PinholeCamera cam = renderer.intrinsics();
  const Eigen::Isometry3d T_wc = CameraPose();
  // Wall: above the horizon on the right (the box is on the left).
  for (const cv::Point px : {cv::Point(100, 20), cv::Point(150, 5), cv::Point(120, 55),
                             cv::Point(85, 40)}) {
    const double z = f.depth_m.at<float>(px);
    const Eigen::Vector3d p_w = T_wc * cam.BackProject(Eigen::Vector2d(px.x, px.y), z);
    EXPECT_NEAR(p_w.x(), kWallX, 0.002) << "pixel " << px;
    EXPECT_EQ(f.instance_ids.at<std::uint16_t>(px), 0);
  }
  // Floor: bottom rows, far from the box.
  for (const cv::Point px : {cv::Point(140, 115), cv::Point(100, 110), cv::Point(20, 118)}) {
    const double z = f.depth_m.at<float>(px);
    ASSERT_GT(z, 0);
    const Eigen::Vector3d p_w = T_wc * cam.BackProject(Eigen::Vector2d(px.x, px.y), z);
    EXPECT_NEAR(p_w.z(), 0.0, 0.003) << "pixel " << px;
  }
}

TEST_P(WorldRendererTest, MaskCoversExactlyTheProjectedBoxSilhouette) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame f = RenderTestFrame(&renderer);
  const PinholeCamera cam = renderer.intrinsics();
  const Eigen::Isometry3d T_cw = CameraPose().inverse();
  std::vector<cv::Point2f> corners;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d sign(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    const Eigen::Vector2d px = cam.Project(T_cw * (kBoxCentre + sign.cwiseProduct(kBoxHalf)));
    corners.emplace_back(static_cast<float>(px.x()), static_cast<float>(px.y()));
  }
  std::vector<cv::Point2f> hull;
  cv::convexHull(corners, hull);
  // Only {0, 7} occur; pixels more than 1 px inside the silhouette are 7, more than
  // 1 px outside are not.
  int inside = 0, wrong = 0;
  std::set<int> ids;
  cv::Rect mask_box;
  for (int r = 0; r < f.instance_ids.rows; ++r) {
    for (int c = 0; c < f.instance_ids.cols; ++c) {
      const int id = f.instance_ids.at<std::uint16_t>(r, c);
      ids.insert(id);
      const double d = cv::pointPolygonTest(hull, cv::Point2f(c, r), true);
      if (d > 1.0) {
        ++inside;
        wrong += id != kBoxInstance;
      } else if (d < -1.0) {
        wrong += id == kBoxInstance;
      }
      if (id == kBoxInstance) mask_box |= cv::Rect(c, r, 1, 1);
    }
  }
  EXPECT_EQ(ids, (std::set<int>{0, kBoxInstance}));
  EXPECT_GT(inside, 100);
  EXPECT_EQ(wrong, 0);
  // Bounding box of the mask vs the projected corners (pixel centres inside).
  float u0 = 1e9f, v0 = 1e9f, u1 = -1e9f, v1 = -1e9f;
  for (const cv::Point2f& p : hull) {
    u0 = std::min(u0, p.x), v0 = std::min(v0, p.y), u1 = std::max(u1, p.x), v1 = std::max(v1, p.y);
  }
  EXPECT_NEAR(mask_box.x, u0, 1.0);
  EXPECT_NEAR(mask_box.y, v0, 1.0);
  EXPECT_NEAR(mask_box.x + mask_box.width - 1, u1, 1.0);
  EXPECT_NEAR(mask_box.y + mask_box.height - 1, v1, 1.0);
  // The box's depth: its front face is the plane x = 2.75.
  const cv::Point centre(static_cast<int>(mask_box.x + mask_box.width / 2),
                         static_cast<int>(mask_box.y + mask_box.height / 2));
  EXPECT_NEAR(f.depth_m.at<float>(centre), kBoxCentre.x() - kBoxHalf.x(), 0.002);
}

TEST_P(WorldRendererTest, HiddenObjectLeavesNoMaskAndNoDepth) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame shown = RenderTestFrame(&renderer, true);
  const RenderedFrame hidden = RenderTestFrame(&renderer, false);
  EXPECT_GT(cv::countNonZero(shown.instance_ids == kBoxInstance), 100);
  EXPECT_EQ(cv::countNonZero(hidden.instance_ids), 0);
  // Where the box was, the wall or the floor is seen now: farther away.
  const cv::Mat box_pixels = shown.instance_ids == kBoxInstance;
  cv::Mat farther = hidden.depth_m > shown.depth_m + 0.5f;
  EXPECT_EQ(cv::countNonZero(box_pixels & ~farther), 0);
}

TEST_P(WorldRendererTest, TextureIsUprightOnVerticalFaces) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame f = RenderTestFrame(&renderer);
  // Row of wall height z: v = cy - f (z - 1.5) / 5.
  const PinholeCamera cam = renderer.intrinsics();
  auto row_of = [&](double z) { return static_cast<int>(cam.cy - cam.fy * (z - 1.5) / kWallX); };
  const cv::Vec3b upper = f.color_bgr.at<cv::Vec3b>(row_of(3.0), 130);  // red part
  const cv::Vec3b lower = f.color_bgr.at<cv::Vec3b>(row_of(1.2), 130);  // blue part
  EXPECT_GT(upper[2], 2 * upper[0]) << "upper " << upper;
  EXPECT_GT(lower[0], 2 * lower[2]) << "lower " << lower;
}

TEST_P(WorldRendererTest, SkyHasNoDepthAndTheSkyColour) {
  scenes::World world = MakeTestWorld();
  world.static_geoms.resize(1);  // no floor: below the wall, nothing is hit
  world.static_geoms[0].size.z() = 0.5;  // a low wall, sky above it
  world.static_geoms[0].T_parent_geom.translation().z() = 1.5;
  WorldRenderer renderer(world, GetParam());
  const RenderedFrame f = RenderTestFrame(&renderer, false);
  EXPECT_EQ(f.depth_m.at<float>(0, 80), 0.0f);
  EXPECT_EQ(f.instance_ids.at<std::uint16_t>(0, 80), 0);
  const cv::Vec3b sky = f.color_bgr.at<cv::Vec3b>(0, 80);
  EXPECT_LE(cv::norm(cv::Vec3i(sky) - cv::Vec3i(217, 178, 153), cv::NORM_INF), 1)
      << sky;  // (0.85, 0.7, 0.6) * 255 as BGR
}

TEST_P(WorldRendererTest, RenderingTwiceGivesIdenticalBytes) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  const RenderedFrame a = RenderTestFrame(&renderer);
  const RenderedFrame b = RenderTestFrame(&renderer);
  EXPECT_EQ(cv::norm(a.color_bgr, b.color_bgr, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(a.depth_m, b.depth_m, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(a.instance_ids, b.instance_ids, cv::NORM_INF), 0);
}

TEST_P(WorldRendererTest, OptionsSkipPasses) {
  RenderOptions depth_only;
  depth_only.render_color = false;
  depth_only.render_ids = false;
  WorldRenderer renderer(MakeTestWorld(), GetParam(), depth_only);
  const RenderedFrame f = RenderTestFrame(&renderer);
  EXPECT_TRUE(f.color_bgr.empty());
  EXPECT_TRUE(f.instance_ids.empty());
  EXPECT_NEAR(f.depth_m.at<float>(60, 80), kWallX, 0.002);
}

TEST_P(WorldRendererTest, ShadowsRender) {
  RenderOptions shadows;
  shadows.shadows = true;
  WorldRenderer renderer(MakeTestWorld(), GetParam(), shadows);
  const RenderedFrame f = RenderTestFrame(&renderer);
  EXPECT_NEAR(f.depth_m.at<float>(60, 80), kWallX, 0.002);
}

// A crowded city holds thousands of mocap bodies (every part of every person and car of
// both passes); MuJoCo must load such a world, and render its objects.
TEST_P(WorldRendererTest, WorldWithThousandsOfObjectsLoads) {
  scenes::World world = MakeTestWorld();
  constexpr int kExtraObjects = 4000;
  for (int k = 0; k < kExtraObjects; ++k) {
    scenes::Object extra = world.objects[0];
    extra.instance_id = static_cast<std::uint16_t>(1000 + k);
    world.objects.push_back(extra);
  }
  WorldRenderer renderer(world, GetParam());
  EXPECT_EQ(renderer.geom_count(), 3 + kExtraObjects);
  // The last object stands where the box stood; every other one is hidden.
  std::vector<std::vector<Eigen::Isometry3d>> poses(world.objects.size());
  poses.back() = {testing::Translation(kBoxCentre)};
  renderer.SetPartPoses(poses);
  const RenderedFrame f = renderer.RenderFrom(CameraPose());
  EXPECT_GT(cv::countNonZero(f.instance_ids == 1000 + kExtraObjects - 1), 100);
  EXPECT_EQ(cv::countNonZero(f.instance_ids == kBoxInstance), 0);
}

TEST_P(WorldRendererTest, SetPartPosesChecksSizes) {
  WorldRenderer renderer(MakeTestWorld(), GetParam());
  EXPECT_THROW(renderer.SetPartPoses({}), Error);
  EXPECT_THROW(renderer.SetPartPoses({{Eigen::Isometry3d::Identity(),
                                       Eigen::Isometry3d::Identity()}}),
               Error);
}

INSTANTIATE_TEST_SUITE_P(Backends, WorldRendererTest,
                         ::testing::Values(GlBackend::kOsmesa, GlBackend::kEgl),
                         [](const ::testing::TestParamInfo<GlBackend>& info) {
                           return GlBackendName(info.param);
                         });

class BackendAgreementTest : public testing::MujocoWarningGuard {};

TEST_F(BackendAgreementTest, OsmesaAndEglGiveTheSameDepthAndMask) {
  RenderedFrame osmesa, egl;
  {
    WorldRenderer renderer(MakeTestWorld(), GlBackend::kOsmesa);
    osmesa = RenderTestFrame(&renderer);
  }
  {
    WorldRenderer renderer(MakeTestWorld(), GlBackend::kEgl);
    egl = RenderTestFrame(&renderer);
  }
  cv::Mat both_valid = (osmesa.depth_m > 0) & (egl.depth_m > 0);
  cv::Mat diff;
  cv::absdiff(osmesa.depth_m, egl.depth_m, diff);
  double max_diff = 0;
  cv::minMaxLoc(diff, nullptr, &max_diff, nullptr, nullptr, both_valid);
  EXPECT_LT(max_diff, 0.005);
  const int pixels = osmesa.instance_ids.rows * osmesa.instance_ids.cols;
  const int equal = cv::countNonZero(osmesa.instance_ids == egl.instance_ids);
  EXPECT_GE(equal, 0.995 * pixels);
}

TEST_F(BackendAgreementTest, BadWorldIsRefusedWithAnError) {
  scenes::World world = MakeTestWorld();
  world.static_geoms[0].material = 42;
  EXPECT_THROW(WorldRenderer(world, GlBackend::kOsmesa), Error);
  world = MakeTestWorld();
  world.camera.near_m = 200;
  EXPECT_THROW(WorldRenderer(world, GlBackend::kOsmesa), Error);
}

}  // namespace
}  // namespace segslam::sim
