#include "seg/metrics.h"

#include "core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <utility>
#include <vector>

namespace segslam::seg {
namespace {

constexpr int kPerson = 1;  // COCO ids.
constexpr int kCar = 3;
constexpr int kChair = 62;

// Hand-computed values are sums of a few ratios; they agree to rounding.
constexpr double kTolerance = 1e-12;

const cv::Size kFrameSize(20, 20);  // width, height

cv::Mat BoxMask(cv::Rect box, cv::Size size = kFrameSize) {
  cv::Mat mask = cv::Mat::zeros(size, CV_8U);
  mask(box).setTo(1);
  return mask;
}

// Ground truth: boxes painted in the given order (a later box covers an earlier one).
cv::Mat GroundTruth(const std::vector<std::pair<std::uint16_t, cv::Rect>>& boxes,
                    cv::Size size = kFrameSize) {
  cv::Mat ids = cv::Mat::zeros(size, CV_16U);
  for (const auto& [id, box] : boxes) ids(box).setTo(id);
  return ids;
}

InstanceTable Table(const std::vector<std::pair<std::uint16_t, int>>& id_to_category) {
  InstanceTable table;
  for (const auto& [id, category] : id_to_category) table.Add({id, category, "", false});
  return table;
}

InstanceMask Detection(int category, float score, cv::Mat mask) {
  static std::uint16_t next_track_id = 1;
  InstanceMask instance;
  instance.track_id = next_track_id++;
  instance.category_id = category;
  instance.score = score;
  instance.mask = std::move(mask);
  return instance;
}

FrameSegmentation Prediction(std::vector<InstanceMask> instances) {
  FrameSegmentation prediction;
  prediction.instances = std::move(instances);
  return prediction;
}

SegmentationScores ScoreOne(const cv::Mat& gt, const InstanceTable& table,
                            const FrameSegmentation& prediction) {
  return SegmentationEvaluator::ScoreFrame({}, gt, table, prediction);
}

// ---- COCO AP, hand-computed ----

TEST(SegmentationMetrics, PerfectPredictionHasApAndIouOne) {
  const InstanceTable table = Table({{1, kPerson}, {2, kCar}, {3, kCar}});
  const cv::Rect person(0, 0, 5, 10), car_a(8, 0, 4, 4), car_b(8, 10, 6, 6);
  SegmentationEvaluator evaluator;
  for (int frame = 0; frame < 2; ++frame) {
    const cv::Mat gt = GroundTruth({{1, person}, {2, car_a}, {3, car_b}});
    evaluator.AddFrame(gt, table,
                       Prediction({Detection(kPerson, 0.9f, BoxMask(person)),
                                   Detection(kCar, 0.8f, BoxMask(car_a)),
                                   Detection(kCar, 0.7f, BoxMask(car_b))}));
  }
  const SegmentationScores scores = evaluator.Scores();
  EXPECT_NEAR(scores.mAP, 1.0, kTolerance);
  EXPECT_NEAR(scores.AP50, 1.0, kTolerance);
  EXPECT_NEAR(scores.AP75, 1.0, kTolerance);
  EXPECT_NEAR(scores.mIoU, 1.0, kTolerance);
  EXPECT_EQ(scores.frames, 2);
  EXPECT_EQ(scores.gt_instances, 6);
  EXPECT_EQ(scores.detections, 6);
  EXPECT_EQ(scores.ap_per_category.size(), 2u);
  EXPECT_EQ(scores.pixels_per_category.at(kCar).true_positive, 2 * (16 + 36));
}

TEST(SegmentationMetrics, NoDetectionsGiveApZeroForEveryCategoryWithGroundTruth) {
  const InstanceTable table = Table({{1, kPerson}, {2, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 5, 5}}, {2, {10, 10, 5, 5}}});
  const SegmentationScores scores = ScoreOne(gt, table, Prediction({}));
  EXPECT_EQ(scores.ap_per_category.at(kPerson), 0.0);
  EXPECT_EQ(scores.ap_per_category.at(kCar), 0.0);
  EXPECT_EQ(scores.mAP, 0.0);
  EXPECT_EQ(scores.AP50, 0.0);
  // Both classes occur in the ground truth only: IoU 0 each.
  EXPECT_EQ(scores.mIoU, 0.0);
  EXPECT_EQ(scores.pixels_per_category.at(kCar).false_negative, 25);
}

TEST(SegmentationMetrics, CategoryWithoutGroundTruthIsLeftOutOfMap) {
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(0, 0, 5, 5);
  const cv::Mat gt = GroundTruth({{1, person}});
  const SegmentationScores scores =
      ScoreOne(gt, table,
               Prediction({Detection(kPerson, 0.5f, BoxMask(person)),
                           Detection(kCar, 0.9f, BoxMask({10, 10, 4, 4}))}));
  EXPECT_TRUE(std::isnan(scores.ap_per_category.at(kCar)));
  EXPECT_NEAR(scores.ap_per_category.at(kPerson), 1.0, kTolerance);
  EXPECT_NEAR(scores.mAP, 1.0, kTolerance);  // The car's false positive costs nothing here,
  EXPECT_NEAR(scores.iou_per_category.at(kCar), 0.0, kTolerance);  // but in mIoU it does.
  EXPECT_NEAR(scores.mIoU, 0.5, kTolerance);
}

TEST(SegmentationMetrics, MapIsNanWithoutAnyGroundTruth) {
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Mat background = GroundTruth({});
  const SegmentationScores with_detection =
      ScoreOne(background, table, Prediction({Detection(kCar, 0.9f, BoxMask({0, 0, 4, 4}))}));
  EXPECT_TRUE(std::isnan(with_detection.mAP));
  EXPECT_TRUE(std::isnan(with_detection.AP50));
  EXPECT_TRUE(std::isnan(with_detection.AP75));
  EXPECT_EQ(with_detection.mIoU, 0.0);  // The car class occurs, as a false positive.

  const SegmentationScores empty = ScoreOne(background, table, Prediction({}));
  EXPECT_TRUE(std::isnan(empty.mAP));
  EXPECT_TRUE(std::isnan(empty.mIoU));
  EXPECT_TRUE(empty.ap_per_category.empty());

  SegmentationEvaluator no_frames;
  EXPECT_TRUE(std::isnan(no_frames.Scores().mAP));
  EXPECT_TRUE(std::isnan(no_frames.Scores().mIoU));
}

TEST(SegmentationMetrics, DuplicateAfterTheHitIsAFalsePositiveThatCostsNothing) {
  // 1 GT; 0.9 hits, 0.8 duplicates it (FP). Recall [1, 1], precision [1, 0.5]: every
  // recall threshold is first reached at the first detection, precision 1 -> AP 1.
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(2, 2, 6, 6);
  const SegmentationScores scores =
      ScoreOne(GroundTruth({{1, person}}), table,
               Prediction({Detection(kPerson, 0.9f, BoxMask(person)),
                           Detection(kPerson, 0.8f, BoxMask(person))}));
  EXPECT_NEAR(scores.mAP, 1.0, kTolerance);
  EXPECT_EQ(scores.detections, 2);
}

TEST(SegmentationMetrics, FalsePositiveBeforeTheHitHalvesAp) {
  // 1 GT; 0.9 misses (FP), 0.8 hits. Recall [0, 1], precision [0, 0.5]; envelope
  // [0.5, 0.5]; all 101 samples 0.5 -> AP 0.5.
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(2, 2, 6, 6);
  const SegmentationScores scores =
      ScoreOne(GroundTruth({{1, person}}), table,
               Prediction({Detection(kPerson, 0.8f, BoxMask(person)),
                           Detection(kPerson, 0.9f, BoxMask({12, 12, 6, 6}))}));
  EXPECT_NEAR(scores.mAP, 0.5, kTolerance);
  EXPECT_NEAR(scores.AP50, 0.5, kTolerance);
}

TEST(SegmentationMetrics, DuplicateThatIsTheBetterMaskWinsOnlyAtHighThresholds) {
  // 1 GT of 100 px; 0.9 covers 60 of them (IoU 0.6), 0.8 is exact (IoU 1). At
  // t <= 0.60 the 0.9 one is the TP and 0.8 a duplicate: AP_t 1. At t >= 0.65 the 0.9 one
  // is a FP and 0.8 the TP: AP_t 0.5. AP = (3 * 1 + 7 * 0.5) / 10 = 0.65.
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(0, 0, 10, 10);
  const SegmentationScores scores =
      ScoreOne(GroundTruth({{1, person}}), table,
               Prediction({Detection(kPerson, 0.9f, BoxMask({0, 0, 10, 6})),
                           Detection(kPerson, 0.8f, BoxMask(person))}));
  EXPECT_NEAR(scores.mAP, 0.65, kTolerance);
  EXPECT_NEAR(scores.AP50, 1.0, kTolerance);
  EXPECT_NEAR(scores.AP75, 0.5, kTolerance);
}

TEST(SegmentationMetrics, IouOfExactlyPointSixCountsUpToThreshold060) {
  // 60 of the GT's 100 pixels and nothing outside: IoU = 60 / 100 = 0.6, which is the
  // threshold 0.6 exactly -> TP at 0.50, 0.55, 0.60, FP at 0.65..0.95 -> AP 3/10.
  const InstanceTable table = Table({{1, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 10, 10}}});
  const SegmentationScores scores =
      ScoreOne(gt, table, Prediction({Detection(kCar, 0.7f, BoxMask({0, 0, 10, 6}))}));
  EXPECT_NEAR(scores.ap_per_category.at(kCar), 0.3, kTolerance);
  EXPECT_NEAR(scores.AP50, 1.0, kTolerance);
  EXPECT_NEAR(scores.AP75, 0.0, kTolerance);
}

