// Tests of core/coco_rle.h: compressed RLE strings against values worked out by hand from
// pycocotools' rleToString, masks against counts and polygons drawn on paper, and every
// malformed input refused with the origin in the message.
#include "core/coco_rle.h"

#include <random>

#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/core/test_util.h"

namespace segslam {
namespace {

using Counts = std::vector<std::uint32_t>;

// Each string below by hand: a count (from the fourth on, less the count two before it)
// in 5-bit groups, least significant first; character = 48 + group (+32 if more follow).
TEST(CocoRleStringTest, EncodesAndDecodesHandWorkedValues) {
  // 3 -> '3'. 32 -> groups 0 (more) and 1 -> 'P' '1'.
  EXPECT_EQ(EncodeCocoRleString({3}), "3");
  EXPECT_EQ(EncodeCocoRleString({32}), "P1");
  // [5, 2, 3, 1]: the fourth is stored as 1 - 2 = -1: group 31 with the sign bit set and
  // nothing above it -> 'O' (79).
  EXPECT_EQ(EncodeCocoRleString({5, 2, 3, 1}), "523O");
  // [0, 100, 50, 10, 60]: 0 -> '0'; 100 = 4 + 3*32 -> 'T' '3'; 50 = 18 + 1*32, and 18 has
  // bit 4 set, so a group 1 must follow -> 'b' '1'; 10 - 100 = -90 = 6 - 3*32 -> 'V' then
  // -3 -> group 29 with the sign bit, the end -> 'M'; 60 - 50 = 10 -> ':'.
  EXPECT_EQ(EncodeCocoRleString({0, 100, 50, 10, 60}), "0T3b1VM:");

  EXPECT_EQ(DecodeCocoRleString("3", "t"), Counts({3}));
  EXPECT_EQ(DecodeCocoRleString("P1", "t"), Counts({32}));
  EXPECT_EQ(DecodeCocoRleString("523O", "t"), Counts({5, 2, 3, 1}));
  EXPECT_EQ(DecodeCocoRleString("0T3b1VM:", "t"), Counts({0, 100, 50, 10, 60}));
  EXPECT_EQ(DecodeCocoRleString("", "t"), Counts());
}

TEST(CocoRleStringTest, RoundTripsLargeAndFallingCounts) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 200; ++trial) {
    Counts counts(1 + random() % 40);
    for (std::uint32_t& count : counts) count = random() % (trial % 2 == 0 ? 50u : 4000000u);
    EXPECT_EQ(DecodeCocoRleString(EncodeCocoRleString(counts), "t"), counts);
  }
  const Counts extremes = {0, 4294967295u, 0, 1, 4294967295u, 0};
  EXPECT_EQ(DecodeCocoRleString(EncodeCocoRleString(extremes), "t"), extremes);
}

TEST(CocoRleStringTest, MalformedStringsNameTheOriginAndTheProblem) {
  EXPECT_NE(testing::ErrorMessage([] { DecodeCocoRleString("0T", "det.json: detection 4"); }).find("det.json: detection 4: "),
            std::string::npos);
  EXPECT_NE(testing::ErrorMessage([] { DecodeCocoRleString("0T", "o"); }).find("cut short"), std::string::npos);
  EXPECT_NE(testing::ErrorMessage([] { DecodeCocoRleString("12~", "o"); }).find("'~' at position 2"), std::string::npos);
  // After 5, 2, 3: 'L' is group 28, the sign bit set, i.e. -4, and 2 - 4 = -2 pixels.
  EXPECT_NE(testing::ErrorMessage([] { DecodeCocoRleString("523L", "o"); }).find("count 3 decodes to -2, outside 0..2^32-1"),
            std::string::npos);
  EXPECT_NE(testing::ErrorMessage([] { DecodeCocoRleString(std::string(13, 'P'), "o"); }).find("longer than 12"),
            std::string::npos);
}

