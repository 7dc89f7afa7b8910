// Tests of seg/external_masks.h: a hand-made mask folder read back, and every kind of bad
// input answered with an error that names the file and the problem.
#include "seg/external_masks.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "tests/core/test_util.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 64;
constexpr int kHeight = 48;
constexpr int kFrames = 3;

class ExternalMasksTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() /
            ("segslam_ext_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(root_);
    sequence_ = testing::WriteFlatSequence(root_ / "seq", kWidth, kHeight, kFrames, 10.0, 0.5);
    masks_ = root_ / "masks";
    fs::create_directories(masks_);
    for (int i = 0; i < kFrames; ++i) {
      WriteFrame(i, Ids(i), R"({"instances": [{"id": 3, "category_id": 1, "score": 0.93},
                                              {"id": 7, "category": "cup", "score": 0.41},
                                              {"id": 9, "category": "car", "category_id": 3}]})");
    }
  }
  void TearDown() override { fs::remove_all(root_); }

  static cv::Mat Ids(int i) {
    cv::Mat ids(kHeight, kWidth, CV_16U, cv::Scalar(0));
    cv::rectangle(ids, cv::Rect(5 + i, 5, 10, 20), 3, cv::FILLED);
    cv::circle(ids, cv::Point(40, 30), 6, 7, cv::FILLED);
    return ids;  // id 9 is in the table but hidden: no instance
  }
  std::string Stem(int i) const { return TumSequenceWriter::StampName(10.0 + 0.5 * i); }
  void WriteFrame(int i, const cv::Mat& ids, const std::string& json) {
    WriteInstanceMask(masks_ / (Stem(i) + ".png"), ids);
    WriteTable(i, json);
  }
  void WriteTable(int i, const std::string& json) {
    std::ofstream(masks_ / (Stem(i) + ".json")) << json;
  }
  // The message of the error Segment(frame i) throws ("" if none).
  std::string SegmentError(int i) {
    ExternalMaskSegmenter segmenter(masks_, sequence_);
    try {
      segmenter.Segment(sequence_.LoadFrame(i));
    } catch (const Error& e) {
      return e.what();
    }
    ADD_FAILURE() << "expected an error";
    return "";
  }

  fs::path root_, masks_;
  TumSequence sequence_;
};

TEST_F(ExternalMasksTest, ReadsAHandMadeFolder) {
  ExternalMaskSegmenter segmenter(masks_, sequence_);
  EXPECT_EQ(segmenter.name(), "external:" + masks_.string());
  for (int i = 0; i < kFrames; ++i) {
    const FrameSegmentation seg = segmenter.Segment(sequence_.LoadFrame(i));
    EXPECT_EQ(seg.frame_index, i);
    ASSERT_EQ(seg.instances.size(), 2u);
    const InstanceMask& person = seg.instances[0];
    const InstanceMask& cup = seg.instances[1];
    EXPECT_EQ(person.track_id, 3);
    EXPECT_EQ(person.category_id, 1);
    EXPECT_FLOAT_EQ(person.score, 0.93f);
    EXPECT_EQ(cup.track_id, 7);
    EXPECT_EQ(cup.category_id, 47);
    EXPECT_FLOAT_EQ(cup.score, 0.41f);
    EXPECT_EQ(person.mask.type(), CV_8U);
    EXPECT_EQ(person.bounds, cv::boundingRect(person.mask));
    EXPECT_EQ(cup.bounds, cv::boundingRect(cup.mask));
    // Round trip: the id image of the segmentation is the file.
    const cv::Mat back = seg.ToIdImage(cv::Size(kWidth, kHeight));
    EXPECT_EQ(cv::countNonZero(back != Ids(i)), 0);
  }
}

TEST_F(ExternalMasksTest, ScoreDefaultsToOne) {
  WriteTable(0, R"({"instances": [{"id": 3, "category_id": 1}, {"id": 7, "category_id": 47}]})");
  ExternalMaskSegmenter segmenter(masks_, sequence_);
  const FrameSegmentation seg = segmenter.Segment(sequence_.LoadFrame(0));
  ASSERT_EQ(seg.instances.size(), 2u);
  EXPECT_EQ(seg.instances[0].score, 1.0f);
}

TEST_F(ExternalMasksTest, FolderThatSkipsAFrame) {
  fs::remove(masks_ / (Stem(1) + ".png"));
  try {
    ExternalMaskSegmenter segmenter(masks_, sequence_);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(Stem(1) + ".png"), std::string::npos) << message;
    EXPECT_NE(message.find("frame 1"), std::string::npos) << message;
  }
  // A missing table is named the same way.
  WriteInstanceMask(masks_ / (Stem(1) + ".png"), Ids(1));
  fs::remove(masks_ / (Stem(2) + ".json"));
  try {
    ExternalMaskSegmenter segmenter(masks_, sequence_);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(Stem(2) + ".json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ExternalMaskSegmenter(root_ / "nowhere", sequence_), Error);
}

// segslam's writers record the sequence a folder was made for: another sequence with
// the same stamps (the other pass of a generated dataset, another dataset) is refused,
// and a folder without a record (an external tool's) is read as before.
TEST_F(ExternalMasksTest, FolderRecordedForAnotherSequenceIsRefused) {
  WriteMaskFolderRecord(masks_, sequence_);
  EXPECT_NO_THROW(ExternalMaskSegmenter(masks_, sequence_));
  const TumSequence other = testing::WriteFlatSequence(root_ / "other", kWidth, kHeight, kFrames, 10.0, 0.5);
  WriteColorImage(other.dir() / other.entries().front().rgb_file,
                  cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(10, 200, 30)));
  const std::string error = testing::ErrorMessage([&] { ExternalMaskSegmenter(masks_, other); });
  EXPECT_NE(error.find((masks_ / "segslam_sequence.json").string() + ": these masks were made for " + sequence_.dir().string()),
            std::string::npos)
      << error;
  fs::remove(masks_ / "segslam_sequence.json");
  EXPECT_NO_THROW(ExternalMaskSegmenter(masks_, other));
}

