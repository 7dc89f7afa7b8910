#include "core/image_io.h"

#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using ImageIoTest = testing::TempDirTest;

TEST_F(ImageIoTest, DepthRoundTripWithinOneStep) {
  constexpr double kDepthFactor = 5000;
  cv::Mat depth(48, 64, CV_32F);
  cv::RNG rng(11);
  rng.fill(depth, cv::RNG::UNIFORM, 0.2, 13.0);
  depth.at<float>(0, 0) = 0.0f;                                         // No depth.
  depth.at<float>(0, 1) = std::numeric_limits<float>::quiet_NaN();      // Invalid.
  depth.at<float>(0, 2) = -1.0f;                                        // Invalid.
  depth.at<float>(0, 3) = 20.0f;                                        // > 65535 / 5000.
  depth.at<float>(0, 4) = std::numeric_limits<float>::infinity();       // Invalid.
  const auto path = dir() / "d.png";
  WriteDepthImage(path, depth, kDepthFactor);
  const cv::Mat back = ReadDepthImage(path, kDepthFactor);
  ASSERT_EQ(back.type(), CV_32FC1);
  ASSERT_EQ(back.size(), depth.size());
  for (int c = 0; c < 5; ++c) EXPECT_EQ(back.at<float>(0, c), 0.0f) << "column " << c;
  // Rounding to the nearest step: error at most half a step (plus float rounding).
  const double max_error_m = 0.5 / kDepthFactor + 1e-6;
  for (int r = 1; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      ASSERT_NEAR(back.at<float>(r, c), depth.at<float>(r, c), max_error_m);
    }
  }
  // Stored value is metres * factor.
  EXPECT_EQ(cv::imread(path.string(), cv::IMREAD_UNCHANGED).type(), CV_16UC1);
}

TEST_F(ImageIoTest, MaskRoundTripExact) {
  cv::Mat ids(30, 40, CV_16UC1);
  cv::RNG rng(3);
  rng.fill(ids, cv::RNG::UNIFORM, 0, 65536);
  const auto path = dir() / "m.png";
  WriteInstanceMask(path, ids);
  const cv::Mat back = ReadInstanceMask(path);
  ASSERT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(back, ids, cv::NORM_INF), 0.0);

  // Rows of a view into a wider image are not contiguous; the encoder walks them one by one.
  const cv::Mat view = ids(cv::Rect(3, 2, 31, 17));
  ASSERT_FALSE(view.isContinuous());
  const std::vector<unsigned char> png = EncodeInstanceMaskPng(view);
  const cv::Mat decoded = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(decoded.type(), CV_16UC1);
  ASSERT_EQ(decoded.size(), view.size());
  EXPECT_EQ(cv::norm(decoded, view, cv::NORM_INF), 0.0);
  EXPECT_THROW(EncodeInstanceMaskPng(cv::Mat(4, 4, CV_8UC1, cv::Scalar(1))), Error);
}

TEST_F(ImageIoTest, ColorRoundTripAndGrayConversion) {
  cv::Mat bgr(10, 12, CV_8UC3);
  cv::RNG rng(5);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
  WriteColorImage(dir() / "c.png", bgr);
  const cv::Mat back = ReadColorImage(dir() / "c.png");
  ASSERT_EQ(back.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(back, bgr, cv::NORM_INF), 0.0);
  // A view's rows are not contiguous; channels stay in BGR order.
  const cv::Mat view = bgr(cv::Rect(1, 2, 9, 7));
  const cv::Mat decoded = cv::imdecode(EncodeColorPng(view), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(decoded.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(decoded, view, cv::NORM_INF), 0.0);

  cv::Mat gray(10, 12, CV_8UC1, cv::Scalar(77));
  cv::imwrite((dir() / "g.png").string(), gray);
  const cv::Mat converted = ReadColorImage(dir() / "g.png");
  ASSERT_EQ(converted.type(), CV_8UC3);
  EXPECT_EQ(converted.at<cv::Vec3b>(3, 4), cv::Vec3b(77, 77, 77));
}

TEST_F(ImageIoTest, WrongTypesAreErrorsNamingFileAndType) {
  cv::Mat rgb8(10, 12, CV_8UC3, cv::Scalar(1, 2, 3));
  const auto path = dir() / "c.png";
  cv::imwrite(path.string(), rgb8);
  std::string message = ErrorMessage([&] { ReadDepthImage(path, 5000); });
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find("CV_8UC3"), std::string::npos) << message;
  message = ErrorMessage([&] { ReadInstanceMask(path); });
  EXPECT_NE(message.find("CV_8UC3"), std::string::npos) << message;

  cv::Mat depth16(10, 12, CV_16UC1, cv::Scalar(1000));
  cv::imwrite((dir() / "d.png").string(), depth16);
  message = ErrorMessage([&] { ReadColorImage(dir() / "d.png"); });
  EXPECT_NE(message.find("8-bit"), std::string::npos) << message;

  EXPECT_THROW(WriteInstanceMask(dir() / "x.png", rgb8), Error);
  EXPECT_THROW(WriteColorImage(dir() / "x.png", depth16), Error);
  EXPECT_THROW(WriteDepthImage(dir() / "x.png", depth16, 5000), Error);
  EXPECT_THROW(WriteDepthImage(dir() / "x.jpg", cv::Mat(2, 2, CV_32F, 1.0f), 5000), Error);
  EXPECT_THROW(ReadDepthImage(dir() / "d.png", 0), Error);
  EXPECT_FALSE(std::filesystem::exists(dir() / "x.png"));
}

