#include "seg/simulated_segmenter_options.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/option_assignment.h"

namespace segslam::seg {

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

}  // namespace segslam::seg
