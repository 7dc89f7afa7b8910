// Tests of seg/simulated_segmenter.h: clean equals ground truth, determinism whatever the
// frame order, each error mode on its own, scores that follow quality, option checks.
#include "seg/simulated_segmenter.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "core/tracks.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 160;
constexpr int kHeight = 120;

// Instances: 1 person (large), 2 car, 3 truck (as large as the car), 4 cup (small),
// 5 car touching the left border.
InstanceTable TestTable() {
  InstanceTable table;
  table.Add({1, 1, "", false});
  table.Add({2, 3, "", false});
  table.Add({3, 8, "", false});
  table.Add({4, 47, "", false});
  table.Add({5, 3, "", false});
  return table;
}

cv::Mat TestIds(int shift = 0) {
  cv::Mat ids(kHeight, kWidth, CV_16U, cv::Scalar(0));
  cv::ellipse(ids, cv::Point(40 + shift, 60), cv::Size(14, 30), 0, 0, 360, 1, cv::FILLED);
  cv::rectangle(ids, cv::Rect(70 + shift, 70, 30, 18), 2, cv::FILLED);
  cv::rectangle(ids, cv::Rect(105 + shift, 66, 30, 18), 3, cv::FILLED);
  cv::circle(ids, cv::Point(120, 20), 4, 4, cv::FILLED);
  cv::rectangle(ids, cv::Rect(0, 95, 18, 15), 5, cv::FILLED);
  return ids;
}

SimulatedSegmenterOptions Clean() { return SimulatedSegmenterOptions::Preset("clean"); }

cv::Mat GtMask(const cv::Mat& ids, std::uint16_t id) {
  cv::Mat m;
  cv::compare(ids, id, m, cv::CMP_EQ);
  return m / 255;
}

bool SameMask(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

double Iou(const cv::Mat& a, const cv::Mat& b) {
  const double inter = cv::countNonZero(a & b);
  const double uni = cv::countNonZero(a | b);
  return uni > 0 ? inter / uni : 0.0;
}

// Expects two simulated frames to be identical.
void ExpectSameFrame(const SimulatedFrame& a, const SimulatedFrame& b) {
  ASSERT_EQ(a.segmentation.instances.size(), b.segmentation.instances.size());
  EXPECT_EQ(a.gt_ids, b.gt_ids);
  for (size_t i = 0; i < a.segmentation.instances.size(); ++i) {
    const InstanceMask& x = a.segmentation.instances[i];
    const InstanceMask& y = b.segmentation.instances[i];
    EXPECT_EQ(x.track_id, y.track_id);
    EXPECT_EQ(x.category_id, y.category_id);
    EXPECT_EQ(x.score, y.score);
    EXPECT_TRUE(SameMask(x.mask, y.mask));
  }
}

SimulatedFrame Simulate(const SimulatedSegmenterOptions& options, int frame, std::uint64_t seed = 7,
                        const cv::Mat& ids = TestIds()) {
  return SimulateSegmentation(options, seed, frame, ids, TestTable(), {});
}

TEST(SimulatedSegmenterTest, CleanPresetEqualsGroundTruth) {
  const cv::Mat ids = TestIds();
  const SimulatedFrame out = Simulate(Clean(), 0);
  ASSERT_EQ(out.segmentation.instances.size(), 5u);
  std::vector<std::uint16_t> seen = out.gt_ids;
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<std::uint16_t>{1, 2, 3, 4, 5}));
  const InstanceTable table = TestTable();
  for (size_t i = 0; i < out.gt_ids.size(); ++i) {
    const InstanceMask& m = out.segmentation.instances[i];
    EXPECT_TRUE(SameMask(m.mask, GtMask(ids, out.gt_ids[i]))) << "instance " << out.gt_ids[i];
    EXPECT_EQ(m.category_id, table.Find(out.gt_ids[i])->category_id);
    EXPECT_EQ(m.score, 1.0f);
    EXPECT_GE(m.track_id, 1);
  }
  // The id image of the output is the ground truth up to renumbering.
  const cv::Mat out_ids = out.segmentation.ToIdImage(ids.size());
  EXPECT_EQ(cv::countNonZero(out_ids), cv::countNonZero(ids));
}

TEST(SimulatedSegmenterTest, StrengthZeroEqualsClean) {
  for (const std::string& name : SimulatedSegmenterOptions::PresetNames()) {
    SimulatedSegmenterOptions options = SimulatedSegmenterOptions::Preset(name);
    options.strength = 0;
    for (int frame = 0; frame < 5; ++frame) {
      SimulatedFrame a = Simulate(options, frame);
      SimulatedFrame b = Simulate(Clean(), frame);
      ExpectSameFrame(a, b);
    }
  }
}

