#include "slam/fast_corners.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/error.h"

namespace segslam::slam {
namespace {

constexpr int kCirclePixels = 16;
constexpr int kCircleRadiusPx = 3;
// The Bresenham circle of radius 3, in order around it.
constexpr int kCircleDx[kCirclePixels] = {0, 1, 2, 3, 3, 3, 2, 1, 0, -1, -2, -3, -3, -3, -2, -1};
constexpr int kCircleDy[kCirclePixels] = {3, 3, 2, 1, 0, -1, -2, -3, -3, -3, -2, -1, 0, 1, 2, 3};

using CircleOffsets = std::array<std::ptrdiff_t, kCirclePixels>;

// Lanes of bytes. The same code serves one pixel (V = uint8_t) and 16 or 32 at once (GCC
// vector types, which compile to SSE2, AVX2 or NEON): every operation is per lane.
using Bytes16 = std::uint8_t __attribute__((vector_size(16)));
#if defined(__x86_64__)
using Bytes32 = std::uint8_t __attribute__((vector_size(32)));
#endif

// Bytes32 values pass between functions that are all inlined into the one compiled for
// AVX2, so no call ever uses the ABI GCC warns about (parameters go by reference, for
// which it has nothing to say).
#pragma GCC diagnostic ignored "-Wpsabi"

template <typename V>
inline __attribute__((always_inline)) V Load(const std::uint8_t* p) {
  V v;
  std::memcpy(&v, p, sizeof(V));
  return v;
}

template <typename V>
inline __attribute__((always_inline)) V Min(const V& a, const V& b) {
  return a < b ? a : b;
}

template <typename V>
inline __attribute__((always_inline)) V Max(const V& a, const V& b) {
  return a > b ? a : b;
}

// The largest over the 16 arcs of 9 contiguous circle pixels of the smallest contrast on
// the arc: minima over 2, 4, 8 and then 9 neighbours, each from the previous.
template <typename V>
inline __attribute__((always_inline)) V BestArcContrast(const V (&contrast)[kCirclePixels]) {
  V min2[kCirclePixels];
  V min4[kCirclePixels];
  for (int k = 0; k < kCirclePixels; ++k) min2[k] = Min(contrast[k], contrast[(k + 1) % kCirclePixels]);
  for (int k = 0; k < kCirclePixels; ++k) min4[k] = Min(min2[k], min2[(k + 2) % kCirclePixels]);
  V best{};
  for (int k = 0; k < kCirclePixels; ++k) {
    const V min8 = Min(min4[k], min4[(k + 4) % kCirclePixels]);
    best = Max(best, Min(min8, contrast[(k + 8) % kCirclePixels]));
  }
  return best;
}

// How much darker and how much brighter than the centre a circle pixel is (0 if it is not).
template <typename V>
inline __attribute__((always_inline)) void Contrasts(const V& centre, const V& circle, V* darker, V* brighter) {
  const V low = Min(centre, circle);
  *darker = static_cast<V>(centre - low);
  *brighter = static_cast<V>(circle - low);
}

// Whether some lane of x exceeds the threshold.
template <typename V>
inline __attribute__((always_inline)) bool AnyAbove(const V& x, std::uint8_t threshold) {
  if constexpr (sizeof(V) == 1) {
    return x > threshold;
  } else {
    const auto above = x > threshold;  // lanes of all ones or zero
    std::uint64_t words[sizeof(V) / 8];
    std::memcpy(words, &above, sizeof(V));
    std::uint64_t any = 0;
    for (std::uint64_t word : words) any |= word;
    return any != 0;
  }
}

// Whether some pixel of the span may be a corner at `threshold`: an arc of 9 holds two
// circle pixels a quarter turn apart, so one such pair must differ from the centre by more
// than the threshold on the same side. Most spans of flat or smooth image fail this.
template <typename V>
inline __attribute__((always_inline)) bool MayHoldCorner(const V& value, const std::uint8_t* centre,
                                                         const CircleOffsets& offsets,
                                                         std::uint8_t threshold) {
  V darker[4];
  V brighter[4];
  for (int q = 0; q < 4; ++q) {
    Contrasts(value, Load<V>(centre + offsets[4 * q]), &darker[q], &brighter[q]);
  }
  V pair_contrast{};
  for (int q = 0; q < 4; ++q) {
    pair_contrast = Max(pair_contrast, Min(darker[q], darker[(q + 1) % 4]));
    pair_contrast = Max(pair_contrast, Min(brighter[q], brighter[(q + 1) % 4]));
  }
  return AnyAbove(pair_contrast, threshold);
}

// Scores the pixels from `centre` on, sizeof(V) of them: an arc of 9 is darker than
// centre - t exactly when its smallest darkness exceeds t, so the largest t at which the
// pixel is a corner is the best arc's contrast minus one.
template <typename V>
inline __attribute__((always_inline)) void ScoreSpan(const std::uint8_t* centre,
                                                     const CircleOffsets& offsets,
                                                     std::uint8_t min_threshold, std::uint8_t* out) {
  const V value = Load<V>(centre);
  if (!MayHoldCorner(value, centre, offsets, min_threshold)) {
    std::memset(out, 0, sizeof(V));
    return;
  }
  V darker[kCirclePixels];
  V brighter[kCirclePixels];
  for (int k = 0; k < kCirclePixels; ++k) {
    Contrasts(value, Load<V>(centre + offsets[k]), &darker[k], &brighter[k]);
  }
  const V best = Max(BestArcContrast(darker), BestArcContrast(brighter));
  const V one = static_cast<V>(V{} + 1);
  const V score = static_cast<V>(best - Min(best, one));
  const V kept = score >= min_threshold ? score : V{};
  std::memcpy(out, &kept, sizeof(V));
}

// Marks (with 0xFF) the pixels of a row whose score is at least the threshold and above
// all 8 neighbours' scores; the rows are padded by one pixel of score 0 on each side.
template <typename V>
inline __attribute__((always_inline)) void MarkLocalMaximaSpan(const std::uint8_t* above,
                                                               const std::uint8_t* row,
                                                               const std::uint8_t* below,
                                                               std::uint8_t threshold,
                                                               std::uint8_t* marks) {
  const V score = Load<V>(row);
  V neighbours = Max(Load<V>(row - 1), Load<V>(row + 1));
  for (const std::uint8_t* r : {above, below}) {
    neighbours = Max(neighbours, Max(Load<V>(r - 1), Max(Load<V>(r), Load<V>(r + 1))));
  }
  // A score at or below the neighbours' best is lowered to 0 before the threshold test.
  const V peak = score > neighbours ? score : V{};
  const V mark = peak >= threshold ? static_cast<V>(V{} + 0xFF) : V{};
  std::memcpy(marks, &mark, sizeof(V));
}

// The row bodies go along n pixels sizeof(V) at a time; the rest is done by one more span
// ending at the row's end (redoing a few pixels to the same values). A row shorter than a
// span goes by 16 lanes (the ORB cells are 30 pixels wide), or pixel by pixel below that.
// They are plain loops: a lambda would be compiled apart, without its caller's AVX2.
template <typename V>
inline __attribute__((always_inline)) void ScoreRowBody(const std::uint8_t* centre,
                                                        const CircleOffsets& offsets, int n,
                                                        std::uint8_t min_threshold, std::uint8_t* out) {
  constexpr int kLanes = static_cast<int>(sizeof(V));
  if (n < kLanes) {
    if constexpr (kLanes > 16) return ScoreRowBody<Bytes16>(centre, offsets, n, min_threshold, out);
    for (int i = 0; i < n; ++i) ScoreSpan<std::uint8_t>(centre + i, offsets, min_threshold, out + i);
    return;
  }
  int i = 0;
  for (; i + kLanes <= n; i += kLanes) ScoreSpan<V>(centre + i, offsets, min_threshold, out + i);
  if (i < n) ScoreSpan<V>(centre + n - kLanes, offsets, min_threshold, out + n - kLanes);
}

template <typename V>
inline __attribute__((always_inline)) void MarkLocalMaximaRowBody(const std::uint8_t* above,
                                                                  const std::uint8_t* row,
                                                                  const std::uint8_t* below, int n,
                                                                  std::uint8_t threshold,
                                                                  std::uint8_t* marks) {
  constexpr int kLanes = static_cast<int>(sizeof(V));
  if (n < kLanes) {
    if constexpr (kLanes > 16) {
      return MarkLocalMaximaRowBody<Bytes16>(above, row, below, n, threshold, marks);
    }
    for (int i = 0; i < n; ++i) {
      MarkLocalMaximaSpan<std::uint8_t>(above + i, row + i, below + i, threshold, marks + i);
    }
    return;
  }
  int i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    MarkLocalMaximaSpan<V>(above + i, row + i, below + i, threshold, marks + i);
  }
  if (i < n) {
    const int last = n - kLanes;
    MarkLocalMaximaSpan<V>(above + last, row + last, below + last, threshold, marks + last);
  }
}

void ScoreRowDefault(const std::uint8_t* centre, const CircleOffsets& offsets, int n,
                     std::uint8_t min_threshold, std::uint8_t* out) {
  ScoreRowBody<Bytes16>(centre, offsets, n, min_threshold, out);
}

void MarkLocalMaximaRowDefault(const std::uint8_t* above, const std::uint8_t* row,
                               const std::uint8_t* below, int n, std::uint8_t threshold,
                               std::uint8_t* marks) {
  MarkLocalMaximaRowBody<Bytes16>(above, row, below, n, threshold, marks);
}

#if defined(__x86_64__)
__attribute__((target("avx2"))) void ScoreRowAvx2(const std::uint8_t* centre,
                                                  const CircleOffsets& offsets, int n,
                                                  std::uint8_t min_threshold, std::uint8_t* out) {
  ScoreRowBody<Bytes32>(centre, offsets, n, min_threshold, out);
}

__attribute__((target("avx2"))) void MarkLocalMaximaRowAvx2(const std::uint8_t* above,
                                                            const std::uint8_t* row,
                                                            const std::uint8_t* below, int n,
                                                            std::uint8_t threshold,
                                                            std::uint8_t* marks) {
  MarkLocalMaximaRowBody<Bytes32>(above, row, below, n, threshold, marks);
}

bool HasAvx2() {
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  return has_avx2;
}
#endif

void ScoreRow(const std::uint8_t* centre, const CircleOffsets& offsets, int n,
              std::uint8_t min_threshold, std::uint8_t* out) {
#if defined(__x86_64__)
  if (HasAvx2()) return ScoreRowAvx2(centre, offsets, n, min_threshold, out);
#endif
  ScoreRowDefault(centre, offsets, n, min_threshold, out);
}

void MarkLocalMaximaRow(const std::uint8_t* above, const std::uint8_t* row,
                        const std::uint8_t* below, int n, std::uint8_t threshold,
                        std::uint8_t* marks) {
#if defined(__x86_64__)
  if (HasAvx2()) return MarkLocalMaximaRowAvx2(above, row, below, n, threshold, marks);
#endif
  MarkLocalMaximaRowDefault(above, row, below, n, threshold, marks);
}

}  // namespace