TEST(SegmentationMetrics, IouOfPointNineCountsAtNumpysThreshold) {
  // numpy.linspace puts the 0.90 threshold at 0.8999999999999999, so IoU 90/100 is a TP
  // at 9 of the 10 thresholds -> AP 0.9, as pycocotools reports.
  EXPECT_EQ(CocoIouThresholds()[2], 0.6);
  EXPECT_LT(CocoIouThresholds()[8], 0.9);
  const InstanceTable table = Table({{1, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 10, 10}}});
  const SegmentationScores scores =
      ScoreOne(gt, table, Prediction({Detection(kCar, 0.7f, BoxMask({0, 0, 10, 9}))}));
  EXPECT_NEAR(scores.mAP, 0.9, kTolerance);
}

TEST(SegmentationMetrics, MapAveragesCategories) {
  // Person exact (AP 1), car at IoU 0.6 (AP 0.3): mAP 0.65, AP50 1, AP75 0.5.
  const InstanceTable table = Table({{1, kPerson}, {2, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 10, 10}}, {2, {10, 10, 10, 10}}});
  const SegmentationScores scores =
      ScoreOne(gt, table,
               Prediction({Detection(kPerson, 0.4f, BoxMask({0, 0, 10, 10})),
                           Detection(kCar, 0.9f, BoxMask({10, 10, 10, 6}))}));
  EXPECT_NEAR(scores.ap_per_category.at(kPerson), 1.0, kTolerance);
  EXPECT_NEAR(scores.ap_per_category.at(kCar), 0.3, kTolerance);
  EXPECT_NEAR(scores.mAP, 0.65, kTolerance);
  EXPECT_NEAR(scores.AP50, 1.0, kTolerance);
  EXPECT_NEAR(scores.AP75, 0.5, kTolerance);
  EXPECT_NEAR(scores.ap75_per_category.at(kCar), 0.0, kTolerance);
}

