#include "core/tum_dataset.h"

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using testing::SharedDataDir;
using TumDatasetTest = testing::TempDirTest;

SequenceCamera SmallCamera() {
  SequenceCamera camera;
  camera.intrinsics = {32, 24, 30.5, 31.25, 15.5, 11.5};
  camera.depth_factor = 1000;
  return camera;
}

TEST_F(TumDatasetTest, CameraYamlRoundTrip) {
  SequenceCamera camera = SmallCamera();
  // The next double above fx: needs all 17 digits to survive.
  camera.intrinsics.fx = std::nextafter(camera.intrinsics.fx, 1e9);
  const auto path = dir() / "camera.yaml";
  WriteCameraYaml(path, camera);
  const SequenceCamera back = ReadCameraYaml(path);
  EXPECT_EQ(back.intrinsics.width, camera.intrinsics.width);
  EXPECT_EQ(back.intrinsics.height, camera.intrinsics.height);
  EXPECT_EQ(back.intrinsics.fx, camera.intrinsics.fx);
  EXPECT_EQ(back.intrinsics.fy, camera.intrinsics.fy);
  EXPECT_EQ(back.intrinsics.cx, camera.intrinsics.cx);
  EXPECT_EQ(back.intrinsics.cy, camera.intrinsics.cy);
  EXPECT_EQ(back.depth_factor, camera.depth_factor);
  EXPECT_TRUE(back.distortion.IsZero());
  // No distortion: no distortion keys, so the file reads as before they existed.
  std::ifstream written(path);
  const std::string text((std::istreambuf_iterator<char>(written)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("k1"), std::string::npos) << text;

  camera.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  WriteCameraYaml(path, camera);
  const LensDistortion distortion = ReadCameraYaml(path).distortion;
  EXPECT_EQ(distortion.k1, 0.2624);
  EXPECT_EQ(distortion.k2, -0.9531);
  EXPECT_EQ(distortion.p1, -0.0054);
  EXPECT_EQ(distortion.p2, 0.0026);
  EXPECT_EQ(distortion.k3, 1.1633);
}

TEST_F(TumDatasetTest, CameraYamlErrorsNameKeyAndFile) {
  const auto path = dir() / "camera.yaml";
  const std::string good = "width: 640\nheight: 480\nfx: 500\nfy: 500\ncx: 320\ncy: 240\n";
  std::ofstream(path) << good << "depth_factor: 5000\nfocal: 3\n";
  std::string message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find("unknown key 'focal'"), std::string::npos) << message;

  std::ofstream(path) << good;
  message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find("missing key 'depth_factor'"), std::string::npos) << message;

  std::ofstream(path) << good << "depth_factor: lots\n";
  message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find("'depth_factor' must be a finite number"), std::string::npos) << message;

  std::ofstream(path) << "width: 640.5\nheight: 480\nfx: 500\nfy: 500\ncx: 320\ncy: 240\n"
                         "depth_factor: 5000\n";
  message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find("'width' must be an integer"), std::string::npos) << message;

  // Distortion coefficients are optional, each on its own; present, they must be numbers.
  std::ofstream(path) << good << "depth_factor: 5000\nk1: 0.25\n";
  const LensDistortion only_k1 = ReadCameraYaml(path).distortion;
  EXPECT_EQ(only_k1.k1, 0.25);
  EXPECT_EQ(only_k1.k2, 0.0);
  std::ofstream(path) << good << "depth_factor: 5000\np2: .nan\n";
  message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find("'p2' must be a finite number"), std::string::npos) << message;

  std::ofstream(path) << "width: [640\n";
  message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find("malformed YAML"), std::string::npos) << message;
}

