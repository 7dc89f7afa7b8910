// Approximate nearest neighbours among many ORB descriptors, for relocalization on a
// long-term map: by brute force a relocalization on city_boulevard's map took 0.6 s;
// this index searches 50 000 points for a frame's 1000 descriptors in a twentieth of
// the brute force's time (slam_benchmarks, BM_RelocalizationSearch).
//
// Bit-sampling LSH for the Hamming distance (Indyk & Motwani 1998; Gionis et al. 1999),
// as FLANN builds for binary descriptors, with one-bit multi-probe (Lv et al. 2007):
// `tables` hash tables, each keyed on `key_bits` bits of the descriptor; a query looks in
// its own bucket and in the key_bits buckets one bit away, and ranks what it finds there
// by exact distance. A true match `d` bits away shares a probed bucket in one table with
// probability (1-p)^k + k p (1-p)^(k-1), p = d/256: with 12 tables of 14 bits it is found
// with probability 0.999 at d = 30 and 0.94 at d = 50.
//
// Written here rather than taken from cv::flann: FLANN draws its sampled bits from the
// process-wide rand(), so a run's relocalization, and every pose after it, would depend
// on what else called rand() before. Here they come from a fixed seed.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace segslam::slam {

struct DescriptorIndexOptions {
  int tables = 12;
  int key_bits = 14;
  std::uint64_t seed = 0x5e9d5a11ULL;
};

// The two nearest descriptors found for one query (index into the indexed rows), by
// exact Hamming distance among the candidates; -1 / 257 where fewer were found.
struct NearestTwo {
  int best = -1;
  int best_distance = 257;
  int second = -1;
  int second_distance = 257;
  // Keeps the two smallest of what it is offered (the first offered wins a tie).
  void Offer(int index, int distance) {
    if (distance < best_distance) {
      second = best;
      second_distance = best_distance;
      best = index;
      best_distance = distance;
    } else if (distance < second_distance) {
      second = index;
      second_distance = distance;
    }
  }
};

class DescriptorIndex {
 public:
  // `descriptors`: N x 32 CV_8U (one ORB descriptor a row); copied.
  explicit DescriptorIndex(const cv::Mat& descriptors, const DescriptorIndexOptions& options = {});

  // One result per row of `queries` (M x 32 CV_8U).
  std::vector<NearestTwo> Search(const cv::Mat& queries) const;
  int size() const { return descriptors_.rows; }

 private:
  std::uint32_t Key(const std::uint8_t* descriptor, int table) const;

  DescriptorIndexOptions options_;
  cv::Mat descriptors_;
  std::vector<std::vector<int>> sampled_bits_;      // per table: key bit j = descriptor bit [j]
  std::vector<std::vector<int>> bucket_start_;      // per table: 2^key_bits + 1 offsets
  std::vector<std::vector<int>> bucket_members_;    // per table: rows sorted by key
};

}  // namespace segslam::slam
