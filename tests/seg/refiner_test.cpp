#include "seg/refiner.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace segslam::seg {
namespace {

PinholeCamera TestCamera() {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = 500;
  camera.fy = 500;
  camera.cx = 319.5;
  camera.cy = 239.5;
  return camera;
}

cv::Mat RectMask(const cv::Rect& r) {
  cv::Mat m(480, 640, CV_8U, cv::Scalar(0));
  m(r).setTo(1);
  return m;
}

InstanceMask Instance(std::uint16_t id, int category, const cv::Mat& mask,
                      float score = 1.0f) {
  InstanceMask instance;
  instance.track_id = id;
  instance.category_id = category;
  instance.score = score;
  instance.mask = mask;
  return instance;
}

Eigen::Isometry3d Translation(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

// The analytic projection of `source_rect` on the fronto-parallel plane z = depth_m of
// the previous camera: a target pixel is inside when its ray meets the plane at a point
// whose source pixel cell (centres at integers) lies in the rectangle.
cv::Mat ExpectedProjection(const PinholeCamera& camera, const cv::Rect& source_rect,
                           double depth_m, const Eigen::Isometry3d& T_cur_prev) {
  cv::Mat expected(camera.height, camera.width, CV_8U, cv::Scalar(0));
  const Eigen::Isometry3d T_prev_cur = T_cur_prev.inverse();
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d ray = camera.BackProject(Eigen::Vector2d(x, y), 1.0);
      const Eigen::Vector3d origin = T_prev_cur.translation();
      const Eigen::Vector3d direction = T_prev_cur.linear() * ray;
      if (direction.z() <= 0) continue;
      const double lambda = (depth_m - origin.z()) / direction.z();
      if (lambda <= 0) continue;
      const Eigen::Vector2d source = camera.Project(origin + lambda * direction);
      const int su = static_cast<int>(std::floor(source.x() + 0.5));
      const int sv = static_cast<int>(std::floor(source.y() + 0.5));
      if (source_rect.contains(cv::Point(su, sv))) expected.at<std::uint8_t>(y, x) = 1;
    }
  }
  return expected;
}

// Pixels where `actual` differs from `expected` outside the 1-px band around
// expected's border (dilate 3x3 minus erode 3x3).
int DifferencesOutsideBorderBand(const cv::Mat& actual, const cv::Mat& expected) {
  cv::Mat dilated, eroded, band, diff;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::dilate(expected, dilated, kernel);
  cv::erode(expected, eroded, kernel);
  band = dilated != eroded;
  diff = (actual != 0) != (expected != 0);
  diff.setTo(0, band);
  return cv::countNonZero(diff);
}

int Differences(const cv::Mat& a, const cv::Mat& b) {
  return cv::countNonZero((a != 0) != (b != 0));
}

struct PlaneCase {
  const char* name;
  Eigen::Isometry3d T_cur_prev;
  bool exact;  // pixel-exact expected (pure shift)
};

TEST(ProjectRegionsTest, PlanarRegionMatchesAnalyticProjection) {
  const PinholeCamera camera = TestCamera();
  const cv::Rect rect(200, 150, 100, 80);
  const double depth_m = 2.0;
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(depth_m));
  FrameSegmentation previous;
  previous.instances.push_back(Instance(1, 1, RectMask(rect)));

  Eigen::Isometry3d rotation = Eigen::Isometry3d::Identity();
  rotation.linear() =
      Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d rotation_45 = Eigen::Isometry3d::Identity();
  rotation_45.linear() =
      Eigen::AngleAxisd(45.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d general = Translation(0.05, -0.03, -0.4);
  general.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, 1, 0.2).normalized())
                         .toRotationMatrix();
  const PlaneCase cases[] = {
      // Sideways by 25.3 px at 2 m (fx = 500): every pixel shifts by round(25.3) = 25.
      {"translation_x", Translation(25.3 * depth_m / 500.0, 0, 0), true},
      {"translation_xy", Translation(-40.2 * depth_m / 500.0, 12.7 * depth_m / 500.0, 0),
       true},
      // Most of the region leaves the image over its right and top edges: what stays in
      // is clipped exactly at the image's border.
      {"partly_out_right_and_top", Translation(400.3 * depth_m / 500.0, -180.2 * depth_m / 500.0, 0), true},
      {"partly_out_left_and_bottom", Translation(-250.4 * depth_m / 500.0, 300.2 * depth_m / 500.0, 0), true},
      {"rotation_optical_axis_20deg", rotation, false},
      {"rotation_optical_axis_45deg", rotation_45, false},
      // Closer by 0.5 m: magnified 2 / 1.5 = 1.33.
      {"closer_x1.33", Translation(0, 0, -0.5), false},
      // Closer by 1 m: magnified 2x; naive forward projection leaves every other row
      // and column empty.
      {"closer_x2", Translation(0, 0, -1.0), false},
      {"general", general, false},
  };
  for (const bool blocks : {false, true}) {
    RefinerOptions options;
    options.splat_interior_in_blocks = blocks;
    for (const PlaneCase& c : cases) {
      SCOPED_TRACE(std::string(c.name) + (blocks ? ", inside splatted by 2x2 blocks" : ", pixel by pixel"));
      const std::vector<ProjectedRegion> projected =
          ProjectRegions(options, camera, previous, depth, c.T_cur_prev);
      ASSERT_EQ(projected.size(), 1u);
      const cv::Mat expected = ExpectedProjection(camera, rect, depth_m, c.T_cur_prev);
      ASSERT_GT(cv::countNonZero(expected), 0);
      if (c.exact) {
        EXPECT_EQ(Differences(projected[0].mask, expected), 0);
      }
      EXPECT_EQ(DifferencesOutsideBorderBand(projected[0].mask, expected), 0);
      EXPECT_EQ(projected[0].area_px, cv::countNonZero(projected[0].mask));
      EXPECT_EQ(projected[0].bbox, cv::boundingRect(projected[0].mask));
      // Hole-free: the mask's filled outer contour adds no pixel.
      std::vector<std::vector<cv::Point>> contours;
      cv::Mat copy = projected[0].mask.clone();
      cv::findContours(copy, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
      cv::Mat filled(480, 640, CV_8U, cv::Scalar(0));
      cv::drawContours(filled, contours, -1, cv::Scalar(1), cv::FILLED);
      EXPECT_EQ(cv::countNonZero(filled), projected[0].area_px);
      EXPECT_EQ(contours.size(), 1u);
    }
  }
}

