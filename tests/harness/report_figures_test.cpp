// The report's figures as geometry: where a known trajectory lands, equal axis scales,
// gaps for lost frames, error bars; the tracker's feature records on the ray-cast room of
// tests/slam/synthetic_room.h; and a sample report with every figure (written to
// $SEGSLAM_REPORT_SAMPLE_DIR when set, for scripts/check_report.sh and for looking at).
#include "harness/report_figures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>

#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "harness/report_document.h"
#include "mutual/slam_mode.h"
#include "tests/core/test_util.h"
#include "tests/slam/synthetic_room.h"
#include "tests/slam/tracking_steps.h"

namespace segslam::harness {
namespace {

using slam::FeatureKind;
using slam::FeatureRecord;
using slam::FrameResult;

// Sum of absolute channel differences between a pixel and a colour.
int ColorDistance(const cv::Mat& image, cv::Point pixel, const cv::Scalar& color) {
  const cv::Vec3b p = image.at<cv::Vec3b>(pixel);
  return std::abs(p[0] - static_cast<int>(color[0])) + std::abs(p[1] - static_cast<int>(color[1])) +
         std::abs(p[2] - static_cast<int>(color[2]));
}

cv::Point Rounded(const cv::Point2d& p) {
  return {static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y))};
}

// Counter-clockwise around the square [0, side]^2 at 1 m/s, one pose every 0.1 s.
std::vector<StampedPose> SquarePath(double side_m, const Eigen::Vector2d& offset = Eigen::Vector2d::Zero()) {
  const std::vector<Eigen::Vector2d> corners = {{0, 0}, {side_m, 0}, {side_m, side_m}, {0, side_m}, {0, 0}};
  std::vector<StampedPose> poses;
  const int steps_per_edge = static_cast<int>(std::lround(side_m / 0.1));
  for (size_t edge = 0; edge + 1 < corners.size(); ++edge) {
    for (int k = 0; k < steps_per_edge; ++k) {
      const Eigen::Vector2d xy = corners[edge] + (corners[edge + 1] - corners[edge]) * k / steps_per_edge + offset;
      StampedPose pose;
      pose.stamp_s = 0.1 * static_cast<double>(poses.size());
      pose.T_wc.translation() = Eigen::Vector3d(xy.x(), xy.y(), 1.5);
      poses.push_back(pose);
    }
  }
  StampedPose last;
  last.stamp_s = 0.1 * static_cast<double>(poses.size());
  last.T_wc.translation() = Eigen::Vector3d(offset.x(), offset.y(), 1.5);
  poses.push_back(last);
  return poses;
}

// With $SEGSLAM_REPORT_SAMPLE_DIR set, a test's pictures are kept there under tests/ to
// be looked at.
void KeepForLooking(const std::string& name, const cv::Mat& image) {
  const char* keep = std::getenv("SEGSLAM_REPORT_SAMPLE_DIR");
  if (keep == nullptr) return;
  std::filesystem::create_directories(std::filesystem::path(keep) / "tests");
  WriteFigure(std::filesystem::path(keep) / "tests" / (name + ".png"), image);
}

constexpr int kNearColor = 60;  // summed channel difference that still counts as "that colour"

TEST(TopViewTest, ASquareIsDrawnWhereItsCornersAreWithEqualScales) {
  TopViewOptions options;
  options.title = "square";
  options.size = {900, 520};  // wide, so equal scales must widen the x range
  const Figure figure = DrawTopView(options, {"ground truth", SquarePath(10)}, {});
  KeepForLooking("square", figure.image);
  ASSERT_EQ(figure.image.type(), CV_8UC3);
  ASSERT_EQ(figure.image.size(), options.size);
  EXPECT_NEAR(figure.axes.PixelsPerUnitX(), figure.axes.PixelsPerUnitY(), 1e-9);
  EXPECT_GT(figure.axes.x_max - figure.axes.x_min, 1.5 * (figure.axes.y_max - figure.axes.y_min));

  // Points on every edge carry the ground-truth colour; the middle of the square does not.
  for (const cv::Point2d& on_path : {cv::Point2d(5, 0), cv::Point2d(10, 5), cv::Point2d(5, 10), cv::Point2d(0, 5),
                                     cv::Point2d(2.5, 0), cv::Point2d(10, 7.5)}) {
    EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(on_path.x, on_path.y)), kGroundTruthColor),
              kNearColor)
        << on_path;
  }
  EXPECT_GT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(5, 5)), kGroundTruthColor), 300);

  // The drawn square is as wide as it is high, in pixels.
  const cv::Rect around(Rounded(figure.axes.ToPixel(-0.8, 10.8)), Rounded(figure.axes.ToPixel(10.8, -0.8)));
  cv::Mat near_truth;
  cv::inRange(figure.image(around), kGroundTruthColor - cv::Scalar::all(15), kGroundTruthColor + cv::Scalar::all(15),
              near_truth);
  const cv::Rect drawn = cv::boundingRect(near_truth);
  EXPECT_NEAR(drawn.width, drawn.height, 2);
  // Ten metres, plus the line's width and the start marker's radius.
  EXPECT_NEAR(drawn.width, 10 * figure.axes.PixelsPerUnitX() + 7, 5);
}

