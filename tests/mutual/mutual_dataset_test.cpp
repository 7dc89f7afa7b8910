// The mutual loop on the generated 80-frame datasets (tests/sim/datasets.cmake, fixture
// sim_datasets), run as `segslam run --mode mutual --segmenter fcis-like` runs it: the
// refinement with SLAM's poses must repair the simulated FCIS-like masks about as well as
// seg-eval's refinement with the true poses does, and SLAM must track as well as with
// ground-truth masks. Every test prints its figures (ctest -V shows them).
#include "harness/slam_runner.h"
#include "harness/trajectory_metrics.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>

#include <unistd.h>

#include "core/image_io.h"
#include "core/json_file.h"
#include "core/tum_dataset.h"
#include "mutual/frame_pipeline.h"
#include "core/error.h"
#include "core/instances.h"
#include "seg/external_masks.h"
#include "seg/ground_truth.h"
#include "seg/simulated_segmenter.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = SEGSLAM_TEST_DATA_DIR;

struct LoopRun {
  SlamRunResult run;
  AteResult ate;
};

LoopRun RunLoop(const fs::path& sequence_dir, const std::string& segmenter, const fs::path& refined_masks_dir = {},
                int max_frames = 0) {
  const TumSequence sequence = TumSequence::Open(sequence_dir);
  SlamRunOptions options;
  options.run = MakeRunConfig("run", "mutual", "gt", segmenter, 1, 1.0);
  options.refined_masks_dir = refined_masks_dir;
  options.max_frames = max_frames;
  LoopRun loop;
  loop.run = RunSlamOnSequence(sequence, options);
  loop.ate = ComputeAte(sequence.groundtruth(), loop.run.trajectory);
  if (loop.run.segmentation.has_value()) {
    const LoopSegmentationScores& s = *loop.run.segmentation;
    std::printf("%-24s %s: raw mAP %.1f AP50 %.1f mIoU %.1f | refined mAP %.1f AP50 %.1f mIoU %.1f | "
                "ATE rmse %.4f m, localized %.1f%%\n",
                (sequence_dir.parent_path().filename() / sequence_dir.filename()).c_str(), s.segmenter.c_str(),
                100 * s.raw.mAP, 100 * s.raw.AP50, 100 * s.raw.mIoU, 100 * s.refined.mAP, 100 * s.refined.AP50,
                100 * s.refined.mIoU, loop.ate.translation_m.rmse,
                100 * loop.run.LocalizedShare());
  }
  return loop;
}

void RequireDataset(const fs::path& dir) {
  ASSERT_TRUE(fs::is_directory(dir)) << dir << " missing: ctest's sim_datasets fixture makes it";
}

// The acceptance: refined beats raw by at least 2 points of mIoU and of mAP with
// SLAM's poses (seg-eval with the true poses: office pass1 +8.5 mIoU / +5.0 mAP).
void ExpectRefinementHelps(const LoopRun& loop) {
  ASSERT_TRUE(loop.run.segmentation.has_value());
  const LoopSegmentationScores& s = *loop.run.segmentation;
  EXPECT_EQ(s.refined_from_previous, static_cast<int>(loop.run.frames.size()) - 1);
  EXPECT_GE(s.refined.mIoU - s.raw.mIoU, 0.02);
  EXPECT_GE(s.refined.mAP - s.raw.mAP, 0.02);
}

TEST(MutualLoopDatasetTest, OfficeRefinementBeatsRawMasksAndTrackingStaysWithinOneCentimetre) {
  const fs::path dir = kDataDir / "office_seg" / "pass1";
  RequireDataset(dir);
  const LoopRun loop = RunLoop(dir, "fcis-like");
  ExpectRefinementHelps(loop);
  EXPECT_EQ(loop.run.LocalizedShare(), 1.0);
  EXPECT_LT(loop.ate.translation_m.rmse, 0.01);
}

TEST(MutualLoopDatasetTest, CityRefinementBeatsRawMasks) {
  const fs::path dir = kDataDir / "city_seg" / "pass1";
  RequireDataset(dir);
  ExpectRefinementHelps(RunLoop(dir, "fcis-like"));
}

