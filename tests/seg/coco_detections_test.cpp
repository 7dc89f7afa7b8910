// Tests of seg/coco_detections.h on a hand-made three-frame sequence: results files and
// dataset files, each way of naming a frame and a class, overlaps, the score threshold,
// the written folder read back by ExternalMaskSegmenter, and every kind of bad input.
#include "seg/coco_detections.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "core/coco_rle.h"
#include "core/error.h"
#include "seg/external_masks.h"
#include "tests/core/test_util.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kWidth = 40;
constexpr int kHeight = 30;
constexpr int kFrames = 3;

class CocoDetectionsTest : public testing::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    sequence_ = testing::WriteFlatSequence(dir() / "seq", kWidth, kHeight, kFrames, 20.0, 0.25);
  }

  std::string Stem(int i) const { return TumSequenceWriter::StampName(20.0 + 0.25 * i); }

  static cv::Mat Box(const cv::Rect& box) {
    cv::Mat mask(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
    mask(box).setTo(1);
    return mask;
  }
  static json CompressedRle(const cv::Mat& mask) {
    return {{"size", {kHeight, kWidth}}, {"counts", EncodeCocoRleString(CocoRleCounts(mask))}};
  }
  fs::path Write(const std::string& name, const json& content) const {
    const fs::path path = dir() / name;
    std::ofstream(path) << content.dump();
    return path;
  }
  std::string ReadError(const fs::path& file, const CocoImportOptions& options = {}) const {
    return testing::ErrorMessage([&] { CocoDetections::Read(file, sequence_, options); });
  }

  TumSequence sequence_;
};

// A results file as ultralytics writes it for file names that are not numbers: the
// image_id is the stem. Scores order the ids; the higher score wins an overlap.
TEST_F(CocoDetectionsTest, ResultsListWithStemImageIds) {
  const cv::Mat person = Box(cv::Rect(2, 3, 10, 20));
  const cv::Mat cup = Box(cv::Rect(8, 10, 6, 6));  // overlaps the person's right edge
  const json results = json::array({
      {{"image_id", Stem(1)}, {"category_id", 47}, {"segmentation", CompressedRle(cup)}, {"score", 0.9}},
      {{"image_id", Stem(1)}, {"category_id", 1}, {"segmentation", CompressedRle(person)}, {"score", 0.7}},
      {{"image_id", Stem(1)}, {"category_id", 3}, {"segmentation", CompressedRle(Box({30, 0, 5, 5}))}, {"score", 0.2}},
      {{"image_id", Stem(2)}, {"category_id", 1}, {"segmentation", json::array({json::array({20, 5, 30, 5, 30, 15, 20, 15})})}, {"score", 0.8}},
  });
  const CocoDetections detections = CocoDetections::Read(Write("results.json", results), sequence_, {});
  EXPECT_EQ(detections.counts().detections, 4);
  EXPECT_EQ(detections.counts().below_min_score, 1);
  EXPECT_EQ(detections.counts().kept, 3);
  EXPECT_EQ(detections.counts().frames_with_detections, 2);
  EXPECT_EQ(detections.counts().kept_per_category.at(1), 2);

  EXPECT_TRUE(detections.Frame(0).instances.empty());
  const FrameSegmentation frame1 = detections.Frame(1);
  ASSERT_EQ(frame1.instances.size(), 2u);
  EXPECT_EQ(frame1.instances[0].track_id, 1);
  EXPECT_EQ(frame1.instances[0].category_id, 47);
  EXPECT_FLOAT_EQ(frame1.instances[0].score, 0.9f);
  EXPECT_EQ(frame1.instances[1].track_id, 2);
  EXPECT_EQ(frame1.instances[1].category_id, 1);
  const cv::Mat ids = frame1.ToIdImage(cv::Size(kWidth, kHeight));
  EXPECT_EQ(ids.at<std::uint16_t>(12, 9), 1);   // in both: the cup scores higher
  EXPECT_EQ(ids.at<std::uint16_t>(12, 4), 2);   // the person alone
  EXPECT_EQ(cv::countNonZero(ids == 1), 36);
  EXPECT_EQ(cv::countNonZero(ids == 2), 200 - 4 * 6);  // the cup covers 4 of its columns, 6 rows

  const FrameSegmentation frame2 = detections.Frame(2);
  ASSERT_EQ(frame2.instances.size(), 1u);
  EXPECT_EQ(cv::countNonZero(frame2.instances[0].mask != Box(cv::Rect(20, 5, 10, 10))), 0);
  EXPECT_EQ(frame2.instances[0].bounds, cv::Rect(20, 5, 10, 10));

  // A lower threshold keeps the car.
  CocoImportOptions all;
  all.min_score = 0.0;
  EXPECT_EQ(CocoDetections::Read(dir() / "results.json", sequence_, all).Frame(1).instances.size(), 3u);
}