// camera.yaml (run --camera, eval, masks) gets the check a scenario's camera gets: a lens
// generate refuses, and intrinsics beyond sensible ranges, are refused naming the file.
TEST_F(TumDatasetTest, CameraYamlIsCheckedAsGenerateChecksItsCamera) {
  const auto path = dir() / "camera.yaml";
  const std::string good = "width: 640\nheight: 480\nfx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\ndepth_factor: 5000\n";
  std::ofstream(path) << good << "k1: 50\nk2: -90\n";
  std::string message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find(path.string() + ": invalid camera: the lens (k1 50, k2 -90, k3 0) folds the image"),
            std::string::npos)
      << message;
  std::ofstream(path) << "width: 640\nheight: 480\nfx: 1e-9\nfy: 525\ncx: 319.5\ncy: 239.5\ndepth_factor: 5000\n";
  message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find(path.string() + ": invalid camera: fx 1e-09 px gives a horizontal field of view"),
            std::string::npos)
      << message;
  // TUM's published calibrations pass.
  for (const char* name : {"freiburg1", "freiburg2", "freiburg3"}) {
    std::string error;
    EXPECT_TRUE(TumDefaultCamera(name)->IsValid(&error)) << name << ": " << error;
  }
}

TEST(TumDefaultCamera, Freiburg) {
  const auto fr1 = TumDefaultCamera("rgbd_dataset_freiburg1_xyz");
  ASSERT_TRUE(fr1.has_value());
  EXPECT_EQ(fr1->intrinsics.fx, 517.3);
  EXPECT_EQ(fr1->intrinsics.cy, 255.3);
  EXPECT_EQ(fr1->depth_factor, 5000);
  EXPECT_EQ(fr1->distortion.k1, 0.2624);  // TUM's d0..d4 for the freiburg1 colour camera.
  EXPECT_EQ(fr1->distortion.k3, 1.1633);
  const auto fr2 = TumDefaultCamera("rgbd_dataset_freiburg2_desk");
  ASSERT_TRUE(fr2.has_value());
  EXPECT_EQ(fr2->distortion.k2, -0.7849);
  ASSERT_TRUE(TumDefaultCamera("rgbd_dataset_freiburg3_walking_xyz").has_value());
  EXPECT_EQ(TumDefaultCamera("rgbd_dataset_freiburg3_walking_xyz")->intrinsics.fx, 535.4);
  // freiburg3's images are stored undistorted.
  EXPECT_TRUE(TumDefaultCamera("rgbd_dataset_freiburg3_walking_xyz")->distortion.IsZero());
  EXPECT_FALSE(TumDefaultCamera("my_sequence").has_value());
}

TEST(AssociateByTimestamp, GreedyByDifferenceLikeAssociatePy) {
  // Candidates (diff, rgb, depth): (.002, 1.010, 1.008), (.008, 1.000, 1.008),
  // (.009, 1.010, 1.019), (.019, 1.000, 1.019). Greedy takes the first and the last;
  // 1.5 and 2.0 have no partner within 0.02 s.
  const std::vector<std::pair<double, std::string>> rgb = {
      {1.000, "r0"}, {1.010, "r1"}, {1.5, "r2"}};
  const std::vector<std::pair<double, std::string>> depth = {
      {1.019, "d1"}, {1.008, "d0"}, {2.0, "d2"}};  // Unsorted on purpose.
  const auto matches = AssociateByTimestamp(rgb, depth, 0.02);
  ASSERT_EQ(matches.size(), 2u);
  EXPECT_EQ(matches[0].rgb_file, "r0");
  EXPECT_EQ(matches[0].depth_file, "d1");
  EXPECT_EQ(matches[0].depth_stamp_s, 1.019);
  EXPECT_EQ(matches[1].rgb_file, "r1");
  EXPECT_EQ(matches[1].depth_file, "d0");
  // A tighter window drops the 0.019 s pair.
  EXPECT_EQ(AssociateByTimestamp(rgb, depth, 0.01).size(), 1u);
}

// At TUM's stamps (1.3e9 s) a + 0.02 rounds; a pair |a - b| < 0.02 as Python computes
// it must still be found (1305031236.384244 - 1305031236.364244 is 0.0199999809 in
// doubles, so associate.py pairs them).
TEST(AssociateByTimestamp, PairsJustUnderTheLimitAtLargeStamps) {
  const std::vector<std::pair<double, std::string>> rgb = {{1305031236.364244, "r"}};
  const std::vector<std::pair<double, std::string>> depth = {{1305031236.384244, "d"}};
  ASSERT_LT(std::abs(rgb[0].first - depth[0].first), 0.02);
  EXPECT_EQ(AssociateByTimestamp(rgb, depth, 0.02).size(), 1u);
  EXPECT_EQ(AssociateByTimestamp(depth, rgb, 0.02).size(), 1u);
}

