// Generates a few frames of a scenario with segslam's generator, runs the mutual loop on
// pass 1 with the simulated segmenter, and checks the poses against the ground truth.
// Usage: mutual_on_generated SCENARIO.yaml OUT_DIR FRAMES
#include <cstdio>
#include <string>

#include "core/tum_dataset.h"
#include "mutual/frame_pipeline.h"
#include "scenes/scenario.h"
#include "seg/simulated_segmenter.h"
#include "sim/dataset_generator.h"

int main(int argc, char** argv) {
  if (argc != 4) return std::fprintf(stderr, "usage: %s SCENARIO.yaml OUT_DIR FRAMES\n", argv[0]), 2;
  using namespace segslam;
  sim::GenerateOptions generate;
  generate.max_frames_per_pass = std::stoi(argv[3]);
  sim::GenerateDataset(scenes::LoadScenario(argv[1]), argv[2], generate);

  const std::string pass1 = std::string(argv[2]) + "/pass1";
  const TumSequence sequence = TumSequence::Open(pass1);
  seg::SimulatedSegmenter segmenter(pass1, seg::SimulatedSegmenterOptions::Preset("fcis-like"), /*seed=*/1);
  mutual::FramePipeline loop(sequence.camera().intrinsics, mutual::FramePipelineOptions{}, &segmenter);
  // The loop's world frame is its first camera's: compare poses relative to frame 0.
  const Eigen::Isometry3d gt0_inv = sequence.groundtruth().front().T_wc.inverse();
  int localized = 0;
  double worst_m = 0;
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (sequence.groundtruth()[i].stamp_s != sequence.entries()[i].rgb_stamp_s) return 1;  // one pose per frame
    const mutual::FrameStep result = loop.ProcessFrame(sequence.LoadFrame(i));
    if (!result.slam.localized()) continue;
    ++localized;
    const Eigen::Vector3d truth = (gt0_inv * sequence.groundtruth()[i].T_wc).translation();
    worst_m = std::max(worst_m, (result.slam.T_wc.translation() - truth).norm());
  }
  std::printf("%d of %zu frames localized, largest position error %.4f m\n", localized, sequence.size(), worst_m);
  return localized == static_cast<int>(sequence.size()) && worst_m < 0.05 ? 0 : 1;
}