TEST(TopViewTest, AWideTrajectoryGetsALowerFigureWithTheSameScales) {
  std::vector<StampedPose> wide;
  for (int i = 0; i <= 100; ++i) {
    StampedPose pose;
    pose.stamp_s = 0.1 * i;
    pose.T_wc.translation() = Eigen::Vector3d(0.4 * i, i % 2 == 0 ? 0.0 : 10.0, 0);  // zigzag, 40 m x 10 m
    wide.push_back(pose);
  }
  TopViewOptions options;
  const Figure figure = DrawTopView(options, {"zigzag", wide}, {});
  KeepForLooking("wide", figure.image);
  EXPECT_LT(figure.image.rows, options.size.height - 200);
  EXPECT_EQ(figure.image.cols, options.size.width);
  EXPECT_NEAR(figure.axes.PixelsPerUnitX(), figure.axes.PixelsPerUnitY(), 1e-9);
  // The data fills the plot area's width and, within the padding, its height.
  EXPECT_NEAR((figure.axes.x_max - figure.axes.x_min) / (figure.axes.y_max - figure.axes.y_min),
              double(figure.axes.area.width) / figure.axes.area.height, 1e-9);
  // 10 m plus the padding on both sides (a share of the larger, 40 m extent), and little
  // more: the figure is at least 320 pixels high.
  EXPECT_GE(figure.axes.y_max - figure.axes.y_min, 10 + 2 * options.padding * 40 - 1e-9);
  EXPECT_LT(figure.axes.y_max - figure.axes.y_min, 1.1 * (10 + 2 * options.padding * 40));
}

TEST(TopViewTest, EstimatesHaveTheirOwnColours) {
  TopViewOptions options;
  const Figure figure = DrawTopView(options, {"ground truth", SquarePath(10)},
                                    {{"plain", SquarePath(10, {0.8, 0})}, {"mutual", SquarePath(10, {0, -0.8})}});
  KeepForLooking("square_estimates", figure.image);
  // Right edge of the first estimate, bottom edge of the second.
  EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(10.8, 5)), SeriesColor(0)), kNearColor);
  EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(5, -0.8)), SeriesColor(1)), kNearColor);
  EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(0.4, 10)), kGroundTruthColor), kNearColor);
  EXPECT_GT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(5, 5)), SeriesColor(0)), 200);
}

TEST(TopViewTest, LostFramesLeaveAGap) {
  std::vector<StampedPose> with_gap;
  for (const StampedPose& pose : SquarePath(10)) {
    const Eigen::Vector3d& t = pose.T_wc.translation();
    // Tracking lost along the middle of the bottom edge: those stamps are missing.
    if (t.y() < 1e-9 && t.x() > 3 && t.x() < 7) continue;
    with_gap.push_back(pose);
  }
  const Figure figure = DrawTopView(TopViewOptions{}, {"estimate", with_gap}, {});
  KeepForLooking("square_gap", figure.image);
  EXPECT_GT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(5, 0)), kGroundTruthColor), 300);
  EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(2, 0)), kGroundTruthColor), kNearColor);
  EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(8, 0)), kGroundTruthColor), kNearColor);
  // The same poses with a large gap factor are joined across the gap.
  TopViewOptions joined;
  joined.gap_factor = 100;
  const Figure joined_figure = DrawTopView(joined, {"estimate", with_gap}, {});
  EXPECT_LT(ColorDistance(joined_figure.image, Rounded(joined_figure.axes.ToPixel(5, 0)), kGroundTruthColor),
            kNearColor);
}