TEST(SimulatedSegmenterTest, DeterministicInSeedAndFrame) {
  const SimulatedSegmenterOptions options;  // fcis-like
  ExpectSameFrame(Simulate(options, 3, 11), Simulate(options, 3, 11));
  // Another seed or frame gives another result (some mask or score differs).
  auto differs = [](const SimulatedFrame& a, const SimulatedFrame& b) {
    if (a.segmentation.instances.size() != b.segmentation.instances.size()) return true;
    for (size_t i = 0; i < a.segmentation.instances.size(); ++i) {
      if (a.segmentation.instances[i].score != b.segmentation.instances[i].score) return true;
    }
    return false;
  };
  EXPECT_TRUE(differs(Simulate(options, 3, 11), Simulate(options, 3, 12)));
  EXPECT_TRUE(differs(Simulate(options, 3, 11), Simulate(options, 4, 11)));
}

TEST(SimulatedSegmenterTest, MissAlwaysRemovesEverything) {
  SimulatedSegmenterOptions options = Clean();
  options.miss_prob = 1;
  EXPECT_TRUE(Simulate(options, 0).segmentation.instances.empty());
}

TEST(SimulatedSegmenterTest, SmallInstancesAreMissedMoreOften) {
  SimulatedSegmenterOptions options = Clean();
  options.miss_small_prob = 0.8;
  options.small_area_fraction = 0.05;  // 960 px: the cup (~50 px) is small, the person not
  int cup = 0, person = 0;
  for (int frame = 0; frame < 200; ++frame) {
    const SimulatedFrame out = Simulate(options, frame);
    cup += std::count(out.gt_ids.begin(), out.gt_ids.end(), 4);
    person += std::count(out.gt_ids.begin(), out.gt_ids.end(), 1);
  }
  EXPECT_EQ(person, 200);
  EXPECT_LT(cup, 100);
}

TEST(SimulatedSegmenterTest, TruncatedOccludedAndMovingInstancesAreMissedMoreOften) {
  SimulatedSegmenterOptions truncated = Clean();
  truncated.miss_truncated_prob = 0.9;
  SimulatedSegmenterOptions occluded = Clean();
  occluded.miss_occluded_prob = 0.9;
  SimulatedSegmenterOptions moving = Clean();
  moving.miss_moving_prob = 0.9;
  const std::map<std::uint16_t, SimulatedInstanceContext> context = {
      {2, {0.1, false}}, {3, {1.0, true}}};
  int border_car = 0, inner_car = 0, occluded_car = 0, moving_truck = 0;
  for (int frame = 0; frame < 100; ++frame) {
    const auto a = SimulateSegmentation(truncated, 1, frame, TestIds(), TestTable(), {}).gt_ids;
    border_car += std::count(a.begin(), a.end(), 5);
    inner_car += std::count(a.begin(), a.end(), 2);
    const auto b = SimulateSegmentation(occluded, 1, frame, TestIds(), TestTable(), context).gt_ids;
    occluded_car += std::count(b.begin(), b.end(), 2);
    EXPECT_EQ(std::count(b.begin(), b.end(), 3), 1);
    const auto c = SimulateSegmentation(moving, 1, frame, TestIds(), TestTable(), context).gt_ids;
    moving_truck += std::count(c.begin(), c.end(), 3);
    EXPECT_EQ(std::count(c.begin(), c.end(), 2), 1);
  }
  EXPECT_EQ(inner_car, 100);
  EXPECT_LT(border_car, 50);
  EXPECT_LT(occluded_car, 50);
  EXPECT_LT(moving_truck, 50);
}

TEST(SimulatedSegmenterTest, MovingInstancesAreMissedInProportionToTheirOwnImageSpeed) {
  SimulatedSegmenterOptions options = Clean();
  options.miss_moving_prob = 1;
  options.moving_full_miss_speed_px_s = 200;
  auto found_of_100 = [&](double speed_px_s) {
    SimulatedInstanceContext moving_truck;
    moving_truck.moving = true;
    moving_truck.own_image_speed_px_s = speed_px_s;
    int found = 0;
    for (int frame = 0; frame < 100; ++frame) {
      const auto ids =
          SimulateSegmentation(options, 1, frame, TestIds(), TestTable(), {{3, moving_truck}}).gt_ids;
      found += std::count(ids.begin(), ids.end(), 3);
    }
    return found;
  };
  EXPECT_EQ(found_of_100(0), 100);     // limbs moving, the root still: no blur
  EXPECT_EQ(found_of_100(400), 0);     // beyond the full-rate speed
  EXPECT_EQ(found_of_100(-1), 0);      // speed unknown: the full rate
  const int half = found_of_100(100);  // p = 0.5
  EXPECT_GT(half, 30);
  EXPECT_LT(half, 70);
}