// The checks above catch holes: without footprints and closing, a 2x magnification
// leaves every other row and column empty.
TEST(ProjectRegionsTest, NaiveForwardProjectionWouldLeaveHoles) {
  const PinholeCamera camera = TestCamera();
  const cv::Rect rect(200, 150, 100, 80);
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0));
  FrameSegmentation previous;
  previous.instances.push_back(Instance(1, 1, RectMask(rect)));
  RefinerOptions naive;
  naive.splat_footprint_scale = 0.5;
  naive.hole_fill_iterations = 0;
  const Eigen::Isometry3d T = Translation(0, 0, -1.0);
  const cv::Mat expected = ExpectedProjection(camera, rect, 2.0, T);
  EXPECT_GT(DifferencesOutsideBorderBand(
                ProjectRegions(naive, camera, previous, depth, T)[0].mask, expected),
            1000);
}

TEST(ProjectRegionsTest, FrontRegionWinsTheOverlap) {
  const PinholeCamera camera = TestCamera();
  // Far region A (3 m) left of near region B (1 m), side by side in frame t-1.
  const cv::Rect rect_far(100, 100, 150, 200), rect_near(250, 150, 100, 100);
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(0));
  depth(rect_far).setTo(3.0);
  depth(rect_near).setTo(1.0);
  FrameSegmentation previous;
  previous.instances.push_back(Instance(1, 1, RectMask(rect_far)));
  previous.instances.push_back(Instance(2, 1, RectMask(rect_near)));
  // Camera moves right: near B shifts left by 100 px, far A by 33.3 px, B covers A.
  const Eigen::Isometry3d T_cur_prev = Translation(-0.2, 0, 0);
  for (int order = 0; order < 2; ++order) {
    SCOPED_TRACE(order);
    FrameSegmentation prev = previous;
    if (order == 1) std::swap(prev.instances[0], prev.instances[1]);
    const std::vector<ProjectedRegion> projected =
        ProjectRegions(RefinerOptions(), camera, prev, depth, T_cur_prev);
    const cv::Mat& far = projected[order == 0 ? 0 : 1].mask;
    const cv::Mat& near = projected[order == 0 ? 1 : 0].mask;
    const cv::Mat expected_near = RectMask(cv::Rect(150, 150, 100, 100));
    cv::Mat expected_far = RectMask(cv::Rect(67, 100, 150, 200));
    expected_far.setTo(0, expected_near);
    EXPECT_EQ(DifferencesOutsideBorderBand(near, expected_near), 0);
    EXPECT_EQ(DifferencesOutsideBorderBand(far, expected_far), 0);
    EXPECT_EQ(cv::countNonZero(near & far), 0);
  }
}

TEST(ProjectRegionsTest, MissingDepthIsFilledFromTheMedianOrSkipped) {
  const PinholeCamera camera = TestCamera();
  const cv::Rect rect(200, 150, 100, 80);
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0));
  depth(cv::Rect(230, 170, 30, 30)).setTo(0);  // a dropout inside the region
  FrameSegmentation previous;
  previous.instances.push_back(Instance(1, 1, RectMask(rect)));
  const Eigen::Isometry3d T = Translation(0.1, 0, 0);  // 25 px
  const cv::Mat expected = RectMask(rect + cv::Point(25, 0));
  RefinerOptions options;
  EXPECT_EQ(Differences(ProjectRegions(options, camera, previous, depth, T)[0].mask,
                        expected), 0);
  options.fill_missing_depth_with_median = false;
  EXPECT_EQ(ProjectRegions(options, camera, previous, depth, T)[0].area_px,
            100 * 80 - 30 * 30);
}

// A segmenter's table mask that takes in the keyboard on it: the shared pixels have one
// depth, so the z-buffer cannot order them; the keyboard must keep its projection
// whichever region comes first (first-come ties erased it).
TEST(ProjectRegionsTest, OverlappingRegionsLeaveTheSharedPixelsToTheSmaller) {
  const PinholeCamera camera = TestCamera();
  const cv::Rect table(100, 200, 400, 200), keyboard(250, 250, 80, 30);
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0));
  const Eigen::Isometry3d T = Translation(0.1, 0, 0);  // 25 px at 2 m
  const cv::Point shift(25, 0);
  for (int order = 0; order < 2; ++order) {
    SCOPED_TRACE(order);
    FrameSegmentation previous;
    previous.instances.push_back(Instance(1, 67, RectMask(table)));
    previous.instances.push_back(Instance(2, 76, RectMask(keyboard)));
    if (order == 1) std::swap(previous.instances[0], previous.instances[1]);
    const std::vector<ProjectedRegion> projected =
        ProjectRegions(RefinerOptions(), camera, previous, depth, T);
    const cv::Mat& table_projection = projected[order == 0 ? 0 : 1].mask;
    const cv::Mat& keyboard_projection = projected[order == 0 ? 1 : 0].mask;
    EXPECT_EQ(Differences(keyboard_projection, RectMask(keyboard + shift)), 0);
    cv::Mat expected_table = RectMask(table + shift);
    expected_table.setTo(0, RectMask(keyboard + shift));
    EXPECT_EQ(Differences(table_projection, expected_table), 0);
  }
}