TEST(TopViewTest, RefusesWhatCannotBeDrawn) {
  EXPECT_THROW(DrawTopView(TopViewOptions{}, {"empty", {}}, {{"also empty", {}}}), Error);
  TopViewOptions bad;
  bad.gap_factor = 0.5;
  EXPECT_THROW(DrawTopView(bad, {"ground truth", SquarePath(1)}, {}), Error);
  std::vector<StampedPose> nan_pose = SquarePath(1);
  nan_pose[3].T_wc.translation().x() = std::nan("");
  EXPECT_THROW(DrawTopView(TopViewOptions{}, {"ground truth", nan_pose}, {}), Error);
}

TEST(LinePlotTest, PointsAndErrorBarsAreWhereTheValuesAre) {
  LinePlotOptions options;
  options.title = "ATE vs moving cars";
  options.x_label = "moving cars";
  options.y_label = "ATE RMSE [m]";
  const std::vector<double> x = {0, 2, 4, 8};
  PlotSeries mutual{"mutual", {0.02, 0.03, 0.035, 0.05}, {0.01, 0.02, 0.03, 0.04}, {0.03, 0.05, 0.06, 0.08}};
  const Figure figure = DrawLinePlot(options, x, {mutual});
  KeepForLooking("line_plot", figure.image);
  EXPECT_EQ(figure.axes.y_min, 0.0);  // errors start at zero
  EXPECT_GE(figure.axes.y_max, 0.08);
  EXPECT_LT(figure.axes.x_min, 0);
  EXPECT_GT(figure.axes.x_max, 8);
  for (size_t i = 0; i < x.size(); ++i) {
    // The marker's centre, and the error bar halfway between value and maximum.
    EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(x[i], mutual.y[i])), SeriesColor(0)), kNearColor);
    const cv::Point on_bar = Rounded(figure.axes.ToPixel(x[i], (mutual.y[i] + mutual.y_max[i]) / 2));
    bool bar_found = false;
    for (int du = -1; du <= 1; ++du) {
      const cv::Point p = on_bar + cv::Point(du, 0);
      bar_found = bar_found || ColorDistance(figure.image, p, SeriesColor(0)) <
                                   ColorDistance(figure.image, p, cv::Scalar(255, 255, 255));
    }
    EXPECT_TRUE(bar_found) << "no error bar at x = " << x[i];
  }
}

TEST(LinePlotTest, DenseSeriesCanBeDrawnWithoutMarkers) {
  const std::vector<double> x = {0, 1, 2, 3, 4};
  const PlotSeries flat{"error", {1, 1, 1, 1, 1}, {}, {}};
  for (const bool markers : {true, false}) {
    LinePlotOptions options;
    options.markers = markers;
    const Figure figure = DrawLinePlot(options, x, {flat});
    // Three pixels above a point on the horizontal line: inside a marker, else background
    // (and the vertical grid line through the tick there).
    const cv::Point above = Rounded(figure.axes.ToPixel(2, 1)) + cv::Point(0, -3);
    EXPECT_LT(ColorDistance(figure.image, Rounded(figure.axes.ToPixel(2.5, 1)), SeriesColor(0)), kNearColor);
    if (markers) {
      EXPECT_LT(ColorDistance(figure.image, above, SeriesColor(0)), kNearColor);
    } else {
      EXPECT_GT(ColorDistance(figure.image, above, SeriesColor(0)), kNearColor);
    }
  }
}

TEST(LinePlotTest, RefusesMismatchedSeries) {
  LinePlotOptions options;
  EXPECT_THROW(DrawLinePlot(options, {}, {}), Error);
  EXPECT_THROW(DrawLinePlot(options, {0, 1}, {{"short", {1}, {}, {}}}), Error);
  EXPECT_THROW(DrawLinePlot(options, {0, 1}, {{"bars", {1, 2}, {0}, {}}}), Error);
  EXPECT_THROW(DrawLinePlot(options, {1, 0}, {{"decreasing x", {1, 2}, {}, {}}}), Error);
}