TEST(SimulatedSegmenterTest, OwnImageSpeedLeavesTheCameraMotionOut) {
  PinholeCamera camera;
  camera.fx = 500;
  camera.fy = 400;
  camera.cx = 320;
  camera.cy = 240;
  camera.width = 640;
  camera.height = 480;
  TrackSample now, next;
  now.stamp_s = 2.0;
  next.stamp_s = 2.2;
  // Camera at (1, 2, 3) looking along world +z; the object 5 m ahead moves 0.2 m down the
  // camera's y axis in 0.2 s: fy * 0.2 / 5 = 16 px in 0.2 s.
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  T_wc.translation() = Eigen::Vector3d(1, 2, 3);
  now.T_world_object.translation() = Eigen::Vector3d(1, 2, 8);
  next.T_world_object.translation() = Eigen::Vector3d(1, 2.2, 8);
  EXPECT_NEAR(OwnImageSpeedPxPerS(T_wc, camera, now, next), 80.0, 1e-9);
  // The same step seen by a camera turned 90 degrees about its y axis (looking along
  // world +x): the object must be in front, so put it 4 m along +x; its motion is then
  // along the image's y axis again: fy * 0.2 / 4 / 0.2 s = 100 px/s.
  T_wc.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  now.T_world_object.translation() = Eigen::Vector3d(5, 2, 3);
  next.T_world_object.translation() = Eigen::Vector3d(5, 2.2, 3);
  EXPECT_NEAR(OwnImageSpeedPxPerS(T_wc, camera, now, next), 100.0, 1e-9);
  // Moving straight along the ray through the principal point: no image motion.
  next.T_world_object.translation() = Eigen::Vector3d(6, 2, 3);
  EXPECT_NEAR(OwnImageSpeedPxPerS(T_wc, camera, now, next), 0.0, 1e-9);
  // Behind the camera, or no time step: unknown.
  next.T_world_object.translation() = Eigen::Vector3d(-5, 2, 3);
  EXPECT_LT(OwnImageSpeedPxPerS(T_wc, camera, now, next), 0);
  next = now;
  EXPECT_LT(OwnImageSpeedPxPerS(T_wc, camera, now, next), 0);
}

TEST(SimulatedSegmenterTest, MissingPartsOnlyRemovePixels) {
  const cv::Mat ids = TestIds();
  for (const char* mode : {"holes", "cut"}) {
    SimulatedSegmenterOptions options = Clean();
    if (std::string(mode) == "holes") options.hole_prob = 1;
    if (std::string(mode) == "cut") options.cut_prob = 1;
    int removed = 0;
    for (int frame = 0; frame < 10; ++frame) {
      const SimulatedFrame out = Simulate(options, frame);
      for (size_t i = 0; i < out.gt_ids.size(); ++i) {
        const cv::Mat gt = GtMask(ids, out.gt_ids[i]);
        const cv::Mat& m = out.segmentation.instances[i].mask;
        EXPECT_EQ(cv::countNonZero(m & ~gt & 1), 0) << mode << ": pixels added";
        removed += cv::countNonZero(gt) - cv::countNonZero(m);
      }
    }
    EXPECT_GT(removed, 100) << mode;
  }
}

TEST(SimulatedSegmenterTest, BleedingAddsPixelsOutsideTheInstance) {
  const cv::Mat ids = TestIds();
  SimulatedSegmenterOptions options = Clean();
  options.bleed_prob = 1;
  options.bleed_fraction_max = 0.3;
  int added = 0, into_neighbour = 0;
  for (int frame = 0; frame < 10; ++frame) {
    const SimulatedFrame out = Simulate(options, frame);
    ASSERT_EQ(out.gt_ids.size(), 5u);
    for (size_t i = 0; i < out.gt_ids.size(); ++i) {
      const cv::Mat gt = GtMask(ids, out.gt_ids[i]);
      const cv::Mat& m = out.segmentation.instances[i].mask;
      EXPECT_EQ(cv::countNonZero(gt & ~m & 1), 0) << "bleeding removed pixels";
      added += cv::countNonZero(m) - cv::countNonZero(gt);
      cv::Mat others;
      cv::compare(ids, 0, others, cv::CMP_NE);
      into_neighbour += cv::countNonZero(m & (others / 255) & ~gt & 1);
    }
  }
  EXPECT_GT(added, 500);
  EXPECT_GT(into_neighbour, 0);  // car 2 and truck 3 are 5 px apart
}