TEST(SegmentationMetrics, EqualScoresKeepTheirGivenOrder) {
  // Stable sorting (numpy mergesort): with equal scores the listed order decides.
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(2, 2, 6, 6);
  const cv::Mat gt = GroundTruth({{1, person}});
  const InstanceMask hit = Detection(kPerson, 0.5f, BoxMask(person));
  const InstanceMask miss = Detection(kPerson, 0.5f, BoxMask({12, 12, 6, 6}));
  EXPECT_NEAR(ScoreOne(gt, table, Prediction({hit, miss})).mAP, 1.0, kTolerance);
  EXPECT_NEAR(ScoreOne(gt, table, Prediction({miss, hit})).mAP, 0.5, kTolerance);
}

TEST(SegmentationMetrics, GreedyMatchingTakesTheBestUnmatchedGroundTruth) {
  // GT A = cols 0-9, GT B = cols 10-19 of rows 0-9 (100 px each). Detection 0.9 covers B
  // and 5 columns of A (150 px): IoU with B 100/150 = 0.667, with A 50/200 -> it takes B
  // wherever 0.667 passes. Detection 0.8 is B exactly (IoU 1), A's IoU is 0.
  //   t = 0.50..0.65 (4): 0.9 TP on B, 0.8 a duplicate FP. Recall [0.5, 0.5], precision
  //     [1, 0.5]: r = 0.00..0.50 (51 samples) give 1, the rest 0 -> AP_t = 51/101.
  //   t = 0.70..0.95 (6): 0.9 FP, 0.8 TP on B. Recall [0, 0.5], envelope [0.5, 0.5]:
  //     51 samples of 0.5 -> AP_t = 25.5/101.
  // AP = (4 * 51 + 6 * 25.5) / 101 / 10 = 357/1010.
  const InstanceTable table = Table({{1, kCar}, {2, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 10, 10}}, {2, {10, 0, 10, 10}}});
  const SegmentationScores scores =
      ScoreOne(gt, table,
               Prediction({Detection(kCar, 0.9f, BoxMask({5, 0, 15, 10})),
                           Detection(kCar, 0.8f, BoxMask({10, 0, 10, 10}))}));
  EXPECT_NEAR(scores.AP50, 51.0 / 101.0, kTolerance);
  EXPECT_NEAR(scores.AP75, 25.5 / 101.0, kTolerance);
  EXPECT_NEAR(scores.mAP, 357.0 / 1010.0, kTolerance);
}