// Splatting a region's inside by 2x2 blocks (one point at the block's mean depth) moves
// nothing but the z-buffer's depths by a little: on a slanted surface under a general
// motion each region's projection is the one pixel-by-pixel splatting gives, but for a
// few pixels on its outline. Pixels two regions share are never put in a block (their
// blocks would not align: the keyboard starts at an odd column), so the smaller region
// keeps them exactly.
TEST(ProjectRegionsTest, InsideByBlocksProjectsLikePixelByPixel) {
  const PinholeCamera camera = TestCamera();
  const cv::Rect table(100, 200, 400, 200), keyboard(251, 251, 81, 31);
  cv::Mat depth(480, 640, CV_32F);
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) depth.at<float>(v, u) = 1.5f + 0.002f * u + 0.001f * v;
  }
  Eigen::Isometry3d T = Translation(0.06, -0.02, -0.15);
  T.linear() = Eigen::AngleAxisd(0.03, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  FrameSegmentation previous;
  previous.instances.push_back(Instance(1, 67, RectMask(table)));
  previous.instances.push_back(Instance(2, 76, RectMask(keyboard)));
  RefinerOptions by_pixel, by_block;
  by_pixel.splat_interior_in_blocks = false;
  by_block.splat_interior_in_blocks = true;
  const std::vector<ProjectedRegion> expected = ProjectRegions(by_pixel, camera, previous, depth, T);
  const std::vector<ProjectedRegion> actual = ProjectRegions(by_block, camera, previous, depth, T);
  ASSERT_EQ(actual.size(), 2u);
  EXPECT_EQ(Differences(actual[1].mask, expected[1].mask), 0) << "the keyboard";
  EXPECT_EQ(DifferencesOutsideBorderBand(actual[0].mask, expected[0].mask), 0) << "the table";
  EXPECT_LE(Differences(actual[0].mask, expected[0].mask), expected[0].area_px / 200) << "the table";
  EXPECT_GT(expected[0].area_px, 50000);
}

// A region with no depth at all lies beyond the sensor's far limit: it is projected at
// the farthest depth measured in the previous frame, where translation moves it little
// and rotation moves it exactly; with the option off it is not projected.
TEST(ProjectRegionsTest, RegionWithoutDepthIsProjectedAtTheFarLimit) {
  const PinholeCamera camera = TestCamera();
  const cv::Rect far_car(300, 200, 20, 10);
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(10.0));
  depth(cv::Rect(0, 0, 640, 100)).setTo(40.0);  // the far limit: road far ahead
  depth(far_car).setTo(0);
  FrameSegmentation previous;
  previous.instances.push_back(Instance(1, 3, RectMask(far_car)));
  // The translation moves a point at 40 m by 0.4 / 40 * fx = 5 px to the right, the
  // 2 degree pan about y by about fx * tan(2 deg) = 17.5 px to the left at any depth.
  Eigen::Isometry3d T = Translation(0.4, 0, 0);
  T.linear() = Eigen::AngleAxisd(-2.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  RefinerOptions options;
  const std::vector<ProjectedRegion> projected = ProjectRegions(options, camera, previous, depth, T);
  const cv::Mat expected = ExpectedProjection(camera, far_car, 40.0, T);
  ASSERT_GT(cv::countNonZero(expected), 150);
  EXPECT_EQ(DifferencesOutsideBorderBand(projected[0].mask, expected), 0);
  const cv::Rect expected_box = cv::boundingRect(expected);
  EXPECT_LE(std::abs(projected[0].bbox.x - expected_box.x), 1);
  EXPECT_NEAR(expected_box.x - far_car.x, 5 - 17.5, 1.5);
  options.project_depthless_regions_at_far_limit = false;
  EXPECT_EQ(ProjectRegions(options, camera, previous, depth, T)[0].area_px, 0);
}

// Scene for the refiner tests: three previous regions at 2 m, identity camera motion.
struct Scene {
  PinholeCamera camera = TestCamera();
  cv::Mat depth = cv::Mat(480, 640, CV_32F, cv::Scalar(2.0));
  cv::Rect person_a{60, 100, 80, 200};
  cv::Rect chair{250, 200, 120, 100};
  cv::Rect person_b{450, 80, 90, 250};
  FrameSegmentation previous;
  Scene() {
    previous.instances.push_back(Instance(5, 1, RectMask(person_a), 0.9f));
    previous.instances.push_back(Instance(7, 62, RectMask(chair), 0.8f));
    previous.instances.push_back(Instance(9, 1, RectMask(person_b), 0.7f));
  }
  RefinerInput Input(const FrameSegmentation& current) const {
    RefinerInput in;
    in.previous_refined = &previous;
    in.previous_depth_m = depth;
    in.current_initial = current;
    in.camera = camera;
    return in;
  }
};

const InstanceMask* FindTrack(const FrameSegmentation& s, std::uint16_t id) {
  for (const InstanceMask& m : s.instances) {
    if (m.track_id == id) return &m;
  }
  return nullptr;
}