TEST(SimulatedSegmenterTest, NeighbourBleedSpreadsOnlyIntoTouchingInstances) {
  // A car (2) with a cup (4) resting against its top edge, a person (1) alone.
  cv::Mat ids(kHeight, kWidth, CV_16U, cv::Scalar(0));
  cv::rectangle(ids, cv::Rect(70, 60, 60, 30), 2, cv::FILLED);
  cv::rectangle(ids, cv::Rect(90, 50, 10, 10), 4, cv::FILLED);
  cv::ellipse(ids, cv::Point(30, 60), cv::Size(12, 30), 0, 0, 360, 1, cv::FILLED);
  SimulatedSegmenterOptions options = Clean();
  options.neighbour_bleed_prob = 1;
  options.neighbour_bleed_fraction_max = 0.5;
  const SimulatedFrame out = SimulateSegmentation(options, 3, 0, ids, TestTable(), {});
  ASSERT_EQ(out.gt_ids.size(), 3u);
  for (size_t i = 0; i < out.gt_ids.size(); ++i) {
    const cv::Mat gt = GtMask(ids, out.gt_ids[i]);
    const cv::Mat& m = out.segmentation.instances[i].mask;
    SCOPED_TRACE("instance " + std::to_string(out.gt_ids[i]));
    EXPECT_EQ(cv::countNonZero(gt & ~m & 1), 0) << "spreading removed pixels";
    cv::Mat background;
    cv::compare(ids, 0, background, cv::CMP_EQ);
    EXPECT_EQ(cv::countNonZero(m & (background / 255)), 0) << "spread onto the background";
    const int added = cv::countNonZero(m) - cv::countNonZero(gt);
    if (out.gt_ids[i] == 1) {
      EXPECT_EQ(added, 0);  // touches nothing
    } else if (out.gt_ids[i] == 2) {
      // The car (sqrt(area) ~42 px) reaches 7 to 21 px into the cup, which is 10 px tall.
      EXPECT_GE(added, 70);
    } else {
      EXPECT_GT(added, 0);  // the cup, into the car below it
    }
  }
}

TEST(SimulatedSegmenterTest, CoarseMaskHeadLosesThinPartsOfLargeInstancesOnly) {
  // A large person with a 1-px thin arm, and a small cup with a 1-px notch.
  cv::Mat ids(kHeight, kWidth, CV_16U, cv::Scalar(0));
  cv::rectangle(ids, cv::Rect(20, 20, 60, 80), 1, cv::FILLED);
  cv::rectangle(ids, cv::Rect(80, 50, 40, 1), 1, cv::FILLED);
  cv::rectangle(ids, cv::Rect(130, 20, 12, 12), 4, cv::FILLED);
  ids.at<std::uint16_t>(20, 136) = 0;
  SimulatedSegmenterOptions options = Clean();
  options.mask_resolution = 21;
  const SimulatedFrame out = SimulateSegmentation(options, 1, 0, ids, TestTable(), {});
  ASSERT_EQ(out.gt_ids.size(), 2u);
  for (size_t i = 0; i < out.gt_ids.size(); ++i) {
    const cv::Mat gt = GtMask(ids, out.gt_ids[i]);
    const cv::Mat& m = out.segmentation.instances[i].mask;
    if (out.gt_ids[i] == 4) {
      EXPECT_TRUE(SameMask(m, gt)) << "a 12-px instance is finer than the 21-cell grid";
    } else {
      // A grid cell is 100/21 ~ 4.8 px wide and 80/21 ~ 3.8 px tall: the arm is lost,
      // the body's edges are kept to within a cell.
      EXPECT_EQ(cv::countNonZero(m(cv::Rect(85, 48, 35, 6))), 0) << "the arm survived";
      EXPECT_GT(Iou(m, gt), 0.9);
    }
  }
  options.mask_resolution = 0;
  const SimulatedFrame off = SimulateSegmentation(options, 1, 0, ids, TestTable(), {});
  for (size_t i = 0; i < off.gt_ids.size(); ++i) {
    EXPECT_TRUE(SameMask(off.segmentation.instances[i].mask, GtMask(ids, off.gt_ids[i])));
  }
}

TEST(SimulatedSegmenterTest, HardCategoriesAreSegmentedWorse) {
  // Twelve equal squares: six chairs (a hard category), six cups.
  InstanceTable table;
  cv::Mat ids(kHeight, kWidth, CV_16U, cv::Scalar(0));
  for (int k = 0; k < 12; ++k) {
    const std::uint16_t id = static_cast<std::uint16_t>(k + 1);
    table.Add({id, k < 6 ? 62 : 47, "", false});
    cv::rectangle(ids, cv::Rect(5 + (k % 6) * 26, 10 + (k / 6) * 55, 20, 20), id, cv::FILLED);
  }
  SimulatedSegmenterOptions options;  // fcis-like shape errors, no misses or false positives
  options.miss_prob = options.miss_small_prob = options.miss_truncated_prob = 0;
  options.miss_occluded_prob = options.miss_moving_prob = 0;
  options.false_positives_per_frame = 0;
  options.confusion_prob = 0;
  auto mean_iou = [&](std::uint16_t first_id) {
    double sum = 0;
    int n = 0;
    for (int frame = 0; frame < 40; ++frame) {
      const SimulatedFrame out = SimulateSegmentation(options, 5, frame, ids, table, {});
      for (size_t i = 0; i < out.gt_ids.size(); ++i) {
        if (out.gt_ids[i] < first_id || out.gt_ids[i] >= first_id + 6) continue;
        sum += Iou(out.segmentation.instances[i].mask, GtMask(ids, out.gt_ids[i]));
        ++n;
      }
    }
    return n > 0 ? sum / n : 0.0;
  };
  options.hard_category_difficulty = 0;
  const double chairs_plain = mean_iou(1), cups_plain = mean_iou(7);
  options.hard_category_difficulty = 1.5;
  const double chairs_hard = mean_iou(1), cups_hard = mean_iou(7);
  EXPECT_EQ(cups_hard, cups_plain);  // cups are not a hard category
  EXPECT_LT(chairs_hard, chairs_plain - 0.03);
}

