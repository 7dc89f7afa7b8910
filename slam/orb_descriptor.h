// ORB descriptors: 256-bit binary strings stored as 32 bytes (one row of a CV_8U
// matrix with 32 columns, as cv::ORB computes them).
#pragma once

#include <array>
#include <cstdint>

#include <opencv2/core/mat.hpp>

namespace segslam::slam {

constexpr int kOrbDescriptorBytes = 32;
using OrbDescriptor = std::array<std::uint8_t, kOrbDescriptorBytes>;

// Hamming distance between two 32-byte descriptors, 0..256.
int DescriptorDistance(const std::uint8_t* a, const std::uint8_t* b);
inline int DescriptorDistance(const OrbDescriptor& a, const OrbDescriptor& b) {
  return DescriptorDistance(a.data(), b.data());
}

// Row `row` of an N x 32 CV_8U descriptor matrix as an OrbDescriptor.
OrbDescriptor DescriptorFromRow(const cv::Mat& descriptors, int row);

}  // namespace segslam::slam