TEST(SegmentationRefinerTest, FirstFrameGivesFreshIds) {
  SegmentationRefiner refiner;
  RefinerInput in;
  in.camera = TestCamera();
  in.current_initial.instances.push_back(Instance(0, 1, RectMask(cv::Rect(0, 0, 10, 10))));
  in.current_initial.instances.push_back(Instance(0, 3, RectMask(cv::Rect(20, 0, 10, 10))));
  const RefinementResult r = refiner.Refine(in);
  ASSERT_EQ(r.refined.instances.size(), 2u);
  EXPECT_EQ(r.refined.instances[0].track_id, 1);
  EXPECT_EQ(r.refined.instances[1].track_id, 2);
  EXPECT_EQ(r.decisions[0].kind, RegionDecision::Kind::kNew);
}

TEST(SegmentationRefinerTest, RepairsKeepsCarriesIdsAndAddsMissed) {
  const Scene scene;
  FrameSegmentation current;
  // Person A lost its right 40% (a cut-off side); the chair is right; person B missed;
  // the detector numbers its instances freely (ids 1, 2 here are ignored).
  current.instances.push_back(Instance(1, 62, RectMask(scene.chair), 0.85f));
  current.instances.push_back(
      Instance(2, 1, RectMask(cv::Rect(60, 100, 48, 200)), 0.95f));

  RefinerOptions options;
  options.repair_missing_parts = true;
  SegmentationRefiner refiner(options);
  const RefinementResult r = refiner.Refine(scene.Input(current));
  SCOPED_TRACE(r.BriefReport());
  ASSERT_EQ(r.refined.instances.size(), 3u);
  // Chair kept, id carried over, current score kept.
  EXPECT_EQ(r.refined.instances[0].track_id, 7);
  EXPECT_EQ(r.decisions[0].kind, RegionDecision::Kind::kKept);
  EXPECT_EQ(Differences(r.refined.instances[0].mask, RectMask(scene.chair)), 0);
  EXPECT_FLOAT_EQ(r.refined.instances[0].score, 0.85f);
  // Person A repaired to the projection.
  EXPECT_EQ(r.refined.instances[1].track_id, 5);
  EXPECT_EQ(r.decisions[1].kind, RegionDecision::Kind::kReplaced);
  EXPECT_EQ(Differences(r.refined.instances[1].mask, RectMask(scene.person_a)), 0);
  // Person B added from the projection: 3 regions at t-1 > 2 at t.
  EXPECT_EQ(r.refined.instances[2].track_id, 9);
  EXPECT_EQ(r.refined.instances[2].category_id, 1);
  EXPECT_EQ(r.decisions[2].kind, RegionDecision::Kind::kAdded);
  EXPECT_NEAR(r.refined.instances[2].score, 0.7f * options.added_score_decay, 1e-6);
  EXPECT_EQ(Differences(r.refined.instances[2].mask, RectMask(scene.person_b)), 0);
}

// Refine() projects the previous regions by T_cur_prev = T_wc_current_coarse^-1 *
// T_wc_previous_fine: with the camera 0.1 m to the left of where it was (the scene 2 m
// ahead moves 25 px right), on a base pose with a rotation so that a reversed product
// would move the regions elsewhere, the missed person B is added 25 px to the right.
TEST(SegmentationRefinerTest, RegionsFollowTheCameraMotionBetweenThePoses) {
  const Scene scene;
  const cv::Point shift(25, 0);
  FrameSegmentation current;
  current.instances.push_back(Instance(1, 62, RectMask(scene.chair + shift), 0.85f));
  current.instances.push_back(Instance(2, 1, RectMask(scene.person_a + shift), 0.95f));
  RefinerInput in = scene.Input(current);
  Eigen::Isometry3d base = Translation(3, -1, 0.5);
  base.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  in.T_wc_previous_fine = base;
  in.T_wc_current_coarse = base * Translation(-0.1, 0, 0);
  SegmentationRefiner refiner;
  const RefinementResult r = refiner.Refine(in);
  SCOPED_TRACE(r.BriefReport());
  ASSERT_EQ(r.refined.instances.size(), 3u);
  EXPECT_EQ(r.refined.instances[0].track_id, 7);
  EXPECT_EQ(r.refined.instances[1].track_id, 5);
  EXPECT_EQ(r.refined.instances[2].track_id, 9);
  EXPECT_EQ(r.decisions[2].kind, RegionDecision::Kind::kAdded);
  EXPECT_EQ(Differences(r.refined.instances[2].mask, RectMask(scene.person_b + shift)), 0);
}

// A new region scoring under min_new_region_score is dropped without a track id, so a
// long run of weak detections cannot use the 65534 ids up.
// Only a track the segmenter detected in two frames is carried on when it is missed: a
// detection seen once (most likely a false positive) leaves no ghost behind.
TEST(SegmentationRefinerTest, OnlyConfirmedTracksAreAddedBackWhenMissed) {
  const PinholeCamera camera = TestCamera();
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0));
  const cv::Rect person(100, 100, 60, 150), bag(400, 300, 50, 40);
  auto frame = [&](bool with_person, bool with_bag) {
    FrameSegmentation s;
    if (with_person) s.instances.push_back(Instance(0, 1, RectMask(person), 0.9f));
    if (with_bag) s.instances.push_back(Instance(0, 27, RectMask(bag), 0.5f));
    return s;
  };
  SegmentationRefiner refiner;
  RefinerInput in;
  in.camera = camera;
  in.current_initial = frame(true, false);
  FrameSegmentation previous = refiner.Refine(in).refined;  // frame 0: the person
  in.previous_refined = &previous;
  in.previous_depth_m = depth;
  in.current_initial = frame(true, true);  // frame 1: the person again, a bag once
  previous = refiner.Refine(in).refined;
  ASSERT_EQ(previous.instances.size(), 2u);
  const std::uint16_t person_id = previous.instances[0].track_id;
  in.current_initial = frame(false, false);  // frame 2: the segmenter misses both
  const RefinementResult missed = refiner.Refine(in);
  SCOPED_TRACE(missed.BriefReport());
  ASSERT_EQ(missed.refined.instances.size(), 1u);
  EXPECT_EQ(missed.refined.instances[0].track_id, person_id);
  EXPECT_EQ(Differences(missed.refined.instances[0].mask, RectMask(person)), 0);
  ASSERT_EQ(missed.decisions.size(), 2u);
  EXPECT_EQ(missed.decisions[0].kind, RegionDecision::Kind::kAdded);
  EXPECT_EQ(missed.decisions[1].kind, RegionDecision::Kind::kDropped);

  // With every track confirmed from its first detection, the bag's ghost is added too.
  RefinerOptions any_track;
  any_track.min_detections_to_add = 1;
  SegmentationRefiner eager(any_track);
  in.previous_refined = nullptr;
  in.previous_depth_m = cv::Mat();
  in.current_initial = frame(true, false);
  previous = eager.Refine(in).refined;
  in.previous_refined = &previous;
  in.previous_depth_m = depth;
  in.current_initial = frame(true, true);
  previous = eager.Refine(in).refined;
  in.current_initial = frame(false, false);
  EXPECT_EQ(eager.Refine(in).refined.instances.size(), 2u);
}