// Where a stamp is so large that a + 0.04 rounds to a (beyond about 1e15 s), equal
// stamps still pair: a list associated with itself keeps every frame (found by the
// fuzz target fuzz_tum_lists).
TEST(AssociateByTimestamp, EqualStampsPairWhereTheWindowRoundsAway) {
  const std::vector<std::pair<double, std::string>> list = {{7.7e20, "rgb/a.png"}, {7.8e20, "rgb/b.png"}};
  EXPECT_EQ(AssociateByTimestamp(list, list, 0.02).size(), 2u);
}

// yaml-cpp's own exceptions used to escape (an "internal error" naming no file), and
// of a repeated key the first was taken silently.
TEST_F(TumDatasetTest, CameraYamlRefusesNonScalarAndDuplicateKeysNamingFileAndKey) {
  const auto path = dir() / "camera.yaml";
  const std::string good = "width: 640\nheight: 480\nfx: 500\nfy: 500\ncx: 320\ncy: 240\ndepth_factor: 5000\n";
  for (const std::string key : {"[fx, fy]: 500\n", "? {fx: 1}\n: 500\n", "~: 500\n"}) {
    SCOPED_TRACE(key);
    std::ofstream(path) << good << key;
    const std::string message = ErrorMessage([&] { ReadCameraYaml(path); });
    EXPECT_NE(message.find(path.string() + ": line 8: a key must be a plain name"), std::string::npos) << message;
  }

  std::ofstream(path) << good << "fx: 600\n";
  const std::string message = ErrorMessage([&] { ReadCameraYaml(path); });
  EXPECT_NE(message.find(path.string() + ": line 8: key 'fx' appears twice in one mapping (first on line 3)"),
            std::string::npos)
      << message;
}

// Finish() writes the frame lists last: when it stops before them (here: groundtruth.txt
// cannot be written), the folder is not a sequence Open() accepts without ground truth.
TEST_F(TumDatasetTest, FinishWritesTheFrameListsLast) {
  const auto seq_dir = dir() / "seq";
  TumSequenceWriter writer(seq_dir, SmallCamera());
  RgbdFrame frame;
  frame.color_bgr = cv::Mat(24, 32, CV_8UC3, cv::Scalar(1, 2, 3));
  frame.depth_m = cv::Mat(24, 32, CV_32F, cv::Scalar(1.0));
  writer.Add(frame, Eigen::Isometry3d::Identity());
  // A folder in the way of WriteFileAtomically's temporary "<path>.tmp-<pid>".
  std::filesystem::create_directory(seq_dir / ("groundtruth.txt.tmp-" + std::to_string(::getpid())));

  EXPECT_NE(ErrorMessage([&] { writer.Finish(); }).find("groundtruth.txt"), std::string::npos);
  for (const char* list : {"rgb.txt", "depth.txt", "associations.txt"}) {
    EXPECT_FALSE(std::filesystem::exists(seq_dir / list)) << list;
  }
  EXPECT_THROW(TumSequence::Open(seq_dir), Error);
}

