// Speed of the per-frame SLAM building blocks on one core (run under `taskset -c 0`).
// Targets: Extract (1000 features, 640x480) median <= 8 ms; OptimizePose with 500
// observations median <= 2 ms. RunBundleAdjustment (10 keyframes, 2000 points) has no
// target: it runs on the mapping side, not per frame. RelocalizationSearch: a frame's 1000
// descriptors against a city route's long-term map (50 000 points), brute force against
// the index of slam/descriptor_index.h, searched, and built then searched (what a lost
// run pays when its map changed since the last try; no target: it runs on a
// relocalization). RelocalizationRansac: RANSAC PnP on 100 matches of which one in five
// is right, as a relocalization on a city map meets them, with the tracker's budget of
// samples and with the 300 it had before (no target: it runs on a relocalization, twice
// when a rival is sought).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "slam/bundle_adjustment.h"
#include "slam/descriptor_index.h"
#include "slam/orb_descriptor.h"
#include "slam/orb_extractor.h"
#include "slam/pose_optimizer.h"
#include "slam/ransac_pnp.h"
#include "slam/tracker.h"

namespace segslam::slam {
namespace {

PinholeCamera Vga() {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = camera.fy = 525;
  camera.cx = 319.5;
  camera.cy = 239.5;
  return camera;
}

// A real kitchen frame (7-Scenes) when the shared data is present, else a deterministic
// clutter of shapes with smooth shading and sensor-like noise.
cv::Mat BenchmarkImage(std::string* source) {
  const std::filesystem::path real = std::filesystem::path(SEGSLAM_SHARED_DATA_DIR) /
                                     "7scenes_redkitchen_f0000-0109/rgb/0.000000.png";
  cv::Mat gray = cv::imread(real.string(), cv::IMREAD_GRAYSCALE);
  if (!gray.empty() && gray.cols == 640 && gray.rows == 480) {
    *source = "7scenes kitchen frame";
    return gray;
  }
  *source = "synthetic clutter";
  gray = cv::Mat(480, 640, CV_8U);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) gray.at<uchar>(y, x) = static_cast<uchar>(60 + x / 8 + y / 10);
  }
  cv::RNG rng(42);
  for (int i = 0; i < 1200; ++i) {
    const cv::Point centre(rng.uniform(0, 640), rng.uniform(0, 480));
    const cv::Scalar grey(rng.uniform(0, 256));
    if (i % 3 == 0) {
      cv::circle(gray, centre, rng.uniform(3, 25), grey, cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(gray, cv::Rect(centre.x, centre.y, rng.uniform(4, 50), rng.uniform(4, 50)),
                    grey, cv::FILLED);
    }
  }
  cv::GaussianBlur(gray, gray, cv::Size(3, 3), 0.8);
  cv::Mat noise(480, 640, CV_8S);
  rng.fill(noise, cv::RNG::NORMAL, 0, 3);
  cv::add(gray, noise, gray, cv::noArray(), CV_8U);
  return gray;
}

void BM_OrbExtract(benchmark::State& state) {
  cv::setNumThreads(1);
  std::string source;
  const cv::Mat gray = BenchmarkImage(&source);
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.5f));
  const OrbExtractor extractor;
  size_t features = 0;
  for (auto _ : state) {
    const FrameFeatures f = extractor.Extract(gray, depth, Vga());
    features = f.size();
    benchmark::DoNotOptimize(f.descriptors.data);
  }
  state.counters["features"] = static_cast<double>(features);
  state.SetLabel(source);
}
BENCHMARK(BM_OrbExtract)->Unit(benchmark::kMillisecond);

Eigen::Isometry3d RotationAbout(const Eigen::Vector3d& axis, double angle_deg,
                                const Eigen::Vector3d& translation) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_deg * M_PI / 180, axis.normalized()).toRotationMatrix();
  T.translation() = translation;
  return T;
}

