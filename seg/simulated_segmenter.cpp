#include "seg/simulated_segmenter.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/option_assignment.h"
#include "core/tracks.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------
// Counter-based randomness: a generator per (seed, frame, instance, stream), so results
// never depend on call order. SplitMix64 mixing, xorshift-free; portable across standard
// libraries (no std:: distributions).

std::uint64_t Mix(std::uint64_t x) {
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

// ---------------------------------------------------------------------------------------
// Class confusions: groups of COCO ids that networks mix up. Person has no look-alike.
const std::vector<std::vector<int>>& ConfusionGroups() {
  static const std::vector<std::vector<int>> groups = {
      {3, 8, 6},             // car, truck, bus
      {2, 4},                // bicycle, motorcycle
      {17, 18},              // cat, dog
      {19, 20, 21},          // horse, sheep, cow
      {44, 46, 47, 51, 86},  // bottle, wine glass, cup, bowl, vase
      {62, 63, 15},          // chair, couch, bench
      {72, 73},              // tv, laptop
      {74, 75, 77},          // mouse, remote, cell phone
      {27, 31, 33},          // backpack, handbag, suitcase
      {78, 79, 82},          // microwave, oven, refrigerator
      {10, 13},              // traffic light, stop sign
  };
  return groups;
}

// COCO categories among those with the lowest mask AP of FCIS and Mask R-CNN.
bool IsHardCategory(int category_id) {
  // bench, chair, potted plant, dining table, book
  static const std::vector<int> hard = {15, 62, 64, 67, 84};
  return std::find(hard.begin(), hard.end(), category_id) != hard.end();
}

// The look-alikes of a category among `candidates` (empty if none).
std::vector<int> LookAlikes(int category_id, const std::vector<int>& candidates) {
  for (const auto& group : ConfusionGroups()) {
    if (std::find(group.begin(), group.end(), category_id) == group.end()) continue;
    std::vector<int> others;
    for (int id : group) {
      if (id != category_id && std::find(candidates.begin(), candidates.end(), id) != candidates.end()) {
        others.push_back(id);
      }
    }
    return others;
  }
  return {};
}

// The distinct categories of a sequence's table, ascending; the moveable shortlist if
// the table is empty.
std::vector<int> SequenceCategories(const InstanceTable& table) {
  std::vector<int> categories;
  for (const InstanceInfo& info : table.instances()) categories.push_back(info.category_id);
  std::sort(categories.begin(), categories.end());
  categories.erase(std::unique(categories.begin(), categories.end()), categories.end());
  return categories.empty() ? MoveableCategoryIds() : categories;
}

// ---------------------------------------------------------------------------------------
// Per-instance statistics of a ground-truth id image, in one pass.
struct GtInstance {
  std::uint16_t id = 0;
  int area = 0;
  int border_pixels = 0;  // Pixels on the image's outermost rows and columns.
  int x0 = std::numeric_limits<int>::max(), y0 = std::numeric_limits<int>::max();
  int x1 = -1, y1 = -1;   // Inclusive bounding box.
};

std::vector<GtInstance> AnalyseIds(const cv::Mat& ids) {
  std::map<std::uint16_t, GtInstance> stats;
  GtInstance* last = nullptr;
  std::uint16_t last_id = 0;
  for (int y = 0; y < ids.rows; ++y) {
    const auto* row = ids.ptr<std::uint16_t>(y);
    const bool border_row = y == 0 || y == ids.rows - 1;
    for (int x = 0; x < ids.cols; ++x) {
      const std::uint16_t id = row[x];
      if (id == 0) continue;
      if (last == nullptr || id != last_id) {
        last = &stats[id];
        last->id = id;
        last_id = id;
      }
      ++last->area;
      if (border_row || x == 0 || x == ids.cols - 1) ++last->border_pixels;
      last->x0 = std::min(last->x0, x);
      last->x1 = std::max(last->x1, x);
      last->y0 = std::min(last->y0, y);
      last->y1 = std::max(last->y1, y);
    }
  }
  std::vector<GtInstance> out;
  out.reserve(stats.size());
  for (auto& [id, s] : stats) out.push_back(s);
  return out;
}

double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }
double Logit(double p) { return std::log(p / (1.0 - p)); }

// A smooth random field in [-1, 1] (roughly) of `size`, from a grid of uniform values
// every `scale` pixels, interpolated bicubically.
cv::Mat SmoothNoise(Rng* rng, cv::Size size, double scale) {
  const int gw = std::max(2, static_cast<int>(std::ceil(size.width / scale)) + 2);
  const int gh = std::max(2, static_cast<int>(std::ceil(size.height / scale)) + 2);
  cv::Mat grid(gh, gw, CV_32F);
  for (int y = 0; y < gh; ++y) {
    for (int x = 0; x < gw; ++x) grid.at<float>(y, x) = static_cast<float>(rng->Uniform(-1, 1));
  }
  cv::Mat field;
  cv::resize(grid, field, cv::Size(static_cast<int>(gw * scale), static_cast<int>(gh * scale)), 0,
             0, cv::INTER_CUBIC);
  return field(cv::Rect(0, 0, size.width, size.height)).clone();
}

