// The error modes of the simulated segmenter (seg/simulated_segmenter.h), each a step on
// one instance's mask, and the counter-based randomness they draw from. Private to seg/:
// simulated_segmenter.cpp composes them; nothing outside seg/ includes this header.
//
// Images: ground-truth ids CV_16U (0 = background); masks CV_8U 0/1.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include <opencv2/core.hpp>

#include "core/instances.h"
#include "seg/simulated_segmenter.h"

namespace segslam::seg::mask_damage {

// ---------------------------------------------------------------------------------------
// Counter-based randomness: a generator per (seed, frame, instance, stream), so results
// never depend on call order. SplitMix64 mixing, xorshift-free; portable across standard
// libraries (no std:: distributions).

inline std::uint64_t Mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Error-mode streams.
enum Stream : std::uint64_t {
  kStreamDifficulty = 1,
  kStreamMiss,
  kStreamHoles,
  kStreamCut,
  kStreamBleed,
  kStreamJitter,
  kStreamConfusion,
  kStreamConfusionTarget,
  kStreamScore,
  kStreamFalsePositives,
  kStreamOrder,
  kStreamNeighbourBleed,
};

class Rng {
 public:
  Rng(std::uint64_t seed, std::int64_t frame, std::uint64_t instance, Stream stream)
      : state_(Mix(Mix(Mix(Mix(seed) ^ static_cast<std::uint64_t>(frame)) ^ instance) ^ stream)) {}

  std::uint64_t Next() { return Mix(state_++); }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [lo, hi].
  int UniformInt(int lo, int hi) {
    return lo + static_cast<int>(Next() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  bool Bernoulli(double p) { return p > 0 && Uniform() < p; }
  // Standard normal (Box-Muller).
  double Normal() {
    const double u1 = std::max(Uniform(), 1e-300);
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  // Poisson (Knuth), for small means.
  int Poisson(double mean) {
    if (mean <= 0) return 0;
    const double limit = std::exp(-mean);
    int k = 0;
    double p = Uniform();
    while (p > limit && k < 1000) {
      ++k;
      p *= Uniform();
    }
    return k;
  }

 private:
  std::uint64_t state_;
};

// COCO categories among those with the lowest mask AP of FCIS and Mask R-CNN.
bool IsHardCategory(int category_id);
// The look-alikes of a category among `candidates` (empty if none): the COCO classes
// networks mix it up with. Person has no look-alike.
std::vector<int> LookAlikes(int category_id, const std::vector<int>& candidates);
// The distinct categories of a sequence's table, ascending; the moveable shortlist if
// the table is empty.
std::vector<int> SequenceCategories(const InstanceTable& table);

// Per-instance statistics of a ground-truth id image, in one pass.
struct GtInstance {
  std::uint16_t id = 0;
  int area = 0;
  int border_pixels = 0;  // Pixels on the image's outermost rows and columns.
  int x0 = std::numeric_limits<int>::max(), y0 = std::numeric_limits<int>::max();
  int x1 = -1, y1 = -1;   // Inclusive bounding box.
};

// Per-instance statistics of a ground-truth id image, in one pass, by ascending id.
std::vector<GtInstance> AnalyseIds(const cv::Mat& ids);

// Ground-truth pixels per category in view; confusions go towards look-alikes in view.
struct CategoriesInView {
  std::map<int, double> pixels;
  std::vector<int> ids;  // ascending
};

CategoriesInView CountCategoriesInView(const std::vector<GtInstance>& frame_instances,
                                       const InstanceTable& table);

// Chance that the network misses the instance in this frame: a base rate plus shares for
// small, truncated (by the image border; large objects are spared), occluded and moving
// (blurred) objects, shifted on the logit scale by the instance's difficulty.
double MissProbability(const SimulatedSegmenterOptions& o, const GtInstance& gt,
                       const SimulatedInstanceContext& ctx, double difficulty, double image_area);

// How far, in pixels, each mask error may reach for one instance: proportional to the
// square root of its area and scaled up for difficult instances.
struct ErrorReach {
  ErrorReach(const SimulatedSegmenterOptions& o, double sqrt_area, double magnitude)
      : magnitude(magnitude),
        sqrt_area(sqrt_area),
        bleed_px(o.bleed_fraction_max * sqrt_area * magnitude),
        blob_px(o.bleed_blob_prob > 0 ? 6.0 * std::max(bleed_px, 1.0) : 0.0),
        jitter_px(std::min(o.boundary_jitter_px, o.boundary_jitter_fraction * sqrt_area) *
                  magnitude),
        jitter_scale_px(std::max(2.0, o.boundary_jitter_scale_fraction * sqrt_area)),
        neighbour_px(o.neighbour_bleed_fraction_max * sqrt_area * magnitude) {}

  // The margin around the object within which its mask can change.
  int Padding() const {
    return static_cast<int>(std::ceil(std::max({bleed_px, blob_px, neighbour_px}) +
                                      2.0 * jitter_px)) +
           2;
  }

  double magnitude, sqrt_area, bleed_px, blob_px, jitter_px, jitter_scale_px, neighbour_px;
};

// Replaces the 0/1 mask inside `box` by what a mask head of `resolution` x `resolution`
// cells over that box can express: area-averaged onto the grid, resized back bilinearly,
// thresholded at one half.
void CoarsenToGrid(const cv::Rect& box, int resolution, cv::Mat* mask);

// Missing parts: a few round holes centred on the object.
void PunchHoles(const SimulatedSegmenterOptions& o, const ErrorReach& reach, const cv::Mat& truth,
                int area, Rng* rng, cv::Mat* mask);

// Missing parts: one side of the object's box (left, right, top or bottom) cut off.
void CutOffSide(const SimulatedSegmenterOptions& o, const ErrorReach& reach,
                const cv::Rect& object_box, Rng* rng, cv::Mat* mask);

// Oversized: bleeding outward, and sometimes a blob on one side.
void BleedOutward(const SimulatedSegmenterOptions& o, const ErrorReach& reach,
                  const cv::Mat& truth, int area, Rng* rng, cv::Mat* mask);

// Oversized: spread into the touching instances (gt_ids_box: the ids within the mask's box).
void BleedIntoNeighbours(const SimulatedSegmenterOptions& o, const ErrorReach& reach,
                         const cv::Mat& gt_ids_box, std::uint16_t id, const cv::Mat& truth,
                         Rng* rng, cv::Mat* mask);

// Displaces the boundary of the 0/1 mask by `amplitude_px` times a smooth random field
// with features every `scale_px`.
void JitterBoundary(Rng* rng, double amplitude_px, double scale_px, cv::Mat* mask);

// The category the network outputs: sometimes a look-alike in view (the same one while
// the choice stays), leaning towards the class seen more: a rare class is taken for a
// common look-alike at the full rate, a common one for a rare look-alike seldom.
int OutputCategory(const SimulatedSegmenterOptions& o, std::uint64_t seed, int frame_index,
                   std::uint16_t id, int category, const CategoriesInView& in_view);

}  // namespace segslam::seg::mask_damage