// NaN is "no value" (a sweep point whose runs all failed): the line stops on either side
// of it instead of joining its neighbours.
TEST(LinePlotTest, NoValueLeavesAGapInTheLine) {
  LinePlotOptions options;
  options.markers = false;
  const Figure joined = DrawLinePlot(options, {0, 1, 2}, {{"flat", {1, 1, 1}, {}, {}}});
  const Figure hole = DrawLinePlot(options, {0, 1, 2}, {{"hole", {1, std::nan(""), 1}, {}, {}}});
  for (const double x : {0.5, 1.5}) {
    EXPECT_LT(ColorDistance(joined.image, Rounded(joined.axes.ToPixel(x, 1)), SeriesColor(0)), kNearColor) << x;
    EXPECT_GT(ColorDistance(hole.image, Rounded(hole.axes.ToPixel(x, 1)), SeriesColor(0)), kNearColor) << x;
  }
}

// ------------------------------------------------------------------ the tracker's feature records

using slam::testing::BoxQuads;
using slam::testing::LookingAlongX;
using slam::testing::RenderQuads;
using slam::testing::RenderedFrame;
using slam::testing::RoomQuads;

PinholeCamera TestCamera() { return PinholeCamera::FromVerticalFov(640, 480, 50); }

Eigen::Isometry3d PathPose(int i) {
  const double t = i / 30.0;
  return LookingAlongX(Eigen::Vector3d(-2.0 + 0.25 * t, 0.3 * std::sin(1.3 * t), 1.4 + 0.05 * std::sin(2 * t)),
                       0.25 * std::sin(0.9 * t));
}

constexpr std::uint16_t kMovingBoxId = 1;
constexpr std::uint16_t kStillBoxId = 2;

// The room with a box sliding across the view (1.5 m/s) and a box that stays put, both
// of a moveable class (tests/slam/tracker_test.cpp's moving-box scene).
RenderedFrame MovingBoxFrame(int i) {
  auto quads = RoomQuads(5);
  const auto still_box = BoxQuads({1.0, -1.6, 0.0}, {1.8, -0.8, 1.0}, 77, kStillBoxId);
  const double y = -0.2 + 1.5 * i / 30.0 - 0.6;
  const auto moving_box = BoxQuads({1.2, y, 0.0}, {1.8, y + 0.6, 1.6}, 99, kMovingBoxId);
  quads.insert(quads.end(), moving_box.begin(), moving_box.end());
  quads.insert(quads.end(), still_box.begin(), still_box.end());
  return RenderQuads(quads, TestCamera(), PathPose(i), i, i / 30.0);
}

struct TrackedRun {
  std::vector<FrameResult> results;
};

TrackedRun TrackMovingBox(mutual::SlamMode mode, int frames, bool record_features) {
  slam::TrackerOptions options;
  options.initial_T_wc = PathPose(0);
  options.record_features = record_features;
  slam::Tracker tracker(TestCamera(), options);
  slam::FrameInstances instances;
  instances.moveable_ids = {kMovingBoxId, kStillBoxId};
  TrackedRun run;
  for (int i = 0; i < frames; ++i) {
    const RenderedFrame rendered = MovingBoxFrame(i);
    instances.ids = rendered.instance_ids;
    run.results.push_back(mode == mutual::SlamMode::kMaskMoveable
                              ? slam::TrackMaskMoveable(tracker, rendered.frame, instances)
                              : slam::TrackJudging(tracker, rendered.frame, instances));
  }
  return run;
}

// The mutual run is shared by the tests that need it (it takes a few seconds).
const TrackedRun& MutualRun() {
  static const TrackedRun run = TrackMovingBox(mutual::SlamMode::kMutual, 24, true);
  return run;
}

std::map<FeatureKind, int> KindCounts(const FrameResult& result) {
  std::map<FeatureKind, int> counts;
  for (const FeatureRecord& record : result.feature_records) ++counts[record.kind];
  return counts;
}

