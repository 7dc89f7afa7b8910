// The aliasing measure (harness/aliasing.h): the ground-truth common-view test on a
// plane whose answer is known in closed form, and the whole measure on a world rendered
// with sim/ that has two places 200 m apart: with a distinct texture on each place's
// wall the measure stays below a loop detector's acceptance, with one texture copied to
// both it finds the copy, at a pose 200 m off.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "core/image_io.h"
#include "core/tum_dataset.h"
#include "harness/aliasing.h"
#include "harness/aliasing_report.h"
#include "scenes/world.h"
#include "sim/world_renderer.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

// A camera at `x` (m) along the world x axis, optical frame = world frame otherwise:
// looking along +z at the plane z = kPlaneDepth.
constexpr double kPlaneDepth = 5.0;
const PinholeCamera kCamera = PinholeCamera::FromVerticalFov(160, 120, 60.0);

Eigen::Isometry3d CameraAt(double x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, 0, 0);
  return T;
}

cv::Mat ConstantDepth(float depth_m) { return cv::Mat(kCamera.height, kCamera.width, CV_32F, cv::Scalar(depth_m)); }

// Width of the plane a camera sees at kPlaneDepth (pixel centres -0.5 .. W-0.5).
double VisibleWidth() { return kCamera.width / kCamera.fx * kPlaneDepth; }

TEST(CommonViewTest, ASidewaysShiftLeavesTheShareOfThePlaneStillInView) {
  const CommonViewOptions options;
  const GroundTruthView a = MakeGroundTruthView(options, kCamera, CameraAt(0), ConstantDepth(kPlaneDepth), {});
  ASSERT_EQ(a.points_w.size(), static_cast<size_t>((160 / 8) * (120 / 8)));
  for (double fraction : {0.0, 0.25, 0.5, 0.75}) {
    SCOPED_TRACE(fraction);
    const GroundTruthView b =
        MakeGroundTruthView(options, kCamera, CameraAt(fraction * VisibleWidth()), ConstantDepth(kPlaneDepth), {});
    const ViewOverlap overlap = MeasureOverlap(options, kCamera, kPlaneDepth, a, b);
    // The grid's columns are 8 px apart: the share moves in steps of 1/20.
    EXPECT_NEAR(overlap.share_ab, 1.0 - fraction, 0.051);
    EXPECT_NEAR(overlap.share_ba, 1.0 - fraction, 0.051);
  }
  // Past the edge of a's view, and looking the other way: nothing in common.
  const GroundTruthView beside =
      MakeGroundTruthView(options, kCamera, CameraAt(1.05 * VisibleWidth()), ConstantDepth(kPlaneDepth), {});
  EXPECT_LT(MeasureOverlap(options, kCamera, kPlaneDepth, a, beside).Share(), options.min_common_share);
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const GroundTruthView behind = MakeGroundTruthView(options, kCamera, turned, ConstantDepth(kPlaneDepth), {});
  EXPECT_EQ(MeasureOverlap(options, kCamera, kPlaneDepth, a, behind).Share(), 0.0);
}

TEST(CommonViewTest, DepthMustAgreeAndMaskedPixelsDoNotCount) {
  const CommonViewOptions options;  // max(0.1 m, 5 %): 0.25 m at 5 m
  const GroundTruthView a = MakeGroundTruthView(options, kCamera, CameraAt(0), ConstantDepth(kPlaneDepth), {});
  auto seen_with_depth = [&](float depth_m, double range_m) {
    const GroundTruthView b = MakeGroundTruthView(options, kCamera, CameraAt(0), ConstantDepth(depth_m), {});
    return SeenShare(options, kCamera, range_m, a, b);
  };
  EXPECT_EQ(seen_with_depth(kPlaneDepth + 0.2f, 10.0), 1.0) << "within the tolerance";
  EXPECT_EQ(seen_with_depth(kPlaneDepth + 0.4f, 10.0), 0.0) << "outside it";
  EXPECT_EQ(seen_with_depth(2.0f, 10.0), 0.0) << "an occluder 3 m in front";
  // No depth: a dropout nearer than the sensor's range proves nothing; beyond its range
  // nothing can be ruled out.
  EXPECT_EQ(seen_with_depth(0.0f, 10.0), 0.0);
  EXPECT_EQ(seen_with_depth(0.0f, 4.0), 1.0);

  // Only background pixels (id 0) are sampled: the right half belongs to an instance.
  cv::Mat ids(kCamera.height, kCamera.width, CV_16U, cv::Scalar(0));
  ids.colRange(kCamera.width / 2, kCamera.width).setTo(3);
  const GroundTruthView half = MakeGroundTruthView(options, kCamera, CameraAt(0), ConstantDepth(kPlaneDepth), ids);
  EXPECT_EQ(half.points_w.size(), a.points_w.size() / 2);
  for (const Eigen::Vector3d& p : half.points_w) EXPECT_LT(p.x(), 0.0);
  ids.setTo(3);
  EXPECT_TRUE(MakeGroundTruthView(options, kCamera, CameraAt(0), ConstantDepth(kPlaneDepth), ids).points_w.empty());
}