TEST(SimulatedSegmenterTest, JitterMovesTheBoundaryBothWays) {
  const cv::Mat ids = TestIds();
  SimulatedSegmenterOptions options = Clean();
  options.boundary_jitter_fraction = 0.1;
  options.boundary_jitter_px = 10;
  const SimulatedFrame out = Simulate(options, 0);
  int added = 0, removed = 0;
  for (size_t i = 0; i < out.gt_ids.size(); ++i) {
    const cv::Mat gt = GtMask(ids, out.gt_ids[i]);
    const cv::Mat& m = out.segmentation.instances[i].mask;
    added += cv::countNonZero(m & ~gt & 1);
    removed += cv::countNonZero(gt & ~m & 1);
    if (out.gt_ids[i] != 4) {
      EXPECT_GT(Iou(m, gt), 0.6) << "instance " << out.gt_ids[i];
    }
  }
  EXPECT_GT(added, 0);
  EXPECT_GT(removed, 0);
}

TEST(SimulatedSegmenterTest, ConfusionPicksALookAlikeInView) {
  SimulatedSegmenterOptions options = Clean();
  options.confusion_prob = 1;
  options.confusion_score_factor = 0.75;
  const SimulatedFrame out = Simulate(options, 0);
  for (size_t i = 0; i < out.gt_ids.size(); ++i) {
    const int category = out.segmentation.instances[i].category_id;
    switch (out.gt_ids[i]) {
      case 1: EXPECT_EQ(category, 1); break;   // person has no look-alike
      case 4: EXPECT_EQ(category, 47); break;  // no bottle or bowl in view
      case 3: EXPECT_EQ(category, 3); break;   // truck -> car
      default: break;  // cars (more car pixels than truck pixels) seldom become trucks
    }
  }
  // Confused detections score lower than the clean 1.
  for (size_t i = 0; i < out.gt_ids.size(); ++i) {
    if (out.gt_ids[i] == 3) {
      EXPECT_LT(out.segmentation.instances[i].score, 1.0f);
    }
  }
}

TEST(SimulatedSegmenterTest, FalsePositivesDoNotOverlapGroundTruthAndScoreLow) {
  const cv::Mat ids = TestIds();
  SimulatedSegmenterOptions options = Clean();
  options.false_positives_per_frame = 3;
  int false_positives = 0;
  cv::Mat foreground;
  cv::compare(ids, 0, foreground, cv::CMP_NE);
  for (int frame = 0; frame < 20; ++frame) {
    const SimulatedFrame out = Simulate(options, frame);
    for (size_t i = 0; i < out.gt_ids.size(); ++i) {
      if (out.gt_ids[i] != 0) continue;
      ++false_positives;
      const InstanceMask& m = out.segmentation.instances[i];
      EXPECT_EQ(cv::countNonZero(m.mask & foreground), 0);
      EXPECT_LE(m.score, options.false_positive_score_max);
      EXPECT_NE(TestTable().Find(1), nullptr);
    }
  }
  EXPECT_GT(false_positives, 20);
}

// The refinement reads a mask only inside its bounds, so a pixel outside them would be
// lost: every output, bled, jittered or a false positive, must lie inside its bounds.
TEST(SimulatedSegmenterTest, EveryMaskLiesInsideItsBounds) {
  SimulatedSegmenterOptions options = SimulatedSegmenterOptions::Preset("fcis-like");
  options.false_positives_per_frame = 2;
  options.strength = 2.0;
  int instances = 0;
  for (int frame = 0; frame < 20; ++frame) {
    for (const InstanceMask& instance : Simulate(options, frame).segmentation.instances) {
      ++instances;
      EXPECT_FALSE(instance.bounds.empty());
      EXPECT_TRUE(BoundsHoldMask(instance)) << "frame " << frame << " instance " << instance.track_id;
    }
  }
  EXPECT_GT(instances, 60);
}

TEST(SimulatedSegmenterTest, TrackIdsAreAPermutationNotGroundTruth) {
  const SimulatedFrame out = Simulate(SimulatedSegmenterOptions(), 2);
  std::vector<int> track_ids;
  for (const auto& m : out.segmentation.instances) track_ids.push_back(m.track_id);
  std::sort(track_ids.begin(), track_ids.end());
  std::vector<int> expected(track_ids.size());
  std::iota(expected.begin(), expected.end(), 1);
  EXPECT_EQ(track_ids, expected);
}

