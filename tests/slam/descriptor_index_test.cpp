#include "slam/descriptor_index.h"

#include <gtest/gtest.h>

#include <vector>

#include <opencv2/core.hpp>

#include "core/error.h"
#include "slam/orb_descriptor.h"

namespace segslam::slam {
namespace {

cv::Mat RandomDescriptors(int rows, std::uint64_t seed) {
  cv::Mat descriptors(rows, kOrbDescriptorBytes, CV_8U);
  cv::RNG rng(seed);
  rng.fill(descriptors, cv::RNG::UNIFORM, 0, 256);
  return descriptors;
}

// `count` queries, each a copy of a random row of `descriptors` with `flipped_bits`
// distinct bits flipped; `source` gets the row each came from.
cv::Mat PerturbedCopies(const cv::Mat& descriptors, int count, int flipped_bits, std::vector<int>* source) {
  cv::RNG rng(1000 + flipped_bits);
  cv::Mat queries(count, kOrbDescriptorBytes, CV_8U);
  source->clear();
  for (int q = 0; q < count; ++q) {
    const int row = rng.uniform(0, descriptors.rows);
    source->push_back(row);
    descriptors.row(row).copyTo(queries.row(q));
    std::vector<bool> flipped(kOrbDescriptorBytes * 8, false);
    for (int n = 0; n < flipped_bits;) {
      const int bit = rng.uniform(0, kOrbDescriptorBytes * 8);
      if (flipped[static_cast<size_t>(bit)]) continue;
      flipped[static_cast<size_t>(bit)] = true;
      queries.at<std::uint8_t>(q, bit / 8) ^= static_cast<std::uint8_t>(1 << (bit % 8));
      ++n;
    }
  }
  return queries;
}

// Random 256-bit strings lie 128 +- 8 bits apart, so a copy with d <= 64 bits flipped has
// its source as its true nearest neighbour. How often the index finds it follows the
// probability of the header's comment: 0.999 at d = 30, 0.94 at d = 50.
TEST(DescriptorIndexTest, FindsTheNearestNeighbourAsOftenAsTheHashingPromises) {
  const cv::Mat descriptors = RandomDescriptors(20000, 7);
  const DescriptorIndex index(descriptors);
  for (const auto& [flipped_bits, min_recall] : std::vector<std::pair<int, double>>{{10, 1.0}, {30, 0.99}, {50, 0.88}}) {
    std::vector<int> source;
    const cv::Mat queries = PerturbedCopies(descriptors, 400, flipped_bits, &source);
    const std::vector<NearestTwo> found = index.Search(queries);
    ASSERT_EQ(found.size(), 400u);
    int hits = 0;
    for (size_t q = 0; q < found.size(); ++q) {
      if (found[q].best != source[q]) continue;
      ++hits;
      EXPECT_EQ(found[q].best_distance, flipped_bits);
    }
    EXPECT_GE(hits, min_recall * 400) << flipped_bits << " bits flipped";
  }
}

// What the index reports are exact distances, the two smallest in order, and the same
// for an index built again from the same rows (the sampled bits come from a fixed seed).
TEST(DescriptorIndexTest, ReportsExactDistancesInOrderAndIsDeterministic) {
  const cv::Mat descriptors = RandomDescriptors(5000, 11);
  std::vector<int> source;
  const cv::Mat queries = PerturbedCopies(descriptors, 200, 40, &source);
  const std::vector<NearestTwo> first = DescriptorIndex(descriptors).Search(queries);
  const std::vector<NearestTwo> again = DescriptorIndex(descriptors).Search(queries);
  for (size_t q = 0; q < first.size(); ++q) {
    const NearestTwo& f = first[q];
    ASSERT_GE(f.best, 0);
    EXPECT_EQ(f.best_distance, DescriptorDistance(queries.ptr<std::uint8_t>(static_cast<int>(q)),
                                                  descriptors.ptr<std::uint8_t>(f.best)));
    if (f.second >= 0) {
      EXPECT_NE(f.second, f.best);
      EXPECT_LE(f.best_distance, f.second_distance);
      EXPECT_EQ(f.second_distance, DescriptorDistance(queries.ptr<std::uint8_t>(static_cast<int>(q)),
                                                      descriptors.ptr<std::uint8_t>(f.second)));
    }
    EXPECT_EQ(f.best, again[q].best);
    EXPECT_EQ(f.second, again[q].second);
  }
}

TEST(DescriptorIndexTest, EmptyIndexFindsNothingAndBadMatricesAreRefused) {
  const DescriptorIndex empty{cv::Mat()};
  const std::vector<NearestTwo> found = empty.Search(RandomDescriptors(3, 1));
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].best, -1);
  EXPECT_THROW(DescriptorIndex(cv::Mat(10, 16, CV_8U, cv::Scalar(0))), Error);
  EXPECT_THROW(DescriptorIndex(RandomDescriptors(10, 1)).Search(cv::Mat(2, 32, CV_32F, cv::Scalar(0))), Error);
}

}  // namespace
}  // namespace segslam::slam
