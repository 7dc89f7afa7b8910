#include "core/statistics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace segslam {

double Median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  // NaN breaks the strict weak order std::sort needs; its result would be meaningless.
  if (std::any_of(values.begin(), values.end(), [](double v) { return std::isnan(v); })) {
    throw std::invalid_argument("Median: the values hold NaN");
  }
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2;
}

float KthSmallest(std::vector<float>* values, std::size_t k) {
  return KthSmallest(values->data(), values->size(), k);
}

float KthSmallest(float* values, std::size_t n, std::size_t k) {
  if (k >= n) {
    throw std::invalid_argument("KthSmallest: k = " + std::to_string(k) + " but only " + std::to_string(n) +
                                " values");
  }
  // Below this count a histogram costs more than it saves.
  constexpr std::size_t kMinCountForHistogram = 2048;
  constexpr int kBucketBits = 10;
  constexpr std::uint32_t kInfinityBits = 0x7F800000u;  // the bits of +inf
  auto select_among = [&](std::size_t count, std::size_t rank) {
    std::nth_element(values, values + rank, values + count);
    return values[rank];
  };
  if (n < kMinCountForHistogram) return select_among(n, k);

  auto bits_of = [](float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return bits;
  };
  std::uint32_t low = kInfinityBits, high = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t bits = bits_of(values[i]);
    low = std::min(low, bits);
    high = std::max(high, bits);
  }
  // +0 and every negative value, or +inf and NaN, fall outside the positive range.
  if (low == 0 || high >= kInfinityBits) return select_among(n, k);
  if (low == high) return values[0];

  // Buckets of equal width over [low, high], at most 2^kBucketBits of them.
  int range_bits = 0;
  while (range_bits < 32 && ((high - low) >> range_bits) != 0) ++range_bits;
  const int shift = std::max(0, range_bits - kBucketBits);
  // Four interleaved histograms: runs of equal buckets (a surface's depths) would
  // otherwise wait on their own increments.
  std::array<std::array<std::uint32_t, 1u << kBucketBits>, 4> counts{};
  for (std::size_t i = 0; i < n; ++i) ++counts[i & 3][(bits_of(values[i]) - low) >> shift];
  std::size_t below = 0;
  std::uint32_t bucket = 0;
  for (;; ++bucket) {
    const std::size_t in_bucket = counts[0][bucket] + counts[1][bucket] + counts[2][bucket] + counts[3][bucket];
    if (below + in_bucket > k) break;
    below += in_bucket;
  }
  // The bucket's values are moved to the front, and the rank is found among them. Every
  // value is stored and only the bucket's advance the front: a branch on membership
  // would be mispredicted all along a noisy surface.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float v = values[i];
    values[kept] = v;
    kept += ((bits_of(v) - low) >> shift) == bucket;
  }
  return select_among(kept, k - below);
}

}  // namespace segslam