TEST(SegmentationRefinerTest, DroppedNewRegionsTakeNoTrackId) {
  const Scene scene;
  FrameSegmentation current;
  current.instances.push_back(Instance(1, 62, RectMask(scene.chair), 0.85f));
  current.instances.push_back(Instance(2, 44, RectMask(cv::Rect(300, 400, 30, 30)), 0.1f));  // weak, new
  current.instances.push_back(Instance(3, 47, RectMask(cv::Rect(200, 20, 30, 30)), 0.9f));   // strong, new
  SegmentationRefiner refiner;
  const RefinementResult r = refiner.Refine(scene.Input(current));
  SCOPED_TRACE(r.BriefReport());
  ASSERT_GE(r.decisions.size(), 3u);  // the current regions' decisions first, in order
  EXPECT_EQ(r.decisions[1].kind, RegionDecision::Kind::kDropped);
  EXPECT_EQ(r.decisions[1].track_id, 0);
  EXPECT_EQ(r.decisions[2].kind, RegionDecision::Kind::kNew);
  // The previous frame's ids go up to 9: the strong region takes the next one.
  EXPECT_EQ(r.decisions[2].track_id, 10);
  ASSERT_NE(FindTrack(r.refined, 10), nullptr);
  EXPECT_EQ(FindTrack(r.refined, 10)->category_id, 47);
}

TEST(SegmentationRefinerTest, PaperRuleShrinksOversizedAndKeepsCutOff) {
  const Scene scene;
  FrameSegmentation current;
  // Person A oversized (30 px too wide), chair cut off, person B right, plus a new cup.
  current.instances.push_back(Instance(0, 1, RectMask(cv::Rect(60, 100, 110, 200))));
  current.instances.push_back(Instance(0, 62, RectMask(cv::Rect(250, 200, 80, 100))));
  current.instances.push_back(Instance(0, 1, RectMask(scene.person_b)));
  current.instances.push_back(Instance(0, 47, RectMask(cv::Rect(10, 400, 30, 30))));
  RefinerOptions paper;  // the paper's rule: exact ratios, any gap, take Re_p
  paper.replace_min_ratio_gap = 0;
  paper.boundary_tolerance_px = 0;
  paper.trim_instead_of_replace = false;
  SegmentationRefiner refiner(paper);
  const RefinementResult r = refiner.Refine(scene.Input(current));
  SCOPED_TRACE(r.BriefReport());
  ASSERT_EQ(r.refined.instances.size(), 4u);
  EXPECT_EQ(r.decisions[0].kind, RegionDecision::Kind::kReplaced);
  EXPECT_EQ(r.refined.instances[0].track_id, 5);
  EXPECT_EQ(Differences(r.refined.instances[0].mask, RectMask(scene.person_a)), 0);
  EXPECT_EQ(r.decisions[1].kind, RegionDecision::Kind::kKept);
  EXPECT_EQ(r.refined.instances[1].track_id, 7);
  EXPECT_EQ(r.decisions[2].kind, RegionDecision::Kind::kKept);
  EXPECT_EQ(r.refined.instances[2].track_id, 9);
  EXPECT_EQ(r.decisions[3].kind, RegionDecision::Kind::kNew);
  EXPECT_EQ(r.refined.instances[3].track_id, 10);  // above every previous id
}

TEST(SegmentationRefinerTest, DefaultsKeepSlightlyLargerRegionsAndTrimGrossOnes) {
  const Scene scene;
  FrameSegmentation current;
  // Person A 30 px too wide (gap 1 - 80/110 = 0.27 < 0.45: kept as it is, the paper
  // would replace it); person B twice as wide (gap ~0.5: trimmed to the projection
  // plus the 2 px tolerance, on the side where it bled).
  const cv::Rect wide_a(scene.person_a.x, scene.person_a.y, scene.person_a.width + 30,
                        scene.person_a.height);
  const cv::Rect wide_b(scene.person_b.x, scene.person_b.y, 2 * scene.person_b.width,
                        scene.person_b.height);
  current.instances.push_back(Instance(0, 1, RectMask(wide_a), 0.6f));
  current.instances.push_back(Instance(0, 62, RectMask(scene.chair), 0.9f));
  current.instances.push_back(Instance(0, 1, RectMask(wide_b), 0.5f));
  SegmentationRefiner refiner;
  const RefinementResult r = refiner.Refine(scene.Input(current));
  SCOPED_TRACE(r.BriefReport());
  ASSERT_EQ(r.refined.instances.size(), 3u);
  EXPECT_EQ(r.decisions[0].kind, RegionDecision::Kind::kKept);
  EXPECT_EQ(r.refined.instances[0].track_id, 5);
  EXPECT_EQ(Differences(r.refined.instances[0].mask, RectMask(wide_a)), 0);
  EXPECT_EQ(r.decisions[1].kind, RegionDecision::Kind::kKept);
  EXPECT_EQ(r.decisions[2].kind, RegionDecision::Kind::kReplaced);
  EXPECT_EQ(r.refined.instances[2].track_id, 9);
  const cv::Rect trimmed_b(scene.person_b.x, scene.person_b.y, scene.person_b.width + 2,
                           scene.person_b.height);
  EXPECT_LE(Differences(r.refined.instances[2].mask, RectMask(trimmed_b)), 4);
  EXPECT_FLOAT_EQ(r.refined.instances[2].score, 0.5f);  // scores are the segmenter's
}

