// The loop on a ray-cast room (tests/slam/synthetic_room.h) with a scripted segmenter:
// exact poses and masks, so each step's hand-over can be checked without the simulator.
#include "mutual/frame_pipeline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "core/coco.h"
#include "core/error.h"
#include "tests/slam/synthetic_room.h"
#include "tests/slam/tracking_steps.h"

namespace segslam::mutual {
namespace {

using slam::testing::BoxQuads;
using slam::testing::LookingAlongX;
using slam::testing::RenderedFrame;
using slam::testing::RenderQuads;
using slam::testing::RoomQuads;

constexpr int kPersonCategory = 1;
constexpr int kTvCategory = 72;  // not moveable: a fixture
constexpr std::uint16_t kBoxId = 5;
constexpr int kMissedFrame = 6;  // the scripted segmenter misses the box here
constexpr int kFrames = 10;

seg::InstanceMask Box(std::uint16_t id, int category, cv::Rect box, cv::Size size) {
  seg::InstanceMask instance;
  instance.track_id = id;
  instance.category_id = category;
  instance.mask = cv::Mat::zeros(size, CV_8U);
  instance.mask(box).setTo(1);
  return instance;
}

TEST(ToFrameInstancesTest, IdImageAndMoveableIds) {
  const cv::Size size(40, 30);
  seg::FrameSegmentation segmentation;
  segmentation.instances.push_back(Box(7, kPersonCategory, {0, 0, 10, 10}, size));
  segmentation.instances.push_back(Box(9, kTvCategory, {20, 10, 10, 10}, size));
  ASSERT_TRUE(IsMoveableCategory(kPersonCategory));
  ASSERT_FALSE(IsMoveableCategory(kTvCategory));
  const slam::FrameInstances instances = ToFrameInstances(segmentation, size);
  ASSERT_EQ(instances.ids.type(), CV_16U);
  EXPECT_EQ(instances.ids.at<std::uint16_t>(5, 5), 7);
  EXPECT_EQ(instances.ids.at<std::uint16_t>(15, 25), 9);
  EXPECT_EQ(instances.ids.at<std::uint16_t>(25, 5), 0);
  EXPECT_EQ(instances.moveable_ids, (std::unordered_set<std::uint16_t>{7}));
}

// The box's exact mask every frame, with an id of its own choosing, except in
// kMissedFrame, where it reports nothing.
class ScriptedSegmenter : public seg::Segmenter {
 public:
  explicit ScriptedSegmenter(const std::vector<RenderedFrame>& frames) : frames_(frames) {}
  seg::FrameSegmentation Segment(const RgbdFrame& frame) override {
    seg::FrameSegmentation out;
    out.frame_index = frame.index;
    if (frame.index == kMissedFrame) return out;
    seg::InstanceMask box;
    box.track_id = static_cast<std::uint16_t>(100 + frame.index);  // not stable: the refiner's job
    box.category_id = kTvCategory;
    box.score = 0.9f;
    box.mask = frames_[static_cast<size_t>(frame.index)].instance_ids == kBoxId;
    box.mask /= 255;
    out.instances.push_back(box);
    return out;
  }
  std::string name() const override { return "scripted"; }

 private:
  const std::vector<RenderedFrame>& frames_;
};

// The camera turns 0.03 rad a frame (about 15 px of image motion on the box), so the
// previous frame's mask left where it was would no longer fit the box.
Eigen::Isometry3d PathPose(int i) {
  return LookingAlongX(Eigen::Vector3d(-2.0 + 0.01 * i, 0.005 * i, 1.4), 0.03 * i);
}

double IoU(const cv::Mat& a, const cv::Mat& b) {
  return static_cast<double>(cv::countNonZero(a & b)) / cv::countNonZero(a | b);
}

TEST(MutualLoopTest, RefinedIdsStayStableAndAMissedDetectionIsCarriedOver) {
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 50);
  std::vector<slam::testing::TexturedQuad> scene = RoomQuads(1);
  for (auto& quad : BoxQuads({0.5, -0.5, 0.8}, {1.3, 0.4, 1.8}, 7, kBoxId)) scene.push_back(quad);
  std::vector<RenderedFrame> frames;
  for (int i = 0; i < kFrames; ++i) frames.push_back(RenderQuads(scene, camera, PathPose(i), i, i / 30.0));