// Spearman's rank correlation (no tie correction; scores are continuous).
double Spearman(const std::vector<double>& x, const std::vector<double>& y) {
  auto ranks = [](const std::vector<double>& v) {
    std::vector<size_t> order(v.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
    std::vector<double> r(v.size());
    for (size_t i = 0; i < order.size(); ++i) r[order[i]] = static_cast<double>(i);
    return r;
  };
  const std::vector<double> rx = ranks(x), ry = ranks(y);
  const double n = static_cast<double>(x.size());
  double d2 = 0;
  for (size_t i = 0; i < rx.size(); ++i) d2 += (rx[i] - ry[i]) * (rx[i] - ry[i]);
  return 1.0 - 6.0 * d2 / (n * (n * n - 1.0));
}

TEST(SimulatedSegmenterTest, ScoresCorrelateWithIou) {
  const cv::Mat ids = TestIds();
  SimulatedSegmenterOptions options;  // fcis-like, without class confusions
  options.confusion_prob = 0;
  std::vector<double> scores, ious;
  for (int frame = 0; frame < 80; ++frame) {
    const SimulatedFrame out = Simulate(options, frame);
    for (size_t i = 0; i < out.gt_ids.size(); ++i) {
      const InstanceMask& m = out.segmentation.instances[i];
      scores.push_back(m.score);
      ious.push_back(out.gt_ids[i] == 0 ? 0.0 : Iou(m.mask, GtMask(ids, out.gt_ids[i])));
    }
  }
  ASSERT_GT(scores.size(), 100u);
  const double rho = Spearman(scores, ious);
  EXPECT_GT(rho, 0.5);
}

TEST(SimulatedSegmenterTest, StrengthMakesThingsWorse) {
  const cv::Mat ids = TestIds();
  auto mean_iou = [&](double strength) {
    SimulatedSegmenterOptions options;
    options.strength = strength;
    options.false_positives_per_frame = 0;
    double sum = 0;
    int n = 0;
    for (int frame = 0; frame < 40; ++frame) {
      const SimulatedFrame out = Simulate(options, frame);
      for (std::uint16_t id : {1, 2, 3, 4, 5}) {
        double best = 0;
        for (size_t i = 0; i < out.gt_ids.size(); ++i) {
          if (out.gt_ids[i] == id) best = Iou(out.segmentation.instances[i].mask, GtMask(ids, id));
        }
        sum += best;
        ++n;
      }
    }
    return sum / n;
  };
  const double clean = mean_iou(0), preset = mean_iou(1), poor = mean_iou(2.5);
  EXPECT_EQ(clean, 1.0);
  EXPECT_LT(preset, clean);
  EXPECT_LT(poor, preset);
}

TEST(SimulatedSegmenterTest, OptionsAreChecked) {
  for (const std::string& name : SimulatedSegmenterOptions::PresetNames()) {
    std::string error;
    EXPECT_TRUE(SimulatedSegmenterOptions::Preset(name).IsValid(&error)) << name << ": " << error;
  }
  SimulatedSegmenterOptions options;
  options.hole_prob = 1.5;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("hole_prob"), std::string::npos) << error;
  options = SimulatedSegmenterOptions();
  options.strength = -1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("strength"), std::string::npos) << error;
  EXPECT_THROW(Simulate(options, 0), Error);
  // The newer fields are range-checked too, each named in its message.
  auto expect_refused = [](const std::string& assignment) {
    SimulatedSegmenterOptions refused;
    refused.Set(assignment);
    std::string message;
    EXPECT_FALSE(refused.IsValid(&message)) << assignment;
    const std::string field = assignment.substr(0, assignment.find('='));
    EXPECT_NE(message.find(field), std::string::npos) << message;
  };
  expect_refused("mask_resolution=-1");
  expect_refused("neighbour_bleed_prob=2");
  expect_refused("moving_full_miss_speed_px_s=0");
  expect_refused("hard_category_difficulty=-0.5");
  try {
    SimulatedSegmenterOptions::Preset("fcis");
    ADD_FAILURE() << "expected an exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("fcis-like"), std::string::npos) << e.what();
  }
}

TEST(SimulatedSegmenterTest, RejectsBadGroundTruth) {
  cv::Mat eight_bit(kHeight, kWidth, CV_8U, cv::Scalar(0));
  EXPECT_THROW(SimulateSegmentation(Clean(), 1, 0, eight_bit, TestTable(), {}), Error);
  cv::Mat unknown = TestIds();
  unknown.at<std::uint16_t>(5, 5) = 99;
  EXPECT_THROW(SimulateSegmentation(Clean(), 1, 0, unknown, TestTable(), {}), Error);
}

// ---- The segmenter over a sequence on disk ----

class SimulatedSegmenterSequenceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("segslam_seg_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    SequenceCamera camera;
    camera.intrinsics = PinholeCamera::FromVerticalFov(kWidth, kHeight, 60);
    camera.depth_factor = 5000;
    TumSequenceWriter writer(dir_, camera);
    fs::create_directories(dir_ / "masks");
    std::vector<ObjectTrack> tracks;
    for (int i = 0; i < kFrames; ++i) {
      RgbdFrame frame;
      frame.index = i;
      frame.stamp_s = 1.0 + 0.1 * i;
      frame.color_bgr = cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(50, 60, 70));
      frame.depth_m = cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(2.0f));
      writer.Add(frame, Eigen::Isometry3d::Identity());
      WriteInstanceMask(dir_ / "masks" / (TumSequenceWriter::StampName(frame.stamp_s) + ".png"),
                        TestIds(i));
    }
    writer.Finish();
    TestTable().Write(dir_ / "instances.json");
  }
  void TearDown() override { fs::remove_all(dir_); }

  static constexpr int kFrames = 4;
  fs::path dir_;
};

