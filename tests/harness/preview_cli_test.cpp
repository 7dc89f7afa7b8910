// `segslam preview` on a generated sequence (fixture sim_datasets): the contact sheet has
// one row per asked frame of colour | depth | instances, the colour tile is the frame
// itself, a sequence without camera.yaml is read with --camera, a folder of external masks
// is overlaid instead of the sequence's own, and a frame out of range or a missing mask is
// named with nothing written.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <string>

#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;

const fs::path kSequence = fs::path(SEGSLAM_TEST_DATA_DIR) / "office_clean" / "pass1";
constexpr int kWidth = 640, kHeight = 480;
// Captions are drawn over the top of each tile; below this row the tiles are untouched.
constexpr int kBelowCaption = 40;

class PreviewCliTest : public segslam::testing::CliScratchTest {
 protected:
  PreviewCliTest() : CliScratchTest("segslam_preview_") {}
};

cv::Mat Tile(const cv::Mat& sheet, int row, int column) {
  return sheet(cv::Rect(column * kWidth, row * kHeight + kBelowCaption, kWidth, kHeight - kBelowCaption));
}

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST_F(PreviewCliTest, SheetShowsEachFrameAsColourDepthAndInstances) {
  ASSERT_TRUE(fs::is_directory(kSequence)) << kSequence;
  const fs::path sheet_file = dir_ / "sheet.png";
  const CommandOutput out = Run("preview " + kSequence.string() + " --frames 0,39 --out " + sheet_file.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("2 frames"), std::string::npos) << out.stdout_text;

  const cv::Mat sheet = cv::imread(sheet_file.string(), cv::IMREAD_COLOR);
  ASSERT_EQ(sheet.cols, 3 * kWidth);
  ASSERT_EQ(sheet.rows, 2 * kHeight);
  // TUM layout: frame k is the k-th line of rgb.txt; the generator names files by stamp.
  const struct {
    int row;
    const char* rgb_file;
  } rows[] = {{0, "rgb/0.000000.png"}, {1, "rgb/1.300000.png"}};
  for (const auto& r : rows) {
    SCOPED_TRACE(r.rgb_file);
    const cv::Mat rgb = cv::imread((kSequence / r.rgb_file).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(rgb.empty());
    EXPECT_TRUE(SameImage(Tile(sheet, r.row, 0), rgb(cv::Rect(0, kBelowCaption, kWidth, kHeight - kBelowCaption))));
    // The office has furniture in view from the first frame: the overlay tints it.
    EXPECT_FALSE(SameImage(Tile(sheet, r.row, 2), Tile(sheet, r.row, 0)));
    EXPECT_FALSE(SameImage(Tile(sheet, r.row, 1), Tile(sheet, r.row, 0)));
  }
}

TEST_F(PreviewCliTest, SequenceWithoutCameraYamlIsReadWithCamera) {
  ASSERT_TRUE(fs::is_directory(kSequence)) << kSequence;
  const fs::path copy = dir_ / "no_camera";
  fs::copy(kSequence, copy, fs::copy_options::recursive);
  fs::remove(copy / "camera.yaml");

  const CommandOutput refused = Run("preview " + copy.string() + " --out " + (dir_ / "refused.png").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find("no camera intrinsics"), std::string::npos) << refused.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "refused.png"));

  // The depth tile depends on the camera's depth_factor: with the sequence's own camera
  // the sheet is the original's, byte for byte.
  const CommandOutput original = Run("preview " + kSequence.string() + " --out " + (dir_ / "original.png").string());
  const CommandOutput with_camera = Run("preview " + copy.string() + " --camera " + (kSequence / "camera.yaml").string() +
                                        " --out " + (dir_ / "with_camera.png").string());
  ASSERT_EQ(original.exit_code, 0) << original.stderr_text;
  ASSERT_EQ(with_camera.exit_code, 0) << with_camera.stderr_text;
  EXPECT_EQ(ReadText(dir_ / "original.png"), ReadText(dir_ / "with_camera.png"));
}

TEST_F(PreviewCliTest, ExternalMasksAreOverlaidInsteadOfTheSequences) {
  ASSERT_TRUE(fs::is_directory(kSequence)) << kSequence;
  // Frame 39 with no detection: its instance tile is the colour frame as it is.
  const fs::path masks = dir_ / "detections";
  fs::create_directories(masks);
  cv::imwrite((masks / "1.300000.png").string(), cv::Mat(kHeight, kWidth, CV_16UC1, cv::Scalar(0)));
  const fs::path sheet_file = dir_ / "sheet.png";
  const CommandOutput out = Run("preview " + kSequence.string() + " --frames 39 --masks " + masks.string() +
                                " --out " + sheet_file.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  const cv::Mat sheet = cv::imread(sheet_file.string(), cv::IMREAD_COLOR);
  EXPECT_TRUE(SameImage(Tile(sheet, 0, 2), Tile(sheet, 0, 0)));

  // Frame 0 has no file there: named, nothing written.
  const CommandOutput missing = Run("preview " + kSequence.string() + " --frames 0 --masks " + masks.string() +
                                    " --out " + (dir_ / "missing.png").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.stderr_text.find((masks / "0.000000.png").string() + ": missing: the mask of frame 0"),
            std::string::npos)
      << missing.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "missing.png"));
}

TEST_F(PreviewCliTest, FrameOutOfRangeIsNamedAndNothingWritten) {
  ASSERT_TRUE(fs::is_directory(kSequence)) << kSequence;
  const fs::path sheet_file = dir_ / "sheet.png";
  const CommandOutput out = Run("preview " + kSequence.string() + " --frames 0,40 --out " + sheet_file.string());
  EXPECT_EQ(out.exit_code, 1);
  EXPECT_NE(out.stderr_text.find("frame 40 out of range (0..39)"), std::string::npos) << out.stderr_text;
  EXPECT_FALSE(fs::exists(sheet_file));
}

}  // namespace