// Integer image ids through an image list (what `segslam masks images` writes), its
// categories naming the classes of a network with its own numbering.
TEST_F(CocoDetectionsTest, IntegerImageIdsAndOwnCategoriesThroughAnImageList) {
  const json images = {
      {"images", json::array({{{"id", 11}, {"file_name", "/elsewhere/rgb/" + Stem(0) + ".jpg"}},
                              {{"id", 12}, {"file_name", "rgb/" + Stem(2) + ".png"}},
                              {{"id", 13}, {"file_name", "rgb/other_sequence.png"}}})},
      {"categories", json::array({{{"id", 0}, {"name", "person"}}, {{"id", 1}, {"name", "traffic light"}}})}};
  const json results = json::array({
      {{"image_id", 12}, {"category_id", 1}, {"segmentation", CompressedRle(Box({1, 1, 3, 3}))}, {"score", 0.6}},
      {{"image_id", 11}, {"category_id", 0}, {"segmentation", CompressedRle(Box({5, 5, 3, 3}))}, {"score", 0.99}},
      {{"image_id", 13}, {"category_id", 0}, {"segmentation", CompressedRle(Box({5, 5, 3, 3}))}, {"score", 0.99}},
  });
  CocoImportOptions options;
  options.images_file = Write("images.json", images);
  const fs::path results_file = Write("results.json", results);
  const CocoDetections detections = CocoDetections::Read(results_file, sequence_, options);
  EXPECT_EQ(detections.counts().other_images, 1);
  ASSERT_EQ(detections.Frame(0).instances.size(), 1u);
  EXPECT_EQ(detections.Frame(0).instances[0].category_id, 1);   // person
  ASSERT_EQ(detections.Frame(2).instances.size(), 1u);
  EXPECT_EQ(detections.Frame(2).instances[0].category_id, 10);  // traffic light

  // A string image id the list does not hold is a stem (ultralytics' ids beside an image
  // list), and a score equal to the threshold is kept.
  json mixed = results;
  mixed.push_back({{"image_id", Stem(1)}, {"category_id", 0}, {"segmentation", CompressedRle(Box({2, 2, 3, 3}))},
                   {"score", 0.7}});
  CocoImportOptions at_threshold = options;
  at_threshold.min_score = 0.7;
  const CocoDetections with_stem = CocoDetections::Read(Write("mixed.json", mixed), sequence_, at_threshold);
  ASSERT_EQ(with_stem.Frame(1).instances.size(), 1u);
  EXPECT_EQ(with_stem.Frame(1).instances[0].category_id, 1);
  EXPECT_EQ(with_stem.counts().below_min_score, 1);  // image 12's 0.6

  // Without the list an integer image id cannot be placed.
  EXPECT_NE(ReadError(results_file).find("detection 0 (image_id 12): an integer image_id needs the image list"),
            std::string::npos);
  // An id the list does not hold.
  json missing = results;
  missing[1]["image_id"] = 99;
  EXPECT_NE(ReadError(Write("missing.json", missing), options).find("image_id 99 is not in the image list of"),
            std::string::npos);
  // A category the list does not name, and one that is not COCO's.
  json bad_category = results;
  bad_category[0]["category_id"] = 5;
  EXPECT_NE(ReadError(Write("bad_category.json", bad_category), options).find("category_id 5 is not among"),
            std::string::npos);
  json not_coco = images;
  not_coco["categories"][1]["name"] = "lamp post";
  options.images_file = Write("not_coco.json", not_coco);
  EXPECT_NE(ReadError(results_file, options).find("\"lamp post\""), std::string::npos);
}