TEST_F(TumDatasetTest, WriterThenOpenRoundTrip) {
  const SequenceCamera camera = SmallCamera();
  const auto seq_dir = dir() / "seq";
  std::vector<RgbdFrame> frames;
  {
    TumSequenceWriter writer(seq_dir, camera);
    for (int i = 0; i < 3; ++i) {
      RgbdFrame frame;
      frame.index = i;
      frame.stamp_s = 10.0 + i / 30.0;
      frame.color_bgr = cv::Mat(24, 32, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i));
      frame.depth_m = cv::Mat(24, 32, CV_32F, cv::Scalar(1.0 + i));
      Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
      T_wc.translation() = Eigen::Vector3d(i, 0, 0);
      writer.Add(frame, T_wc);
      frames.push_back(frame);
    }
    // Not a complete sequence before Finish().
    EXPECT_THROW(TumSequence::Open(seq_dir), Error);
    RgbdFrame late = frames[0];
    EXPECT_NE(ErrorMessage([&] { writer.Add(late, Eigen::Isometry3d::Identity()); })
                  .find("does not increase"),
              std::string::npos);
    writer.Finish();
  }
  EXPECT_EQ(TumSequenceWriter::StampName(10.0 + 1 / 30.0), "10.033333");
  EXPECT_TRUE(std::filesystem::exists(seq_dir / "rgb" / "10.033333.png"));

  const TumSequence sequence = TumSequence::Open(seq_dir);  // Camera from camera.yaml.
  ASSERT_EQ(sequence.size(), 3u);
  EXPECT_EQ(sequence.camera().depth_factor, 1000);
  EXPECT_EQ(sequence.camera().intrinsics.fy, 31.25);
  ASSERT_TRUE(sequence.has_groundtruth());
  ASSERT_EQ(sequence.groundtruth().size(), 3u);
  EXPECT_NEAR(sequence.groundtruth()[2].T_wc.translation().x(), 2.0, 1e-9);
  for (size_t i = 0; i < 3; ++i) {
    const RgbdFrame frame = sequence.LoadFrame(i);
    EXPECT_EQ(frame.index, static_cast<int>(i));
    EXPECT_NEAR(frame.stamp_s, frames[i].stamp_s, 1e-6);
    EXPECT_EQ(cv::norm(frame.color_bgr, frames[i].color_bgr, cv::NORM_INF), 0.0);
    EXPECT_NEAR(cv::norm(frame.depth_m, frames[i].depth_m, cv::NORM_INF), 0.0,
                0.5 / camera.depth_factor);
  }
  EXPECT_THROW(sequence.LoadFrame(3), Error);
  EXPECT_EQ(sequence.FrameStem(1), "10.033333");
  EXPECT_THROW(sequence.FrameStem(3), Error);

  // Without associations.txt the lists are associated by timestamp, to the same frames.
  std::filesystem::remove(seq_dir / "associations.txt");
  const TumSequence associated = TumSequence::Open(seq_dir);
  ASSERT_EQ(associated.size(), 3u);
  EXPECT_EQ(associated.entries()[1].depth_file, sequence.entries()[1].depth_file);

  // A camera whose size differs from the images is caught when loading.
  SequenceCamera wrong = camera;
  wrong.intrinsics.width = 64;
  const std::string message =
      ErrorMessage([&] { TumSequence::Open(seq_dir, wrong).LoadFrame(0); });
  EXPECT_NE(message.find("camera expects 64x24"), std::string::npos) << message;
}

