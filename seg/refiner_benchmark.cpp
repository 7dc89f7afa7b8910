// Speed of the segmentation refinement on one 640x480 frame with 10 instances (2-8% of
// the image each) on realistic depth (a room 3-4.5 m deep, objects at 1-3 m, dropouts),
// camera moved by a typical inter-frame step (1 cm, 0.5 deg at 30 Hz).
// Target: median <= 5 ms on one core.
#include <random>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "seg/refiner.h"

namespace segslam::seg {
namespace {

struct BenchFrame {
  PinholeCamera camera;
  cv::Mat depth;
  FrameSegmentation previous;
  FrameSegmentation current;
  Eigen::Isometry3d T_wc_previous = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_wc_current = Eigen::Isometry3d::Identity();
};

BenchFrame MakeFrame() {
  BenchFrame f;
  f.camera.width = 640;
  f.camera.height = 480;
  f.camera.fx = f.camera.fy = 525;
  f.camera.cx = 319.5;
  f.camera.cy = 239.5;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0, 1);
  // Background: a slanted wall and floor, 3-4.5 m.
  f.depth = cv::Mat(480, 640, CV_32F);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      f.depth.at<float>(y, x) = 3.0f + 1.5f * x / 640.0f - 0.5f * y / 480.0f;
    }
  }
  // Ten objects (ellipses) of 2-8% of the image, at 1-3 m, each a little slanted.
  const int categories[] = {1, 62, 1, 44, 47, 62, 63, 1, 56, 67};
  for (int i = 0; i < 10; ++i) {
    const double area = (0.02 + 0.06 * uniform(rng)) * 640 * 480;
    const double aspect = 0.6 + 0.8 * uniform(rng);
    const int a = static_cast<int>(std::sqrt(area / M_PI * aspect));
    const int b = static_cast<int>(std::sqrt(area / M_PI / aspect));
    const cv::Point centre(static_cast<int>(40 + 560 * uniform(rng)),
                           static_cast<int>(40 + 400 * uniform(rng)));
    const float z0 = static_cast<float>(1.0 + 2.0 * uniform(rng));
    cv::Mat mask(480, 640, CV_8U, cv::Scalar(0));
    cv::ellipse(mask, centre, cv::Size(a, b), 180 * uniform(rng), 0, 360, cv::Scalar(1),
                cv::FILLED);
    for (int y = 0; y < 480; ++y) {
      for (int x = 0; x < 640; ++x) {
        if (mask.at<std::uint8_t>(y, x)) {
          f.depth.at<float>(y, x) = z0 + 0.0005f * (x - centre.x) + 0.0003f * (y - centre.y);
        }
      }
    }
    InstanceMask instance;
    instance.track_id = static_cast<std::uint16_t>(i + 1);
    instance.category_id = categories[i];
    instance.score = 0.9f;
    instance.mask = mask;
    f.previous.instances.push_back(instance);
  }
  // Later objects are in front in the image, so previous masks do not overlap.
  for (int i = 0; i < 10; ++i) {
    for (int j = i + 1; j < 10; ++j) {
      f.previous.instances[i].mask.setTo(0, f.previous.instances[j].mask);
    }
  }
  // Depth dropouts: 2% of pixels.
  for (int k = 0; k < 6000; ++k) {
    f.depth.at<float>(static_cast<int>(480 * uniform(rng)),
                      static_cast<int>(640 * uniform(rng))) = 0;
  }
  // Camera step; the current detections are the previous ones, a few pixels off.
  f.T_wc_current.translation() = Eigen::Vector3d(0.01, 0.002, 0.005);
  f.T_wc_current.linear() =
      Eigen::AngleAxisd(0.5 * M_PI / 180, Eigen::Vector3d(0.2, 1, 0.1).normalized())
          .toRotationMatrix();
  for (const InstanceMask& p : f.previous.instances) {
    InstanceMask c = p;
    c.track_id = 0;
    cv::Mat shifted(480, 640, CV_8U, cv::Scalar(0));
    p.mask(cv::Rect(0, 0, 634, 480)).copyTo(shifted(cv::Rect(6, 0, 634, 480)));
    c.mask = shifted;
    f.current.instances.push_back(c);
  }
  f.current.instances.pop_back();  // one missed detection: exercises the add path
  return f;
}

void BM_Refine640x480TenInstances(benchmark::State& state) {
  cv::setNumThreads(1);
  const BenchFrame f = MakeFrame();
  RefinerInput in;
  in.previous_refined = &f.previous;
  in.previous_depth_m = f.depth;
  in.T_wc_previous_fine = f.T_wc_previous;
  in.T_wc_current_coarse = f.T_wc_current;
  in.current_initial = f.current;
  in.camera = f.camera;
  SegmentationRefiner refiner;
  for (auto _ : state) {
    RefinementResult r = refiner.Refine(in);
    benchmark::DoNotOptimize(r);
  }
  const RefinementResult r = refiner.Refine(in);
  state.SetLabel(r.BriefReport());
}
BENCHMARK(BM_Refine640x480TenInstances)->Unit(benchmark::kMillisecond);

void BM_ProjectRegions640x480TenInstances(benchmark::State& state) {
  cv::setNumThreads(1);
  const BenchFrame f = MakeFrame();
  const Eigen::Isometry3d T_cur_prev = f.T_wc_current.inverse() * f.T_wc_previous;
  const RefinerOptions options;
  for (auto _ : state) {
    auto projected = ProjectRegions(options, f.camera, f.previous, f.depth, T_cur_prev);
    benchmark::DoNotOptimize(projected);
  }
}
BENCHMARK(BM_ProjectRegions640x480TenInstances)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace segslam::seg

BENCHMARK_MAIN();