  ScriptedSegmenter segmenter(frames);
  FramePipelineOptions options;
  options.tracker.initial_T_wc = PathPose(0);
  FramePipeline loop(camera, options, &segmenter);
  std::set<std::uint16_t> refined_ids;
  for (int i = 0; i < kFrames; ++i) {
    const FrameStep result = loop.ProcessFrame(frames[static_cast<size_t>(i)].frame);
    ASSERT_TRUE(result.slam.localized()) << "frame " << i;
    EXPECT_LT((result.slam.T_wc.translation() - PathPose(i).translation()).norm(), 0.01) << "frame " << i;
    EXPECT_EQ(result.refined_from_previous, i > 0) << "frame " << i;
    EXPECT_EQ(result.initial.instances.size(), i == kMissedFrame ? 0u : 1u);
    // The missed box comes back from the projection of the previous refined mask.
    ASSERT_EQ(result.refined.instances.size(), 1u) << "frame " << i;
    const seg::InstanceMask& refined = result.refined.instances[0];
    refined_ids.insert(refined.track_id);
    const cv::Mat truth = frames[static_cast<size_t>(i)].instance_ids == kBoxId;
    EXPECT_GT(IoU(truth, refined.mask != 0), 0.95) << "frame " << i;
    if (i == kMissedFrame) {
      const cv::Mat unmoved = frames[static_cast<size_t>(i) - 1].instance_ids == kBoxId;
      EXPECT_LT(IoU(truth, unmoved), 0.9) << "the test's motion is too small to show the projection";
    }
    // SLAM judged the refined instance, under the refined id.
    ASSERT_EQ(result.slam.instances.size(), 1u) << "frame " << i;
    EXPECT_EQ(result.slam.instances[0].id, refined.track_id);
    EXPECT_FALSE(result.slam.instances[0].moving) << "frame " << i;
  }
  EXPECT_EQ(refined_ids.size(), 1u);
}

// Every instance of the rendered id image with its true mask, under a fixed COCO class
// per rendered id and the rendered id as the segmenter's track id.
class GroundTruthSegmenter : public seg::Segmenter {
 public:
  GroundTruthSegmenter(const std::vector<RenderedFrame>& frames, std::map<std::uint16_t, int> category_of)
      : frames_(frames), category_of_(std::move(category_of)) {}
  seg::FrameSegmentation Segment(const RgbdFrame& frame) override {
    seg::FrameSegmentation out;
    out.frame_index = frame.index;
    for (const auto& [rendered_id, category] : category_of_) {
      seg::InstanceMask instance;
      instance.track_id = rendered_id;
      instance.category_id = category;
      instance.score = 0.9f;
      instance.mask = frames_[static_cast<size_t>(frame.index)].instance_ids == rendered_id;
      instance.mask /= 255;
      if (cv::countNonZero(instance.mask) > 0) out.instances.push_back(instance);
    }
    return out;
  }
  std::string name() const override { return "ground truth"; }