// ---- The measure on a rendered world ----

constexpr double kPlaceApartM = 200.0;

// A texture of random rectangles and discs in grey and colour: corners everywhere, and
// no two seeds alike.
scenes::Texture RandomTexture(std::uint64_t seed) {
  scenes::Texture texture;
  texture.name = "random_" + std::to_string(seed);
  texture.image_bgr = cv::Mat(512, 512, CV_8UC3, cv::Scalar(128, 128, 128));
  cv::RNG rng(seed);
  for (int k = 0; k < 600; ++k) {
    const cv::Scalar colour(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
    const cv::Point centre(rng.uniform(0, 512), rng.uniform(0, 512));
    const int size = rng.uniform(4, 28);
    if (k % 2 == 0) {
      cv::rectangle(texture.image_bgr, cv::Rect(centre.x, centre.y, size, rng.uniform(4, 28)), colour, cv::FILLED);
    } else {
      cv::circle(texture.image_bgr, centre, size / 2, colour, cv::FILLED);
    }
  }
  texture.tile_size_m = Eigen::Vector2d(10.0, 6.0);  // one copy covers the whole wall
  return texture;
}

// Two walls 10 m x 6 m, 5 m in front of two camera spots 200 m apart along x, each spot
// looking along +x; an untextured ground (depth, no features). `same_texture`: the
// second wall carries the first's texture.
scenes::World TwoPlacesWorld(bool same_texture) {
  scenes::World w;
  w.name = "two_places";
  w.kind = "office";
  w.camera.width = 320;
  w.camera.height = 240;
  w.camera.fovy_deg = 60.0;
  w.camera.near_m = 0.05;
  w.camera.far_m = 100.0;
  w.textures = {RandomTexture(11), RandomTexture(same_texture ? 11 : 29)};
  scenes::Material first, second, ground;
  first.texture = 0;
  second.texture = 1;
  ground.rgba = Eigen::Vector4f(0.45f, 0.45f, 0.45f, 1.f);
  first.name = "first";
  second.name = "second";
  ground.name = "ground";
  w.materials = {first, second, ground};
  for (int place = 0; place < 2; ++place) {
    scenes::Geom wall;
    wall.shape = scenes::Shape::kBox;
    wall.size = Eigen::Vector3d(0.1, 5.0, 3.0);
    wall.T_parent_geom = Eigen::Isometry3d::Identity();
    wall.T_parent_geom.translation() = Eigen::Vector3d(place * kPlaceApartM + 5.1, 0, 2.0);
    wall.material = place;
    w.static_geoms.push_back(wall);
  }
  scenes::Geom floor;
  floor.shape = scenes::Shape::kPlane;
  floor.size = Eigen::Vector3d(150, 20, 0);
  floor.T_parent_geom = Eigen::Isometry3d::Identity();
  floor.T_parent_geom.translation() = Eigen::Vector3d(kPlaceApartM / 2, 0, 0);
  floor.material = 2;
  w.static_geoms.push_back(floor);
  scenes::Light light;
  light.direction = Eigen::Vector3d(0.5, -0.3, -1.0);
  w.lights = {light};
  return w;
}

// Camera at (x, y, 1.5) looking along world +x (optical z), image right = world -y.
Eigen::Isometry3d LookingAlongX(double x, double y) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = Eigen::Vector3d(0, -1, 0);
  T.linear().col(1) = Eigen::Vector3d(0, 0, -1);
  T.linear().col(2) = Eigen::Vector3d(1, 0, 0);
  T.translation() = Eigen::Vector3d(x, y, 1.5);
  return T;
}