void ComputeFastScores(const cv::Mat& image, const cv::Rect& region, int min_threshold,
                       cv::Mat* scores) {
  if (image.empty() || image.type() != CV_8UC1) {
    throw Error("ComputeFastScores: the image must be a non-empty one-channel 8-bit image");
  }
  const cv::Rect inner(kCircleRadiusPx, kCircleRadiusPx, image.cols - 2 * kCircleRadiusPx,
                       image.rows - 2 * kCircleRadiusPx);
  if (region.width <= 0 || region.height <= 0 || (region & inner) != region) {
    throw Error(fmt::format(
        "ComputeFastScores: region {}x{} at ({}, {}) does not keep {} px from the edges of a "
        "{}x{} image",
        region.width, region.height, region.x, region.y, kCircleRadiusPx, image.cols, image.rows));
  }
  if (min_threshold < 1 || min_threshold > 254) {
    throw Error(fmt::format("ComputeFastScores: min_threshold must be 1..254, got {}", min_threshold));
  }
  scores->create(image.size(), CV_8UC1);
  scores->setTo(0);
  CircleOffsets offsets;
  for (int k = 0; k < kCirclePixels; ++k) {
    offsets[k] = static_cast<std::ptrdiff_t>(kCircleDy[k]) * static_cast<std::ptrdiff_t>(image.step) +
                 kCircleDx[k];
  }
  for (int y = region.y; y < region.y + region.height; ++y) {
    ScoreRow(image.ptr<std::uint8_t>(y) + region.x, offsets, region.width,
             static_cast<std::uint8_t>(min_threshold), scores->ptr<std::uint8_t>(y) + region.x);
  }
}