// trim_keeps_region_depth (on by default): person B twice as wide as its projection (gap
// ~0.5, so the trim rule fires). Where the extra width has the person's depth, it grew (stepped in from behind
// something): kept whole. Where the extra width shows the wall 2 m behind, it is bleeding:
// trimmed as without the option.
TEST(SegmentationRefinerTest, TrimKeepsWhatLiesAtTheRegionsDepth) {
  const Scene scene;
  const cv::Rect wide_b(scene.person_b.x, scene.person_b.y, 2 * scene.person_b.width, scene.person_b.height);
  FrameSegmentation current;
  current.instances.push_back(Instance(0, 1, RectMask(scene.person_a)));
  current.instances.push_back(Instance(0, 62, RectMask(scene.chair)));
  current.instances.push_back(Instance(0, 1, RectMask(wide_b)));
  RefinerOptions options;
  options.trim_keeps_region_depth = true;
  const cv::Rect trimmed_b(scene.person_b.x, scene.person_b.y, scene.person_b.width + 2, scene.person_b.height);

  RefinerInput grown = scene.Input(current);
  grown.current_depth_m = scene.depth.clone();  // the whole wide region at 2 m
  const RefinementResult kept = SegmentationRefiner(options).Refine(grown);
  SCOPED_TRACE(kept.BriefReport());
  ASSERT_EQ(kept.refined.instances.size(), 3u);
  EXPECT_EQ(kept.decisions[2].kind, RegionDecision::Kind::kReplaced);  // the trim rule fired
  EXPECT_EQ(Differences(kept.refined.instances[2].mask, RectMask(wide_b)), 0);

  RefinerInput bled = scene.Input(current);
  bled.current_depth_m = scene.depth.clone();
  bled.current_depth_m(cv::Rect(scene.person_b.br().x, 0, 640 - scene.person_b.br().x, 480)).setTo(4.0);
  const RefinementResult cut = SegmentationRefiner(options).Refine(bled);
  SCOPED_TRACE(cut.BriefReport());
  ASSERT_EQ(cut.refined.instances.size(), 3u);
  EXPECT_EQ(cut.decisions[2].kind, RegionDecision::Kind::kReplaced);
  EXPECT_LE(Differences(cut.refined.instances[2].mask, RectMask(trimmed_b)), 4);
  // Without the option the grown region is trimmed too: what the option changes.
  RefinerOptions without = options;
  without.trim_keeps_region_depth = false;
  const RefinementResult plain_trim = SegmentationRefiner(without).Refine(grown);
  EXPECT_LE(Differences(plain_trim.refined.instances[2].mask, RectMask(trimmed_b)), 4);
}

// The refinement reads each mask only inside its bounds (seg/segmentation.h). Tight,
// loose or no bounds give the same refinement, two frames on, and every refined region
// (kept, repaired, trimmed, added, new) comes out with bounds that hold its pixels.
TEST(SegmentationRefinerTest, BoundsTightLooseOrNoneRefineAlike) {
  const Scene scene;
  const cv::Rect wide_b(scene.person_b.x, scene.person_b.y, 2 * scene.person_b.width, scene.person_b.height);
  FrameSegmentation repaired_and_added;  // person A cut off, chair right, person B missed
  repaired_and_added.instances.push_back(Instance(0, 62, RectMask(scene.chair), 0.85f));
  repaired_and_added.instances.push_back(Instance(0, 1, RectMask(cv::Rect(60, 100, 48, 200)), 0.95f));
  FrameSegmentation trimmed_and_new;  // person B bled twice as wide, a new cup
  trimmed_and_new.instances.push_back(Instance(0, 1, RectMask(scene.person_a)));
  trimmed_and_new.instances.push_back(Instance(0, 62, RectMask(scene.chair)));
  trimmed_and_new.instances.push_back(Instance(0, 1, RectMask(wide_b)));
  trimmed_and_new.instances.push_back(Instance(0, 47, RectMask(cv::Rect(10, 400, 30, 30))));
  RefinerOptions options;
  options.repair_missing_parts = true;

  const auto with_bounds = [](FrameSegmentation s, int margin) {
    for (InstanceMask& instance : s.instances) {
      if (margin < 0) continue;  // none: the whole frame
      FitBounds(&instance);
      instance.bounds = cv::Rect(instance.bounds.x - margin, instance.bounds.y - margin,
                                 instance.bounds.width + 2 * margin, instance.bounds.height + 2 * margin);
    }
    return s;
  };
  for (const FrameSegmentation& current : {repaired_and_added, trimmed_and_new}) {
    std::vector<RefinementResult> second_frames;
    for (const int margin : {-1, 0, 7}) {
      SCOPED_TRACE("margin " + std::to_string(margin));
      SegmentationRefiner refiner(options);
      RefinerInput in = scene.Input(with_bounds(current, margin));
      in.current_depth_m = scene.depth;
      const RefinementResult first = refiner.Refine(in);
      SCOPED_TRACE(first.BriefReport());
      for (const InstanceMask& instance : first.refined.instances) {
        EXPECT_FALSE(instance.bounds.empty());
        EXPECT_TRUE(BoundsHoldMask(instance)) << "track " << instance.track_id;
      }
      // The next frame projects the refined regions: their bounds are what it reads.
      in.previous_refined = &first.refined;
      second_frames.push_back(refiner.Refine(in));
    }
    for (size_t k = 1; k < second_frames.size(); ++k) {
      const RefinementResult& a = second_frames[0];
      const RefinementResult& b = second_frames[k];
      EXPECT_EQ(a.BriefReport(), b.BriefReport());
      ASSERT_EQ(a.refined.instances.size(), b.refined.instances.size());
      for (size_t i = 0; i < a.refined.instances.size(); ++i) {
        EXPECT_EQ(a.refined.instances[i].track_id, b.refined.instances[i].track_id);
        EXPECT_EQ(Differences(a.refined.instances[i].mask, b.refined.instances[i].mask), 0);
      }
    }
  }
}