 private:
  const std::vector<RenderedFrame>& frames_;
  std::map<std::uint16_t, int> category_of_;
};

// A slow walk forward with a little sway and yaw, keeping both halves of the room in view.
Eigen::Isometry3d SwayingPose(int i) {
  const double t = i / 30.0;
  return LookingAlongX(Eigen::Vector3d(-2.0 + 0.25 * t, 0.1 * std::sin(1.3 * t), 1.4 + 0.05 * std::sin(2 * t)),
                       0.08 * std::sin(2 * t));
}

double PositionErrorM(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

// An axis-aligned box standing on the floor (z = 0).
struct Volume {
  Eigen::Vector3d min, max;
  // Whether `p` lies on or in the box, `margin_m` allowing for the depth noise of a
  // point on its surface.
  bool Holds(const Eigen::Vector3d& p, double margin_m) const {
    return (p.array() > min.array() - margin_m).all() && (p.array() < max.array() + margin_m).all();
  }
  // The same, leaving out the floor around the box's foot, which is background.
  bool HoldsAboveTheFloor(const Eigen::Vector3d& p, double margin_m) const {
    return Holds(p, margin_m) && p.z() > margin_m;
  }
};

// A person walks away from the camera at 1.5 m/s in the right half of the view, from
// 1.2 m in front of it, while a car stands parked in the left half. The walker covers a
// third of the first frame, enough to drag a tracker that does not judge it; the two never
// overlap in the image (an occluding walker's silhouette lends its motion to the features
// of what it hides, a case of its own). Both are of moveable classes, so neither belongs
// in the long-term map; only the walker must be kept out of the pose and the tracking map.
TEST(MutualLoopTest, WalkingPersonIsJudgedMovingAndParkedCarStaticThroughTheLoop) {
  constexpr std::uint16_t kWalker = 1, kCar = 2;
  constexpr int kCarCategory = 3;
  ASSERT_TRUE(IsMoveableCategory(kPersonCategory));
  ASSERT_TRUE(IsMoveableCategory(kCarCategory));
  constexpr int kFrames = 40;
  auto walker_at = [](int i) {
    const double x = -0.8 + 1.5 * i / 30.0;
    return Volume{{x, 0.1, 0.0}, {x + 0.4, 0.7, 1.8}};
  };
  const Volume car{{1.5, -1.7, 0.0}, {3.9, -0.2, 1.4}};
  const Volume walker_swept{walker_at(0).min, walker_at(kFrames - 1).max};
  // Depth noise allowance around a surface (the rendered depth is exact; the estimated
  // pose is good to about a centimetre).
  constexpr double kSurfaceMarginM = 0.02;

  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 50);
  const std::vector<slam::testing::TexturedQuad> room = RoomQuads(5);
  const auto car_quads = BoxQuads(car.min, car.max, 77, kCar);
  std::vector<RenderedFrame> frames;
  for (int i = 0; i < kFrames; ++i) {
    auto scene = room;
    const auto walker_quads = BoxQuads(walker_at(i).min, walker_at(i).max, 99, kWalker);
    scene.insert(scene.end(), walker_quads.begin(), walker_quads.end());
    scene.insert(scene.end(), car_quads.begin(), car_quads.end());
    frames.push_back(RenderQuads(scene, camera, SwayingPose(i), i, i / 30.0));
  }

  GroundTruthSegmenter segmenter(frames, {{kWalker, kPersonCategory}, {kCar, kCarCategory}});
  FramePipelineOptions options;
  options.tracker.initial_T_wc = SwayingPose(0);
  FramePipeline loop(camera, options, &segmenter);
  std::set<std::uint16_t> walker_ids, car_ids;
  int walker_judged = 0, walker_moving = 0, car_judged = 0, car_static = 0;
  double worst_m = 0, sum_squared_m2 = 0, worst_deg = 0;
  for (int i = 0; i < kFrames; ++i) {
    const FrameStep result = loop.ProcessFrame(frames[static_cast<size_t>(i)].frame);
    ASSERT_TRUE(result.slam.localized()) << "frame " << i;
    const double error_m = PositionErrorM(result.slam.T_wc, SwayingPose(i));
    worst_m = std::max(worst_m, error_m);
    sum_squared_m2 += error_m * error_m;
    worst_deg = std::max(worst_deg, Eigen::AngleAxisd(result.slam.T_wc.linear().transpose() * SwayingPose(i).linear())
                                            .angle() * 180.0 / M_PI);
    // The refined instance of each rendered one, by overlap: the refiner numbers them.
    std::map<std::uint16_t, std::uint16_t> rendered_of_refined;
    for (const seg::InstanceMask& refined : result.refined.instances) {
      for (const std::uint16_t rendered : {kWalker, kCar}) {
        if (IoU(frames[static_cast<size_t>(i)].instance_ids == rendered, refined.mask != 0) > 0.9) {
          rendered_of_refined[refined.track_id] = rendered;
        }
      }
    }
    ASSERT_EQ(rendered_of_refined.size(), 2u) << "frame " << i;
    // No point lies where the walker walked, whatever its label (a point of the walker
    // labelled background would be as wrong), after any frame: one made on the walker
    // and dropped a frame later would still have served that frame's coarse pose.
    int walker_points = 0;
    for (const auto& point : loop.tracker().map().points()) {
      walker_points += !point->bad && walker_swept.HoldsAboveTheFloor(point->position_w, kSurfaceMarginM);
    }
    EXPECT_EQ(walker_points, 0) << "frame " << i;
    for (const slam::InstanceJudgement& judgement : result.slam.instances) {
      ASSERT_EQ(rendered_of_refined.count(judgement.id), 1u) << "frame " << i << ": judged id " << judgement.id;
      EXPECT_TRUE(judgement.moveable_class);
      const bool is_walker = rendered_of_refined[judgement.id] == kWalker;
      (is_walker ? walker_ids : car_ids).insert(judgement.id);
      if (!judgement.judged) continue;
      if (is_walker) {
        ++walker_judged;
        walker_moving += judgement.moving;
      } else {
        ++car_judged;
        car_static += !judgement.moving;
      }
    }
  }
  ASSERT_EQ(walker_ids.size(), 1u) << "the refiner keeps the walker's id";
  ASSERT_EQ(car_ids.size(), 1u) << "the refiner keeps the car's id";
  const std::uint16_t walker_id = *walker_ids.begin(), car_id = *car_ids.begin();

  // Both are unjudged, and kept out, until a motion baseline (0.3 s, 9 frames) has passed.
  EXPECT_GE(walker_judged, kFrames / 2);
  EXPECT_GE(walker_moving, 0.9 * walker_judged);
  EXPECT_GE(car_judged, kFrames / 2);
  EXPECT_GE(car_static, 0.9 * car_judged);

  // The room alone is tracked to within 1 cm and 0.3 degrees (TrackerTest.
  // FollowsAKnownPathInATexturedRoom); with the walker kept out, so is this scene, to
  // twice that at worst. Tracked without masks (plain), the walker drags the pose by tens
  // of centimetres: the tolerance is far below what a walker in the pose costs.
  EXPECT_LT(std::sqrt(sum_squared_m2 / kFrames), 0.01);
  EXPECT_LT(worst_m, 0.02);
  EXPECT_LT(worst_deg, 0.5);
  slam::Tracker plain(camera, options.tracker);
  double plain_worst_m = 0;
  for (int i = 0; i < kFrames; ++i) {
    const slam::FrameResult result = TrackPlain(plain, frames[static_cast<size_t>(i)].frame);
    if (result.localized()) plain_worst_m = std::max(plain_worst_m, PositionErrorM(result.T_wc, SwayingPose(i)));
  }
  EXPECT_GT(plain_worst_m, 0.1) << "the walker no longer drags an unjudging tracker: the scene does not test the pose";

  // Tracking map at the end: the car's points, and none labelled as the walker's (none
  // lies where it walked, checked after every frame above).
  int car_points = 0;
  for (const auto& point : loop.tracker().map().points()) {
    if (point->bad) continue;
    EXPECT_NE(point->instance_id, walker_id) << "a point of the walker is in the tracking map";
    if (point->instance_id == car_id) {
      ++car_points;
      EXPECT_TRUE(car.Holds(point->position_w, kSurfaceMarginM)) << point->position_w.transpose();
    }
  }
  EXPECT_GT(car_points, 0) << "the parked car belongs to the tracking map";

  // Long-term map: background only, so nothing of either instance. Hundreds of points:
  // with the car mapped on its verdict, tracking needs four keyframes here (six without).
  const slam::LongTermMapData long_term = loop.tracker().ExportLongTermMap(/*include_instances=*/false);
  EXPECT_GT(long_term.points.size(), 200u);
  for (const slam::StoredMapPoint& stored : long_term.points) {
    EXPECT_FALSE(car.HoldsAboveTheFloor(stored.position_w, kSurfaceMarginM)) << stored.position_w.transpose();
    EXPECT_FALSE(walker_swept.HoldsAboveTheFloor(stored.position_w, kSurfaceMarginM)) << stored.position_w.transpose();
  }
}

// mutual judges from depth samples of each instance, mutual-sparse from its re-found
// sparse features only (the paper's judgement): a parked car 2 m away has far more depth
// samples than features, and mutual-sparse never counts more measurements than features.
TEST(MutualLoopTest, MutualSparseJudgesFromFeaturesAndMutualFromDepth) {
  constexpr std::uint16_t kCar = 2;
  constexpr int kCarCategory = 3;
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 50);
  auto scene = RoomQuads(5);
  const auto car_quads = BoxQuads({1.5, -1.7, 0.0}, {3.9, -0.2, 1.4}, 77, kCar);
  scene.insert(scene.end(), car_quads.begin(), car_quads.end());
  std::vector<RenderedFrame> frames;
  for (int i = 0; i < 20; ++i) frames.push_back(RenderQuads(scene, camera, SwayingPose(i), i, i / 30.0));
  // Per mode: the most measurements of one judgement, and of features, over the frames.
  auto most_measured = [&](SlamMode mode, int* most_features) {
    GroundTruthSegmenter segmenter(frames, {{kCar, kCarCategory}});
    FramePipelineOptions options;
    options.mode = mode;
    options.tracker.initial_T_wc = SwayingPose(0);
    FramePipeline loop(camera, options, &segmenter);
    int most = 0;
    *most_features = 0;
    for (const RenderedFrame& frame : frames) {
      for (const slam::InstanceJudgement& judgement : loop.ProcessFrame(frame.frame).slam.instances) {
        most = std::max(most, judgement.num_points);
        *most_features = std::max(*most_features, judgement.num_features);
        if (mode == SlamMode::kMutualSparse) {
          EXPECT_LE(judgement.num_points, judgement.num_features);
        }
      }
    }
    return most;
  };
  int sparse_features = 0, depth_features = 0;
  const int sparse = most_measured(SlamMode::kMutualSparse, &sparse_features);
  const int depth = most_measured(SlamMode::kMutual, &depth_features);
  EXPECT_GT(sparse, 0);
  EXPECT_GT(depth, 2 * depth_features) << "depth samples, both ways, outnumber the car's features";
}