// A 3-row, 4-column mask; column-major order runs down each column.
//   . # . .
//   . # # .
//   . . # #
TEST(CocoRleMaskTest, CountsRunDownTheColumns) {
  cv::Mat mask = (cv::Mat_<std::uint8_t>(3, 4) << 0, 1, 0, 0,  //
                  0, 1, 1, 0,                                 //
                  0, 0, 1, 1);
  // Column 0: 3 background; column 1: 2 inside, 1 out; column 2: 1 out, 2 in; column 3:
  // 2 out, 1 in.
  const Counts expected = {3, 2, 2, 2, 2, 1};
  EXPECT_EQ(CocoRleCounts(mask), expected);
  const cv::Mat decoded = CocoRleToMask(expected, mask.size(), "t");
  EXPECT_EQ(cv::countNonZero(decoded != mask), 0);
  // A mask whose first pixel is inside starts with an empty background run.
  cv::Mat full(2, 2, CV_8UC1, cv::Scalar(5));
  EXPECT_EQ(CocoRleCounts(full), Counts({0, 4}));
  EXPECT_EQ(cv::countNonZero(CocoRleToMask({0, 4}, full.size(), "t")), 4);
}

TEST(CocoRleMaskTest, RandomMasksRoundTrip) {
  std::mt19937 random(3);
  for (int trial = 0; trial < 20; ++trial) {
    cv::Mat mask(17 + trial, 23, CV_8UC1);
    cv::randu(mask, 0, 2);
    const cv::Mat decoded = CocoRleToMask(DecodeCocoRleString(EncodeCocoRleString(CocoRleCounts(mask)), "t"),
                                          mask.size(), "t");
    EXPECT_EQ(cv::countNonZero(decoded != mask), 0) << "trial " << trial;
  }
}

TEST(CocoRleMaskTest, CountsThatDoNotCoverTheImageAreRefused) {
  const std::string error = testing::ErrorMessage([] { CocoRleToMask({3, 2}, cv::Size(4, 3), "det.json: detection 2"); });
  EXPECT_NE(error.find("det.json: detection 2: RLE counts cover 5 pixels, a 4x3 mask has 12"), std::string::npos)
      << error;
}

// Pixel (x, y) covers [x, x+1] x [y, y+1] in COCO's polygon coordinates.
TEST(CocoPolygonTest, PixelsInsideAreThoseWhoseCentresAre) {
  // A rectangle from (1.2, 1.2) to (3.8, 2.8): centres 1.5, 2.5, 3.5 across, 1.5, 2.5 down.
  const cv::Mat mask = CocoPolygonsToMask({{1.2, 1.2, 3.8, 1.2, 3.8, 2.8, 1.2, 2.8}}, cv::Size(6, 5), "t");
  cv::Mat expected(5, 6, CV_8UC1, cv::Scalar(0));
  expected(cv::Rect(1, 1, 3, 2)).setTo(1);
  EXPECT_EQ(cv::countNonZero(mask != expected), 0) << mask;

  // A right triangle (0, 0), (8, 0), (0, 8): a centre (x + 0.5, y + 0.5) is inside when
  // x + y + 1 < 8, i.e. x + y <= 6, 28 pixels; the diagonal's pixels (x + y = 7) have
  // their centres on the edge and may go either way.
  const cv::Mat triangle = CocoPolygonsToMask({{0, 0, 8, 0, 0, 8}}, cv::Size(10, 10), "t");
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 10; ++x) {
      if (x + y == 7) continue;
      EXPECT_EQ(triangle.at<std::uint8_t>(y, x), x + y <= 6 ? 1 : 0) << "x " << x << " y " << y;
    }
  }
}

TEST(CocoPolygonTest, SeveralPolygonsAreAUnion) {
  const cv::Mat mask = CocoPolygonsToMask({{0.2, 0.2, 4.8, 0.2, 4.8, 2.8, 0.2, 2.8},  // x 0..4, y 0..2
                                           {2.2, 1.2, 6.8, 1.2, 6.8, 3.8, 2.2, 3.8}},  // x 2..6, y 1..3
                                          cv::Size(8, 5), "t");
  EXPECT_EQ(cv::countNonZero(mask), 15 + 15 - 6);
  EXPECT_EQ(mask.at<std::uint8_t>(2, 3), 1);  // in both
}

