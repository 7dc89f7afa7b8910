// Speed of the paper's whole loop per frame without the segmenter (coarse pose, mask
// refinement, moving/static judgement, fine pose, map update), on one core, on a
// generated walking office with the fcis-like segmenter's masks. The masks are made
// before timing and handed back frame by frame, so the segmenter's own time is left out,
// as the budget and `segslam bench slam`'s "loop" row leave it out.
//
// The sequence: $SEGSLAM_BENCH_SEQUENCE, else build/test_data/office_seg/pass1 (made by
// the tests' sim_datasets fixture: `ctest -R sim_datasets`). Counters, medians per frame
// over every frame of every iteration (one iteration: the whole sequence with a fresh
// pipeline): loop_ms, tracking (features to map update) plus refinement, as `bench slam`
// counts them; refine_ms; tracking_ms; and process_frame_ms, the whole call, which adds
// the local bundle adjustment of keyframes and the pipeline's bookkeeping.
#include <chrono>
#include <cstdlib>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "core/statistics.h"
#include "core/tum_dataset.h"
#include "mutual/frame_pipeline.h"
#include "seg/simulated_segmenter.h"

namespace segslam::mutual {
namespace {

// Hands back segmentations made beforehand, by frame index.
class ReplayedSegmenter : public seg::Segmenter {
 public:
  explicit ReplayedSegmenter(std::vector<seg::FrameSegmentation> frames) : frames_(std::move(frames)) {}
  seg::FrameSegmentation Segment(const RgbdFrame& frame) override { return frames_.at(static_cast<size_t>(frame.index)); }
  std::string name() const override { return "replayed"; }

 private:
  std::vector<seg::FrameSegmentation> frames_;
};

std::filesystem::path SequenceDir() {
  if (const char* dir = std::getenv("SEGSLAM_BENCH_SEQUENCE")) return dir;
  return std::filesystem::path(SEGSLAM_BINARY_DIR) / "test_data" / "office_seg" / "pass1";
}

void BM_MutualLoopWalkingOffice(benchmark::State& state) {
  cv::setNumThreads(1);
  const std::filesystem::path dir = SequenceDir();
  if (!std::filesystem::is_directory(dir)) {
    state.SkipWithError(("no sequence at " + dir.string() + " (set SEGSLAM_BENCH_SEQUENCE)").c_str());
    return;
  }
  const TumSequence sequence = TumSequence::Open(dir);
  std::vector<RgbdFrame> frames;
  std::vector<seg::FrameSegmentation> masks;
  seg::SimulatedSegmenter segmenter(dir, seg::SimulatedSegmenterOptions::Preset("fcis-like"), 1);
  for (size_t i = 0; i < sequence.size(); ++i) {
    frames.push_back(sequence.LoadFrame(i));
    frames.back().index = static_cast<int>(i);
    masks.push_back(segmenter.Segment(frames.back()));
  }
  ReplayedSegmenter replayed(masks);
  FramePipelineOptions options;
  options.mode = SlamMode::kMutual;
  std::vector<double> loop_ms, refine_ms, tracking_ms, process_frame_ms;
  for (auto _ : state) {
    state.PauseTiming();
    auto pipeline = std::make_unique<FramePipeline>(sequence.camera().intrinsics, options, &replayed);
    state.ResumeTiming();
    for (const RgbdFrame& frame : frames) {
      const auto start = std::chrono::steady_clock::now();
      const FrameStep step = pipeline->ProcessFrame(frame);
      process_frame_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      refine_ms.push_back(step.refine_ms);
      tracking_ms.push_back(step.slam.timings.TrackingMs());
      loop_ms.push_back(tracking_ms.back() + refine_ms.back());
    }
    state.PauseTiming();
    pipeline.reset();
    state.ResumeTiming();
  }
  state.counters["frames"] = static_cast<double>(frames.size());
  state.counters["loop_ms_median"] = Median(loop_ms);
  state.counters["refine_ms_median"] = Median(refine_ms);
  state.counters["tracking_ms_median"] = Median(tracking_ms);
  state.counters["process_frame_ms_median"] = Median(process_frame_ms);
}
BENCHMARK(BM_MutualLoopWalkingOffice)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
}  // namespace segslam::mutual

BENCHMARK_MAIN();