// One instance of a moveable class in the room of RoomQuads(5) along SwayingPose, seen
// by the ground truth's segmenter; `volume_at(i)` is where it stands in frame i.
struct OneInstanceScene {
  static constexpr std::uint16_t kRenderedId = 2;
  std::vector<RenderedFrame> frames;
  OneInstanceScene(const PinholeCamera& camera, int num_frames, const std::function<Volume(int)>& volume_at) {
    const auto room = RoomQuads(5);
    for (int i = 0; i < num_frames; ++i) {
      auto scene = room;
      const auto box = BoxQuads(volume_at(i).min, volume_at(i).max, 77, kRenderedId);
      scene.insert(scene.end(), box.begin(), box.end());
      frames.push_back(RenderQuads(scene, camera, SwayingPose(i), i, i / 30.0));
    }
  }
};

struct PassOutcome {
  std::vector<slam::FrameResult> frames;
  size_t trajectory_size = 0;
  int instance_points_from_the_first_frame = 0;  // the instance's map points made at frame 0
  slam::LongTermMapData long_term;
};

PassOutcome RunPass(const PinholeCamera& camera, const OneInstanceScene& scene, int category, bool retrack_map_start,
                    const slam::LongTermMapData* long_term_map = nullptr) {
  GroundTruthSegmenter segmenter(scene.frames, {{OneInstanceScene::kRenderedId, category}});
  FramePipelineOptions options;
  options.tracker.initial_T_wc = SwayingPose(0);
  options.tracker.retrack_map_start = retrack_map_start;
  FramePipeline loop(camera, options, &segmenter);
  if (long_term_map != nullptr) loop.LoadLongTermMap(*long_term_map, "pass 1");
  for (const RenderedFrame& frame : scene.frames) loop.ProcessFrame(frame.frame);
  PassOutcome outcome;
  outcome.frames = loop.frames();
  outcome.trajectory_size = loop.trajectory().size();
  for (const auto& point : loop.tracker().map().points()) {
    outcome.instance_points_from_the_first_frame +=
        !point->bad && point->instance_id != 0 && point->first_stamp_s < 1e-9;
  }
  outcome.long_term = loop.ExportLongTermMap();
  return outcome;
}