TEST(SegmentationMetrics, EqualIouGoesToTheLaterGroundTruth) {
  // GT A = cols 0-4, GT B = cols 5-9 of rows 0-9 (50 px each). Detection 0.9 is A u B:
  // IoU 50/100 = 0.5 with both; pycocotools keeps the later one of equal IoUs, B.
  // Detection 0.8 is A exactly, still free at t = 0.50 -> two TPs, AP50 = 1 (taking A
  // first would make 0.8 a FP and AP50 51/101). At t >= 0.55, 0.9 is a FP and 0.8 a TP:
  // recall [0, 0.5], envelope 0.5 over r = 0.00..0.50 -> 25.5/101.
  const InstanceTable table = Table({{1, kCar}, {2, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 5, 10}}, {2, {5, 0, 5, 10}}});
  const SegmentationScores scores =
      ScoreOne(gt, table,
               Prediction({Detection(kCar, 0.9f, BoxMask({0, 0, 10, 10})),
                           Detection(kCar, 0.8f, BoxMask({0, 0, 5, 10}))}));
  EXPECT_NEAR(scores.AP50, 1.0, kTolerance);
  EXPECT_NEAR(scores.mAP, (1.0 + 9 * 25.5 / 101.0) / 10, kTolerance);
}

TEST(SegmentationMetrics, RecallThresholdsAreNumpysProducts) {
  // 20 GT, 7 found exactly and nothing else: recall climbs to 7/20 = 0.35 at precision 1.
  // numpy's r_35 = 35 * 0.01 = 0.35000000000000003 > 0.35, so only r_0..r_34 are
  // reached: AP = 35/101 (36/101 with r_k = k / 100).
  const cv::Size size(20, 16);
  std::vector<std::pair<std::uint16_t, int>> categories;
  std::vector<std::pair<std::uint16_t, cv::Rect>> boxes;
  std::vector<InstanceMask> found;
  for (std::uint16_t id = 1; id <= 20; ++id) {
    const cv::Rect box(4 * ((id - 1) % 5), 4 * ((id - 1) / 5), 4, 4);
    categories.emplace_back(id, kPerson);
    boxes.emplace_back(id, box);
    if (id <= 7) found.push_back(Detection(kPerson, 0.5f, BoxMask(box, size)));
  }
  const SegmentationScores scores =
      ScoreOne(GroundTruth(boxes, size), Table(categories), Prediction(found));
  EXPECT_NEAR(scores.mAP, 35.0 / 101.0, kTolerance);
}

TEST(SegmentationMetrics, GroundTruthWithoutPixelsIsNoGroundTruth) {
  // Instance 2 is listed in the table but entirely covered by instance 1 in this frame.
  const InstanceTable table = Table({{1, kPerson}, {2, kPerson}});
  const cv::Rect box(0, 0, 8, 8);
  const cv::Mat gt = GroundTruth({{2, {2, 2, 3, 3}}, {1, box}});
  const SegmentationScores scores =
      ScoreOne(gt, table, Prediction({Detection(kPerson, 0.9f, BoxMask(box))}));
  EXPECT_EQ(scores.gt_instances, 1);
  EXPECT_NEAR(scores.mAP, 1.0, kTolerance);
}