TEST_F(SimulatedSegmenterSequenceTest, SameResultWhateverTheFrameOrder) {
  SimulatedSegmenter forward(dir_, SimulatedSegmenterOptions(), 5);
  SimulatedSegmenter backward(dir_, SimulatedSegmenterOptions(), 5);
  const TumSequence sequence = TumSequence::Open(dir_);
  std::vector<SimulatedFrame> a(kFrames), b(kFrames);
  for (int i = 0; i < kFrames; ++i) a[i] = forward.SegmentWithTruth(sequence.LoadFrame(i));
  for (int i = kFrames - 1; i >= 0; --i) b[i] = backward.SegmentWithTruth(sequence.LoadFrame(i));
  for (int i = 0; i < kFrames; ++i) ExpectSameFrame(a[i], b[i]);
  // Segment() returns the same segmentation.
  const FrameSegmentation again = forward.Segment(sequence.LoadFrame(1));
  ASSERT_EQ(again.instances.size(), a[1].segmentation.instances.size());
  EXPECT_EQ(forward.name(), "simulated:fcis-like");
}

TEST_F(SimulatedSegmenterSequenceTest, CleanEqualsTheMaskFiles) {
  SimulatedSegmenter clean(dir_, Clean(), 5, "clean");
  const TumSequence sequence = TumSequence::Open(dir_);
  for (int i = 0; i < kFrames; ++i) {
    const SimulatedFrame out = clean.SegmentWithTruth(sequence.LoadFrame(i));
    const cv::Mat ids = ReadInstanceMask(clean.MaskPath(i));
    ASSERT_EQ(out.gt_ids.size(), 5u);
    for (size_t k = 0; k < out.gt_ids.size(); ++k) {
      EXPECT_TRUE(SameMask(out.segmentation.instances[k].mask, GtMask(ids, out.gt_ids[k])));
    }
  }
}

TEST_F(SimulatedSegmenterSequenceTest, TracksMakeOccludedInstancesHarder) {
  // Instance 2 visible 1000 px in frame 0 and 100 px later: occluded from frame 1.
  std::vector<ObjectTrack> tracks(1);
  tracks[0].instance_id = 2;
  for (int i = 0; i < kFrames; ++i) {
    TrackSample s;
    s.frame = i;
    s.stamp_s = 1.0 + 0.1 * i;
    s.visible_pixels = i == 0 ? 1000 : 100;
    tracks[0].samples.push_back(s);
  }
  WriteTracks(dir_ / "tracks.json", tracks);
  SimulatedSegmenterOptions options = Clean();
  options.miss_occluded_prob = 1;
  SimulatedSegmenter segmenter(dir_, options, 5);
  const TumSequence sequence = TumSequence::Open(dir_);
  auto has = [](const SimulatedFrame& f, std::uint16_t id) {
    return std::count(f.gt_ids.begin(), f.gt_ids.end(), id) > 0;
  };
  EXPECT_TRUE(has(segmenter.SegmentWithTruth(sequence.LoadFrame(0)), 2));
  EXPECT_FALSE(has(segmenter.SegmentWithTruth(sequence.LoadFrame(1)), 2));
  EXPECT_TRUE(has(segmenter.SegmentWithTruth(sequence.LoadFrame(1)), 3));
}

TEST_F(SimulatedSegmenterSequenceTest, OnlyFastMovingInstancesAreBlurredAway) {
  // Both flagged moving in every frame; 2 keeps its root still (a sitting person moving
  // an arm), 3 crosses the view 2 m in front of the camera (at identity) at 1 m/s.
  std::vector<ObjectTrack> tracks(2);
  tracks[0].instance_id = 2;
  tracks[1].instance_id = 3;
  for (int i = 0; i < kFrames; ++i) {
    TrackSample s;
    s.frame = i;
    s.stamp_s = 1.0 + 0.1 * i;
    s.moving = true;
    s.visible_pixels = 500;
    s.T_world_object.translation() = Eigen::Vector3d(0, 0, 2);
    tracks[0].samples.push_back(s);
    s.T_world_object.translation() = Eigen::Vector3d(0.1 * i, 0, 2);
    tracks[1].samples.push_back(s);
  }
  WriteTracks(dir_ / "tracks.json", tracks);
  SimulatedSegmenterOptions options = Clean();
  options.miss_moving_prob = 1;
  // fx * 1 m/s / 2 m = fx / 2 px/s: well over this.
  options.moving_full_miss_speed_px_s = 10;
  SimulatedSegmenter segmenter(dir_, options, 5);
  const TumSequence sequence = TumSequence::Open(dir_);
  ASSERT_GT(sequence.camera().intrinsics.fx / 2, 10.0);
  for (int i = 0; i < kFrames; ++i) {
    const SimulatedFrame f = segmenter.SegmentWithTruth(sequence.LoadFrame(i));
    EXPECT_EQ(std::count(f.gt_ids.begin(), f.gt_ids.end(), 2), 1) << "frame " << i;
    EXPECT_EQ(std::count(f.gt_ids.begin(), f.gt_ids.end(), 3), 0) << "frame " << i;
  }
}