// TrackerOptions::retrack_map_start: a parked car in view from the first frame cannot be
// judged in the pass's first baseline (9 frames), and is kept out of the founding
// keyframe. Judged still at the baseline's end, the start is tracked again with it: from
// the first frame it is judged still and mapped, in a first pass and in a second on the
// first's long-term map alike.
TEST(FramePipelineTest, StillInstanceInViewFromTheStartIsTrackedThereOnceJudged) {
  constexpr int kCarCategory = 3, kFrames = 14, kBaselineFrames = 9;
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 50);
  ASSERT_NEAR(FramePipelineOptions().tracker.motion_baseline_s, kBaselineFrames / 30.0, 1e-9);
  const OneInstanceScene scene(camera, kFrames, [](int) { return Volume{{1.5, -1.7, 0.0}, {3.9, -0.2, 1.4}}; });
  const PassOutcome as_it_came = RunPass(camera, scene, kCarCategory, /*retrack_map_start=*/false);
  const PassOutcome retracked = RunPass(camera, scene, kCarCategory, /*retrack_map_start=*/true);
  const PassOutcome second_pass = RunPass(camera, scene, kCarCategory, true, &retracked.long_term);
  for (const PassOutcome* pass : {&as_it_came, &retracked, &second_pass}) {
    ASSERT_EQ(pass->frames.size(), static_cast<size_t>(kFrames));
    EXPECT_EQ(pass->trajectory_size, static_cast<size_t>(kFrames));
    for (int i = 0; i < kFrames; ++i) {
      const slam::FrameResult& frame = pass->frames[static_cast<size_t>(i)];
      ASSERT_TRUE(frame.localized()) << "frame " << i;
      EXPECT_EQ(frame.retracked, pass != &as_it_came && i <= kBaselineFrames) << "frame " << i;
      EXPECT_LT(PositionErrorM(frame.T_wc, SwayingPose(i)), 0.01) << "frame " << i;
      ASSERT_EQ(frame.instances.size(), 1u) << "frame " << i;
      const slam::InstanceJudgement& car = frame.instances[0];
      const bool judged_in_hindsight = pass != &as_it_came;
      if (i < kBaselineFrames) {
        EXPECT_EQ(car.judged, judged_in_hindsight) << "frame " << i;
      }
      if (car.judged) {
        EXPECT_FALSE(car.moving) << "frame " << i;
      }
    }
  }
  // Without hindsight the car is mapped on its verdict, as a keyframe then would have made it.
  EXPECT_EQ(as_it_came.instance_points_from_the_first_frame, 0);
  EXPECT_GT(retracked.instance_points_from_the_first_frame, 20);
  EXPECT_GT(second_pass.instance_points_from_the_first_frame, 20);
  for (const slam::FrameResult& frame : second_pass.frames) {
    EXPECT_GT(frame.num_long_term_inliers, 0) << "frame " << frame.frame_index << ": not on the loaded map";
  }
}