TEST(FeatureRecordTest, MutualRecordsEveryFeatureOnceWithAConsistentKind) {
  const TrackedRun& run = MutualRun();
  int frames_with_moving_drops = 0;
  for (const FrameResult& result : run.results) {
    ASSERT_TRUE(result.localized()) << "frame " << result.frame_index;
    ASSERT_EQ(result.feature_records.size(), static_cast<size_t>(result.num_features)) << "frame " << result.frame_index;
    std::map<FeatureKind, int> counts = KindCounts(result);
    EXPECT_EQ(counts[FeatureKind::kUsed], result.num_fine_inliers) << "frame " << result.frame_index;
    std::map<std::uint16_t, bool> moving, judged;
    for (const slam::InstanceJudgement& judgement : result.instances) {
      moving[judgement.id] = judgement.moving;
      judged[judgement.id] = judgement.judged;
    }
    const RenderedFrame rendered = MovingBoxFrame(result.frame_index);
    for (const FeatureRecord& record : result.feature_records) {
      // The recorded instance is the one under the keypoint; a background feature kept
      // out with an instance is recorded as that one's: one whose mask lies within the
      // margin, or one not judged yet whose outline its map point was made on in the
      // run's first frames (it waits for the verdict wherever the instance is now).
      const cv::Point pixel(static_cast<int>(std::lround(record.pixel.x)), static_cast<int>(std::lround(record.pixel.y)));
      const std::uint16_t under = rendered.instance_ids.at<std::uint16_t>(pixel);
      if (under != 0 || record.instance_id == 0) {
        ASSERT_EQ(record.instance_id, under);
      } else {
        const slam::TrackerOptions defaults;
        const double level_scale = defaults.instance_margin_scales_with_level
                                       ? std::pow(static_cast<double>(defaults.orb.scale_factor), record.level)
                                       : 1.0;
        const int margin = static_cast<int>(std::lround(defaults.instance_margin_px * level_scale));
        const cv::Rect near = cv::Rect(pixel.x - margin, pixel.y - margin, 2 * margin + 1, 2 * margin + 1) &
                              cv::Rect(0, 0, rendered.instance_ids.cols, rendered.instance_ids.rows);
        const bool waits_for_verdict = !judged[record.instance_id] && record.kind == FeatureKind::kDroppedMoveable;
        ASSERT_TRUE(cv::countNonZero(rendered.instance_ids(near) == record.instance_id) > 0 || waits_for_verdict)
            << "recorded as instance " << record.instance_id << ", none of it within " << margin << " px";
        ASSERT_TRUE(record.kind == FeatureKind::kDroppedMoving || record.kind == FeatureKind::kDroppedMoveable);
      }
      if (record.kind == FeatureKind::kDroppedMoving) {
        EXPECT_TRUE(moving[record.instance_id]) << "dropped as moving on an instance not judged moving";
      }
      if (record.kind == FeatureKind::kDroppedMoveable) {
        EXPECT_NE(record.instance_id, 0) << "a background feature dropped as moveable";
        EXPECT_FALSE(moving[record.instance_id]);
      }
    }
    frames_with_moving_drops += counts[FeatureKind::kDroppedMoving] > 0;
  }
  EXPECT_GT(frames_with_moving_drops, 10);
}

TEST(FeatureRecordTest, MaskMoveableRecordsTheFeaturesItRemoved) {
  const TrackedRun run = TrackMovingBox(mutual::SlamMode::kMaskMoveable, 6, true);
  for (const FrameResult& result : run.results) {
    ASSERT_EQ(result.feature_records.size(), static_cast<size_t>(result.num_features));
    const RenderedFrame rendered = MovingBoxFrame(result.frame_index);
    int dropped = 0, on_boxes = 0;
    for (const FeatureRecord& record : result.feature_records) {
      const cv::Point pixel(static_cast<int>(std::lround(record.pixel.x)), static_cast<int>(std::lround(record.pixel.y)));
      const std::uint16_t id = rendered.instance_ids.at<std::uint16_t>(pixel);
      on_boxes += id != 0;
      if (record.kind == FeatureKind::kDroppedMoveable) {
        ++dropped;
        EXPECT_EQ(record.instance_id, id);
      }
      EXPECT_NE(record.kind, FeatureKind::kDroppedMoving);
    }
    EXPECT_EQ(dropped, on_boxes) << "frame " << result.frame_index;
    EXPECT_GT(dropped, 0);
    EXPECT_EQ(KindCounts(result)[FeatureKind::kUsed], result.num_fine_inliers);
  }
}

TEST(FeatureRecordTest, OffByDefault) {
  const TrackedRun run = TrackMovingBox(mutual::SlamMode::kMutual, 2, false);
  for (const FrameResult& result : run.results) EXPECT_TRUE(result.feature_records.empty());
}