// With a distorted camera the ground truth is degraded as stored, as a network segments
// the stored image, and the masks come back undistorted. Undistorted first, car 5 would
// no longer touch the image border (the lens saw less than the pinhole frame shows
// there), and its truncation would go unnoticed.
TEST_F(SimulatedSegmenterSequenceTest, DistortedSequenceIsSegmentedAsStored) {
  SequenceCamera camera = ReadCameraYaml(dir_ / "camera.yaml");
  camera.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};  // TUM freiburg1
  WriteCameraYaml(dir_ / "camera.yaml", camera);
  const TumSequence sequence = TumSequence::Open(dir_);
  const ImageUndistorter lens(camera.intrinsics, camera.distortion);
  ASSERT_EQ(cv::countNonZero(sequence.LoadInstanceMask(dir_ / "masks" / (TumSequenceWriter::StampName(1.0) + ".png")).col(0) == 5), 0)
      << "the undistorted car must have left the border for this test to mean something";

  SimulatedSegmenterOptions truncated = Clean();
  truncated.miss_truncated_prob = 0.9;
  int border_car = 0, inner_car = 0;
  for (std::uint64_t seed = 1; seed <= 25; ++seed) {
    SimulatedSegmenter segmenter(dir_, truncated, seed);
    for (int i = 0; i < kFrames; ++i) {
      const SimulatedFrame f = segmenter.SegmentWithTruth(sequence.LoadFrame(i));
      border_car += std::count(f.gt_ids.begin(), f.gt_ids.end(), 5);
      // The resampled masks are bounded anew.
      for (const InstanceMask& instance : f.segmentation.instances) EXPECT_TRUE(BoundsHoldMask(instance));
      for (size_t k = 0; k < f.gt_ids.size(); ++k) {
        if (f.gt_ids[k] != 2) continue;
        ++inner_car;
        EXPECT_TRUE(SameMask(f.segmentation.instances[k].mask, lens.UndistortIds(GtMask(TestIds(i), 2))));
      }
    }
  }
  EXPECT_EQ(inner_car, 100);
  EXPECT_LT(border_car, 50);
}

TEST_F(SimulatedSegmenterSequenceTest, BadMasksGiveClearErrors) {
  SimulatedSegmenter segmenter(dir_, Clean(), 5);
  const TumSequence sequence = TumSequence::Open(dir_);
  auto message = [&](int i) {
    try {
      segmenter.Segment(sequence.LoadFrame(i));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // Wrong size.
  WriteInstanceMask(segmenter.MaskPath(0), cv::Mat(10, 10, CV_16U, cv::Scalar(0)));
  EXPECT_NE(message(0).find("10x10"), std::string::npos) << message(0);
  // Missing.
  fs::remove(segmenter.MaskPath(1));
  EXPECT_NE(message(1).find("missing"), std::string::npos) << message(1);
  // Unknown id.
  cv::Mat ids = TestIds();
  ids.at<std::uint16_t>(0, 0) = 42;
  WriteInstanceMask(segmenter.MaskPath(2), ids);
  EXPECT_NE(message(2).find("42"), std::string::npos) << message(2);
  // No masks folder.
  fs::remove_all(dir_ / "masks");
  EXPECT_THROW(SimulatedSegmenter(dir_, Clean(), 5), Error);
}

}  // namespace
}  // namespace segslam::seg

namespace segslam::seg {
namespace {

TEST(SimulatedSegmenterOptionsTest, SetByNameChangesOnlyThatField) {
  SimulatedSegmenterOptions options = SimulatedSegmenterOptions::Preset("fcis-like");
  options.Set("miss_truncated_prob=0.25");
  options.Set("hole_count_max=5");
  EXPECT_DOUBLE_EQ(options.miss_truncated_prob, 0.25);
  EXPECT_EQ(options.hole_count_max, 5);
  EXPECT_DOUBLE_EQ(options.miss_prob, SimulatedSegmenterOptions().miss_prob);
  for (const char* bad : {"miss_truncated=0.2", "miss_prob=often", "hole_count_max=2.5", "miss_prob"}) {
    EXPECT_THROW(options.Set(bad), Error) << bad;
  }
  const std::vector<std::string> names = SimulatedSegmenterOptions::FieldNames();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_NE(std::find(names.begin(), names.end(), "false_positive_area_max"), names.end());
}

}  // namespace
}  // namespace segslam::seg