// Displaces the boundary of the 0/1 mask by `amplitude_px` times a smooth random field.
void JitterBoundary(Rng* rng, double amplitude_px, double scale_px, cv::Mat* mask) {
  if (amplitude_px <= 0 || cv::countNonZero(*mask) == 0) return;
  const cv::Mat noise = SmoothNoise(rng, mask->size(), scale_px);
  // Only pixels closer to the boundary than the largest displacement can change side,
  // so the distances are needed in the object's box grown by that much, not in the whole
  // mask (the jitter took a sixth of a mutual run's time, by perf). Within that box
  // they are exact: every object pixel is inside it.
  double noise_min = 0, noise_max = 0;
  cv::minMaxLoc(noise, &noise_min, &noise_max);
  const int reach = static_cast<int>(std::ceil(amplitude_px * std::max(-noise_min, noise_max))) + 2;
  const cv::Rect object = cv::boundingRect(*mask);
  const cv::Rect band = cv::Rect(object.x - reach, object.y - reach, object.width + 2 * reach,
                                 object.height + 2 * reach) &
                        cv::Rect(0, 0, mask->cols, mask->rows);
  cv::Mat roi = (*mask)(band);
  cv::Mat inside, outside, not_mask;
  cv::distanceTransform(roi, inside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::compare(roi, 0, not_mask, cv::CMP_EQ);
  cv::distanceTransform(not_mask, outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  // Signed distance to the boundary: +-0.5 at the pixels either side of it, growing
  // inward (positive) and outward (negative).
  cv::Mat inside_f;
  roi.convertTo(inside_f, CV_32F);
  cv::Mat signed_distance = inside - outside + 0.5f - inside_f;
  cv::Mat displaced = signed_distance + static_cast<float>(amplitude_px) * noise(band);
  cv::Mat result;
  cv::compare(displaced, 0, result, cv::CMP_GT);
  result.convertTo(roi, CV_8U, 1.0 / 255.0);
}

// Replaces the 0/1 mask inside `box` by what a mask head of `resolution` x `resolution`
// cells over that box can express: area-averaged onto the grid, resized back bilinearly,
// thresholded at one half.
void CoarsenToGrid(const cv::Rect& box, int resolution, cv::Mat* mask) {
  if (box.width <= resolution && box.height <= resolution) return;  // Finer than the grid.
  cv::Mat roi = (*mask)(box);
  cv::Mat fine, coarse, back;
  roi.convertTo(fine, CV_32F);
  cv::resize(fine, coarse, cv::Size(resolution, resolution), 0, 0, cv::INTER_AREA);
  cv::resize(coarse, back, box.size(), 0, 0, cv::INTER_LINEAR);
  cv::Mat thresholded;
  cv::compare(back, 0.5f, thresholded, cv::CMP_GE);
  thresholded.convertTo(roi, CV_8U, 1.0 / 255.0);
}

// A random pixel of the 0/1 mask `m` (which has `count` nonzero pixels).
cv::Point RandomPixelOf(Rng* rng, const cv::Mat& m, int count) {
  int k = rng->UniformInt(0, count - 1);
  for (int y = 0; y < m.rows; ++y) {
    const auto* row = m.ptr<std::uint8_t>(y);
    for (int x = 0; x < m.cols; ++x) {
      if (row[x] && k-- == 0) return {x, y};
    }
  }
  return {0, 0};
}

// Share of the full moving-miss rate for an instance's own image motion.
double MotionBlurShare(const SimulatedInstanceContext& ctx, const SimulatedSegmenterOptions& o) {
  if (ctx.own_image_speed_px_s < 0) return 1.0;
  return std::min(1.0, ctx.own_image_speed_px_s / o.moving_full_miss_speed_px_s);
}

float Clamp01(double v, double lo = 0.0) {
  return static_cast<float>(std::clamp(v, lo, 1.0));
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Options.

SimulatedSegmenterOptions SimulatedSegmenterOptions::Preset(const std::string& name) {
  SimulatedSegmenterOptions o;
  if (name == "fcis-like") return o;
  if (name == "clean") {
    o.miss_prob = o.miss_small_prob = o.miss_truncated_prob = o.miss_occluded_prob = 0;
    o.miss_moving_prob = o.difficulty_sd = o.hard_category_difficulty = 0;
    o.min_area_px = 0;
    o.hole_prob = o.cut_prob = o.bleed_prob = o.bleed_blob_prob = 0;
    o.neighbour_bleed_prob = 0;
    o.boundary_jitter_fraction = o.boundary_jitter_px = 0;
    o.mask_resolution = 0;
    o.confusion_prob = 0;
    o.false_positives_per_frame = 0;
    o.score_noise_sd = 0;
    o.confusion_score_factor = 1;
    return o;
  }
  if (name == "mask-rcnn-like") {
    o.miss_prob *= 0.6;
    o.miss_small_prob *= 0.7;
    o.miss_truncated_prob *= 0.6;
    o.miss_occluded_prob *= 0.7;
    o.miss_moving_prob *= 0.6;
    o.hole_prob *= 0.5;
    o.cut_prob *= 0.5;
    o.bleed_prob *= 0.6;
    o.boundary_jitter_fraction *= 0.6;
    o.confusion_prob *= 0.6;
    o.false_positives_per_frame *= 0.6;
    return o;
  }
  if (name == "poor") {
    // A weak network: every error twice as likely and as large, coarse masks that
    // spread into their neighbours.
    o.strength = 2.0;
    o.mask_resolution = 21;
    o.neighbour_bleed_prob = 0.1;
    return o;
  }
  std::string names;
  for (const auto& n : PresetNames()) names += (names.empty() ? "" : ", ") + n;
  throw Error("unknown simulated segmenter preset '" + name + "' (known: " + names + ")");
}

std::vector<std::string> SimulatedSegmenterOptions::PresetNames() {
  return {"clean", "fcis-like", "mask-rcnn-like", "poor"};
}

namespace {

// The tunable fields by name; one table serves Set() and FieldNames().
std::map<std::string, double*> DoubleFields(SimulatedSegmenterOptions* o) {
  return {{"strength", &o->strength},
          {"miss_prob", &o->miss_prob},
          {"miss_small_prob", &o->miss_small_prob},
          {"small_area_fraction", &o->small_area_fraction},
          {"miss_truncated_prob", &o->miss_truncated_prob},
          {"truncated_large_area_fraction", &o->truncated_large_area_fraction},
          {"miss_occluded_prob", &o->miss_occluded_prob},
          {"miss_moving_prob", &o->miss_moving_prob},
          {"moving_full_miss_speed_px_s", &o->moving_full_miss_speed_px_s},
          {"difficulty_sd", &o->difficulty_sd},
          {"hard_category_difficulty", &o->hard_category_difficulty},
          {"hole_prob", &o->hole_prob},
          {"hole_radius_fraction", &o->hole_radius_fraction},
          {"cut_prob", &o->cut_prob},
          {"cut_fraction_max", &o->cut_fraction_max},
          {"bleed_prob", &o->bleed_prob},
          {"bleed_fraction_max", &o->bleed_fraction_max},
          {"bleed_blob_prob", &o->bleed_blob_prob},
          {"neighbour_bleed_prob", &o->neighbour_bleed_prob},
          {"neighbour_bleed_fraction_max", &o->neighbour_bleed_fraction_max},
          {"boundary_jitter_fraction", &o->boundary_jitter_fraction},
          {"boundary_jitter_px", &o->boundary_jitter_px},
          {"boundary_jitter_scale_fraction", &o->boundary_jitter_scale_fraction},
          {"confusion_prob", &o->confusion_prob},
          {"false_positives_per_frame", &o->false_positives_per_frame},
          {"false_positive_area_min", &o->false_positive_area_min},
          {"false_positive_area_max", &o->false_positive_area_max},
          {"score_iou_weight", &o->score_iou_weight},
          {"score_noise_sd", &o->score_noise_sd},
          {"confusion_score_factor", &o->confusion_score_factor},
          {"false_positive_score_max", &o->false_positive_score_max}};
}

std::map<std::string, int*> IntFields(SimulatedSegmenterOptions* o) {
  return {{"min_area_px", &o->min_area_px},
          {"occlusion_window", &o->occlusion_window},
          {"hole_count_max", &o->hole_count_max},
          {"mask_resolution", &o->mask_resolution}};
}

}  // namespace

void SimulatedSegmenterOptions::Set(const std::string& assignment) {
  const std::string what = "segmenter option";
  const NumericAssignment parsed = ParseNumericAssignment(assignment, what);
  const auto doubles = DoubleFields(this);
  const auto ints = IntFields(this);
  if (auto it = doubles.find(parsed.name); it != doubles.end()) {
    *it->second = parsed.value;
  } else if (auto it = ints.find(parsed.name); it != ints.end()) {
    *it->second = WholeNumberValue(parsed, what);
  } else {
    ThrowUnknownOption(what, parsed.name, FieldNames());
  }
}

std::vector<std::string> SimulatedSegmenterOptions::FieldNames() {
  SimulatedSegmenterOptions scratch;
  std::vector<std::string> names;
  for (const auto& [name, field] : DoubleFields(&scratch)) names.push_back(name);
  for (const auto& [name, field] : IntFields(&scratch)) names.push_back(name);
  std::sort(names.begin(), names.end());
  return names;
}

SimulatedSegmenterOptions SimulatedSegmenterOptions::Effective() const {
  SimulatedSegmenterOptions e = *this;
  const double s = strength;
  auto prob = [s](double p) { return std::min(1.0, p * s); };
  e.strength = 1.0;
  e.miss_prob = prob(miss_prob);
  e.miss_small_prob = prob(miss_small_prob);
  e.miss_truncated_prob = prob(miss_truncated_prob);
  e.miss_occluded_prob = prob(miss_occluded_prob);
  e.miss_moving_prob = prob(miss_moving_prob);
  e.min_area_px = static_cast<int>(std::lround(min_area_px * s));
  e.difficulty_sd = difficulty_sd * s;
  e.hard_category_difficulty = hard_category_difficulty * s;
  e.hole_prob = prob(hole_prob);
  e.hole_radius_fraction = std::min(1.0, hole_radius_fraction * s);
  e.cut_prob = prob(cut_prob);
  e.cut_fraction_max = std::min(0.9, cut_fraction_max * s);
  e.bleed_prob = prob(bleed_prob);
  e.bleed_fraction_max = std::min(1.0, bleed_fraction_max * s);
  e.bleed_blob_prob = prob(bleed_blob_prob);
  e.neighbour_bleed_prob = prob(neighbour_bleed_prob);
  e.neighbour_bleed_fraction_max = std::min(1.0, neighbour_bleed_fraction_max * s);
  e.boundary_jitter_fraction = std::min(1.0, boundary_jitter_fraction * s);
  e.boundary_jitter_px = boundary_jitter_px * s;
  e.mask_resolution =
      (s > 0 && mask_resolution > 0) ? std::max(2, static_cast<int>(std::lround(mask_resolution / s))) : 0;
  e.confusion_prob = prob(confusion_prob);
  e.false_positives_per_frame = false_positives_per_frame * s;
  e.score_noise_sd = score_noise_sd * s;
  e.confusion_score_factor = std::clamp(1.0 - (1.0 - confusion_score_factor) * s, 0.01, 1.0);
  return e;
}

bool SimulatedSegmenterOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& what) {
    if (error) *error = what;
    return false;
  };
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  struct Range {
    const char* name;
    double value, lo, hi;
  };
  const double inf = std::numeric_limits<double>::max();
  const Range ranges[] = {
      {"strength", strength, 0, 10},
      {"miss_prob", miss_prob, 0, 1},
      {"miss_small_prob", miss_small_prob, 0, 1},
      {"small_area_fraction", small_area_fraction, 0, 1},
      {"min_area_px", static_cast<double>(min_area_px), 0, inf},
      {"miss_truncated_prob", miss_truncated_prob, 0, 1},
      {"truncated_large_area_fraction", truncated_large_area_fraction, 0, 1},
      {"miss_occluded_prob", miss_occluded_prob, 0, 1},
      {"occlusion_window", static_cast<double>(occlusion_window), 0, inf},
      {"miss_moving_prob", miss_moving_prob, 0, 1},
      {"moving_full_miss_speed_px_s", moving_full_miss_speed_px_s, 1e-9, inf},
      {"difficulty_sd", difficulty_sd, 0, 10},
      {"hard_category_difficulty", hard_category_difficulty, 0, 10},
      {"hole_prob", hole_prob, 0, 1},
      {"hole_count_max", static_cast<double>(hole_count_max), 1, 100},
      {"hole_radius_fraction", hole_radius_fraction, 0, 1},
      {"cut_prob", cut_prob, 0, 1},
      {"cut_fraction_max", cut_fraction_max, 0, 0.99},
      {"bleed_prob", bleed_prob, 0, 1},
      {"bleed_fraction_max", bleed_fraction_max, 0, 1},
      {"bleed_blob_prob", bleed_blob_prob, 0, 1},
      {"neighbour_bleed_prob", neighbour_bleed_prob, 0, 1},
      {"neighbour_bleed_fraction_max", neighbour_bleed_fraction_max, 0, 1},
      {"boundary_jitter_fraction", boundary_jitter_fraction, 0, 1},
      {"boundary_jitter_px", boundary_jitter_px, 0, 100},
      {"boundary_jitter_scale_fraction", boundary_jitter_scale_fraction, 1e-9, 10},
      {"mask_resolution", static_cast<double>(mask_resolution), 0, 1000},
      {"confusion_prob", confusion_prob, 0, 1},
      {"false_positives_per_frame", false_positives_per_frame, 0, 100},
      {"false_positive_area_min", false_positive_area_min, 1e-9, 1},
      {"false_positive_area_max", false_positive_area_max, 1e-9, 1},
      {"score_iou_weight", score_iou_weight, 0, 5},
      {"score_noise_sd", score_noise_sd, 0, 10},
      {"confusion_score_factor", confusion_score_factor, 1e-9, 1},
      {"false_positive_score_max", false_positive_score_max, 0.01, 1},
  };
  for (const Range& r : ranges) {
    if (!in(r.value, r.lo, r.hi)) {
      return fail(fmt::format("simulated segmenter option {} = {} is outside [{}, {}]", r.name,
                              r.value, r.lo, r.hi == inf ? std::string("inf") : fmt::format("{}", r.hi)));
    }
  }
  if (false_positive_area_min > false_positive_area_max) {
    return fail("simulated segmenter option false_positive_area_min exceeds false_positive_area_max");
  }
  return true;
}

// ---------------------------------------------------------------------------------------
// The simulation of one frame.

namespace {

// Ground-truth pixels per category in view; confusions go towards look-alikes in view.
struct CategoriesInView {
  std::map<int, double> pixels;
  std::vector<int> ids;  // ascending
};

CategoriesInView CountCategoriesInView(const std::vector<GtInstance>& frame_instances,
                                       const InstanceTable& table) {
  CategoriesInView in_view;
  for (const GtInstance& gt : frame_instances) {
    const InstanceInfo* info = table.Find(gt.id);
    if (info != nullptr) in_view.pixels[info->category_id] += gt.area;
  }
  for (const auto& [category, pixels] : in_view.pixels) in_view.ids.push_back(category);
  return in_view;
}

// Chance that the network misses the instance in this frame: a base rate plus shares for
// small, truncated (by the image border; large objects are spared), occluded and moving
// (blurred) objects, shifted on the logit scale by the instance's difficulty.
double MissProbability(const SimulatedSegmenterOptions& o, const GtInstance& gt,
                       const SimulatedInstanceContext& ctx, double difficulty, double image_area) {
  const double sqrt_area = std::sqrt(static_cast<double>(gt.area));
  const double small_share =
      o.small_area_fraction > 0
          ? std::max(0.0, 1.0 - gt.area / (o.small_area_fraction * image_area))
          : 0.0;
  const double large_relief =
      o.truncated_large_area_fraction > 0
          ? std::max(0.0, 1.0 - gt.area / (o.truncated_large_area_fraction * image_area))
          : 1.0;
  const double truncation =
      std::min(1.0, gt.border_pixels / std::max(1.0, sqrt_area)) * large_relief;
  const double occlusion = 1.0 - std::clamp(ctx.visible_share, 0.0, 1.0);
  double p_miss = o.miss_prob + o.miss_small_prob * small_share +
                  o.miss_truncated_prob * truncation + o.miss_occluded_prob * occlusion +
                  (ctx.moving ? o.miss_moving_prob * MotionBlurShare(ctx, o) : 0.0);
  p_miss = std::clamp(p_miss, 0.0, 1.0);
  if (p_miss > 0 && p_miss < 1) p_miss = Logistic(Logit(p_miss) + difficulty);
  return p_miss;
}

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

// Missing parts: a few round holes centred on the object.
void PunchHoles(const SimulatedSegmenterOptions& o, const ErrorReach& reach, const cv::Mat& truth,
                int area, Rng* rng, cv::Mat* mask) {
  if (!rng->Bernoulli(o.hole_prob)) return;
  const int holes = rng->UniformInt(1, o.hole_count_max);
  for (int h = 0; h < holes; ++h) {
    const cv::Point centre = RandomPixelOf(rng, truth, area);
    const double radius =
        rng->Uniform(0.3, 1.0) * o.hole_radius_fraction * reach.sqrt_area * reach.magnitude;
    cv::circle(*mask, centre, static_cast<int>(std::lround(radius)), 0, cv::FILLED);
  }
}

// Missing parts: one side of the object's box (left, right, top or bottom) cut off.
void CutOffSide(const SimulatedSegmenterOptions& o, const ErrorReach& reach,
                const cv::Rect& object_box, Rng* rng, cv::Mat* mask) {
  if (!rng->Bernoulli(o.cut_prob)) return;
  const double fraction =
      std::min(0.9, rng->Uniform(0.2, 1.0) * o.cut_fraction_max * reach.magnitude);
  const int side = rng->UniformInt(0, 3);
  const int cut_w = static_cast<int>(std::lround(fraction * object_box.width));
  const int cut_h = static_cast<int>(std::lround(fraction * object_box.height));
  const cv::Rect& b = object_box;
  const cv::Rect cuts[4] = {
      cv::Rect(b.x, b.y, cut_w, b.height),                       // left
      cv::Rect(b.x + b.width - cut_w, b.y, cut_w, b.height),     // right
      cv::Rect(b.x, b.y, b.width, cut_h),                        // top
      cv::Rect(b.x, b.y + b.height - cut_h, b.width, cut_h)};    // bottom
  (*mask)(cuts[side] & cv::Rect(0, 0, mask->cols, mask->rows)).setTo(0);
}

// Oversized: bleeding outward, and sometimes a blob on one side.
void BleedOutward(const SimulatedSegmenterOptions& o, const ErrorReach& reach,
                  const cv::Mat& truth, int area, Rng* rng, cv::Mat* mask) {
  if (!rng->Bernoulli(o.bleed_prob)) return;
  const int radius = static_cast<int>(std::lround(rng->Uniform(0.3, 1.0) * reach.bleed_px));
  if (radius > 0) {
    const cv::Mat kernel =
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
    cv::dilate(*mask, *mask, kernel);
  }
  if (!rng->Bernoulli(o.bleed_blob_prob)) return;
  const cv::Point centre = RandomPixelOf(rng, truth, area);
  const double angle = rng->Uniform(0, 2 * M_PI);
  const double distance = rng->Uniform(1.0, 3.0) * std::max(reach.bleed_px, 1.0);
  const cv::Point shifted(centre.x + static_cast<int>(std::lround(distance * std::cos(angle))),
                          centre.y + static_cast<int>(std::lround(distance * std::sin(angle))));
  const int axis = static_cast<int>(std::lround(std::max(2.0, distance)));
  cv::ellipse(*mask, shifted, cv::Size(axis, std::max(1, axis / 2)), angle * 180 / M_PI, 0, 360,
              1, cv::FILLED);
}

// Oversized: spread into the touching instances (gt_ids_box: the ids within the mask's box).
void BleedIntoNeighbours(const SimulatedSegmenterOptions& o, const ErrorReach& reach,
                         const cv::Mat& gt_ids_box, std::uint16_t id, const cv::Mat& truth,
                         Rng* rng, cv::Mat* mask) {
  if (!rng->Bernoulli(o.neighbour_bleed_prob)) return;
  const int radius =
      static_cast<int>(std::lround(rng->Uniform(1.0 / 3.0, 1.0) * reach.neighbour_px));
  if (radius <= 0) return;
  const cv::Mat others = (gt_ids_box != 0) & (gt_ids_box != id);  // 0/255
  cv::Mat reached;
  const cv::Mat kernel =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  cv::dilate(truth, reached, kernel);
  *mask |= reached & (others / 255);
}

// The category the network outputs: sometimes a look-alike in view (the same one while
// the choice stays), leaning towards the class seen more: a rare class is taken for a
// common look-alike at the full rate, a common one for a rare look-alike seldom.
int OutputCategory(const SimulatedSegmenterOptions& o, std::uint64_t seed, int frame_index,
                   std::uint16_t id, int category, const CategoriesInView& in_view) {
  Rng confusion_rng(seed, frame_index, id, kStreamConfusion);
  const std::vector<int> look_alikes = LookAlikes(category, in_view.ids);
  if (look_alikes.empty()) return category;
  Rng target_rng(seed, -1, id, kStreamConfusionTarget);
  const int target =
      look_alikes[target_rng.UniformInt(0, static_cast<int>(look_alikes.size()) - 1)];
  const double own = in_view.pixels.at(category);
  const double other = in_view.pixels.at(target);
  const double lean = std::min(1.0, 2.0 * other / (own + other));
  return confusion_rng.Bernoulli(o.confusion_prob * lean) ? target : category;
}

// The network's output for one ground-truth instance, or nothing when it is missed.
std::optional<InstanceMask> SimulateInstance(const SimulatedSegmenterOptions& o,
                                             std::uint64_t seed, int frame_index,
                                             const cv::Mat& gt_ids, const GtInstance& gt,
                                             const InstanceInfo& info,
                                             const SimulatedInstanceContext& ctx,
                                             const CategoriesInView& in_view) {
  const double image_area = static_cast<double>(gt_ids.total());
  // Persistent difficulty of this instance (the same in every frame).
  Rng difficulty_rng(seed, -1, gt.id, kStreamDifficulty);
  const double difficulty = o.difficulty_sd * difficulty_rng.Normal() +
                            (IsHardCategory(info.category_id) ? o.hard_category_difficulty : 0.0);

  // Missed? A fresh draw per frame: flicker.
  if (gt.area < o.min_area_px) return std::nullopt;
  Rng miss_rng(seed, frame_index, gt.id, kStreamMiss);
  if (miss_rng.Bernoulli(MissProbability(o, gt, ctx, difficulty, image_area))) {
    return std::nullopt;
  }

  // Work in the bounding box grown by the largest outward change.
  const ErrorReach reach(o, std::sqrt(static_cast<double>(gt.area)), std::exp(0.5 * difficulty));
  const int pad = reach.Padding();
  const cv::Rect box = cv::Rect(gt.x0 - pad, gt.y0 - pad, gt.x1 - gt.x0 + 1 + 2 * pad,
                                gt.y1 - gt.y0 + 1 + 2 * pad) &
                       cv::Rect(0, 0, gt_ids.cols, gt_ids.rows);
  cv::Mat truth;
  cv::compare(gt_ids(box), gt.id, truth, cv::CMP_EQ);
  truth /= 255;
  cv::Mat mask = truth.clone();
  const cv::Rect object_box(gt.x0 - box.x, gt.y0 - box.y, gt.x1 - gt.x0 + 1, gt.y1 - gt.y0 + 1);

  // The mask head's fixed resolution, then each kind of error from its own stream.
  if (o.mask_resolution > 0) CoarsenToGrid(object_box, o.mask_resolution, &mask);
  Rng holes_rng(seed, frame_index, gt.id, kStreamHoles);
  PunchHoles(o, reach, truth, gt.area, &holes_rng, &mask);
  Rng cut_rng(seed, frame_index, gt.id, kStreamCut);
  CutOffSide(o, reach, object_box, &cut_rng, &mask);
  Rng bleed_rng(seed, frame_index, gt.id, kStreamBleed);
  BleedOutward(o, reach, truth, gt.area, &bleed_rng, &mask);
  Rng neighbour_rng(seed, frame_index, gt.id, kStreamNeighbourBleed);
  BleedIntoNeighbours(o, reach, gt_ids(box), gt.id, truth, &neighbour_rng, &mask);
  Rng jitter_rng(seed, frame_index, gt.id, kStreamJitter);
  JitterBoundary(&jitter_rng, reach.jitter_px, reach.jitter_scale_px, &mask);

  const int produced = cv::countNonZero(mask);
  if (produced == 0) return std::nullopt;
  const int intersection = cv::countNonZero(mask & truth);
  const double iou = intersection / static_cast<double>(gt.area + produced - intersection);

  InstanceMask out;
  out.category_id = OutputCategory(o, seed, frame_index, gt.id, info.category_id, in_view);
  // The score follows the mask's quality; a confused class scores lower.
  Rng score_rng(seed, frame_index, gt.id, kStreamScore);
  double score = 1.0 - o.score_iou_weight * (1.0 - iou) + o.score_noise_sd * score_rng.Normal();
  if (out.category_id != info.category_id) score *= o.confusion_score_factor;
  out.score = Clamp01(score, 0.01);
  out.mask = cv::Mat::zeros(gt_ids.size(), CV_8U);
  mask.copyTo(out.mask(box));
  return out;
}

// False positives: blobs on the background, mostly low-scored, each like an object in
// view: the class and (scaled) size of a random ground-truth instance of the frame, else
// of a random class of the sequence at the size range.
std::vector<InstanceMask> SimulateFalsePositives(const SimulatedSegmenterOptions& o,
                                                 std::uint64_t seed, int frame_index,
                                                 const cv::Mat& gt_ids,
                                                 const std::vector<GtInstance>& frame_instances,
                                                 const InstanceTable& table) {
  std::vector<InstanceMask> blobs;
  Rng rng(seed, frame_index, 0, kStreamFalsePositives);
  const int count = rng.Poisson(o.false_positives_per_frame);
  if (count == 0) return blobs;
  const cv::Size size = gt_ids.size();
  const double image_area = static_cast<double>(size.area());
  const std::vector<int> sequence_categories = SequenceCategories(table);
  cv::Mat background;
  cv::compare(gt_ids, 0, background, cv::CMP_EQ);
  background /= 255;
  for (int k = 0; k < count; ++k) {
    int category = 0;
    double area = 0;
    if (!frame_instances.empty()) {
      const GtInstance& like =
          frame_instances[rng.UniformInt(0, static_cast<int>(frame_instances.size()) - 1)];
      category = table.Find(like.id)->category_id;
      area = std::clamp(like.area * std::exp(rng.Uniform(std::log(0.3), std::log(2.0))),
                        o.false_positive_area_min * image_area,
                        o.false_positive_area_max * image_area);
    } else {
      category = sequence_categories[rng.UniformInt(
          0, static_cast<int>(sequence_categories.size()) - 1)];
      area = image_area * std::exp(rng.Uniform(std::log(o.false_positive_area_min),
                                               std::log(o.false_positive_area_max)));
    }
    const double aspect = std::exp(rng.Uniform(std::log(0.4), std::log(2.5)));
    const int a = std::max(1, static_cast<int>(std::lround(std::sqrt(area * aspect / M_PI))));
    const int b = std::max(1, static_cast<int>(std::lround(std::sqrt(area / aspect / M_PI))));
    const cv::Point centre(rng.UniformInt(0, size.width - 1), rng.UniformInt(0, size.height - 1));
    const double angle = rng.Uniform(0, 180);
    const double score = rng.Uniform(0.01, o.false_positive_score_max);
    cv::Mat blob = cv::Mat::zeros(size, CV_8U);
    cv::ellipse(blob, centre, cv::Size(a, b), angle, 0, 360, 1, cv::FILLED);
    const double sqrt_area = std::sqrt(area);
    JitterBoundary(&rng, std::min(o.boundary_jitter_px, o.boundary_jitter_fraction * sqrt_area),
                   std::max(2.0, o.boundary_jitter_scale_fraction * sqrt_area), &blob);
    blob &= background;
    if (cv::countNonZero(blob) < std::max(20, o.min_area_px)) continue;
    InstanceMask out;
    out.category_id = category;
    out.score = Clamp01(score, 0.01);
    out.mask = std::move(blob);
    blobs.push_back(std::move(out));
  }
  return blobs;
}

}  // namespace

SimulatedFrame SimulateSegmentation(const SimulatedSegmenterOptions& options, std::uint64_t seed,
                                    int frame_index, const cv::Mat& gt_ids,
                                    const InstanceTable& table,
                                    const std::map<std::uint16_t, SimulatedInstanceContext>& context) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  if (gt_ids.type() != CV_16U) {
    throw Error("simulated segmenter: ground-truth ids must be CV_16UC1, got " +
                CvTypeName(gt_ids.type()));
  }
  const SimulatedSegmenterOptions o = options.Effective();

  std::vector<InstanceMask> outputs;
  std::vector<std::uint16_t> sources;  // ground-truth id of each output; 0: a false positive
  const std::vector<GtInstance> frame_instances = AnalyseIds(gt_ids);
  const CategoriesInView in_view = CountCategoriesInView(frame_instances, table);
  for (const GtInstance& gt : frame_instances) {
    const InstanceInfo* info = table.Find(gt.id);
    if (info == nullptr) {
      throw Error(fmt::format("simulated segmenter: frame {}: id {} is not in the instance table",
                              frame_index, gt.id));
    }
    const auto found = context.find(gt.id);
    const SimulatedInstanceContext ctx =
        found == context.end() ? SimulatedInstanceContext{} : found->second;
    std::optional<InstanceMask> out =
        SimulateInstance(o, seed, frame_index, gt_ids, gt, *info, ctx, in_view);
    if (!out) continue;
    outputs.push_back(std::move(*out));
    sources.push_back(gt.id);
  }
  for (InstanceMask& blob :
       SimulateFalsePositives(o, seed, frame_index, gt_ids, frame_instances, table)) {
    outputs.push_back(std::move(blob));
    sources.push_back(0);
  }

  // Number the outputs 1..N in a seeded per-frame order, so ids carry no ground truth.
  std::vector<size_t> order(outputs.size());
  std::iota(order.begin(), order.end(), 0);
  Rng order_rng(seed, frame_index, 0, kStreamOrder);
  for (size_t i = order.size(); i > 1; --i) {
    std::swap(order[i - 1], order[static_cast<size_t>(order_rng.UniformInt(0, static_cast<int>(i) - 1))]);
  }
  SimulatedFrame result;
  result.segmentation.frame_index = frame_index;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    InstanceMask& out = outputs[order[rank]];
    out.track_id = static_cast<std::uint16_t>(rank + 1);
    result.segmentation.instances.push_back(std::move(out));
    result.gt_ids.push_back(sources[order[rank]]);
  }
  return result;
}

