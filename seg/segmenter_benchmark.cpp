// Speed of what the bench does per frame around the refinement, on one core: the
// simulated FCIS-like segmenter degrading one 640x480 ground-truth frame, and scoring a
// segmentation of it (mAP, AP50, mIoU). The frame is city-like: 14 instances from a car
// filling a quarter of the image to pedestrians of a few hundred pixels.
// No targets: both run once or twice per frame beside tracking (about 15 ms). Medians on
// one core here: the segmenter 16 ms and the scoring 3.0 ms; 80 and 6.8 ms before their
// distance transforms and pixel scans were limited to each object's box (9606d81).
#include <cstdint>
#include <map>
#include <random>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/instances.h"
#include "seg/metrics.h"
#include "seg/simulated_segmenter.h"

namespace segslam::seg {
namespace {

struct GroundTruthFrame {
  cv::Mat ids;  // CV_16U
  InstanceTable table;
};

GroundTruthFrame MakeCityLikeFrame() {
  GroundTruthFrame frame;
  frame.ids = cv::Mat(480, 640, CV_16U, cv::Scalar(0));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(0, 1);
  // (COCO category, share of the image): a close car, cars further on, people, a bus.
  const std::pair<int, double> objects[] = {{3, 0.25},  {3, 0.06},   {3, 0.03},   {3, 0.015},  {3, 0.008},
                                            {6, 0.05},  {1, 0.01},   {1, 0.006},  {1, 0.004},  {1, 0.002},
                                            {1, 0.001}, {2, 0.004},  {10, 0.0008}, {13, 0.002}};
  std::uint16_t id = 1;
  for (const auto& [category, share] : objects) {
    const double area = share * 640 * 480;
    const double aspect = category == 1 ? 0.4 : 1.8;  // people are tall, vehicles wide
    const int a = static_cast<int>(std::sqrt(area / M_PI * aspect));
    const int b = static_cast<int>(std::sqrt(area / M_PI / aspect));
    const cv::Point centre(static_cast<int>(40 + 560 * uniform(rng)), static_cast<int>(200 + 200 * uniform(rng)));
    cv::ellipse(frame.ids, centre, cv::Size(a, b), 0, 0, 360, cv::Scalar(id), cv::FILLED);
    InstanceInfo info;
    info.id = id;
    info.category_id = category;
    frame.table.Add(info);
    ++id;
  }
  return frame;
}

void BM_SimulateSegmentationFcisLikeCityFrame(benchmark::State& state) {
  cv::setNumThreads(1);
  const GroundTruthFrame frame = MakeCityLikeFrame();
  const SimulatedSegmenterOptions options = SimulatedSegmenterOptions::Preset("fcis-like");
  int frame_index = 0;
  for (auto _ : state) {
    // A new frame index each time: the errors drawn (and so the work) vary as in a run.
    SimulatedFrame simulated = SimulateSegmentation(options, 1, frame_index++, frame.ids, frame.table, {});
    benchmark::DoNotOptimize(simulated);
  }
}
BENCHMARK(BM_SimulateSegmentationFcisLikeCityFrame)->Unit(benchmark::kMillisecond);

void BM_ScoreFrameCityFrame(benchmark::State& state) {
  cv::setNumThreads(1);
  const GroundTruthFrame frame = MakeCityLikeFrame();
  const SimulatedFrame simulated = SimulateSegmentation(SimulatedSegmenterOptions::Preset("fcis-like"), 1, 0,
                                                        frame.ids, frame.table, {});
  const EvaluationOptions options;
  for (auto _ : state) {
    SegmentationScores scores = SegmentationEvaluator::ScoreFrame(options, frame.ids, frame.table, simulated.segmentation);
    benchmark::DoNotOptimize(scores);
  }
  state.SetLabel(std::to_string(simulated.segmentation.instances.size()) + " detections");
}
BENCHMARK(BM_ScoreFrameCityFrame)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace segslam::seg