TEST(SegmentationRefinerTest, NoAddWhenCountsAreEqualAndCategoryMustMatch) {
  const Scene scene;
  FrameSegmentation current;
  // Person B missed, but a dog appears where the chair was: 3 = 3 regions, no add; the
  // dog does not take the chair's id.
  current.instances.push_back(Instance(0, 1, RectMask(scene.person_a)));
  current.instances.push_back(Instance(0, 18, RectMask(scene.chair)));
  current.instances.push_back(Instance(0, 1, RectMask(cv::Rect(300, 20, 40, 40))));
  RefinerOptions paper;  // the paper's count rule (the default adds per region)
  paper.add_unmatched = AddUnmatchedRule::kPaperCountRule;
  SegmentationRefiner refiner(paper);
  const RefinementResult r = refiner.Refine(scene.Input(current));
  SCOPED_TRACE(r.BriefReport());
  ASSERT_EQ(r.refined.instances.size(), 3u);
  EXPECT_EQ(r.refined.instances[0].track_id, 5);
  EXPECT_EQ(r.decisions[1].kind, RegionDecision::Kind::kNew);
  EXPECT_NE(r.refined.instances[1].track_id, 7);
  EXPECT_EQ(FindTrack(r.refined, 9), nullptr);
  EXPECT_EQ(r.decisions.back().kind, RegionDecision::Kind::kDropped);
}

TEST(SegmentationRefinerTest, PerfectInputWithIdentityMotionIsUnchanged) {
  // Several regions on a slanted, noisy-free depth with dropouts, camera still.
  const PinholeCamera camera = TestCamera();
  cv::Mat depth(480, 640, CV_32F);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) depth.at<float>(y, x) = 1.5f + 0.002f * x + 0.001f * y;
  }
  depth(cv::Rect(100, 100, 10, 10)).setTo(0);
  FrameSegmentation previous;
  cv::Mat ellipse(480, 640, CV_8U, cv::Scalar(0));
  cv::ellipse(ellipse, cv::Point(400, 300), cv::Size(60, 40), 30, 0, 360, cv::Scalar(1),
              cv::FILLED);
  previous.instances.push_back(Instance(3, 1, RectMask(cv::Rect(90, 90, 60, 90))));
  previous.instances.push_back(Instance(4, 62, ellipse));
  previous.instances.push_back(Instance(8, 44, RectMask(cv::Rect(500, 20, 3, 300))));
  FrameSegmentation current = previous;
  for (InstanceMask& m : current.instances) m.track_id = 0;
  RefinerInput in;
  in.previous_refined = &previous;
  in.previous_depth_m = depth;
  in.current_initial = current;
  in.camera = camera;
  const Eigen::Isometry3d pose = Translation(1, 2, 3);
  in.T_wc_previous_fine = pose;
  in.T_wc_current_coarse = pose;
  for (bool repair : {false, true}) {
    RefinerOptions options;
    options.repair_missing_parts = repair;
    SegmentationRefiner refiner(options);
    const RefinementResult r = refiner.Refine(in);
    SCOPED_TRACE(r.BriefReport());
    ASSERT_EQ(r.refined.instances.size(), previous.instances.size());
    for (size_t i = 0; i < previous.instances.size(); ++i) {
      EXPECT_EQ(r.refined.instances[i].track_id, previous.instances[i].track_id);
      EXPECT_EQ(r.decisions[i].kind, RegionDecision::Kind::kKept);
      EXPECT_EQ(Differences(r.refined.instances[i].mask, previous.instances[i].mask), 0);
    }
  }
}