TEST_F(TumDatasetTest, DistortedSequenceIsReadUndistortedAndMasksWrittenBackAsStored) {
  SequenceCamera camera;
  camera.intrinsics = {64, 48, 51.7, 51.6, 31.9, 25.5};  // freiburg1's field of view, small
  camera.depth_factor = 5000;
  camera.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  const auto seq_dir = dir() / "seq";
  {
    TumSequenceWriter writer(seq_dir, camera);
    RgbdFrame frame;
    frame.stamp_s = 1.0;
    frame.color_bgr = cv::Mat(48, 64, CV_8UC3);
    cv::randu(frame.color_bgr, 0, 256);
    frame.depth_m = cv::Mat(48, 64, CV_32F);
    cv::randu(frame.depth_m, 0.5, 4.0);
    writer.Add(frame, Eigen::Isometry3d::Identity());
    writer.Finish();
  }
  cv::Mat stored_ids(48, 64, CV_16UC1, cv::Scalar(0));
  stored_ids(cv::Rect(0, 0, 20, 16)).setTo(7);  // Reaches into the corner the lens bends most.
  stored_ids(cv::Rect(30, 20, 10, 10)).setTo(3);
  std::filesystem::create_directories(seq_dir / "masks");
  WriteInstanceMask(seq_dir / "masks" / "1.000000.png", stored_ids);

  const TumSequence sequence = TumSequence::Open(seq_dir);
  EXPECT_EQ(sequence.camera().distortion.k3, 1.1633);
  const ImageUndistorter undistorter(camera.intrinsics, camera.distortion);
  const RgbdFrame frame = sequence.LoadFrame(0);
  const cv::Mat stored_colour = ReadColorImage(seq_dir / "rgb" / "1.000000.png");
  const cv::Mat stored_depth = ReadDepthImage(seq_dir / "depth" / "1.000000.png", camera.depth_factor);
  EXPECT_EQ(cv::norm(frame.color_bgr, undistorter.UndistortColour(stored_colour), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(frame.depth_m, undistorter.UndistortDepth(stored_depth), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(frame.depth_m, stored_depth, cv::NORM_INF), 0.0);  // It did change.

  const cv::Mat ids = sequence.LoadInstanceMask(seq_dir / "masks" / "1.000000.png");
  EXPECT_EQ(cv::norm(ids, undistorter.UndistortIds(stored_ids), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(ids != stored_ids), 0);
  EXPECT_EQ(cv::norm(sequence.InstanceMaskAsStored(ids), undistorter.DistortIds(ids), cv::NORM_INF), 0.0);

  WriteInstanceMask(dir() / "small.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(0)));
  const std::string message = ErrorMessage([&] { sequence.LoadInstanceMask(dir() / "small.png"); });
  EXPECT_NE(message.find((dir() / "small.png").string()), std::string::npos) << message;
  EXPECT_NE(message.find("mask is 32x24, the sequence's images are 64x48"), std::string::npos) << message;
}

// A TUM freiburg1 sequence as downloaded (no camera.yaml) is read with TUM's calibration,
// its lens included.
TEST_F(TumDatasetTest, Freiburg1SequenceWithoutCameraYamlIsUndistorted) {
  const auto seq_dir = dir() / "rgbd_dataset_freiburg1_xyz";
  const SequenceCamera fr1 = *TumDefaultCamera("freiburg1");
  cv::Mat stored_depth(480, 640, CV_32F);
  cv::randu(stored_depth, 0.5, 4.0);
  {
    SequenceCamera pinhole = fr1;
    pinhole.distortion = {};
    TumSequenceWriter writer(seq_dir, pinhole);
    RgbdFrame frame;
    frame.stamp_s = 1305031102.175304;
    frame.color_bgr = cv::Mat(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));
    frame.depth_m = stored_depth;
    writer.Add(frame, Eigen::Isometry3d::Identity());
    writer.Finish();
  }
  std::filesystem::remove(seq_dir / "camera.yaml");
  const TumSequence sequence = TumSequence::Open(seq_dir);
  EXPECT_EQ(sequence.camera().distortion.k1, 0.2624);
  const cv::Mat stored = ReadDepthImage(seq_dir / sequence.entries()[0].depth_file, 5000);
  EXPECT_EQ(cv::norm(sequence.LoadFrame(0).depth_m,
                     ImageUndistorter(fr1.intrinsics, fr1.distortion).UndistortDepth(stored), cv::NORM_INF),
            0.0);
}

TEST_F(TumDatasetTest, OpenErrors) {
  const auto seq_dir = dir() / "seq";
  {
    TumSequenceWriter writer(seq_dir, SmallCamera());
    RgbdFrame frame;
    frame.stamp_s = 1.0;
    frame.color_bgr = cv::Mat(24, 32, CV_8UC3, cv::Scalar(0));
    frame.depth_m = cv::Mat(24, 32, CV_32F, cv::Scalar(1.0));
    writer.Add(frame, Eigen::Isometry3d::Identity());
    EXPECT_THROW(writer.Add(RgbdFrame{}, Eigen::Isometry3d::Identity()), Error);
    writer.Finish();
  }
  EXPECT_NE(ErrorMessage([&] { TumSequence::Open(dir() / "nope"); }).find("does not exist"),
            std::string::npos);

  // Missing image file.
  std::filesystem::remove(seq_dir / "depth" / "1.000000.png");
  std::string message = ErrorMessage([&] { TumSequence::Open(seq_dir); });
  EXPECT_NE(message.find("depth/1.000000.png"), std::string::npos) << message;

  // No camera.yaml and a name without a known default.
  std::filesystem::remove(seq_dir / "camera.yaml");
  message = ErrorMessage([&] { TumSequence::Open(seq_dir); });
  EXPECT_NE(message.find("add camera.yaml"), std::string::npos) << message;

  // Non-monotonic stamps in a list.
  std::filesystem::remove(seq_dir / "associations.txt");
  std::ofstream(seq_dir / "rgb.txt") << "# c\n2.0 rgb/1.000000.png\n1.0 rgb/1.000000.png\n";
  message = ErrorMessage([&] { TumSequence::Open(seq_dir, SmallCamera()); });
  EXPECT_NE(message.find("rgb.txt:3"), std::string::npos) << message;
  EXPECT_NE(message.find("does not increase"), std::string::npos) << message;

  // Missing list.
  std::filesystem::remove(seq_dir / "depth.txt");
  message = ErrorMessage([&] { TumSequence::Open(seq_dir, SmallCamera()); });
  EXPECT_NE(message.find("depth.txt"), std::string::npos) << message;

  // No list at all: not a sequence, whatever its camera.
  std::filesystem::remove(seq_dir / "rgb.txt");
  for (const std::optional<SequenceCamera>& camera : {std::optional<SequenceCamera>(), std::optional(SmallCamera())}) {
    message = ErrorMessage([&] { TumSequence::Open(seq_dir, camera); });
    EXPECT_NE(message.find(seq_dir.string() + ": not a TUM-layout sequence"), std::string::npos) << message;
  }
}

TEST(TumSequenceRealData, SevenScenesRedKitchen) {
  const auto dir = SharedDataDir() / "7scenes_redkitchen_f0000-0109";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not present";
  SequenceCamera camera;
  camera.intrinsics = {640, 480, 585.0, 585.0, 320.0, 240.0};
  camera.depth_factor = 5000;
  const TumSequence sequence = TumSequence::Open(dir, camera);
  ASSERT_EQ(sequence.size(), 110u);
  ASSERT_TRUE(sequence.has_groundtruth());
  EXPECT_EQ(sequence.groundtruth().size(), 110u);
  EXPECT_NEAR(sequence.entries().back().rgb_stamp_s, 3.633333, 1e-9);
  // SOURCE.md gives the valid range to the centimetre (0.80 .. 3.60 m).
  constexpr double kRangeSlack_m = 0.01;
  for (size_t i = 0; i < sequence.size(); ++i) {
    const RgbdFrame frame = sequence.LoadFrame(i);
    ASSERT_EQ(frame.color_bgr.type(), CV_8UC3);
    ASSERT_EQ(frame.depth_m.type(), CV_32FC1);
    double min_m = 0, max_m = 0;
    cv::minMaxLoc(frame.depth_m, &min_m, &max_m, nullptr, nullptr, frame.depth_m > 0);
    EXPECT_GE(min_m, 0.8 - kRangeSlack_m) << "frame " << i;
    EXPECT_LE(max_m, 3.6 + kRangeSlack_m) << "frame " << i;
    EXPECT_GT(cv::countNonZero(frame.depth_m), 640 * 480 / 2) << "frame " << i;
  }
  // The lists alone associate to the same 110 pairs as associations.txt.
  const auto associated = AssociateByTimestamp(ReadTumFileList(dir / "rgb.txt"),
                                               ReadTumFileList(dir / "depth.txt"));
  ASSERT_EQ(associated.size(), 110u);
  for (size_t i = 0; i < associated.size(); ++i) {
    EXPECT_EQ(associated[i].rgb_file, sequence.entries()[i].rgb_file);
    EXPECT_EQ(associated[i].depth_file, sequence.entries()[i].depth_file);
  }
}

}  // namespace
}  // namespace segslam