// Coordinates far beyond int (valid JSON numbers) used to overflow the conversion of the
// crossings to columns, undefined behaviour that on x86 filled whole rows.
TEST(CocoPolygonTest, HugeCoordinatesGiveTheMaskOfThePartInTheImage) {
  // The triangle (0, 0), (3e9, 0), (0, 10) covers all 8 columns of rows 0..9 (its
  // slanted edge crosses row 9's centre line at x = 1.5e8).
  const cv::Mat triangle = CocoPolygonsToMask({{0, 0, 3e9, 0, 0, 10}}, cv::Size(8, 12), "t");
  cv::Mat expected(12, 8, CV_8UC1, cv::Scalar(0));
  expected.rowRange(0, 10).setTo(1);
  EXPECT_EQ(cv::countNonZero(triangle != expected), 0) << triangle;

  // Entirely right of or left of the image: nothing.
  EXPECT_EQ(cv::countNonZero(CocoPolygonsToMask({{3e9, 0, 4e9, 0, 4e9, 10, 3e9, 10}}, cv::Size(8, 12), "t")), 0);
  EXPECT_EQ(cv::countNonZero(CocoPolygonsToMask({{-4e9, 0, -3e9, 0, -3e9, 10, -4e9, 10}}, cv::Size(8, 12), "t")),
            0);
  // Corners near the largest double: row 0's crossing of the first edge is 0 * inf, NaN;
  // the rows below cross it at +inf. The triangle's tip lies on row 0's centre line.
  const cv::Mat extreme = CocoPolygonsToMask({{-1e308, 0.5, 1e308, 1e308, -1e308, 1e308}}, cv::Size(8, 12), "t");
  expected.setTo(1);
  expected.row(0).setTo(0);
  EXPECT_EQ(cv::countNonZero(extreme != expected), 0) << extreme;
}

TEST(CocoSegmentationTest, DecodesEveryEncoding) {
  cv::Mat mask(6, 5, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(1, 2, 3, 3)).setTo(1);
  const Counts counts = CocoRleCounts(mask);
  const nlohmann::json uncompressed = {{"size", {6, 5}}, {"counts", counts}};
  const nlohmann::json compressed = {{"size", {6, 5}}, {"counts", EncodeCocoRleString(counts)}};
  const nlohmann::json polygons = nlohmann::json::array({nlohmann::json::array({1, 2, 4, 2, 4, 5, 1, 5})});
  for (const nlohmann::json& segmentation : {uncompressed, compressed}) {
    EXPECT_EQ(cv::countNonZero(DecodeCocoSegmentation(segmentation, cv::Size(5, 6), "t") != mask), 0);
  }
  // The polygon's corners lie on pixel corners, so its interior holds the same centres.
  EXPECT_EQ(cv::countNonZero(DecodeCocoSegmentation(polygons, cv::Size(5, 6), "t") != mask), 0);
}

TEST(CocoSegmentationTest, MalformedValuesNameTheOrigin) {
  const cv::Size size(5, 6);
  auto error_of = [&](const nlohmann::json& segmentation) {
    return testing::ErrorMessage([&] { DecodeCocoSegmentation(segmentation, size, "r.json: detection 1"); });
  };
  EXPECT_NE(error_of({{"size", {480, 640}}, {"counts", "0"}}).find("RLE size [480, 640] (height, width) is not the "
                                                                    "image's [6, 5]"),
            std::string::npos);
  EXPECT_NE(error_of({{"size", {6, 5}}}).find("neither a list of polygons nor an RLE"), std::string::npos);
  EXPECT_NE(error_of({{"size", {6}}, {"counts", "0"}}).find("not [height, width]"), std::string::npos);
  EXPECT_NE(error_of({{"size", {6, 5}}, {"counts", {30, -1}}}).find("other than a count"), std::string::npos);
  EXPECT_NE(error_of({{"size", {6, 5}}, {"counts", 3}}).find("neither a string nor a list"), std::string::npos);
  EXPECT_NE(error_of(nlohmann::json::array({nlohmann::json::array({1, 2, 3})})).find("polygon 0 has 3 coordinates"),
            std::string::npos);
  EXPECT_NE(error_of(nlohmann::json::array({"x"})).find("polygon 0 is not a list"), std::string::npos);
  EXPECT_NE(error_of("rle").find("r.json: detection 1: "), std::string::npos);
}

}  // namespace
}  // namespace segslam