double OwnImageSpeedPxPerS(const Eigen::Isometry3d& T_wc, const PinholeCamera& camera,
                           const TrackSample& now, const TrackSample& next) {
  const double dt = next.stamp_s - now.stamp_s;
  if (!(dt > 0)) return -1.0;
  const Eigen::Isometry3d T_cw = T_wc.inverse();
  const Eigen::Vector3d a = T_cw * now.T_world_object.translation();
  const Eigen::Vector3d b = T_cw * next.T_world_object.translation();
  constexpr double kMinDepthM = 0.1;
  if (a.z() < kMinDepthM || b.z() < kMinDepthM) return -1.0;
  const Eigen::Vector2d shift(camera.fx * (b.x() / b.z() - a.x() / a.z()),
                              camera.fy * (b.y() / b.z() - a.y() / a.z()));
  return shift.norm() / dt;
}

// ---------------------------------------------------------------------------------------
// The segmenter over a sequence directory.

namespace {

// The ground-truth pose whose stamp is nearest to `stamp_s` and within `tolerance_s` of
// it, or nullptr (generated sequences write one pose per frame, at the frame's stamp).
const StampedPose* NearestPose(const std::vector<StampedPose>& poses, double stamp_s,
                               double tolerance_s) {
  auto after = std::lower_bound(poses.begin(), poses.end(), stamp_s,
                                [](const StampedPose& p, double stamp) { return p.stamp_s < stamp; });
  const StampedPose* best = nullptr;
  if (after != poses.end()) best = &*after;
  if (after != poses.begin() &&
      (best == nullptr || stamp_s - std::prev(after)->stamp_s < best->stamp_s - stamp_s)) {
    best = &*std::prev(after);
  }
  return best != nullptr && std::abs(best->stamp_s - stamp_s) <= tolerance_s ? best : nullptr;
}

}  // namespace