// 500 observations as tracking sees them: 80% with depth, 0.5 px noise, 10% outliers,
// starting from a motion-model guess 3 cm / 1 degree off.
void BM_OptimizePose(benchmark::State& state) {
  const PinholeCamera camera = Vga();
  const double bf = camera.fx * 0.08;
  const Eigen::Isometry3d T_cw = RotationAbout({0, 1, 0}, 20, {0.3, 0.1, 1.0});
  const Eigen::Isometry3d T_wc = T_cw.inverse();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(20, 620), v(20, 460), z(0.8, 6);
  std::normal_distribution<double> noise(0, 0.5);
  std::vector<PoseObservation> observations;
  for (int i = 0; i < 500; ++i) {
    PoseObservation o;
    const Eigen::Vector2d pixel(u(rng), v(rng));
    const double depth = z(rng);
    o.point_w = T_wc * camera.BackProject(pixel, depth);
    o.pixel = pixel + Eigen::Vector2d(noise(rng), noise(rng));
    if (i % 5 != 0) o.right_u = o.pixel.x() - bf / depth;
    if (i % 10 == 3) o.pixel += Eigen::Vector2d(25, -15);
    o.information = 1.0 / std::pow(1.44, i % 4);
    observations.push_back(o);
  }
  PoseOptimizerOptions options;
  options.bf = bf;
  const Eigen::Isometry3d start = RotationAbout({1, 0.3, 0}, 1, {0.02, -0.02, 0.01}) * T_cw;
  int inliers = 0;
  for (auto _ : state) {
    const PoseOptimizationResult r = OptimizePose(start, observations, camera, options);
    inliers = r.num_inliers;
    benchmark::DoNotOptimize(r.T_cw);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_OptimizePose)->Unit(benchmark::kMillisecond);

// Local BA as a new keyframe triggers it: 10 keyframes (2 fixed) along a 1.35 m path,
// 2000 points 2-8 m away seen by every keyframe that images them, half with depth,
// 0.5 px noise, 2% outliers; points 3 cm and free poses 2 cm / 0.5 degree off.
void BM_BundleAdjustment(benchmark::State& state) {
  const PinholeCamera camera = Vga();
  const double bf = camera.fx * 0.08;
  std::mt19937 rng(2);
  std::normal_distribution<double> gauss(0, 1);
  std::vector<Eigen::Isometry3d> T_cw_true;
  for (int k = 0; k < 10; ++k) {
    T_cw_true.push_back(
        (Eigen::Translation3d(0.15 * k, 0, 0) * RotationAbout({0, 1, 0}, k - 5.0, {0, 0, 0}))
            .inverse());
  }
  std::uniform_real_distribution<double> x(-3, 4.5), y(-2, 2), z(2, 8);
  std::vector<Eigen::Vector3d> points_true;
  for (int p = 0; p < 2000; ++p) points_true.emplace_back(x(rng), y(rng), z(rng));
  std::vector<BaObservation> observations;
  for (int p = 0; p < 2000; ++p) {
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector3d p_c = T_cw_true[k] * points_true[p];
      if (p_c.z() < 0.5) continue;
      const Eigen::Vector2d pixel = camera.Project(p_c);
      if (!camera.InImage(pixel, 20)) continue;
      BaObservation o;
      o.keyframe = k;
      o.point = p;
      o.pixel = pixel + 0.5 * Eigen::Vector2d(gauss(rng), gauss(rng));
      if (p % 2 == 0) o.right_u = o.pixel.x() - bf / p_c.z();
      if (observations.size() % 50 == 7) o.pixel += Eigen::Vector2d(20, 10);
      o.information = 1.0 / std::pow(1.44, (p + k) % 4);
      observations.push_back(o);
    }
  }
  std::vector<BaKeyframe> keyframes;
  for (int k = 0; k < 10; ++k) {
    BaKeyframe kf{T_cw_true[k], k < 2};
    if (!kf.fixed) {
      kf.T_cw =
          RotationAbout({gauss(rng), gauss(rng), gauss(rng)}, 0.5,
                        0.02 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized()) *
          kf.T_cw;
    }
    keyframes.push_back(kf);
  }
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector3d& p : points_true) {
    points.push_back(p + 0.03 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized());
  }
  BundleAdjustmentOptions options;
  options.bf = bf;
  for (auto _ : state) {
    const BundleAdjustmentResult r =
        RunBundleAdjustment(camera, keyframes, points, observations, options);
    benchmark::DoNotOptimize(r.final_cost);
  }
  state.counters["observations"] = static_cast<double>(observations.size());
}
BENCHMARK(BM_BundleAdjustment)->Unit(benchmark::kMillisecond);