// Three frames at each place, 0.3 m apart sideways, written as a TUM sequence without
// masks (every pixel background).
fs::path RenderTwoPlaces(bool same_texture, const fs::path& dir) {
  const scenes::World world = TwoPlacesWorld(same_texture);
  sim::WorldRenderer renderer(world, sim::GlBackend::kOsmesa);
  renderer.SetPartPoses({});
  SequenceCamera camera;
  camera.intrinsics = renderer.intrinsics();
  camera.depth_factor = 1000;
  TumSequenceWriter writer(dir, camera);
  int frame = 0;
  for (int place = 0; place < 2; ++place) {
    for (double y : {-0.3, 0.0, 0.3}) {
      const Eigen::Isometry3d T_wc = LookingAlongX(place * kPlaceApartM, y);
      sim::RenderedFrame rendered = renderer.RenderFrom(T_wc);
      RgbdFrame rgbd;
      rgbd.index = frame;
      rgbd.stamp_s = 1.0 + frame;
      rgbd.color_bgr = rendered.color_bgr;
      rgbd.depth_m = rendered.depth_m;
      writer.Add(rgbd, T_wc);
      ++frame;
    }
  }
  writer.Finish();
  return dir;
}

class AliasingMeasureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("segslam_aliasing_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static AliasingOptions Options() {
    AliasingOptions options;
    options.sample_spacing_m = 0.2;  // every frame: they lie 0.3 m apart
    return options;
  }
  fs::path dir_;
};

TEST_F(AliasingMeasureTest, DistinctTexturesStayBelowALoopDetectorsAcceptance) {
  const TumSequence sequence = TumSequence::Open(RenderTwoPlaces(false, dir_ / "distinct"));
  const AliasingSummary summary = MeasureAliasing(Options(), sequence);
  EXPECT_EQ(summary.sampled_frames, 6);
  EXPECT_EQ(summary.pairs_tested, 15);
  // The three pairs at each place see the same wall; the nine across places nothing alike.
  EXPECT_EQ(summary.pairs_no_common_view, 9);
  for (const AliasingPair& pair : summary.worst_pairs) {
    EXPECT_NEAR(pair.distance_m, kPlaceApartM, 1.0);
    EXPECT_LT(pair.common_share, Options().common_view.min_common_share);
  }
  EXPECT_LT(summary.max_verified_matches, kLoopAcceptanceMatches);
  EXPECT_EQ(summary.pairs_at_or_above_acceptance, 0);
}

TEST_F(AliasingMeasureTest, ACopiedTextureIsFoundAtAWrongPose) {
  const TumSequence sequence = TumSequence::Open(RenderTwoPlaces(true, dir_ / "copied"));
  const AliasingSummary summary = MeasureAliasing(Options(), sequence);
  EXPECT_EQ(summary.pairs_no_common_view, 9);
  EXPECT_GE(summary.max_verified_matches, kLoopAcceptanceMatches);
  EXPECT_EQ(summary.pairs_at_or_above_acceptance, 9) << "every pair across places sees the copy";
  ASSERT_FALSE(summary.worst_pairs.empty());
  const AliasingPair& worst = summary.worst_pairs.front();
  EXPECT_EQ(worst.verified_matches, summary.max_verified_matches);
  EXPECT_NEAR(worst.distance_m, kPlaceApartM, 1.0);
  // PnP puts the far camera where the near one stands in front of its own wall.
  EXPECT_NEAR(worst.pose_error_m, kPlaceApartM, 2.0);
  EXPECT_GE(summary.p50, kLoopAcceptanceMatches);

  // The same bytes whatever the threads; the picture has both frames side by side.
  AliasingOptions one_thread = Options();
  one_thread.threads = 1;
  EXPECT_EQ(MeasureAliasing(one_thread, sequence).ToJson().dump(), summary.ToJson().dump());
  const cv::Mat picture = AliasingPairPicture(Options(), sequence, worst);
  EXPECT_EQ(picture.cols, 2 * sequence.camera().intrinsics.width);
  EXPECT_EQ(picture.rows, sequence.camera().intrinsics.height);
}

TEST(AliasingOptionsTest, RefusesWhatCannotBeMeasured) {
  std::string problem;
  EXPECT_TRUE(AliasingOptions().IsValid(&problem)) << problem;
  AliasingOptions options;
  options.common_view.min_common_share = 0;
  EXPECT_FALSE(options.IsValid(&problem));
  EXPECT_NE(problem.find("min_common_share"), std::string::npos) << problem;
  options = AliasingOptions();
  options.ratio = 1.5f;
  EXPECT_FALSE(options.IsValid(&problem));
  EXPECT_NE(problem.find("ratio"), std::string::npos) << problem;
  options = AliasingOptions();
  options.sample_spacing_m = 0;
  EXPECT_FALSE(options.IsValid(&problem));
}

}  // namespace
}  // namespace segslam::harness