TEST(FeatureFigureTest, PicksTheFrameWithMostMovingDropsAndDrawsItsFeatures) {
  const TrackedRun& run = MutualRun();
  const std::optional<size_t> picked = PickFeatureFigureFrame(run.results);
  ASSERT_TRUE(picked.has_value());
  const auto moving_drops = [](const FrameResult& result) { return KindCounts(result)[FeatureKind::kDroppedMoving]; };
  for (const FrameResult& result : run.results) EXPECT_LE(moving_drops(result), moving_drops(run.results[*picked]));

  const FrameResult& result = run.results[*picked];
  const RenderedFrame rendered = MovingBoxFrame(result.frame_index);
  const cv::Mat picture = DrawFeatureKinds(rendered.frame.color_bgr, rendered.instance_ids, result, "frame");
  KeepForLooking("features", picture);
  ASSERT_EQ(picture.cols, rendered.frame.color_bgr.cols);
  ASSERT_GT(picture.rows, rendered.frame.color_bgr.rows);  // the legend strip below
  // Dropped-moving dots are drawn last: their centres show their colour.
  int checked = 0, matching = 0;
  for (const FeatureRecord& record : result.feature_records) {
    if (record.kind != FeatureKind::kDroppedMoving) continue;
    ++checked;
    matching += ColorDistance(picture, Rounded({record.pixel.x, record.pixel.y}), FeatureKindColor(record.kind)) <
                kNearColor;
  }
  EXPECT_GT(checked, 0);
  EXPECT_GT(matching, 0.95 * checked);

  std::vector<FrameResult> without_records = run.results;
  for (FrameResult& r : without_records) r.feature_records.clear();
  EXPECT_FALSE(PickFeatureFigureFrame(without_records).has_value());
  EXPECT_THROW(DrawFeatureKinds(rendered.frame.color_bgr, cv::Mat(10, 10, CV_16U), result, ""), Error);
}

TEST(FeatureFigureTest, EachKindHasItsColourAndTheMovingInstanceItsOutline) {
  const cv::Mat frame(160, 200, CV_8UC3, cv::Scalar(120, 120, 120));
  cv::Mat ids(frame.size(), CV_16U, cv::Scalar(0));
  ids(cv::Rect(100, 40, 60, 80)).setTo(7);
  FrameResult result;
  slam::InstanceJudgement moving;
  moving.id = 7;
  moving.judged = moving.moving = true;
  result.instances = {moving};
  result.feature_records = {{{20, 20}, 0, FeatureKind::kUsed},
                            {{120, 60}, 7, FeatureKind::kDroppedMoving},
                            {{40, 100}, 0, FeatureKind::kDroppedMoveable},
                            {{60, 20}, 0, FeatureKind::kOutlier},
                            {{80, 140}, 0, FeatureKind::kUnmatched}};
  const cv::Mat picture = DrawFeatureKinds(frame, ids, result, "synthetic");
  KeepForLooking("features_synthetic", picture);
  ASSERT_GT(picture.rows, frame.rows);
  for (const FeatureRecord& record : result.feature_records) {
    const cv::Point center = Rounded({record.pixel.x, record.pixel.y});
    if (record.kind == FeatureKind::kUnmatched) {
      // Hollow: the frame shows through the centre, the ring has the colour.
      EXPECT_LT(ColorDistance(picture, center, cv::Scalar(120, 120, 120)), 10);
      EXPECT_LT(ColorDistance(picture, center + cv::Point(3, 0), FeatureKindColor(record.kind)), 150);
    } else {
      EXPECT_LT(ColorDistance(picture, center, FeatureKindColor(record.kind)), 10) << ToString(record.kind);
    }
  }
  // The moving instance's outline on its left edge, away from its label.
  EXPECT_LT(ColorDistance(picture, {100, 100}, cv::Scalar(255, 0, 255)), kNearColor);
  // Inside it, away from the features, the frame is unchanged.
  EXPECT_LT(ColorDistance(picture, {130, 100}, cv::Scalar(120, 120, 120)), 10);
}

// ------------------------------------------------------------------ masks

