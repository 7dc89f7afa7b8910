#include "seg/mask_damage_internal.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "core/coco.h"

namespace segslam::seg::mask_damage {
namespace {

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

}  // namespace

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

}  // namespace segslam::seg::mask_damage