TEST(SegmentationRefinerTest, InstanceOwnMotionMovesOnlyThatRegion) {
  const Scene scene;
  // The chair (id 7) moved 0.1 m right at 2 m depth: 25 px; the camera is still.
  RefinerInput in = scene.Input(FrameSegmentation());
  in.instance_motion_prev[7] = Translation(0.1, 0, 0);
  const std::vector<ProjectedRegion> projected =
      ProjectRegions(RefinerOptions(), scene.camera, scene.previous, scene.depth,
                     Eigen::Isometry3d::Identity(), in.instance_motion_prev);
  EXPECT_EQ(Differences(projected[0].mask, RectMask(scene.person_a)), 0);
  EXPECT_EQ(Differences(projected[1].mask, RectMask(scene.chair + cv::Point(25, 0))), 0);
  EXPECT_EQ(Differences(projected[2].mask, RectMask(scene.person_b)), 0);

  // Through Refine: the moved chair is matched and keeps its id.
  FrameSegmentation current;
  current.instances.push_back(Instance(0, 1, RectMask(scene.person_a)));
  current.instances.push_back(Instance(0, 62, RectMask(scene.chair + cv::Point(25, 0))));
  current.instances.push_back(Instance(0, 1, RectMask(scene.person_b)));
  in.current_initial = current;
  SegmentationRefiner refiner;
  const RefinementResult r = refiner.Refine(in);
  EXPECT_EQ(r.refined.instances[1].track_id, 7);
  EXPECT_EQ(r.decisions[1].kind, RegionDecision::Kind::kKept);
  EXPECT_DOUBLE_EQ(r.decisions[1].ratio_current, 1.0);
}

TEST(RefinerOptionsTest, IsValidReportsEachError) {
  std::string error;
  EXPECT_TRUE(RefinerOptions().IsValid(&error));
  auto expect_invalid = [](RefinerOptions o, const std::string& field) {
    std::string message;
    EXPECT_FALSE(o.IsValid(&message)) << field;
    EXPECT_NE(message.find(field), std::string::npos) << message;
    EXPECT_FALSE(o.IsValid(nullptr));
  };
  RefinerOptions o;
  o.w_barycenter = -1;
  expect_invalid(o, "w_barycenter");
  o = {};
  o.w_shape = NAN;
  expect_invalid(o, "w_shape");
  o = {};
  o.w_shape = 0;
  o.w_barycenter = 0;
  expect_invalid(o, "both");
  o = {};
  o.max_match_cost = 0;
  expect_invalid(o, "max_match_cost");
  o = {};
  o.splat_footprint_scale = 0.2;
  expect_invalid(o, "splat_footprint_scale");
  o = {};
  o.hole_fill_iterations = -1;
  expect_invalid(o, "hole_fill_iterations");
  o = {};
  o.depth_tolerance = 1;
  expect_invalid(o, "depth_tolerance");
  o = {};
  o.min_depth_m = 0;
  expect_invalid(o, "min_depth_m");
  o = {};
  o.min_projected_area_px = -1;
  expect_invalid(o, "min_projected_area_px");
  o = {};
  o.min_far_projected_area_px = -1;
  expect_invalid(o, "min_far_projected_area_px");
  o = {};
  o.repair_min_current_inside = 1.5;
  expect_invalid(o, "repair_min_current_inside");
  o = {};
  o.repair_max_projected_covered = 0;
  expect_invalid(o, "repair_max_projected_covered");
  o = {};
  o.added_score_decay = 0;
  expect_invalid(o, "added_score_decay");
  o = {};
  o.min_added_score = 2;
  expect_invalid(o, "min_added_score");
  o = {};
  o.min_detections_to_add = 0;
  expect_invalid(o, "min_detections_to_add");
  RefinerOptions bad;
  bad.max_match_cost = -1;
  EXPECT_THROW(SegmentationRefiner{bad}, Error);
}

TEST(SegmentationRefinerTest, RejectsWrongImageSizes) {
  const Scene scene;
  RefinerInput in = scene.Input(FrameSegmentation());
  in.previous_depth_m = cv::Mat(10, 10, CV_32F, cv::Scalar(1));
  SegmentationRefiner refiner;
  EXPECT_THROW(refiner.Refine(in), Error);
}

// A wrong-sized mask is refused before any work, on the first frame too, and leaves the
// refiner as it was: the next frame is refined as by a refiner that never saw it.
TEST(SegmentationRefinerTest, WrongSizedMaskLeavesTheRefinerAsItWas) {
  const Scene scene;
  const cv::Mat small(240, 320, CV_8U, cv::Scalar(1));
  FrameSegmentation broken_previous;
  broken_previous.instances.push_back(Instance(5, 1, RectMask(scene.person_a)));
  broken_previous.instances.push_back(Instance(6, 1, small));
  RefinerInput broken = scene.Input(FrameSegmentation());
  broken.previous_refined = &broken_previous;
  SegmentationRefiner used;
  EXPECT_THROW(used.Refine(broken), Error);

  FrameSegmentation first_frame;
  first_frame.instances.push_back(Instance(1, 1, small));
  RefinerInput first = scene.Input(first_frame);
  first.previous_refined = nullptr;
  EXPECT_THROW(used.Refine(first), Error);

  // The next frame's previous regions lie elsewhere, then where the refused one's first
  // region was.
  FrameSegmentation previous;
  previous.instances.push_back(Instance(7, 62, RectMask(scene.chair)));
  previous.instances.push_back(Instance(9, 1, RectMask(scene.person_a)));
  FrameSegmentation current;
  current.instances.push_back(Instance(1, 1, RectMask(scene.person_a)));
  RefinerInput next = scene.Input(current);
  next.previous_refined = &previous;
  SegmentationRefiner fresh;
  const RefinementResult expected = fresh.Refine(next);
  const RefinementResult actual = used.Refine(next);
  ASSERT_EQ(actual.decisions.size(), expected.decisions.size());
  for (size_t i = 0; i < expected.decisions.size(); ++i) {
    EXPECT_EQ(actual.decisions[i].kind, expected.decisions[i].kind) << "decision " << i;
    EXPECT_EQ(actual.decisions[i].projected_area_px, expected.decisions[i].projected_area_px) << "decision " << i;
  }
  ASSERT_GT(expected.decisions[0].projected_area_px, 0);
}

}  // namespace
}  // namespace segslam::seg