// A dataset file (ground truth, or a segslam dataset's annotations_coco.json): its own
// image list, crowd regions skipped, no score means 1.
TEST_F(CocoDetectionsTest, DatasetFileWithItsOwnImages) {
  const json dataset = {
      {"images", json::array({{{"id", 1}, {"file_name", "rgb/" + Stem(0) + ".png"}}})},
      {"annotations",
       json::array({{{"id", 1}, {"image_id", 1}, {"category_id", 3}, {"iscrowd", 0},
                     {"segmentation", {{"size", {kHeight, kWidth}}, {"counts", CocoRleCounts(Box({0, 0, 4, 4}))}}}},
                    {{"id", 2}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 1},
                     {"segmentation", {{"size", {kHeight, kWidth}}, {"counts", CocoRleCounts(Box({9, 9, 4, 4}))}}}}})},
      {"categories", json::array({{{"id", 1}, {"name", "person"}}, {{"id", 3}, {"name", "car"}}})}};
  const CocoDetections detections = CocoDetections::Read(Write("dataset.json", dataset), sequence_, {});
  EXPECT_EQ(detections.counts().crowd, 1);
  // iscrowd as a JSON boolean is a crowd region as well.
  json boolean_crowd = dataset;
  boolean_crowd["annotations"][1]["iscrowd"] = true;
  boolean_crowd["annotations"][0]["iscrowd"] = false;
  EXPECT_EQ(CocoDetections::Read(Write("boolean.json", boolean_crowd), sequence_, {}).counts().crowd, 1);
  boolean_crowd["annotations"][1]["iscrowd"] = "yes";
  EXPECT_NE(ReadError(Write("odd_crowd.json", boolean_crowd)).find("iscrowd is neither 0/1 nor true/false"),
            std::string::npos);
  // Polygons of a listed image of another size belong to another image.
  json listed_size = dataset;
  listed_size["images"][0]["width"] = 2 * kWidth;
  listed_size["images"][0]["height"] = 2 * kHeight;
  EXPECT_NE(ReadError(Write("listed_size.json", listed_size)).find("gives its image 80x60, but the sequence's frames "
                                                                   "are 40x30"),
            std::string::npos);
  listed_size["images"][0]["width"] = kWidth;
  listed_size["images"][0]["height"] = kHeight;
  EXPECT_EQ(CocoDetections::Read(Write("listed_size.json", listed_size), sequence_, {}).Frame(0).instances.size(), 1u);
  // An image list that names this sequence's first frame with another image's SHA-256
  // (segslam writes both) was made for another sequence with the same stamps.
  json recorded = dataset;
  recorded["info"] = {{"description", "segslam synthetic sequence other"},
                      {"first_frame", sequence_.entries().front().rgb_file},
                      {"first_frame_sha256", std::string(64, '0')}};
  EXPECT_NE(ReadError(Write("recorded.json", recorded)).find("made for another sequence than"), std::string::npos);
  recorded["info"]["first_frame_sha256"] = sequence_.FirstFrameSha256();
  EXPECT_EQ(CocoDetections::Read(Write("recorded.json", recorded), sequence_, {}).Frame(0).instances.size(), 1u);
  const FrameSegmentation frame0 = detections.Frame(0);
  ASSERT_EQ(frame0.instances.size(), 1u);
  EXPECT_EQ(frame0.instances[0].category_id, 3);
  EXPECT_FLOAT_EQ(frame0.instances[0].score, 1.0f);
  EXPECT_EQ(cv::countNonZero(frame0.instances[0].mask), 16);
}