void AppendFastCorners(const cv::Mat& scores, const cv::Rect& window, int threshold,
                       std::vector<FastCorner>* corners) {
  if (window.width <= 0 || window.height <= 0) return;
  if (threshold > 255) return;  // no score reaches it
  // The window's rows are copied between columns of score 0, and rows of 0 lie above and
  // below it: neighbours outside the window count as no corner, as for cv::FAST there.
  const int padded_width = window.width + 2;
  std::vector<std::uint8_t> padded(static_cast<size_t>(padded_width) * (window.height + 2), 0);
  for (int r = 0; r < window.height; ++r) {
    std::memcpy(&padded[static_cast<size_t>(r + 1) * padded_width + 1],
                scores.ptr<std::uint8_t>(window.y + r) + window.x, window.width);
  }
  // Whole 8-byte words of marks are tested at once: corners are sparse.
  std::vector<std::uint8_t> marks((window.width + 7) / 8 * 8, 0);
  const std::uint8_t threshold_byte = static_cast<std::uint8_t>(std::max(1, threshold));
  for (int r = 0; r < window.height; ++r) {
    const std::uint8_t* row = &padded[static_cast<size_t>(r + 1) * padded_width + 1];
    MarkLocalMaximaRow(row - padded_width, row, row + padded_width, window.width, threshold_byte,
                       marks.data());
    for (int x = 0; x < window.width; x += 8) {
      std::uint64_t word;
      std::memcpy(&word, &marks[x], sizeof(word));
      if (word == 0) continue;
      for (int i = x; i < std::min(x + 8, window.width); ++i) {
        if (marks[i] != 0) corners->push_back({window.x + i, window.y + r, static_cast<float>(row[i])});
      }
    }
  }
}

}  // namespace segslam::slam