// A segmentation from an id image: one instance per id with the given category.
seg::FrameSegmentation SegmentationOf(const cv::Mat& ids, const std::map<std::uint16_t, int>& categories) {
  seg::FrameSegmentation segmentation;
  for (const auto& [id, category] : categories) {
    seg::InstanceMask instance;
    instance.track_id = id;
    instance.category_id = category;
    instance.mask = cv::Mat(ids == id) / 255;
    if (cv::countNonZero(instance.mask) > 0) segmentation.instances.push_back(instance);
  }
  return segmentation;
}

InstanceTable BoxTable() {
  InstanceTable table;
  table.Add({kMovingBoxId, 1, "", false});   // person
  table.Add({kStillBoxId, 62, "", false});   // chair
  return table;
}

// "Raw" masks as a weak segmenter gives them: eroded, and the still box missed.
cv::Mat RawIds(const cv::Mat& truth) {
  cv::Mat moving = truth == kMovingBoxId;
  cv::erode(moving, moving, cv::getStructuringElement(cv::MORPH_ELLIPSE, {25, 25}));
  cv::Mat raw(truth.size(), CV_16U, cv::Scalar(0));
  raw.setTo(kMovingBoxId, moving);
  return raw;
}

TEST(MaskComparisonTest, ThreePanelsOfTheFrameWithInstancesTinted) {
  const RenderedFrame rendered = MovingBoxFrame(10);
  const cv::Mat& truth = rendered.instance_ids;
  const auto raw = SegmentationOf(RawIds(truth), {{kMovingBoxId, 1}});
  const auto refined = SegmentationOf(truth, {{kMovingBoxId, 1}, {kStillBoxId, 62}});
  const cv::Mat picture = DrawMaskComparison(rendered.frame.color_bgr, truth, BoxTable(), raw, refined);
  const cv::Size frame = rendered.frame.color_bgr.size();
  constexpr int kBorder = 3;
  ASSERT_EQ(picture.cols, 3 * (frame.width + 2 * kBorder) + 2 * kBorder);
  ASSERT_EQ(picture.rows, frame.height + 4 * kBorder);
  // A pixel inside the still box: tinted in the ground-truth and refined panels, as the
  // frame in the raw panel (which missed it).
  cv::Mat still = truth == kStillBoxId;
  cv::erode(still, still, cv::getStructuringElement(cv::MORPH_RECT, {9, 9}));
  std::vector<cv::Point> inside;
  cv::findNonZero(still, inside);
  ASSERT_FALSE(inside.empty());
  const cv::Point p = inside[inside.size() / 2];
  const cv::Vec3b original = rendered.frame.color_bgr.at<cv::Vec3b>(p);
  const auto panel_pixel = [&](int panel) {
    return picture.at<cv::Vec3b>(p + cv::Point(2 * kBorder + panel * (frame.width + 2 * kBorder), 2 * kBorder));
  };
  EXPECT_NE(panel_pixel(0), original);
  EXPECT_EQ(panel_pixel(1), original);
  EXPECT_NE(panel_pixel(2), original);
  EXPECT_THROW(DrawMaskComparison(rendered.frame.color_bgr, cv::Mat(4, 4, CV_16U), BoxTable(), raw, refined), Error);
}

// ------------------------------------------------------------------ a whole sample report

class SampleReportTest : public segslam::testing::TempDirTest {};