// Nothing judged still at the start's end, nothing is tracked again: a person walking
// away from the first frame leaves every pose as it was.
TEST(FramePipelineTest, StartWithOnlyAWalkerInViewIsNotTrackedAgain) {
  constexpr int kFrames = 14;
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 50);
  const OneInstanceScene scene(camera, kFrames, [](int i) {
    const double x = -0.8 + 1.5 * i / 30.0;
    return Volume{{x, 0.1, 0.0}, {x + 0.4, 0.7, 1.8}};
  });
  const PassOutcome as_it_came = RunPass(camera, scene, kPersonCategory, /*retrack_map_start=*/false);
  const PassOutcome hindsight = RunPass(camera, scene, kPersonCategory, /*retrack_map_start=*/true);
  ASSERT_EQ(hindsight.frames.size(), as_it_came.frames.size());
  int judged_moving = 0;
  for (size_t i = 0; i < hindsight.frames.size(); ++i) {
    EXPECT_FALSE(hindsight.frames[i].retracked) << "frame " << i;
    EXPECT_TRUE(hindsight.frames[i].T_wc.isApprox(as_it_came.frames[i].T_wc, 1e-12)) << "frame " << i;
    for (const slam::InstanceJudgement& walker : hindsight.frames[i].instances) judged_moving += walker.moving;
  }
  EXPECT_GT(judged_moving, kFrames / 2);
  EXPECT_EQ(hindsight.instance_points_from_the_first_frame, 0);
}