SimulatedSegmenter::SimulatedSegmenter(const fs::path& sequence_dir,
                                       const SimulatedSegmenterOptions& options,
                                       std::uint64_t seed, std::string preset_name)
    : dir_(sequence_dir), options_(options), seed_(seed), preset_name_(std::move(preset_name)) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
  sequence_ = TumSequence::Open(dir_);
  if (!fs::is_directory(dir_ / "masks")) {
    throw FileError(dir_ / "masks", "no ground-truth masks folder (the simulated segmenter needs "
                                    "a generated sequence)");
  }
  table_ = InstanceTable::Read(dir_ / "instances.json");
  if (fs::exists(dir_ / "tracks.json")) {
    for (const ObjectTrack& track : ReadTracks(dir_ / "tracks.json")) {
      auto& states = tracks_[track.instance_id];
      for (size_t k = 0; k < track.samples.size(); ++k) {
        const TrackSample& s = track.samples[k];
        TrackState& state = states[s.frame];
        state.visible_pixels = s.visible_pixels;
        state.moving = s.moving;
        // "moving" means since the previous frame: the speed over the same step (the
        // first sample has none: the step after it).
        if (!s.moving || track.samples.size() < 2) continue;
        const size_t from = std::max<size_t>(k, 1) - 1;
        const TrackSample& a = track.samples[from];
        const TrackSample& b = track.samples[from + 1];
        const StampedPose* pose =
            NearestPose(sequence_.groundtruth(), a.stamp_s, 0.5 * (b.stamp_s - a.stamp_s));
        if (pose != nullptr) {
          state.own_image_speed_px_s =
              OwnImageSpeedPxPerS(pose->T_wc, sequence_.camera().intrinsics, a, b);
        }
      }
    }
  }
}