TEST(SegmentationMetrics, DetectionsBeyondTheCapAreDropped) {
  // With a cap of 1 only the 0.9 FP is kept, the 0.8 hit is never seen: AP 0.
  EvaluationOptions options;
  options.max_detections_per_frame = 1;
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(2, 2, 6, 6);
  const FrameSegmentation prediction =
      Prediction({Detection(kPerson, 0.8f, BoxMask(person)),
                  Detection(kPerson, 0.9f, BoxMask({12, 12, 6, 6}))});
  const SegmentationScores scores =
      SegmentationEvaluator::ScoreFrame(options, GroundTruth({{1, person}}), table, prediction);
  EXPECT_EQ(scores.mAP, 0.0);
  EXPECT_EQ(scores.detections, 1);
}

// ---- mIoU, hand-computed ----

TEST(SegmentationMetrics, MiouCountsPixelsWithTheHigherScoreWinningOverlaps) {
  // 4 x 6 image. GT: person cols 0-2 (12 px), background col 3, car cols 4-5 (8 px).
  // Prediction: person cols 0-3, car cols 2-5; they overlap in cols 2-3.
  const cv::Size size(6, 4);
  const InstanceTable table = Table({{1, kPerson}, {2, kCar}});
  const cv::Mat gt = GroundTruth({{1, {0, 0, 3, 4}}, {2, {4, 0, 2, 4}}}, size);
  const auto predict = [&](float car_score) {
    return Prediction({Detection(kPerson, 0.9f, BoxMask({0, 0, 4, 4}, size)),
                       Detection(kCar, car_score, BoxMask({2, 0, 4, 4}, size))});
  };
  {
    // Person wins cols 2-3. Person: TP 12, FP 4 (col 3), FN 0 -> 0.75. Car: TP 8 -> 1.
    const SegmentationScores scores = ScoreOne(gt, table, predict(0.5f));
    EXPECT_NEAR(scores.iou_per_category.at(kPerson), 0.75, kTolerance);
    EXPECT_NEAR(scores.iou_per_category.at(kCar), 1.0, kTolerance);
    EXPECT_NEAR(scores.mIoU, 0.875, kTolerance);
    EXPECT_EQ(scores.pixels_per_category.at(kPerson).false_positive, 4);
  }
  {
    // Car wins cols 2-3. Person: TP 8, FN 4 (col 2) -> 8/12. Car: TP 8, FP 8 (cols 2-3)
    // -> 8/16. mIoU = (2/3 + 1/2) / 2 = 7/12.
    const SegmentationScores scores = ScoreOne(gt, table, predict(0.95f));
    EXPECT_NEAR(scores.iou_per_category.at(kPerson), 2.0 / 3.0, kTolerance);
    EXPECT_NEAR(scores.iou_per_category.at(kCar), 0.5, kTolerance);
    EXPECT_NEAR(scores.mIoU, 7.0 / 12.0, kTolerance);
    const PixelCounts car = scores.pixels_per_category.at(kCar);
    EXPECT_EQ(car.true_positive, 8);
    EXPECT_EQ(car.false_positive, 8);
    EXPECT_EQ(car.false_negative, 0);
  }
}

