#include "slam/orb_descriptor.h"

#include <cstring>

namespace segslam::slam {

int DescriptorDistance(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int i = 0; i < kOrbDescriptorBytes; i += 8) {
    std::uint64_t wa = 0;
    std::uint64_t wb = 0;
    std::memcpy(&wa, a + i, 8);  // memcpy: rows need not be 8-byte aligned
    std::memcpy(&wb, b + i, 8);
    distance += __builtin_popcountll(wa ^ wb);
  }
  return distance;
}

OrbDescriptor DescriptorFromRow(const cv::Mat& descriptors, int row) {
  OrbDescriptor descriptor;
  std::memcpy(descriptor.data(), descriptors.ptr<std::uint8_t>(row), kOrbDescriptorBytes);
  return descriptor;
}

}  // namespace segslam::slam