fs::path SimulatedSegmenter::MaskPath(size_t i) const {
  if (i >= sequence_.size()) {
    throw FileError(dir_, fmt::format("frame {} is out of range (the sequence has {} frames)", i,
                                      sequence_.size()));
  }
  return dir_ / "masks" / (fs::path(sequence_.entries()[i].rgb_file).stem().string() + ".png");
}

SimulatedFrame SimulatedSegmenter::SegmentWithTruth(const RgbdFrame& frame) {
  if (frame.index < 0) throw FileError(dir_, fmt::format("negative frame index {}", frame.index));
  const fs::path path = MaskPath(static_cast<size_t>(frame.index));
  if (!fs::exists(path)) throw FileError(path, "ground-truth mask is missing");
  // As stored: a network segments the stored image; its masks are then read into the
  // frame's geometry, as external masks are.
  const cv::Mat ids = ReadInstanceMask(path);
  const cv::Size expected = !frame.color_bgr.empty()
                                ? frame.color_bgr.size()
                                : cv::Size(sequence_.camera().intrinsics.width,
                                           sequence_.camera().intrinsics.height);
  if (ids.size() != expected) {
    throw FileError(path, fmt::format("mask is {}x{}, the frame is {}x{}", ids.cols, ids.rows,
                                      expected.width, expected.height));
  }
  CheckMaskIds(ids, table_, path.string());

  // Context from tracks.json: visible share against the recent maximum, and motion.
  std::map<std::uint16_t, SimulatedInstanceContext> context;
  for (const auto& [id, samples] : tracks_) {
    const auto here = samples.find(frame.index);
    if (here == samples.end()) continue;
    int recent_max = 0;
    for (auto it = samples.lower_bound(frame.index - options_.occlusion_window);
         it != samples.end() && it->first <= frame.index + options_.occlusion_window; ++it) {
      recent_max = std::max(recent_max, it->second.visible_pixels);
    }
    SimulatedInstanceContext ctx;
    ctx.visible_share =
        recent_max > 0 ? here->second.visible_pixels / static_cast<double>(recent_max) : 1.0;
    ctx.moving = here->second.moving;
    ctx.own_image_speed_px_s = here->second.own_image_speed_px_s;
    context[id] = ctx;
  }
  SimulatedFrame simulated = SimulateSegmentation(options_, seed_, frame.index, ids, table_, context);
  if (sequence_.camera().distortion.IsZero()) return simulated;
  SimulatedFrame loaded;
  loaded.segmentation.frame_index = simulated.segmentation.frame_index;
  for (size_t k = 0; k < simulated.segmentation.instances.size(); ++k) {
    InstanceMask& instance = simulated.segmentation.instances[k];
    instance.mask = sequence_.InstanceMaskAsLoaded(instance.mask);
    // Gone in the resampling: a sliver, or (barrel lens) all of it outside the pinhole frame.
    if (cv::countNonZero(instance.mask) == 0) continue;
    loaded.segmentation.instances.push_back(std::move(instance));
    loaded.gt_ids.push_back(simulated.gt_ids[k]);
  }
  return loaded;
}

FrameSegmentation SimulatedSegmenter::Segment(const RgbdFrame& frame) {
  return SegmentWithTruth(frame).segmentation;
}

std::string SimulatedSegmenter::name() const {
  std::string n = "simulated:" + preset_name_;
  if (options_.strength != 1.0) n += fmt::format("@{}", options_.strength);
  return n;
}

}  // namespace segslam::seg
