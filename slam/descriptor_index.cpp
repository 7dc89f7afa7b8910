#include "slam/descriptor_index.h"

#include <random>

#include "core/error.h"
#include "slam/orb_descriptor.h"

namespace segslam::slam {

namespace {

int Bit(const std::uint8_t* descriptor, int bit) { return (descriptor[bit >> 3] >> (bit & 7)) & 1; }

}  // namespace

DescriptorIndex::DescriptorIndex(const cv::Mat& descriptors, const DescriptorIndexOptions& options)
    : options_(options), descriptors_(descriptors.clone()) {
  if (!descriptors.empty() && (descriptors.type() != CV_8U || descriptors.cols != kOrbDescriptorBytes)) {
    throw Error("descriptor index: descriptors must be N x 32 CV_8U");
  }
  if (options.tables < 1 || options.key_bits < 1 || options.key_bits > 24) {
    throw Error("descriptor index: needs at least one table and 1 to 24 key bits");
  }
  // mt19937_64's output is fixed by the standard (its distributions are not): the sampled
  // bits are the same on every platform.
  std::mt19937_64 random(options.seed);
  const std::size_t buckets = std::size_t{1} << options.key_bits;
  for (int table = 0; table < options.tables; ++table) {
    std::vector<int> bits;
    std::vector<bool> taken(kOrbDescriptorBytes * 8, false);
    while (static_cast<int>(bits.size()) < options.key_bits) {
      const int bit = static_cast<int>(random() % (kOrbDescriptorBytes * 8));
      if (taken[static_cast<std::size_t>(bit)]) continue;
      taken[static_cast<std::size_t>(bit)] = true;
      bits.push_back(bit);
    }
    sampled_bits_.push_back(std::move(bits));

    // Counting sort of the rows by key: bucket b holds members [start[b], start[b+1]).
    std::vector<std::uint32_t> keys(static_cast<std::size_t>(descriptors_.rows));
    std::vector<int> start(buckets + 1, 0);
    for (int row = 0; row < descriptors_.rows; ++row) {
      keys[static_cast<std::size_t>(row)] = Key(descriptors_.ptr<std::uint8_t>(row), table);
      ++start[keys[static_cast<std::size_t>(row)] + 1];
    }
    for (std::size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
    std::vector<int> members(static_cast<std::size_t>(descriptors_.rows));
    std::vector<int> next(start.begin(), start.end() - 1);
    for (int row = 0; row < descriptors_.rows; ++row) {
      members[static_cast<std::size_t>(next[keys[static_cast<std::size_t>(row)]]++)] = row;
    }
    bucket_start_.push_back(std::move(start));
    bucket_members_.push_back(std::move(members));
  }
}

std::uint32_t DescriptorIndex::Key(const std::uint8_t* descriptor, int table) const {
  std::uint32_t key = 0;
  const std::vector<int>& bits = sampled_bits_[static_cast<std::size_t>(table)];
  for (std::size_t j = 0; j < bits.size(); ++j) key |= static_cast<std::uint32_t>(Bit(descriptor, bits[j])) << j;
  return key;
}

std::vector<NearestTwo> DescriptorIndex::Search(const cv::Mat& queries) const {
  if (!queries.empty() && (queries.type() != CV_8U || queries.cols != kOrbDescriptorBytes)) {
    throw Error("descriptor index: queries must be M x 32 CV_8U");
  }
  std::vector<NearestTwo> results(static_cast<std::size_t>(queries.rows));
  // The query that last looked at each row: a row met in several buckets is ranked once.
  std::vector<int> seen_by(static_cast<std::size_t>(descriptors_.rows), -1);
  for (int q = 0; q < queries.rows; ++q) {
    const std::uint8_t* query = queries.ptr<std::uint8_t>(q);
    NearestTwo& result = results[static_cast<std::size_t>(q)];
    for (int table = 0; table < options_.tables; ++table) {
      const std::uint32_t key = Key(query, table);
      const std::vector<int>& start = bucket_start_[static_cast<std::size_t>(table)];
      const std::vector<int>& members = bucket_members_[static_cast<std::size_t>(table)];
      for (int flip = -1; flip < options_.key_bits; ++flip) {
        const std::uint32_t probe = flip < 0 ? key : key ^ (std::uint32_t{1} << flip);
        for (int k = start[probe]; k < start[probe + 1]; ++k) {
          const int row = members[static_cast<std::size_t>(k)];
          if (seen_by[static_cast<std::size_t>(row)] == q) continue;
          seen_by[static_cast<std::size_t>(row)] = q;
          result.Offer(row, DescriptorDistance(query, descriptors_.ptr<std::uint8_t>(row)));
        }
      }
    }
  }
  return results;
}

}  // namespace segslam::slam
