#include "slam/orb_descriptor.h"

#include <gtest/gtest.h>

namespace segslam::slam {
namespace {

TEST(OrbDescriptorTest, HammingDistanceCountsDifferingBits) {
  OrbDescriptor a{};
  OrbDescriptor b{};
  EXPECT_EQ(DescriptorDistance(a, b), 0);
  b[0] = 0b1011;     // 3 bits
  b[31] = 0xFF;      // 8 bits
  b[13] = 0x80;      // 1 bit
  EXPECT_EQ(DescriptorDistance(a, b), 12);
  a.fill(0xFF);
  b.fill(0x00);
  EXPECT_EQ(DescriptorDistance(a, b), 256);
}

TEST(OrbDescriptorTest, RowOfMatrixRoundTrips) {
  cv::Mat descriptors(3, kOrbDescriptorBytes, CV_8U);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < kOrbDescriptorBytes; ++c) descriptors.at<std::uint8_t>(r, c) = r * 40 + c;
  const OrbDescriptor row1 = DescriptorFromRow(descriptors, 1);
  for (int c = 0; c < kOrbDescriptorBytes; ++c) EXPECT_EQ(row1[c], 40 + c);
  EXPECT_EQ(DescriptorDistance(descriptors.ptr<std::uint8_t>(1), row1.data()), 0);
}

}  // namespace
}  // namespace segslam::slam