TEST_F(ImageIoTest, MissingAndCorruptFiles) {
  std::string message = ErrorMessage([&] { ReadColorImage(dir() / "none.png"); });
  EXPECT_NE(message.find("none.png"), std::string::npos) << message;
  EXPECT_NE(message.find("does not exist"), std::string::npos) << message;
  // A truncated PNG.
  const std::vector<unsigned char> png =
      EncodeInstanceMaskPng(cv::Mat(20, 20, CV_16UC1, cv::Scalar(9)));
  const std::string half(png.begin(), png.begin() + png.size() / 2);
  std::ofstream(dir() / "bad.png", std::ios::binary) << half;
  message = ErrorMessage([&] { ReadDepthImage(dir() / "bad.png", 5000); });
  EXPECT_NE(message.find("bad.png"), std::string::npos) << message;
}

TEST(CvTypeName, Names) {
  EXPECT_EQ(CvTypeName(CV_16UC1), "CV_16UC1");
  EXPECT_EQ(CvTypeName(CV_32FC3), "CV_32FC3");
}

}  // namespace
}  // namespace segslam

namespace segslam {
namespace {

// PNG's CRC-32 (ISO 3309) of `bytes`, for a header patched by hand.
std::uint32_t PngCrc(const unsigned char* bytes, std::size_t size) {
  std::uint32_t crc = 0xffffffffu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= bytes[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xffffffffu;
}

// A 4x4 16-bit PNG whose header claims `width` x `height`: its pixel data cannot fill
// that, so a decoder run on it fails; only a check of the header gives a size.
std::string PngClaimingSize(std::uint32_t width, std::uint32_t height) {
  const std::vector<unsigned char> real = EncodeInstanceMaskPng(cv::Mat(4, 4, CV_16UC1, cv::Scalar(7)));
  std::vector<unsigned char> png = real;
  // Signature (8), IHDR length (4), "IHDR" (4), then width and height, big-endian.
  constexpr std::size_t kIhdrType = 12, kWidth = 16, kIhdrCrc = 29;
  for (int i = 0; i < 4; ++i) {
    png[kWidth + i] = static_cast<unsigned char>(width >> (24 - 8 * i));
    png[kWidth + 4 + i] = static_cast<unsigned char>(height >> (24 - 8 * i));
  }
  const std::uint32_t crc = PngCrc(&png[kIhdrType], kIhdrCrc - kIhdrType);
  for (int i = 0; i < 4; ++i) png[kIhdrCrc + i] = static_cast<unsigned char>(crc >> (24 - 8 * i));
  return std::string(png.begin(), png.end());
}

TEST_F(ImageIoTest, PngHeaderIsReadWithoutDecoding) {
  const auto path = dir() / "huge.png";
  std::ofstream(path, std::ios::binary) << PngClaimingSize(20000, 20000);
  const std::optional<PngHeader> header = ReadPngHeader(path);
  ASSERT_TRUE(header.has_value());
  EXPECT_EQ(header->width, 20000);
  EXPECT_EQ(header->height, 20000);
  EXPECT_EQ(header->bit_depth, 16);
  EXPECT_EQ(header->channels, 1);
  // Not a PNG: no header to read, the decoder decides.
  std::ofstream(dir() / "text.png") << "not an image";
  EXPECT_FALSE(ReadPngHeader(dir() / "text.png").has_value());
}

// A small file claiming a huge image is refused from its header: the message gives the
// claimed size, which the decoder, failing on the missing pixels, could not have given.
TEST_F(ImageIoTest, OversizedPngIsRefusedBeforeDecoding) {
  const auto path = dir() / "huge.png";
  std::ofstream(path, std::ios::binary) << PngClaimingSize(20000, 20000);
  EXPECT_NE(ErrorMessage([&] { ReadDepthImage(path, 5000, cv::Size(640, 480)); })
                .find("huge.png: image is 20000x20000, camera expects 640x480"),
            std::string::npos);
  EXPECT_NE(ErrorMessage([&] { ReadInstanceMask(path, cv::Size(640, 480)); })
                .find("huge.png: mask is 20000x20000, the sequence's images are 640x480"),
            std::string::npos);
  // Without an expected size, the largest image any reader takes.
  EXPECT_NE(ErrorMessage([&] { ReadDepthImage(path, 5000); }).find("image is 20000x20000, larger than any camera image"),
            std::string::npos);
  // The type too: 16 bits are no colour image.
  std::ofstream(dir() / "small.png", std::ios::binary) << PngClaimingSize(640, 480);
  EXPECT_NE(ErrorMessage([&] { ReadColorImage(dir() / "small.png", cv::Size(640, 480)); })
                .find("colour image must be 8-bit, found CV_16UC1"),
            std::string::npos);
}

}  // namespace
}  // namespace segslam
