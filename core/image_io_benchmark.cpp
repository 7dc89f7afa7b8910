// Speed of writing and reading a sequence's PNGs, per frame, on one core (run under
// `taskset -c 0`). The generator encodes every frame once; every run over a dataset
// decodes it again, so both sides count. Also the lens undistortion that reading a
// distorted camera's frames adds (TUM freiburg1's lens, 640x480 frames only).
//
//   core_benchmarks [--sequence DIR] [Google Benchmark flags]
//
// DIR is a TUM-layout sequence, e.g. a generated pass (`data/city/pass1`): its rgb.txt,
// depth.txt, masks/ (if present) and camera.yaml (for the depth factor; 5000 without
// one). Default: the real Kinect frames in ../shared/data, which have no masks. Every
// tenth frame is used, at most 20. Decoding goes through cv::imdecode, the decoder that
// ReadColorImage and the other readers use, on bytes already in memory, so the disk does
// not enter the figures.
#include <benchmark/benchmark.h>

#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "core/lens_distortion.h"
#include "core/tum_dataset.h"

namespace segslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrameStride = 10;
constexpr size_t kMaxFrames = 20;

struct BenchmarkFrames {
  std::string label;
  double depth_factor = 5000;
  std::vector<cv::Mat> color;  // CV_8UC3
  std::vector<cv::Mat> depth;  // CV_32F metres
  std::vector<cv::Mat> masks;  // CV_16U, empty without masks/
};

fs::path& SequenceDir() {
  static fs::path dir = fs::path(SEGSLAM_SHARED_DATA_DIR) / "7scenes_redkitchen_f0000-0109";
  return dir;
}

std::vector<fs::path> EveryTenthFile(const fs::path& dir, const char* list) {
  std::vector<fs::path> files;
  const auto entries = ReadTumFileList(dir / list);
  for (size_t i = 0; i < entries.size() && files.size() < kMaxFrames; i += kFrameStride) {
    files.push_back(dir / entries[i].second);
  }
  return files;
}

const BenchmarkFrames& Frames() {
  static const BenchmarkFrames frames = [] {
    const fs::path& dir = SequenceDir();
    BenchmarkFrames loaded;
    if (fs::exists(dir / "camera.yaml")) {
      loaded.depth_factor = ReadCameraYaml(dir / "camera.yaml").depth_factor;
    }
    for (const fs::path& file : EveryTenthFile(dir, "rgb.txt")) {
      loaded.color.push_back(ReadColorImage(file));
      const fs::path mask = dir / "masks" / file.filename();
      if (fs::exists(mask)) loaded.masks.push_back(ReadInstanceMask(mask));
    }
    for (const fs::path& file : EveryTenthFile(dir, "depth.txt")) {
      loaded.depth.push_back(ReadDepthImage(file, loaded.depth_factor));
    }
    if (loaded.color.empty()) throw FileError(dir / "rgb.txt", "lists no frames");
    // "city/pass1" rather than "pass1": a generated dataset's passes share their names.
    loaded.label = (dir.parent_path().filename() / dir.filename()).string() + ", " + std::to_string(loaded.color.size()) +
                   " frames " + std::to_string(loaded.color.front().cols) + "x" +
                   std::to_string(loaded.color.front().rows);
    return loaded;
  }();
  return frames;
}

// Runs `encode` over `images` round-robin, one image per iteration, and reports the
// mean encoded size over the images.
template <typename Encode>
void EncodeEach(benchmark::State& state, const std::vector<cv::Mat>& images, Encode encode) {
  if (images.empty()) {
    state.SkipWithError("the sequence has no such images");
    return;
  }
  double bytes = 0;
  for (const cv::Mat& image : images) bytes += static_cast<double>(encode(image).size());
  size_t i = 0;
  for (auto _ : state) {
    const std::vector<unsigned char> png = encode(images[i++ % images.size()]);
    benchmark::DoNotOptimize(png.data());
  }
  state.counters["KiB"] = bytes / 1024.0 / static_cast<double>(images.size());
  state.SetLabel(Frames().label);
}

template <typename Encode>
void DecodeEach(benchmark::State& state, const std::vector<cv::Mat>& images, Encode encode) {
  if (images.empty()) {
    state.SkipWithError("the sequence has no such images");
    return;
  }
  std::vector<std::vector<unsigned char>> pngs;
  for (const cv::Mat& image : images) pngs.push_back(encode(image));
  size_t i = 0;
  for (auto _ : state) {
    const cv::Mat decoded = cv::imdecode(pngs[i++ % pngs.size()], cv::IMREAD_UNCHANGED);
    benchmark::DoNotOptimize(decoded.data);
  }
  state.SetLabel(Frames().label);
}