TEST(SegmentationMetrics, SequenceAccumulatesRatherThanAveragingFrames) {
  // Frame 1: person hit (score 0.5). Frame 2: the person is missed and a 0.9 detection
  // lands on background. Per frame: AP 1 and 0, person IoU 1 and 0.
  // Sequence AP: sorted 0.9 FP, 0.5 TP; recall [0, 0.5], precision envelope [0.5, 0.5];
  // r = 0.00..0.50 (51 samples) give 0.5 -> AP = 25.5 / 101 (not the frames' mean 0.5).
  // Sequence IoU: TP 25, FP 25, FN 25 -> 1/3 (not 0.5).
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(0, 0, 5, 5);
  const cv::Mat gt = GroundTruth({{1, person}});
  SegmentationEvaluator evaluator;
  const SegmentationScores first =
      evaluator.AddFrame(gt, table, Prediction({Detection(kPerson, 0.5f, BoxMask(person))}));
  const SegmentationScores second = evaluator.AddFrame(
      gt, table, Prediction({Detection(kPerson, 0.9f, BoxMask({10, 10, 5, 5}))}));
  EXPECT_NEAR(first.mAP, 1.0, kTolerance);
  EXPECT_NEAR(second.mAP, 0.0, kTolerance);
  EXPECT_NEAR(first.mIoU, 1.0, kTolerance);
  EXPECT_NEAR(second.mIoU, 0.0, kTolerance);

  const SegmentationScores sequence = evaluator.Scores();
  EXPECT_NEAR(sequence.mAP, 25.5 / 101.0, kTolerance);
  EXPECT_NEAR(sequence.AP50, 25.5 / 101.0, kTolerance);
  EXPECT_NEAR(sequence.mIoU, 1.0 / 3.0, kTolerance);
  EXPECT_EQ(sequence.frames, 2);
  EXPECT_EQ(sequence.gt_instances, 2);
  EXPECT_EQ(sequence.detections, 2);
}

// ---- Configuration, errors, JSON ----

TEST(SegmentationMetrics, OptionsAreChecked) {
  EvaluationOptions options;
  EXPECT_TRUE(options.IsValid(nullptr));
  options.max_detections_per_frame = 0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("max_detections_per_frame"), std::string::npos);
  EXPECT_THROW(SegmentationEvaluator{options}, Error);
}

TEST(SegmentationMetrics, BadFramesThrowAndAddNothing) {
  const InstanceTable table = Table({{1, kPerson}});
  SegmentationEvaluator evaluator;
  // An id missing from the table.
  EXPECT_THROW(evaluator.AddFrame(GroundTruth({{7, {0, 0, 2, 2}}}), table, Prediction({})),
               Error);
  // A mask of the wrong size, a wrong category, a wrong id image type.
  const cv::Mat gt = GroundTruth({{1, {0, 0, 2, 2}}});
  EXPECT_THROW(evaluator.AddFrame(gt, table,
                                  Prediction({Detection(kPerson, 0.5f,
                                                        BoxMask({0, 0, 2, 2}, {10, 10}))})),
               Error);
  EXPECT_THROW(evaluator.AddFrame(gt, table,
                                  Prediction({Detection(/*category=*/12, 0.5f,
                                                        BoxMask({0, 0, 2, 2}))})),
               Error);
  cv::Mat wrong_type;
  gt.convertTo(wrong_type, CV_32S);
  EXPECT_THROW(evaluator.AddFrame(wrong_type, table, Prediction({})), Error);
  EXPECT_EQ(evaluator.Scores().frames, 0);
}

TEST(SegmentationMetrics, JsonWritesNanAsNull) {
  const InstanceTable table = Table({{1, kPerson}});
  const cv::Rect person(0, 0, 5, 5);
  const SegmentationScores scores =
      ScoreOne(GroundTruth({{1, person}}), table,
               Prediction({Detection(kPerson, 0.5f, BoxMask(person)),
                           Detection(kChair, 0.9f, BoxMask({10, 10, 2, 2}))}));
  const nlohmann::json json = scores.ToJson();
  EXPECT_DOUBLE_EQ(json.at("mAP").get<double>(), 1.0);
  EXPECT_EQ(json.at("frames"), 1);
  ASSERT_EQ(json.at("categories").size(), 2u);
  const nlohmann::json& chair = json.at("categories").at(1);
  EXPECT_EQ(chair.at("category_id"), kChair);
  EXPECT_EQ(chair.at("category"), "chair");
  EXPECT_TRUE(chair.at("ap").is_null());
  EXPECT_EQ(chair.at("iou"), 0.0);
  EXPECT_EQ(chair.at("fp_pixels"), 4);
}

// ---- Cross-check against an independent brute-force implementation ----

struct RandomFrame {
  cv::Mat gt;
  FrameSegmentation prediction;
};