TEST(MutualLoopTest, InvalidRefinerOptionsAreAnError) {
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(64, 48, 50);
  std::vector<RenderedFrame> frames;
  ScriptedSegmenter segmenter(frames);
  FramePipelineOptions options;
  options.refiner.max_match_cost = -1;
  EXPECT_THROW(FramePipeline(camera, options, &segmenter), Error);
}

// A mode's needs are checked once, when the pipeline is made: every mode but plain
// reads masks, and the oracle takes the ground truth's verdicts.
TEST(FramePipelineTest, ModesWithoutWhatTheyNeedAreRefused) {
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(64, 48, 50);
  std::vector<RenderedFrame> frames;
  ScriptedSegmenter segmenter(frames);
  FramePipelineOptions options;
  for (const SlamMode mode : {SlamMode::kMaskMoveable, SlamMode::kMutual, SlamMode::kOracle}) {
    options.mode = mode;
    EXPECT_THROW(FramePipeline(camera, options, nullptr), Error) << ToString(mode);
  }
  options.mode = SlamMode::kOracle;
  EXPECT_THROW(FramePipeline(camera, options, &segmenter), Error);
  options.mode = SlamMode::kPlain;
  EXPECT_NO_THROW(FramePipeline(camera, options, nullptr));
}

// Plain mode is the tracker's every-feature tracking: the pipeline gives the same poses
// as the tracker's calls made by hand.
TEST(FramePipelineTest, PlainModeIsTheTrackersOwnTracking) {
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(640, 480, 50);
  const auto room = RoomQuads(1);
  FramePipelineOptions options;
  options.mode = SlamMode::kPlain;
  FramePipeline pipeline(camera, options, nullptr);
  slam::Tracker tracker(camera, options.tracker);
  for (int i = 0; i < 12; ++i) {
    const RgbdFrame frame = RenderQuads(room, camera, slam::testing::HandHeldPathPose(i), i, i / 30.0).frame;
    const FrameStep step = pipeline.ProcessFrame(frame);
    const slam::FrameResult by_hand = slam::TrackPlain(tracker, frame);
    ASSERT_EQ(step.slam.status, by_hand.status) << "frame " << i;
    EXPECT_TRUE(step.slam.T_wc.isApprox(by_hand.T_wc, 1e-12)) << "frame " << i;
    EXPECT_TRUE(step.initial.instances.empty());
  }
  EXPECT_EQ(pipeline.frames().size(), 12u);
  EXPECT_EQ(pipeline.trajectory().size(), 12u);
}

}  // namespace
}  // namespace segslam::mutual
