// The moving-state hysteresis of the paper's judgement from sparse features
// (slam/instance_judgement.cpp, TrackerOptions::judge_by_depth off; moving_streak_frames,
// moving_memory_s, min_points_to_clear_moving and static_frames_to_trust_young_points),
// through the tracker's public interface, on ray-cast frames of a textured box in a
// textured room (tests/slam/synthetic_room.h). The judgement from depth has its own
// tests (depth_judgement_test.cpp).
//
// How much of the box a frame measures is set through its depth: features without depth
// have no 3-D motion measurement, so a box whose depth the sensor loses (a dark or shiny
// surface) is seen but not measured, and a box with depth on a small patch only is
// measured on a handful of features.
#include "slam/tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "tests/slam/synthetic_room.h"
#include "tests/slam/tracking_steps.h"

namespace segslam::slam {
namespace {

using testing::BoxQuads;
using testing::HandHeldPathPose;
using testing::RenderedFrame;
using testing::RenderQuads;
using testing::RoomQuads;

constexpr std::uint16_t kBoxId = 1;

// The options of the judgement from sparse features, as mutual-sparse runs it.
TrackerOptions SparseJudgement() {
  TrackerOptions options;
  options.judge_by_depth = false;
  return options;
}

PinholeCamera TestCamera() { return PinholeCamera::FromVerticalFov(640, 480, 50); }

// The camera follows testing::HandHeldPathPose by frame index: its motion per frame stays
// the same whatever the frames' stamps.

enum class BoxDepth {
  kFull,   // depth on the whole box
  kPatch,  // depth on a patch in the middle of the box only: a handful of measured features
  kNone,   // no depth on the box
};

struct ScriptedFrame {
  double stamp_s = 0;
  double box_y_m = 0;  // the box's side nearest world -y
  BoxDepth box_depth = BoxDepth::kFull;
};

// Takes away the box's depth, or all of it but a patch in its middle.
void DropBoxDepth(BoxDepth depth, RenderedFrame* rendered) {
  if (depth == BoxDepth::kFull) return;
  const cv::Mat box_pixels = rendered->instance_ids == kBoxId;
  cv::Mat no_depth = box_pixels.clone();
  if (depth == BoxDepth::kPatch) {
    const cv::Rect bounds = cv::boundingRect(box_pixels);
    no_depth(cv::Rect(bounds.x + bounds.width / 3, bounds.y + bounds.height / 3, bounds.width / 3, bounds.height / 3))
        .setTo(0);
  }
  rendered->frame.depth_m.setTo(0, no_depth);
}

// A 0.4 x 0.6 x 1.2 m box about 3 m in front of the camera: some 140 features, five to
// ten of them with depth in the patch.
std::vector<RenderedFrame> Render(const std::vector<ScriptedFrame>& script) {
  const PinholeCamera camera = TestCamera();
  const auto room = RoomQuads(8);
  std::vector<RenderedFrame> frames;
  for (size_t i = 0; i < script.size(); ++i) {
    auto quads = room;
    const double y = script[i].box_y_m;
    const auto box = BoxQuads({1.0, y, 0.4}, {1.4, y + 0.6, 1.6}, 23, kBoxId);
    quads.insert(quads.end(), box.begin(), box.end());
    RenderedFrame rendered = RenderQuads(quads, camera, HandHeldPathPose(static_cast<int>(i)), static_cast<int>(i),
                                         script[i].stamp_s);
    DropBoxDepth(script[i].box_depth, &rendered);
    frames.push_back(std::move(rendered));
  }
  return frames;
}

// The box is the only instance, of a moveable class; the tracker starts at the true pose.
// The scripts count the box's features kept out of the pose, so only those on its mask
// are: no margin (TrackerTest.BackgroundJustOutsideAKeptOutMaskIsKeptOutWithIt tests it).
std::vector<FrameResult> TrackMutual(const std::vector<RenderedFrame>& frames, TrackerOptions options) {
  options.initial_T_wc = HandHeldPathPose(0);
  options.instance_margin_px = 0;
  Tracker tracker(TestCamera(), options);
  FrameInstances instances;
  instances.moveable_ids = {kBoxId};
  std::vector<FrameResult> results;
  for (const RenderedFrame& rendered : frames) {
    instances.ids = rendered.instance_ids;
    results.push_back(TrackJudging(tracker, rendered.frame, instances));
    EXPECT_TRUE(results.back().localized()) << "frame " << rendered.frame.index;
  }
  return results;
}

InstanceJudgement BoxJudgement(const FrameResult& result) {
  for (const InstanceJudgement& judgement : result.instances) {
    if (judgement.id == kBoxId) return judgement;
  }
  ADD_FAILURE() << "frame " << result.frame_index << " did not judge the box";
  return {};
}

std::vector<InstanceJudgement> JudgeBox(const std::vector<RenderedFrame>& frames, const TrackerOptions& options) {
  std::vector<InstanceJudgement> judgements;
  for (const FrameResult& result : TrackMutual(frames, options)) judgements.push_back(BoxJudgement(result));
  return judgements;
}

// How many measured features clear an instance kept moving by its streak: the option,
// or an eighth of the instance's features when that is fewer (but never fewer than
// judge it at all), as TrackerOptions::min_points_to_clear_moving says.
int PointsToClear(const TrackerOptions& options, const InstanceJudgement& judgement) {
  return std::min(options.min_points_to_clear_moving,
                  std::max(options.min_points_to_judge, judgement.num_features / 8));
}

int CountMoving(const std::vector<InstanceJudgement>& judgements, int first, int end) {
  return static_cast<int>(std::count_if(judgements.begin() + first, judgements.begin() + end,
                                        [](const InstanceJudgement& j) { return j.moving; }));
}

// --- Streaks: frames far enough apart that each has a full motion baseline behind it.

// Longer than motion_baseline_s (0.3 s): every frame measures the box against where it
// stood in the frame before, a full baseline back, and no map point is ever too young to
// judge. Three such intervals fit in moving_memory_s (1 s).
constexpr double kFrameIntervalS = 0.32;
constexpr int kStillFrames = 6;
// A move per frame far above the moving threshold (0.11 m at 3 m).
constexpr double kStepM = 0.25;

// The box stands for kStillFrames frames, moves kStepM in each of the next `moves` + 1
// frames and stands again. The frame of the first move is not judged moving yet (its few
// measured features do not agree on a displacement), and the frame after the last move
// measures it still against the frame before: `moves` moving verdicts, on frames
// kStillFrames + 1 .. LastMovingFrame(moves); the tests check that count. `pause_s` is
// the time between the second and third moving verdicts (a frame interval unless
// longer), `depth_after` the box's depth in the frames after the last one.
int LastMovingFrame(int moves) { return kStillFrames + moves; }

std::vector<ScriptedFrame> MoveAndStop(int moves, const std::vector<BoxDepth>& depth_after,
                                       double pause_s = kFrameIntervalS) {
  std::vector<ScriptedFrame> script;
  const int last_moving = LastMovingFrame(moves);
  const int frames = last_moving + 1 + static_cast<int>(depth_after.size());
  double y = -0.9;
  for (int i = 0; i < frames; ++i) {
    if (i >= kStillFrames && i <= last_moving) y += kStepM;
    const double pause_extra_s = i >= kStillFrames + 3 ? pause_s - kFrameIntervalS : 0.0;
    const BoxDepth depth = i > last_moving ? depth_after[static_cast<size_t>(i - last_moving - 1)] : BoxDepth::kFull;
    script.push_back({i * kFrameIntervalS + pause_extra_s, y, depth});
  }
  return script;
}

// After it stops, the box is measured still on the few features of a depth patch: that
// is enough to clear a box moved for fewer frames than a streak, and not one moved for a
// full streak, which stays moving (and out of the pose and map).
TEST(InstanceJudgementTest, OnlyAFullStreakOfMovingFramesKeepsAnObjectMovingAfterItStops) {
  const TrackerOptions options = SparseJudgement();
  const int streak = options.moving_streak_frames;
  ASSERT_GE(streak, 2);
  for (const int moves : {streak, streak - 1}) {
    SCOPED_TRACE(::testing::Message() << moves << " moves");
    const int last_moving = LastMovingFrame(moves);
    const auto judgements = JudgeBox(Render(MoveAndStop(moves, {BoxDepth::kPatch})), options);
    ASSERT_EQ(CountMoving(judgements, 0, last_moving + 1), moves) << "the script's moving verdicts";
    ASSERT_TRUE(judgements[static_cast<size_t>(last_moving)].moving);
    const InstanceJudgement& stopped = judgements[static_cast<size_t>(last_moving) + 1];
    // Measured still, on fewer features than would clear a known mover.
    ASSERT_GE(stopped.num_points, options.min_points_to_judge);
    ASSERT_LT(stopped.num_points, PointsToClear(options, stopped));
    EXPECT_EQ(stopped.num_moving_points, 0);
    EXPECT_TRUE(stopped.judged);
    EXPECT_EQ(stopped.moving, moves >= streak);
  }
}

// A box kept moving by its streak is released by the first frame that measures it still
// on at least min_points_to_clear_moving features, and that ends the streak: a later
// frame with fewer measured features no longer keeps it moving. A frame measures the box
// against the one before: with depth on the whole box again after a frame with depth on
// the patch only, it still finds the patch's features alone.
TEST(InstanceJudgementTest, ObjectKeptMovingIsClearedOnlyByEnoughMeasuredFeatures) {
  TrackerOptions options = SparseJudgement();
  const int moves = options.moving_streak_frames;
  const int stopped = LastMovingFrame(moves) + 1;
  const auto frames =
      Render(MoveAndStop(moves, {BoxDepth::kPatch, BoxDepth::kFull, BoxDepth::kFull, BoxDepth::kPatch}));
  const auto judgements = JudgeBox(frames, options);
  auto at = [&](int frame) { return judgements[static_cast<size_t>(frame)]; };
  ASSERT_TRUE(at(stopped - 1).moving);

  for (const int kept : {stopped, stopped + 1}) {
    SCOPED_TRACE(::testing::Message() << "frame " << kept);
    ASSERT_LT(at(kept).num_points, PointsToClear(options, at(kept)));
    EXPECT_TRUE(at(kept).moving) << "kept moving on " << at(kept).num_points << " still features";
    EXPECT_TRUE(at(kept).judged);
    EXPECT_LT(at(kept).moving_share, options.moving_share_threshold) << "measured still";
  }
  ASSERT_GE(at(stopped + 2).num_points, PointsToClear(options, at(stopped + 2)));
  EXPECT_FALSE(at(stopped + 2).moving) << "measured still on the whole box";
  EXPECT_TRUE(at(stopped + 2).judged);
  EXPECT_FALSE(at(stopped + 3).moving) << "the streak ended when the box was cleared";
  EXPECT_TRUE(at(stopped + 3).judged);

  // With the option at what the patch shows, the patch alone clears the box (the box
  // has enough features for the option, not the eighth of them, to decide).
  const int patch_points = at(stopped).num_points;
  ASSERT_GE(patch_points, options.min_points_to_judge);
  ASSERT_GE(at(stopped).num_features / 8, patch_points);
  options.min_points_to_clear_moving = patch_points;
  const auto lower = JudgeBox(frames, options);
  EXPECT_FALSE(lower[static_cast<size_t>(stopped)].moving);
  EXPECT_TRUE(lower[static_cast<size_t>(stopped)].judged);
}

// A full streak's moving verdicts with a pause in the middle (the camera missed the
// frames in between): a pause within moving_memory_s continues the streak, which keeps
// the box moving once it stops; a longer one begins a new, shorter streak, which does not.
TEST(InstanceJudgementTest, MovingFramesFartherApartThanMovingMemoryBeginANewStreak) {
  const TrackerOptions options = SparseJudgement();
  const int moves = options.moving_streak_frames;
  ASSERT_GE(moves, 3) << "the pause must split the streak into two shorter ones";
  const int stopped = LastMovingFrame(moves) + 1;
  ASSERT_LE(3 * kFrameIntervalS, options.moving_memory_s);
  ASSERT_GT(4 * kFrameIntervalS, options.moving_memory_s);
  for (const double pause_s : {3 * kFrameIntervalS, 4 * kFrameIntervalS}) {
    SCOPED_TRACE(::testing::Message() << "pause " << pause_s << " s");
    const auto judgements = JudgeBox(Render(MoveAndStop(moves, {BoxDepth::kPatch}, pause_s)), options);
    ASSERT_EQ(CountMoving(judgements, 0, stopped), moves);
    const InstanceJudgement& at_stop = judgements[static_cast<size_t>(stopped)];
    ASSERT_LT(at_stop.num_points, PointsToClear(options, at_stop));
    EXPECT_TRUE(at_stop.judged);
    EXPECT_EQ(at_stop.moving, pause_s <= options.moving_memory_s);
  }
}

// After a full streak the box stands still and is measured on a few features only, frame
// after frame: it stays moving as long as its last moving verdict lies within
// moving_memory_s, and no longer.
TEST(InstanceJudgementTest, StreakKeepsAnObjectMovingForMovingMemoryAfterItsLastMovingFrame) {
  const TrackerOptions options = SparseJudgement();
  const int moves = options.moving_streak_frames;
  const int last_moving = LastMovingFrame(moves);
  const std::vector<BoxDepth> patches(5, BoxDepth::kPatch);
  const auto script = MoveAndStop(moves, patches);
  const auto judgements = JudgeBox(Render(script), options);
  ASSERT_EQ(CountMoving(judgements, 0, last_moving + 1), moves);
  int remembered = 0;
  for (int i = last_moving + 1; i < static_cast<int>(script.size()); ++i) {
    const InstanceJudgement& judgement = judgements[static_cast<size_t>(i)];
    const double since_last_moving_s = script[static_cast<size_t>(i)].stamp_s - script[static_cast<size_t>(last_moving)].stamp_s;
    SCOPED_TRACE(::testing::Message() << "frame " << i << ", " << since_last_moving_s << " s after the last move");
    ASSERT_LT(judgement.num_points, PointsToClear(options, judgement));
    EXPECT_EQ(judgement.num_moving_points, 0);
    const bool within_memory = since_last_moving_s <= options.moving_memory_s;
    EXPECT_EQ(judgement.moving, within_memory);
    remembered += within_memory;
  }
  EXPECT_GE(remembered, 2);
  EXPECT_LT(remembered, static_cast<int>(patches.size()));
}

// --- Young map points: frames at 30 Hz, so that points made a few frames ago are
// younger than motion_baseline_s.

// A box that stands still from the first frame is judged static once a baseline has
// passed; its first map points come with the next keyframe. Two frames later the box
// loses its depth: only those young points can measure it (by reprojection), the frames
// a baseline back cannot (they need depth now). The young points judge it only when it
// has been judged static on static_frames_to_trust_young_points frames in a row by then;
// judged, its features serve the fine pose, unjudged they are kept out.
TEST(InstanceJudgementTest, YoungMapPointsJudgeAnInstanceOnlyOnceItWasJudgedStaticLongEnough) {
  std::vector<ScriptedFrame> script;
  for (int i = 0; i < 30; ++i) script.push_back({i / 30.0, -0.9, BoxDepth::kFull});
  std::vector<RenderedFrame> frames = Render(script);

  // Where the box's first points are made, on a run whose young points never judge: by
  // the first keyframe after its verdict. (Mapped on the verdict instead, they are as
  // young there: TrackerTest.InstanceJudgedStillIsMappedInTheKeyframesThatKeptItOut.)
  TrackerOptions options = SparseJudgement();
  options.map_instances_on_verdict = false;
  options.record_features = true;
  options.static_frames_to_trust_young_points = 1 << 20;
  const std::vector<FrameResult> reference = TrackMutual(frames, options);
  int first_static = -1, first_keyframe = -1;
  for (const FrameResult& result : reference) {
    const InstanceJudgement box = BoxJudgement(result);
    if (first_static < 0 && box.judged) {
      ASSERT_FALSE(box.moving);
      first_static = result.frame_index;
    }
    if (first_static >= 0 && result.keyframe) {
      first_keyframe = result.frame_index;
      break;
    }
  }
  ASSERT_GE(first_static, 0);
  ASSERT_GE(first_keyframe, 0) << "no keyframe after the box was judged static";
  const int dropout = first_keyframe + 2;
  ASSERT_LT(dropout, static_cast<int>(frames.size()));
  ASSERT_LT(script[static_cast<size_t>(dropout)].stamp_s - script[static_cast<size_t>(first_keyframe)].stamp_s,
            options.motion_baseline_s);
  for (int i = first_static; i < dropout; ++i) {
    ASSERT_TRUE(BoxJudgement(reference[static_cast<size_t>(i)]).judged) << "frame " << i;
    ASSERT_FALSE(BoxJudgement(reference[static_cast<size_t>(i)]).moving) << "frame " << i;
  }
  const int static_frames = dropout - first_static;

  frames.resize(static_cast<size_t>(dropout) + 1);
  DropBoxDepth(BoxDepth::kNone, &frames.back());
  for (const int needed : {static_frames, static_frames + 1}) {
    SCOPED_TRACE(::testing::Message() << "static_frames_to_trust_young_points " << needed << ", box judged static on "
                                      << static_frames << " frames");
    options.static_frames_to_trust_young_points = needed;
    const FrameResult result = TrackMutual(frames, options).back();
    const InstanceJudgement box = BoxJudgement(result);
    const bool trusted = static_frames >= needed;
    EXPECT_EQ(box.judged, trusted);
    EXPECT_FALSE(box.moving);
    if (trusted) {
      EXPECT_GE(box.num_points, options.min_points_to_judge);
    } else {
      EXPECT_LT(box.num_points, options.min_points_to_judge);
    }
    int box_features = 0, box_features_in_pose = 0;
    for (const FeatureRecord& record : result.feature_records) {
      if (record.instance_id != kBoxId) continue;
      ++box_features;
      box_features_in_pose += record.kind != FeatureKind::kDroppedMoveable;
    }
    EXPECT_GT(box_features, 0);
    EXPECT_EQ(box_features_in_pose > 0, trusted);
  }
}

}  // namespace
}  // namespace segslam::slam