TEST_F(SampleReportTest, EveryFigureInAReportWhoseImagesExist) {
  const char* keep = std::getenv("SEGSLAM_REPORT_SAMPLE_DIR");
  const std::filesystem::path out = keep != nullptr ? std::filesystem::path(keep) : dir() / "report";
  std::filesystem::create_directories(out / "figures");

  // Fig. 4: ground truth and two estimates of a city block loop, one losing frames.
  std::vector<StampedPose> truth, plain, mutual;
  for (int i = 0; i <= 400; ++i) {
    const double t = i * 0.1, angle = 2 * M_PI * i / 400;
    StampedPose pose;
    pose.stamp_s = t;
    pose.T_wc.translation() = Eigen::Vector3d(30 * std::cos(angle) + 4 * std::cos(3 * angle), 18 * std::sin(angle), 1.6);
    truth.push_back(pose);
    StampedPose drifting = pose;
    drifting.T_wc.translation() += Eigen::Vector3d(0.02 * i * std::sin(angle), 0.012 * i, 0);
    if (i < 120 || i > 150) plain.push_back(drifting);
    StampedPose close = pose;
    close.T_wc.translation() += Eigen::Vector3d(0.3 * std::sin(5 * angle), 0.25 * std::cos(3 * angle), 0);
    mutual.push_back(close);
  }
  TopViewOptions top_view;
  top_view.title = "Top view, pass 1 (x-y ground plane)";
  WriteFigure(out / "figures/top_view.png",
              DrawTopView(top_view, {"ground truth", truth}, {{"plain", plain}, {"mutual", mutual}}).image);

  // The density sweep.
  LinePlotOptions sweep;
  sweep.title = "ATE vs number of moving cars";
  sweep.x_label = "moving cars";
  sweep.y_label = "ATE RMSE [m]";
  const std::vector<double> cars = {0, 2, 4, 8, 16};
  const std::vector<PlotSeries> series = {
      {"plain", {0.05, 0.11, 0.24, 0.41, 0.75}, {0.04, 0.08, 0.17, 0.30, 0.55}, {0.07, 0.15, 0.33, 0.52, 0.98}},
      {"mask-moveable", {0.06, 0.07, 0.09, 0.14, 0.22}, {0.05, 0.06, 0.07, 0.11, 0.18}, {0.07, 0.09, 0.12, 0.18, 0.29}},
      {"mutual", {0.05, 0.06, 0.07, 0.09, 0.12}, {0.04, 0.05, 0.06, 0.07, 0.10}, {0.06, 0.07, 0.09, 0.12, 0.16}}};
  WriteFigure(out / "figures/density_sweep.png", DrawLinePlot(sweep, cars, series).image);

  // Fig. 5 and Fig. 6 from the ray-cast room.
  const RenderedFrame masks_frame = MovingBoxFrame(10);
  WriteFigure(out / "figures/masks.png",
              DrawMaskComparison(masks_frame.frame.color_bgr, masks_frame.instance_ids, BoxTable(),
                                 SegmentationOf(RawIds(masks_frame.instance_ids), {{kMovingBoxId, 1}}),
                                 SegmentationOf(masks_frame.instance_ids, {{kMovingBoxId, 1}, {kStillBoxId, 62}})));
  const TrackedRun& run = MutualRun();
  const size_t picked = PickFeatureFigureFrame(run.results).value();
  const RenderedFrame feature_frame = MovingBoxFrame(run.results[picked].frame_index);
  WriteFigure(out / "figures/features.png",
              DrawFeatureKinds(feature_frame.frame.color_bgr, feature_frame.instance_ids, run.results[picked],
                               "mutual, frame " + std::to_string(run.results[picked].frame_index)));

  ReportDocument document("segslam sample report");
  document.AddMetadata("scenario", "(synthetic test data)");
  document.AddMetadata("seeds", "5, 77, 99");
  document.AddMetadata("code version", "test");
  document.AddHeading("Trajectories");
  document.AddParagraph("Estimates aligned to the ground truth. The plain baseline lost frames 120-150.");
  document.AddTable({"ATE RMSE [m], median over repeats", {"mode", "median", "min", "max"},
                     {{"plain", "0.412", "0.300", "0.520"}, {"mutual", "0.091", "0.070", "0.120"}}});
  document.AddImage("figures/top_view.png", "Top view of the trajectories (cf. the paper's Fig. 4).");
  document.AddImage("figures/density_sweep.png", "ATE against the number of moving cars, median with min/max.");
  document.AddHeading("Segmentation");
  document.AddImage("figures/masks.png", "Ground truth, raw and refined masks (cf. Fig. 5).");
  document.AddImage("figures/features.png", "Features kept and dropped on a moving object (cf. Fig. 6).");
  document.Write(out);
  EXPECT_TRUE(document.MissingImages(out).empty());
  std::ifstream html_file(out / "report.html");
  const std::string html((std::istreambuf_iterator<char>(html_file)), std::istreambuf_iterator<char>());
  for (const char* name : {"figures/top_view.png", "figures/density_sweep.png", "figures/masks.png",
                           "figures/features.png"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(out / name)) << name;
    EXPECT_NE(html.find(std::string("<img src=\"") + name + "\""), std::string::npos) << name << " not shown";
  }
  EXPECT_TRUE(std::filesystem::is_regular_file(out / "report.md"));
}

}  // namespace
}  // namespace segslam::harness