std::vector<unsigned char> EncodeDepth(const cv::Mat& depth_m) {
  return EncodeDepthPng(depth_m, Frames().depth_factor);
}

// Encoding and decoding of each kind of image, as BM_Encode<Kind>Png and BM_Decode<Kind>Png.
struct PngKind {
  const char* name;
  std::vector<cv::Mat> BenchmarkFrames::*images;
  std::vector<unsigned char> (*encode)(const cv::Mat&);
};

void RegisterPngBenchmarks() {
  static const PngKind kKinds[] = {{"Color", &BenchmarkFrames::color, EncodeColorPng},
                                   {"Depth", &BenchmarkFrames::depth, EncodeDepth},
                                   {"InstanceMask", &BenchmarkFrames::masks, EncodeInstanceMaskPng}};
  for (const PngKind& kind : kKinds) {
    benchmark::RegisterBenchmark((std::string("BM_Encode") + kind.name + "Png").c_str(),
                                 [&kind](benchmark::State& state) {
                                   cv::setNumThreads(1);
                                   EncodeEach(state, Frames().*kind.images, kind.encode);
                                 })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark((std::string("BM_Decode") + kind.name + "Png").c_str(),
                                 [&kind](benchmark::State& state) {
                                   cv::setNumThreads(1);
                                   DecodeEach(state, Frames().*kind.images, kind.encode);
                                 })
        ->Unit(benchmark::kMillisecond);
  }
}

// TUM freiburg1's colour camera; its lens's maps are built once, outside the timings.
const ImageUndistorter* Freiburg1Lens(benchmark::State& state) {
  const cv::Mat& frame = Frames().color.front();
  if (frame.cols != 640 || frame.rows != 480) {
    state.SkipWithError("the lens benchmarks need 640x480 frames");
    return nullptr;
  }
  static const SequenceCamera camera = *TumDefaultCamera("freiburg1");
  static const ImageUndistorter lens(camera.intrinsics, camera.distortion);
  return &lens;
}

template <typename Undistort>
void UndistortEach(benchmark::State& state, const std::vector<cv::Mat>& images, Undistort undistort) {
  cv::setNumThreads(1);
  const ImageUndistorter* lens = Freiburg1Lens(state);
  if (lens == nullptr) return;
  size_t i = 0;
  for (auto _ : state) {
    const cv::Mat out = undistort(*lens, images[i++ % images.size()]);
    benchmark::DoNotOptimize(out.data);
  }
  state.SetLabel(Frames().label);
}

void BM_UndistortColour(benchmark::State& state) {
  UndistortEach(state, Frames().color, [](const ImageUndistorter& lens, const cv::Mat& image) {
    return lens.UndistortColour(image);
  });
}
BENCHMARK(BM_UndistortColour)->Unit(benchmark::kMillisecond);

void BM_UndistortDepth(benchmark::State& state) {
  UndistortEach(state, Frames().depth, [](const ImageUndistorter& lens, const cv::Mat& image) {
    return lens.UndistortDepth(image);
  });
}
BENCHMARK(BM_UndistortDepth)->Unit(benchmark::kMillisecond);

// Once per sequence opened (TumSequence::Open), for a distorted camera.
void BM_BuildUndistortionMaps(benchmark::State& state) {
  cv::setNumThreads(1);
  const SequenceCamera camera = *TumDefaultCamera("freiburg1");
  for (auto _ : state) {
    const ImageUndistorter lens(camera.intrinsics, camera.distortion);
    benchmark::DoNotOptimize(&lens);
  }
}
BENCHMARK(BM_BuildUndistortionMaps)->Unit(benchmark::kMillisecond);

// Takes `--sequence DIR` (or `--sequence=DIR`) out of argv before Google Benchmark sees
// it. Returns false, after printing why, on a missing value.
bool TakeSequenceFlag(int* argc, char** argv) {
  int kept = 1;
  for (int i = 1; i < *argc; ++i) {
    const char* arg = argv[i];
    if (std::strcmp(arg, "--sequence") == 0) {
      if (i + 1 == *argc) {
        std::cerr << "core_benchmarks: --sequence needs a directory\n";
        return false;
      }
      SequenceDir() = argv[++i];
    } else if (std::strncmp(arg, "--sequence=", 11) == 0) {
      SequenceDir() = arg + 11;
    } else {
      argv[kept++] = argv[i];
    }
  }
  *argc = kept;
  return true;
}

}  // namespace
}  // namespace segslam

int main(int argc, char** argv) {
  if (!segslam::TakeSequenceFlag(&argc, argv)) return 2;
  try {
    segslam::Frames();  // errors in the sequence surface here, not inside a benchmark
  } catch (const segslam::Error& e) {
    std::cerr << "core_benchmarks: " << e.what() << "\n";
    return 1;
  }
  segslam::RegisterPngBenchmarks();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