// What WriteExternalMaskFiles writes, ExternalMaskSegmenter reads back unchanged.
TEST_F(CocoDetectionsTest, WrittenFolderReadsBack) {
  const json results = json::array({
      {{"image_id", Stem(0)}, {"category_id", 1}, {"segmentation", CompressedRle(Box({2, 3, 10, 20}))}, {"score", 0.7}},
      {{"image_id", Stem(0)}, {"category_id", 47}, {"segmentation", CompressedRle(Box({8, 10, 6, 6}))}, {"score", 0.9}},
      {{"image_id", Stem(0)}, {"category_id", 44}, {"segmentation", CompressedRle(Box({9, 11, 2, 2}))}, {"score", 0.8}},
  });
  const CocoDetections detections = CocoDetections::Read(Write("results.json", results), sequence_, {});
  const fs::path folder = dir() / "masks";
  fs::create_directories(folder);
  for (int i = 0; i < kFrames; ++i) {
    const FrameSegmentation masks = detections.Frame(static_cast<size_t>(i));
    WriteExternalMaskFiles(folder, Stem(i), masks.ToIdImage(cv::Size(kWidth, kHeight)), masks);
  }
  ExternalMaskSegmenter reader(folder, sequence_);
  const FrameSegmentation back = reader.Segment(sequence_.LoadFrame(0));
  // The bottle (0.8) lies wholly under the cup (0.9): its entry is written, it has no pixel.
  ASSERT_EQ(back.instances.size(), 2u);
  EXPECT_EQ(back.instances[0].track_id, 1);
  EXPECT_EQ(back.instances[0].category_id, 47);
  EXPECT_FLOAT_EQ(back.instances[0].score, 0.9f);
  EXPECT_EQ(back.instances[1].track_id, 3);
  EXPECT_EQ(back.instances[1].category_id, 1);
  const cv::Mat expected = detections.Frame(0).ToIdImage(cv::Size(kWidth, kHeight));
  EXPECT_EQ(cv::countNonZero(back.ToIdImage(cv::Size(kWidth, kHeight)) != expected), 0);
  EXPECT_TRUE(reader.Segment(sequence_.LoadFrame(1)).instances.empty());
}

// An empty list is a failed or wrong export, not "nothing in view": importing it would
// leave a folder of empty masks that passes for a network's output.
TEST_F(CocoDetectionsTest, EmptyDetectionListIsAnError) {
  EXPECT_NE(ReadError(Write("empty.json", json::array())).find("empty.json: an empty results list: no detection to "
                                                               "import"),
            std::string::npos);
  EXPECT_NE(ReadError(Write("dataset.json", {{"images", json::array()}, {"annotations", json::array()}}))
                .find("dataset.json: \"annotations\" is an empty list"),
            std::string::npos);
}

TEST_F(CocoDetectionsTest, BadInputIsNamed) {
  const json good = {{"image_id", Stem(0)}, {"category_id", 1}, {"segmentation", CompressedRle(Box({0, 0, 2, 2}))},
                     {"score", 0.9}};
  auto error_with = [&](const std::function<void(json&)>& spoil) {
    json entry = good;
    spoil(entry);
    return ReadError(Write("bad.json", json::array({good, entry})));
  };
  EXPECT_NE(error_with([](json& e) { e.erase("segmentation"); })
                .find("bad.json: detection 1 needs \"image_id\", \"category_id\" and \"segmentation\""),
            std::string::npos);
  EXPECT_NE(error_with([](json& e) { e["score"] = 1.5; }).find("detection 1 (image_id " + Stem(0) + "): score is not"),
            std::string::npos);
  EXPECT_NE(error_with([](json& e) { e["category_id"] = 91; }).find("category_id 91 is not a COCO category id"),
            std::string::npos);
  EXPECT_NE(error_with([](json& e) { e["image_id"] = 1.5; }).find("neither an integer nor a string"),
            std::string::npos);
  EXPECT_NE(ReadError(Write("object.json", {{"images", json::array()}})).find("expected a COCO results list"),
            std::string::npos);
  std::ofstream(dir() / "broken.json") << "[{\"image_id\": ";
  EXPECT_NE(ReadError(dir() / "broken.json").find("broken.json"), std::string::npos);
  EXPECT_NE(ReadError(dir() / "absent.json").find("absent.json"), std::string::npos);

  // Every detection on images this sequence does not have: the wrong file.
  json foreign = json::array({good});
  foreign[0]["image_id"] = "1305031102.175304";
  EXPECT_NE(ReadError(Write("foreign.json", foreign)).find("none of its 1 detections is on a frame of"),
            std::string::npos);

  // A mask made for another image size is named when its frame is decoded.
  json other_size = json::array({good});
  other_size[0]["segmentation"]["size"] = {480, 640};
  const CocoDetections detections = CocoDetections::Read(Write("size.json", other_size), sequence_, {});
  const std::string error = testing::ErrorMessage([&] { detections.Frame(0); });
  EXPECT_NE(error.find("size.json: detection 0 (image_id " + Stem(0) +
                       "): RLE size [480, 640] (height, width) is not the image's [30, 40]"),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace segslam::seg
