// The moving/static judgement from depth (slam/depth_judgement.cpp, TrackerOptions::
// judge_by_depth), through the tracker's public interface, on ray-cast frames of a
// textured box in a textured room (tests/slam/synthetic_room.h) seen by a hand-held
// camera at 30 Hz. Known answers: a box that stands is still, one that recedes,
// approaches or crosses the view moves, a box hidden behind another is not taken for
// moving, one seen moving for long is kept out until seen still for long enough, and a
// still box whose repeated texture fools the sparse features is still.
//
// Most tests take the sparse features' measurement away
// (DepthJudgementOptions::sparse_features off), so that depth alone decides.
#include "slam/tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "tests/slam/synthetic_room.h"
#include "tests/slam/tracking_steps.h"

namespace segslam::slam {
namespace {

using testing::BoxQuads;
using testing::CornerRichTexture;
using testing::HandHeldPathPose;
using testing::LookingAlongX;
using testing::RenderedFrame;
using testing::RenderQuads;
using testing::RoomQuads;

constexpr std::uint16_t kBoxId = 1;
constexpr std::uint16_t kScreenId = 2;
constexpr double kFps = 30.0;

PinholeCamera TestCamera() { return PinholeCamera::FromVerticalFov(640, 480, 50); }

// Depth alone judges. The box is not mapped on its verdict (TrackerOptions::
// map_instances_on_verdict): these tests measure what the judgement sees of a box the pose does not follow. A mapped box
// that starts to move drags the coarse pose it is judged against, as any mapped object
// does (TrackerTest.ObjectFillingTheViewThatStartsToMoveIsJudgedMovingAndLeftOutOfThePose).
TrackerOptions DepthOnly() {
  TrackerOptions options;
  options.depth_judgement.sparse_features = false;
  options.instance_margin_px = 0;
  options.map_instances_on_verdict = false;
  return options;
}

// Where the box stands in frame i: its offset from its first place, world frame (the
// camera looks along +x, from x = -2 m).
using BoxPath = Eigen::Vector3d (*)(int frame);

// A 0.4 m deep, `width_m` wide, 1.2 m tall box about 3 m in front of the camera, of a
// moveable class; with `screen`, a 0.6 m wide board (instance kScreenId) passes between
// camera and box.
std::vector<InstanceJudgement> JudgeBox(BoxPath path, int frames, TrackerOptions options, double width_m = 0.6,
                                        bool screen = false) {
  const PinholeCamera camera = TestCamera();
  options.initial_T_wc = HandHeldPathPose(0);
  Tracker tracker(camera, options);
  FrameInstances instances;
  instances.moveable_ids = {kBoxId, kScreenId};
  const auto room = RoomQuads(8);
  std::vector<InstanceJudgement> box;
  for (int i = 0; i < frames; ++i) {
    auto quads = room;
    const Eigen::Vector3d offset = path(i);
    const auto box_quads = BoxQuads(Eigen::Vector3d(1.0, -width_m / 2, 0.4) + offset,
                                    Eigen::Vector3d(1.4, width_m / 2, 1.6) + offset, 23, kBoxId);
    quads.insert(quads.end(), box_quads.begin(), box_quads.end());
    if (screen) {
      // From the left of the view to the right at 1 m/s, 1.2 m in front of the box.
      const double y = 1.5 - 1.0 * i / kFps;
      const auto board = BoxQuads({-0.25, y - 0.3, 0.3}, {-0.2, y + 0.3, 1.7}, 77, kScreenId);
      quads.insert(quads.end(), board.begin(), board.end());
    }
    const RenderedFrame rendered = RenderQuads(quads, camera, HandHeldPathPose(i), i, i / kFps);
    instances.ids = rendered.instance_ids;
    const FrameResult result = TrackJudging(tracker, rendered.frame, instances);
    EXPECT_TRUE(result.localized()) << "frame " << i;
    InstanceJudgement judgement;  // not seen: not judged
    for (const InstanceJudgement& j : result.instances) {
      if (j.id == kBoxId) judgement = j;
    }
    box.push_back(judgement);
  }
  return box;
}

// The frames a full baseline (motion_baseline_s, 0.3 s) after the first.
int FirstFullBaselineFrame(const TrackerOptions& options) {
  return static_cast<int>(std::ceil(options.motion_baseline_s * kFps - 1e-9));
}

TEST(DepthJudgementTest, StandingBoxIsStillOnceAFullBaselineIsBehindIt) {
  const TrackerOptions options = DepthOnly();
  const auto box = JudgeBox([](int) -> Eigen::Vector3d { return Eigen::Vector3d::Zero(); }, 40, options);
  // Before a baseline no frame can tell a walker's pace from standing still.
  for (int i = 0; i < FirstFullBaselineFrame(options); ++i) EXPECT_FALSE(box[i].judged) << "frame " << i;
  for (int i = FirstFullBaselineFrame(options); i < 40; ++i) {
    SCOPED_TRACE(::testing::Message() << "frame " << i);
    EXPECT_TRUE(box[i].judged);
    EXPECT_FALSE(box[i].moving);
    // Both ways, up to two samples_per_instance samples of its interior land on depth.
    EXPECT_GE(box[i].num_points, options.depth_judgement.samples_per_instance / 2);
    EXPECT_LT(box[i].moving_share, 0.05);
  }
}

// After 15 still frames the box moves at 1 m/s: away from the camera, towards it, or
// across the view. Each is seen moving within a few frames of its start and stays so.
void ExpectSeenMovingSoonAfterItStarts(BoxPath path) {
  constexpr int kStill = 15, kFrames = 40;
  const TrackerOptions options = DepthOnly();
  const auto box = JudgeBox(path, kFrames, options);
  EXPECT_FALSE(box[kStill].moving) << "a still box";
  // In 0.2 s it has moved 0.2 m: twice the threshold at 3 m (0.05 m + 0.02 m per metre)
  // away or closer, a third of its width across.
  constexpr int kSeenBy = kStill + 6;
  for (int i = kSeenBy; i < kFrames; ++i) {
    SCOPED_TRACE(::testing::Message() << "frame " << i);
    EXPECT_TRUE(box[i].judged);
    EXPECT_TRUE(box[i].moving);
  }
}

TEST(DepthJudgementTest, BoxMovingAwayIsSeenMoving) {
  ExpectSeenMovingSoonAfterItStarts(
      [](int i) { return Eigen::Vector3d(i < 15 ? 0.0 : (i - 15) / kFps, 0, 0); });
}

TEST(DepthJudgementTest, BoxComingCloserIsSeenMoving) {
  ExpectSeenMovingSoonAfterItStarts(
      [](int i) { return Eigen::Vector3d(i < 15 ? 0.0 : -(i - 15) / kFps, 0, 0); });
}

TEST(DepthJudgementTest, BoxCrossingTheViewIsSeenMoving) {
  ExpectSeenMovingSoonAfterItStarts(
      [](int i) { return Eigen::Vector3d(0, i < 15 ? 0.0 : (i - 15) / kFps, 0); });
}

// A board passing in front hides part of the standing box: the hidden samples land on
// nearer depth and count neither way, so the box stays still.
TEST(DepthJudgementTest, BoxHiddenBehindAPassingBoardIsNotTakenForMoving) {
  const TrackerOptions options = DepthOnly();
  const auto box = JudgeBox([](int) -> Eigen::Vector3d { return Eigen::Vector3d::Zero(); }, 60, options, 0.6, /*screen=*/true);
  int judged = 0;
  for (int i = FirstFullBaselineFrame(options); i < 60; ++i) {
    SCOPED_TRACE(::testing::Message() << "frame " << i);
    EXPECT_FALSE(box[i].moving);
    judged += box[i].judged;
  }
  // Wholly hidden for a few frames at most.
  EXPECT_GE(judged, 40);
}

// Seen moving for 1 s (the log-odds at their bound), then standing: kept out of the pose
// and map (moving, then not judged) until max_log_odds / static_log_odds frames have seen
// it still, and then still.
TEST(DepthJudgementTest, BoxSeenMovingForLongIsKeptOutUntilSeenStillForLongEnough) {
  constexpr int kStop = 45, kFrames = 70;
  const TrackerOptions options = DepthOnly();
  const auto box = JudgeBox(
      [](int i) {
        const int moving_frames = std::clamp(i - 15, 0, kStop - 15);
        return Eigen::Vector3d(0, 0.6 * moving_frames / kFps, 0);
      },
      kFrames, options);
  ASSERT_TRUE(box[kStop - 1].moving);
  const DepthJudgementOptions& o = options.depth_judgement;
  // Every frame from the stop on measures it against a frame a baseline back: the first
  // ones still see it move (the remembered frame saw it elsewhere).
  int first_still_measured = -1;
  for (int i = kStop; i < kFrames && first_still_measured < 0; ++i) {
    if (box[i].num_points > 0 && box[i].moving_share < o.moving_share) first_still_measured = i;
  }
  ASSERT_GE(first_still_measured, kStop);
  EXPECT_LE(first_still_measured, kStop + FirstFullBaselineFrame(options) + 1);
  const int frames_to_clear = static_cast<int>(std::lround(o.max_log_odds / o.static_log_odds));
  for (int i = first_still_measured; i < first_still_measured + frames_to_clear - 1; ++i) {
    EXPECT_TRUE(box[i].moving) << "frame " << i << ", still for " << i - first_still_measured + 1 << " frames";
  }
  // At 0 the log-odds judge nothing; then still.
  EXPECT_FALSE(box[first_still_measured + frames_to_clear - 1].judged);
  for (int i = first_still_measured + frames_to_clear; i < kFrames; ++i) {
    SCOPED_TRACE(::testing::Message() << "frame " << i);
    EXPECT_TRUE(box[i].judged);
    EXPECT_FALSE(box[i].moving);
  }
}

// A box that slides within the plane it shows the camera leaves its depth where it was;
// the sparse features see it (TrackerOptions::judge_by_depth: either one seeing motion
// is motion). Here a 1.6 m wide face towards the camera slides sideways at 0.5 m/s: 0.15 m
// in a baseline, over the features' threshold (0.11 m at 3 m), while its ends, all that
// depth sees move, are under a tenth of it.
TEST(DepthJudgementTest, SparseFeaturesSeeWhatDepthCannot) {
  constexpr int kStill = 15, kFrames = 45;
  BoxPath slide = [](int i) { return Eigen::Vector3d(0, i < kStill ? 0.0 : 0.5 * (i - kStill) / kFps, 0); };
  TrackerOptions both;
  both.instance_margin_px = 0;
  both.map_instances_on_verdict = false;  // as DepthOnly() says
  const auto with_features = JudgeBox(slide, kFrames, both, 1.6);
  const auto depth_only = JudgeBox(slide, kFrames, DepthOnly(), 1.6);
  int moving_with_features = 0, moving_depth_only = 0;
  for (int i = kStill + FirstFullBaselineFrame(both); i < kFrames; ++i) {
    moving_with_features += with_features[i].moving;
    moving_depth_only += depth_only[i].moving;
  }
  const int frames = kFrames - kStill - FirstFullBaselineFrame(both);
  EXPECT_GE(moving_with_features, frames - 2);
  EXPECT_LT(moving_depth_only, moving_with_features);
}

// A still object with repeated structure (a car's two wheels, a row of windows) passed
// by a camera driving along it: a feature on one copy, matched to the frame a baseline
// back, finds the copy the camera then saw from where it is now, and reads one period of
// displacement. Here a box's side shows one texture three times over, its period the
// camera's travel in a baseline, so every such match aliases. Moved that way, the box's
// depth samples would pass its ends: depth refutes the features, and the box stays still.
// The paper's judgement from the sparse features alone is fooled on the same frames.
std::vector<InstanceJudgement> JudgeBoxWithRepeatedSide(TrackerOptions options, int frames) {
  constexpr double kSpeed = 1.5;  // m/s, along world +x
  const double period = kSpeed * options.motion_baseline_s;
  const PinholeCamera camera = TestCamera();
  const auto pose = [](int i) { return LookingAlongX({-3.0 + kSpeed * i / kFps, 0.0, 1.0}, -0.6); };
  options.initial_T_wc = pose(0);
  Tracker tracker(camera, options);
  FrameInstances instances;
  instances.moveable_ids = {kBoxId};
  auto quads = RoomQuads(8);
  auto box = BoxQuads({-1.0, -1.6, 0.4}, {-1.0 + 3 * period, -1.2, 1.6}, 23, kBoxId);
  cv::repeat(CornerRichTexture(256, 5), 1, 3, box[1].texture);  // the side facing the camera
  quads.insert(quads.end(), box.begin(), box.end());
  std::vector<InstanceJudgement> judgements;
  for (int i = 0; i < frames; ++i) {
    const RenderedFrame rendered = RenderQuads(quads, camera, pose(i), i, i / kFps);
    instances.ids = rendered.instance_ids;
    const FrameResult result = TrackJudging(tracker, rendered.frame, instances);
    EXPECT_TRUE(result.localized()) << "frame " << i;
    InstanceJudgement judgement;
    for (const InstanceJudgement& j : result.instances) {
      if (j.id == kBoxId) judgement = j;
    }
    judgements.push_back(judgement);
  }
  return judgements;
}

TEST(DepthJudgementTest, StillObjectWhoseFeaturesAliasIsNotTakenForMoving) {
  constexpr int kFrames = 40;
  TrackerOptions with_features;
  with_features.instance_margin_px = 0;
  TrackerOptions sparse_only = with_features;
  sparse_only.judge_by_depth = false;
  const auto judged = JudgeBoxWithRepeatedSide(with_features, kFrames);
  const auto paper = JudgeBoxWithRepeatedSide(sparse_only, kFrames);
  int moving = 0, moving_by_paper = 0, still = 0;
  for (int i = FirstFullBaselineFrame(with_features); i < kFrames; ++i) {
    moving += judged[i].moving;
    still += judged[i].judged && !judged[i].moving;
    moving_by_paper += paper[i].moving;
  }
  EXPECT_EQ(moving, 0);
  EXPECT_GT(still, 0);
  EXPECT_GE(moving_by_paper, 5) << "the scene no longer makes the features alias";
}

}  // namespace
}  // namespace segslam::slam