// The refined masks are written in the external-mask layout: a later run reads them back
// with --masks, as any external segmenter's. What is read back is, pixel for pixel and
// with its categories, what the loop refined (the same loop run here on its own).
TEST(MutualLoopDatasetTest, RefinedMasksReadBackAsExternalMasks) {
  const fs::path dir = kDataDir / "office_seg" / "pass1";
  RequireDataset(dir);
  const fs::path out = fs::temp_directory_path() / ("segslam_mutual_refined_" + std::to_string(::getpid()));
  fs::remove_all(out);
  constexpr int kFrames = 5;
  RunLoop(dir, "fcis-like", out, kFrames);
  // Only kFrames of the sequence were run, so the folder is read file by file with the
  // external-mask parsers rather than through ExternalMaskSegmenter (which wants every frame).
  const TumSequence sequence = TumSequence::Open(dir);
  const cv::Size size(sequence.camera().intrinsics.width, sequence.camera().intrinsics.height);
  seg::SimulatedSegmenter segmenter(dir, seg::SimulatedSegmenterOptions::Preset("fcis-like"), 1, "fcis-like");
  mutual::FramePipeline loop(sequence.camera().intrinsics, mutual::FramePipelineOptions{}, &segmenter);
  for (int i = 0; i < kFrames; ++i) {
    RgbdFrame frame = sequence.LoadFrame(static_cast<size_t>(i));
    frame.index = i;
    const seg::FrameSegmentation refined = loop.ProcessFrame(frame).refined;
    const std::string stem = fs::path(sequence.entries()[static_cast<size_t>(i)].rgb_file).stem().string();
    const fs::path table_path = out / (stem + ".json");
    const auto table = seg::ParseExternalMaskTable(ReadJsonFile(table_path), table_path.string());
    const seg::FrameSegmentation masks = seg::ExternalMasksToSegmentation(
        ReadInstanceMask(out / (stem + ".png")), table, size, i, (out / (stem + ".png")).string());
    ASSERT_FALSE(masks.instances.empty()) << "frame " << i;
    std::map<int, int> categories_read, categories_refined;
    for (const seg::InstanceMask& m : masks.instances) categories_read[m.track_id] = m.category_id;
    // The layout holds one id per pixel: a region that others cover entirely is not in it.
    const cv::Mat refined_ids = refined.ToIdImage(size);
    EXPECT_EQ(cv::countNonZero(masks.ToIdImage(size) != refined_ids), 0) << "frame " << i;
    for (const seg::InstanceMask& m : refined.instances) {
      if (cv::countNonZero(refined_ids == m.track_id) > 0) categories_refined[m.track_id] = m.category_id;
    }
    EXPECT_EQ(categories_read, categories_refined) << "frame " << i;
  }
  fs::remove_all(out);
}

// The pipeline's ground truth: the segmenter gives back the stored id image, each
// instance with its category from instances.json, and the oracle's verdicts name
// walkers (the office's only moving class) on most frames.
TEST(GroundTruthTest, SegmenterGivesTheStoredMasksAndMotionTheWalkers) {
  const fs::path dir = kDataDir / "office_seg" / "pass1";
  const TumSequence sequence = TumSequence::Open(dir);
  const InstanceTable table = InstanceTable::Read(dir / "instances.json");
  seg::GroundTruthSegmenter segmenter(sequence);
  const seg::GroundTruthMotion motion(dir);
  int frames_with_movers = 0;
  for (int i = 0; i < 20; ++i) {
    RgbdFrame frame = sequence.LoadFrame(static_cast<size_t>(i));
    frame.index = i;
    const seg::FrameSegmentation segmentation = segmenter.Segment(frame);
    const cv::Mat stored = sequence.LoadInstanceMask(dir / "masks" / (sequence.FrameStem(static_cast<size_t>(i)) + ".png"));
    EXPECT_EQ(cv::countNonZero(segmentation.ToIdImage(frame.color_bgr.size()) != stored), 0) << "frame " << i;
    ASSERT_FALSE(segmentation.instances.empty());
    for (const seg::InstanceMask& instance : segmentation.instances) {
      ASSERT_NE(table.Find(instance.track_id), nullptr);
      EXPECT_EQ(instance.category_id, table.Find(instance.track_id)->category_id);
    }
    for (const std::uint16_t id : motion.MovingIds(i)) {
      ASSERT_NE(table.Find(id), nullptr);
      EXPECT_EQ(table.Find(id)->category_name, "person") << "frame " << i << ", instance " << id;
    }
    frames_with_movers += !motion.MovingIds(i).empty();
  }
  EXPECT_GE(frames_with_movers, 15);
  EXPECT_THROW(seg::GroundTruthMotion(kDataDir / "no_such_sequence"), Error);
}

}  // namespace
}  // namespace segslam::harness