// A run cut with --frames N writes masks for its N frames; a run cut the same way reads
// them back, and a longer one is refused naming the first frame without its files.
TEST_F(ExternalMasksTest, FolderOfTheFirstFramesServesARunOfThoseFrames) {
  fs::remove(masks_ / (Stem(2) + ".png"));
  fs::remove(masks_ / (Stem(2) + ".json"));
  ExternalMaskSegmenter first_two(masks_, sequence_, 2);
  EXPECT_EQ(first_two.Segment(sequence_.LoadFrame(1)).instances.size(), 2u);
  EXPECT_THROW(ExternalMaskSegmenter(masks_, sequence_, 3), Error);
  EXPECT_THROW(ExternalMaskSegmenter(masks_, sequence_), Error);
}

TEST_F(ExternalMasksTest, WrongSize) {
  WriteInstanceMask(masks_ / (Stem(0) + ".png"), cv::Mat(20, 30, CV_16U, cv::Scalar(0)));
  const std::string message = SegmentError(0);
  EXPECT_NE(message.find(Stem(0) + ".png"), std::string::npos) << message;
  EXPECT_NE(message.find("30x20"), std::string::npos) << message;
  EXPECT_NE(message.find("64x48"), std::string::npos) << message;
}

TEST_F(ExternalMasksTest, EightBitPng) {
  cv::Mat eight_bit;
  Ids(0).convertTo(eight_bit, CV_8U);
  ASSERT_TRUE(cv::imwrite((masks_ / (Stem(0) + ".png")).string(), eight_bit));
  const std::string message = SegmentError(0);
  EXPECT_NE(message.find(Stem(0) + ".png"), std::string::npos) << message;
  EXPECT_NE(message.find("16-bit"), std::string::npos) << message;
  EXPECT_NE(message.find("CV_8UC1"), std::string::npos) << message;
}

TEST_F(ExternalMasksTest, IdMissingFromTable) {
  WriteTable(1, R"({"instances": [{"id": 3, "category_id": 1, "score": 0.5}]})");
  const std::string message = SegmentError(1);
  EXPECT_NE(message.find(Stem(1) + ".png"), std::string::npos) << message;
  EXPECT_NE(message.find("id 7"), std::string::npos) << message;
  EXPECT_NE(message.find("no entry"), std::string::npos) << message;
}

TEST_F(ExternalMasksTest, UnknownCategory) {
  WriteTable(0, R"({"instances": [{"id": 3, "category_id": 12}, {"id": 7, "category_id": 47}]})");
  std::string message = SegmentError(0);
  EXPECT_NE(message.find(Stem(0) + ".json"), std::string::npos) << message;
  EXPECT_NE(message.find("unknown COCO category_id 12"), std::string::npos) << message;
  WriteTable(0, R"({"instances": [{"id": 3, "category": "unicorn"}, {"id": 7, "category_id": 47}]})");
  message = SegmentError(0);
  EXPECT_NE(message.find("unknown COCO category \"unicorn\""), std::string::npos) << message;
  WriteTable(0, R"({"instances": [{"id": 3, "category": "car", "category_id": 1}]})");
  message = SegmentError(0);
  EXPECT_NE(message.find("not \"car\""), std::string::npos) << message;
  WriteTable(0, R"({"instances": [{"id": 3}]})");
  message = SegmentError(0);
  EXPECT_NE(message.find("needs \"category_id\" or \"category\""), std::string::npos) << message;
}

TEST_F(ExternalMasksTest, ScoreOutOfRange) {
  WriteTable(2, R"({"instances": [{"id": 3, "category_id": 1, "score": 1.5},
                                  {"id": 7, "category_id": 47}]})");
  const std::string message = SegmentError(2);
  EXPECT_NE(message.find(Stem(2) + ".json"), std::string::npos) << message;
  EXPECT_NE(message.find("score 1.5 is outside [0, 1]"), std::string::npos) << message;
}

TEST_F(ExternalMasksTest, MalformedTables) {
  WriteTable(0, "{not json");
  EXPECT_NE(SegmentError(0).find(Stem(0) + ".json"), std::string::npos);
  WriteTable(0, R"({"detections": []})");
  EXPECT_NE(SegmentError(0).find("\"instances\" array"), std::string::npos);
  WriteTable(0, R"({"instances": [{"id": 3, "category_id": 1}, {"id": 3, "category_id": 1}]})");
  EXPECT_NE(SegmentError(0).find("appears twice"), std::string::npos);
  WriteTable(0, R"({"instances": [{"id": 0, "category_id": 1}]})");
  EXPECT_NE(SegmentError(0).find("outside 1..65535"), std::string::npos);
  WriteTable(0, R"({"instances": [{"id": 3, "category_id": 1, "label": "x"}]})");
  EXPECT_NE(SegmentError(0).find("unknown key \"label\""), std::string::npos);
}

TEST_F(ExternalMasksTest, FrameIndexOutOfRange) {
  ExternalMaskSegmenter segmenter(masks_, sequence_);
  RgbdFrame frame = sequence_.LoadFrame(0);
  frame.index = kFrames;
  EXPECT_THROW(segmenter.Segment(frame), Error);
}

}  // namespace
}  // namespace segslam::seg