// Brute-force AP of one category at one IoU threshold, written from COCO's definition
// without sharing code: IoU from cv::countNonZero of AND / OR of masks; interpolated
// precision at r = max precision over all ranks with recall >= r.
double ReferenceAp(const std::vector<RandomFrame>& frames, const InstanceTable& table,
                   int category, double iou_threshold) {
  struct Ranked {
    float score;
    bool true_positive;
  };
  std::vector<Ranked> ranked;  // Frame order, then score order within a frame.
  int num_gt = 0;
  for (const RandomFrame& frame : frames) {
    std::vector<cv::Mat> gt_masks;  // Ascending id.
    for (const InstanceInfo& info : table.instances()) {
      if (info.category_id != category) continue;
      cv::Mat mask = frame.gt == info.id;
      if (cv::countNonZero(mask) > 0) gt_masks.push_back(mask);
    }
    num_gt += static_cast<int>(gt_masks.size());
    std::vector<const InstanceMask*> detections;
    for (const InstanceMask& instance : frame.prediction.instances) {
      if (instance.category_id == category) detections.push_back(&instance);
    }
    std::stable_sort(detections.begin(), detections.end(),
                     [](const InstanceMask* a, const InstanceMask* b) { return a->score > b->score; });
    std::vector<bool> taken(gt_masks.size(), false);
    for (const InstanceMask* detection : detections) {
      const cv::Mat inside = detection->mask != 0;
      int best = -1;
      double best_iou = iou_threshold;
      for (size_t g = 0; g < gt_masks.size(); ++g) {
        if (taken[g]) continue;
        const double iou = static_cast<double>(cv::countNonZero(inside & gt_masks[g])) /
                           cv::countNonZero(inside | gt_masks[g]);
        if (iou >= best_iou) {  // >=: the later of equal IoUs wins, as pycocotools.
          best_iou = iou;
          best = static_cast<int>(g);
        }
      }
      if (best >= 0) taken[best] = true;
      ranked.push_back({detection->score, best >= 0});
    }
  }
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const Ranked& a, const Ranked& b) { return a.score > b.score; });
  std::vector<double> precision, recall;
  int true_positives = 0;
  for (size_t i = 0; i < ranked.size(); ++i) {
    true_positives += ranked[i].true_positive ? 1 : 0;
    precision.push_back(static_cast<double>(true_positives) / (i + 1));
    recall.push_back(static_cast<double>(true_positives) / num_gt);
  }
  double sum = 0;
  for (int k = 0; k <= 100; ++k) {
    const double r = k == 100 ? 1.0 : k * 0.01;  // numpy.linspace(0, 1, 101)
    double best = 0;
    for (size_t i = 0; i < ranked.size(); ++i) {
      if (recall[i] >= r) best = std::max(best, precision[i]);
    }
    sum += best;
  }
  return sum / 101;
}

TEST(SegmentationMetrics, ApMatchesBruteForceReferenceOnRandomFrames) {
  constexpr int kSeeds = 300;
  const cv::Size size(16, 12);
  const std::vector<int> categories = {kPerson, kCar};
  const InstanceTable table = Table({{1, kPerson}, {2, kPerson}, {3, kCar}, {4, kCar}, {5, kPerson}});
  for (int seed = 0; seed < kSeeds; ++seed) {
    std::mt19937 rng(seed);
    const auto uniform = [&](int low, int high) {
      return std::uniform_int_distribution<int>(low, high)(rng);
    };
    const auto random_box = [&]() {
      const int x = uniform(0, size.width - 2), y = uniform(0, size.height - 2);
      return cv::Rect(x, y, uniform(1, size.width - x), uniform(1, size.height - y));
    };
    std::vector<RandomFrame> frames(uniform(1, 4));
    for (RandomFrame& frame : frames) {
      std::vector<std::pair<std::uint16_t, cv::Rect>> boxes;
      std::vector<cv::Rect> gt_boxes;
      for (const InstanceInfo& info : table.instances()) {
        if (uniform(0, 2) == 0) continue;  // Absent in this frame.
        boxes.emplace_back(info.id, random_box());
        gt_boxes.push_back(boxes.back().second);
      }
      frame.gt = GroundTruth(boxes, size);
      for (int d = uniform(0, 6); d > 0; --d) {
        cv::Rect box = random_box();
        if (!gt_boxes.empty() && uniform(0, 2) > 0) {
          // Near a GT box, so that matches at many IoUs happen.
          const cv::Rect near = gt_boxes[uniform(0, static_cast<int>(gt_boxes.size()) - 1)];
          box = cv::Rect(near.x + uniform(-1, 1), near.y + uniform(-1, 1),
                         near.width + uniform(-1, 1), near.height + uniform(-1, 1)) &
                cv::Rect({0, 0}, size);
          if (box.empty()) box = near;
        }
        // Few distinct scores, so that ties are common.
        const float score = static_cast<float>(uniform(1, 4)) / 4.0f;
        const int category = categories[uniform(0, 1)];
        frame.prediction.instances.push_back(Detection(category, score, BoxMask(box, size)));
      }
    }

    SegmentationEvaluator evaluator;
    for (const RandomFrame& frame : frames) evaluator.AddFrame(frame.gt, table, frame.prediction);
    const SegmentationScores scores = evaluator.Scores();
    for (int category : categories) {
      const auto ap50 = scores.ap50_per_category.find(category);
      const auto ap75 = scores.ap75_per_category.find(category);
      if (ap50 == scores.ap50_per_category.end()) continue;  // Neither GT nor detections.
      if (std::isnan(ap50->second)) continue;                // No GT: no reference AP.
      EXPECT_NEAR(ap50->second, ReferenceAp(frames, table, category, /*iou_threshold=*/0.5),
                  kTolerance)
          << "seed " << seed << " category " << category;
      EXPECT_NEAR(ap75->second, ReferenceAp(frames, table, category, /*iou_threshold=*/0.75),
                  kTolerance)
          << "seed " << seed << " category " << category;
    }
  }
}