enum RelocalizationSearch { kBruteForce = 0, kIndex = 1, kIndexBuiltEachTime = 2 };

// Map descriptors uniformly random; the frame's are copies of 1000 of them with 40 bits
// flipped (real ORB bits are skewed, which fills some buckets more: the index's figure is
// a lower bound).
void BM_RelocalizationSearch(benchmark::State& state) {
  const auto search = static_cast<RelocalizationSearch>(state.range(0));
  cv::Mat map_descriptors(50000, kOrbDescriptorBytes, CV_8U);
  cv::RNG rng(5);
  rng.fill(map_descriptors, cv::RNG::UNIFORM, 0, 256);
  cv::Mat frame_descriptors(1000, kOrbDescriptorBytes, CV_8U);
  for (int q = 0; q < frame_descriptors.rows; ++q) {
    map_descriptors.row(rng.uniform(0, map_descriptors.rows)).copyTo(frame_descriptors.row(q));
    for (int n = 0; n < 40; ++n) {
      const int bit = rng.uniform(0, kOrbDescriptorBytes * 8);
      frame_descriptors.at<std::uint8_t>(q, bit / 8) ^= static_cast<std::uint8_t>(1 << (bit % 8));
    }
  }
  const DescriptorIndex index(map_descriptors);
  for (auto _ : state) {
    if (search == kIndex) {
      benchmark::DoNotOptimize(index.Search(frame_descriptors));
    } else if (search == kIndexBuiltEachTime) {
      benchmark::DoNotOptimize(DescriptorIndex(map_descriptors).Search(frame_descriptors));
    } else {
      cv::BFMatcher matcher(cv::NORM_HAMMING);
      std::vector<std::vector<cv::DMatch>> knn;
      matcher.knnMatch(frame_descriptors, map_descriptors, knn, 2);
      benchmark::DoNotOptimize(knn);
    }
  }
  state.SetLabel(search == kBruteForce ? "brute force"
                 : search == kIndex     ? "descriptor index"
                                        : "index built and searched");
}
BENCHMARK(BM_RelocalizationSearch)->Arg(kBruteForce)->Arg(kIndex)->Arg(kIndexBuiltEachTime)->Unit(benchmark::kMillisecond);

// Points 2 to 12 m in front of the camera at the origin; four matches in five get a
// random pixel.
void BM_RelocalizationRansac(benchmark::State& state) {
  const PinholeCamera camera = Vga();
  std::mt19937 random(9);
  std::uniform_real_distribution<double> u(0, camera.width), v(0, camera.height), depth(2, 12);
  std::vector<cv::Point3f> points;
  std::vector<cv::Point2f> pixels;
  for (int k = 0; k < 100; ++k) {
    const double z = depth(random), pu = u(random), pv = v(random);
    points.emplace_back(static_cast<float>((pu - camera.cx) / camera.fx * z),
                        static_cast<float>((pv - camera.cy) / camera.fy * z), static_cast<float>(z));
    pixels.emplace_back(k % 5 == 0 ? cv::Point2f(static_cast<float>(pu), static_cast<float>(pv))
                                   : cv::Point2f(static_cast<float>(u(random)), static_cast<float>(v(random))));
  }
  const int samples = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(SolveRansacPnp(points, pixels, camera, samples, 15));
  state.SetLabel(samples == TrackerOptions().relocalization_ransac_iterations ? "tracker's budget" : "budget before");
}
BENCHMARK(BM_RelocalizationRansac)
    ->Arg(300)
    ->Arg(TrackerOptions().relocalization_ransac_iterations)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace segslam::slam

BENCHMARK_MAIN();
