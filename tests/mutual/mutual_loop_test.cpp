// The loop on a ray-cast room (tests/slam/synthetic_room.h) with a scripted segmenter:
// exact poses and masks, so each step's hand-over can be checked without the simulator.
#include "mutual/mutual_loop.h"

#include <gtest/gtest.h>

#include <set>

#include "core/coco.h"
#include "core/error.h"
#include "tests/slam/synthetic_room.h"

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
  MutualLoopOptions options;
  options.tracker.initial_T_wc = PathPose(0);
  MutualLoop loop(camera, segmenter, options);
  std::set<std::uint16_t> refined_ids;
  for (int i = 0; i < kFrames; ++i) {
    const MutualFrameResult result = loop.ProcessFrame(frames[static_cast<size_t>(i)].frame);
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

TEST(MutualLoopTest, InvalidRefinerOptionsAreAnError) {
  const PinholeCamera camera = PinholeCamera::FromVerticalFov(64, 48, 50);
  std::vector<RenderedFrame> frames;
  ScriptedSegmenter segmenter(frames);
  MutualLoopOptions options;
  options.refiner.max_match_cost = -1;
  EXPECT_THROW(MutualLoop(camera, segmenter, options), Error);
}

}  // namespace
}  // namespace segslam::mutual