TEST(SegmentationMetrics, MiouMatchesIdImageReferenceOnRandomFrames) {
  // Reference: FrameSegmentation::ToIdImage (unique track ids here), then id -> category.
  constexpr int kSeeds = 100;
  const cv::Size size(16, 12);
  const InstanceTable table = Table({{1, kPerson}, {2, kCar}, {3, kChair}});
  for (int seed = 0; seed < kSeeds; ++seed) {
    std::mt19937 rng(seed);
    const auto uniform = [&](int low, int high) {
      return std::uniform_int_distribution<int>(low, high)(rng);
    };
    const auto random_box = [&]() {
      const int x = uniform(0, size.width - 2), y = uniform(0, size.height - 2);
      return cv::Rect(x, y, uniform(1, size.width - x), uniform(1, size.height - y));
    };
    SegmentationEvaluator evaluator;
    std::map<int, PixelCounts> reference;
    for (int f = uniform(1, 3); f > 0; --f) {
      const cv::Mat gt = GroundTruth({{1, random_box()}, {2, random_box()}, {3, random_box()}}, size);
      FrameSegmentation prediction;
      std::map<std::uint16_t, int> category_of_track;
      for (int d = uniform(0, 4); d > 0; --d) {
        const int category = std::vector<int>{kPerson, kCar, kChair}[uniform(0, 2)];
        prediction.instances.push_back(Detection(category, static_cast<float>(uniform(1, 3)) / 3.0f,
                                                 BoxMask(random_box(), size)));
        category_of_track[prediction.instances.back().track_id] = category;
      }
      evaluator.AddFrame(gt, table, prediction);
      const cv::Mat predicted_ids = prediction.ToIdImage(size);
      for (int row = 0; row < size.height; ++row) {
        for (int col = 0; col < size.width; ++col) {
          const std::uint16_t gt_id = gt.at<std::uint16_t>(row, col);
          const std::uint16_t track = predicted_ids.at<std::uint16_t>(row, col);
          const int truth = gt_id == 0 ? 0 : table.Find(gt_id)->category_id;
          const int guess = track == 0 ? 0 : category_of_track.at(track);
          if (truth != 0 && truth == guess) ++reference[truth].true_positive;
          if (truth != 0 && truth != guess) ++reference[truth].false_negative;
          if (guess != 0 && truth != guess) ++reference[guess].false_positive;
        }
      }
    }
    double sum = 0;
    int classes = 0;
    for (const auto& [category, counts] : reference) {
      sum += static_cast<double>(counts.true_positive) /
             (counts.true_positive + counts.false_positive + counts.false_negative);
      ++classes;
    }
    const SegmentationScores scores = evaluator.Scores();
    ASSERT_EQ(scores.iou_per_category.size(), static_cast<size_t>(classes)) << "seed " << seed;
    EXPECT_NEAR(scores.mIoU, sum / classes, kTolerance) << "seed " << seed;
  }
}

}  // namespace
}  // namespace segslam::seg
