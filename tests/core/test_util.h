// Helpers shared by the tests: a scratch directory removed after each test, error
// messages, a small hand-made sequence.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/tum_dataset.h"

namespace segslam::testing {

// A fresh directory under the system temp dir, unique per process and test.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("segslam_core_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" +
            info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

// Runs `fn`, expects segslam::Error, and returns its message ("" if none was thrown).
template <typename Fn>
std::string ErrorMessage(Fn&& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an exception";
  return "";
}

// Writes a TUM sequence of `frames` frames (one grey colour, depth 2 m everywhere, the
// camera still) with stamps first_stamp_s + i * period_s into `dir`, and opens it.
inline TumSequence WriteFlatSequence(const std::filesystem::path& dir, int width, int height, int frames,
                                     double first_stamp_s, double period_s) {
  SequenceCamera camera;
  camera.intrinsics = PinholeCamera::FromVerticalFov(width, height, 60);
  TumSequenceWriter writer(dir, camera);
  for (int i = 0; i < frames; ++i) {
    RgbdFrame frame;
    frame.index = i;
    frame.stamp_s = first_stamp_s + period_s * i;
    frame.color_bgr = cv::Mat(height, width, CV_8UC3, cv::Scalar(90, 90, 90));
    frame.depth_m = cv::Mat(height, width, CV_32F, cv::Scalar(2.0f));
    writer.Add(frame, Eigen::Isometry3d::Identity());
  }
  writer.Finish();
  return TumSequence::Open(dir);
}

inline std::filesystem::path SharedDataDir() { return SEGSLAM_SHARED_DATA_DIR; }

}  // namespace segslam::testing
