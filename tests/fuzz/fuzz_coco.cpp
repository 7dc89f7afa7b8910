// Fuzz target: COCO detections (seg/coco_detections.h, and through it the RLE and
// polygon decoders of core/coco_rle.h), as `segslam masks import` reads them, on a
// three-frame 16x12 sequence the target writes once at start-up (stems 1.000000,
// 2.000000, 3.000000). Each input is read as a results list or dataset file, once alone
// and once with an image list giving integer image ids 1, 2, 3 to the three frames, and
// every frame's detections are decoded.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "core/tum_dataset.h"
#include "seg/coco_detections.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

using namespace segslam;

struct Fixture {
  std::unique_ptr<TumSequence> sequence;
  std::filesystem::path images_file;
};

const Fixture& TheFixture() {
  static const Fixture* const fixture = [] {
    auto* f = new Fixture;
    SequenceCamera camera;
    camera.intrinsics.width = 16;
    camera.intrinsics.height = 12;
    camera.intrinsics.fx = camera.intrinsics.fy = 20;
    camera.intrinsics.cx = 7.5;
    camera.intrinsics.cy = 5.5;
    const auto dir = fuzz::ScratchDir() / "sequence";
    TumSequenceWriter writer(dir, camera);
    for (int i = 0; i < 3; ++i) {
      RgbdFrame frame;
      frame.index = i;
      frame.stamp_s = 1.0 + i;
      frame.color_bgr = cv::Mat(12, 16, CV_8UC3, cv::Scalar(40 * i, 90, 200));
      frame.depth_m = cv::Mat(12, 16, CV_32F, cv::Scalar(1.5));
      writer.Add(frame, Eigen::Isometry3d::Identity());
    }
    writer.Finish();
    f->sequence = std::make_unique<TumSequence>(TumSequence::Open(dir));
    f->images_file = fuzz::WriteScratch(
        "images.json",
        R"({"images": [{"id": 1, "file_name": "rgb/1.000000.png"}, {"id": 2, "file_name": "rgb/2.000000.png"},)"
        R"( {"id": 3, "file_name": "rgb/3.000000.png"}]})");
    return f;
  }();
  return *fixture;
}

void ReadAndDecode(const std::filesystem::path& file, const seg::CocoImportOptions& options) {
  const TumSequence& sequence = *TheFixture().sequence;
  std::optional<seg::CocoDetections> detections;
  if (fuzz::Refused([&] { detections = seg::CocoDetections::Read(file, sequence, options); })) return;
  if (detections->num_frames() != sequence.size()) {
    fuzz::PropertyBroken("detections for " + std::to_string(detections->num_frames()) + " frames of " +
                         std::to_string(sequence.size()));
  }
  for (std::size_t i = 0; i < detections->num_frames(); ++i) {
    fuzz::Refused([&] {
      const seg::FrameSegmentation masks = detections->Frame(i);
      const cv::Mat ids = masks.ToIdImage(cv::Size(16, 12));
      if (ids.type() != CV_16UC1 || ids.rows != 12 || ids.cols != 16) {
        fuzz::PropertyBroken("a frame's id image has the wrong type or size");
      }
    });
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  TheFixture();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fuzz::WriteScratch("results.json", data, size);
  seg::CocoImportOptions options;
  options.min_score = 0.0;
  ReadAndDecode(file, options);
  options.images_file = TheFixture().images_file;
  ReadAndDecode(file, options);
  return 0;
}
