#include "seg/metrics.h"

#include "core/coco.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>

#include <opencv2/imgproc.hpp>

namespace segslam::seg {
namespace {

using detail::CategoryMatches;
using detail::ScoredDetection;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// pycocotools' recThrs = numpy.linspace(0, 1, 101): k * 0.01 (the product, which is not
// always the double nearest k / 100), and exactly 1 at the end.
constexpr int kNumRecallThresholds = 101;
double RecallThreshold(int k) {
  constexpr double kStep = 1.0 / (kNumRecallThresholds - 1);
  return k == kNumRecallThresholds - 1 ? 1.0 : k * kStep;
}

// Indices of CocoIouThresholds() that AP50 and AP75 read.
constexpr int kIou50Index = 0;
constexpr int kIou75Index = 5;

constexpr int kNumIds = std::numeric_limits<std::uint16_t>::max() + 1;

// Everything a frame contributes, computed before anything is added to the sequence so
// that a throwing frame leaves the evaluator unchanged.
struct FrameContribution {
  std::map<int, CategoryMatches> matches;
  std::map<int, PixelCounts> pixels;
  int gt_instances = 0;
  int detections = 0;
};

struct GroundTruthInstance {
  std::uint16_t id = 0;
  int category_id = 0;
  std::int64_t area = 0;  // Pixels.
};

// Indices of `detections` sorted by descending score, equal scores in their given order
// (numpy's mergesort of -score, which COCOeval uses both per image and per category).
template <typename ScoreOf>
std::vector<size_t> StableOrderByDescendingScore(size_t count, ScoreOf score_of) {
  std::vector<size_t> order(count);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return score_of(a) > score_of(b); });
  return order;
}

void CheckFrame(const cv::Mat& gt_ids, const FrameSegmentation& prediction) {
  if (gt_ids.empty() || gt_ids.type() != CV_16U) {
    throw Error("segmentation metrics: the ground-truth id image must be a non-empty CV_16U image");
  }
  for (size_t i = 0; i < prediction.instances.size(); ++i) {
    const InstanceMask& instance = prediction.instances[i];
    const std::string where = "segmentation metrics: frame " +
                              std::to_string(prediction.frame_index) + ", predicted instance " +
                              std::to_string(i) + ": ";
    if (instance.mask.type() != CV_8U || instance.mask.size() != gt_ids.size()) {
      throw Error(where + "the mask must be CV_8U of the ground truth's size");
    }
    if (FindCocoCategory(instance.category_id) == nullptr) {
      throw Error(where + "category " + std::to_string(instance.category_id) +
                  " is not a COCO category id");
    }
    if (!std::isfinite(instance.score)) {
      throw Error(where + "the score is not finite");  // It would break the sort order.
    }
  }
}

// AP at one IoU threshold (index `t`) of detections already in the final stable
// descending-score order; steps 4 of the header. `num_gt` > 0.
double AveragePrecisionAt(const std::vector<ScoredDetection>& sorted, int num_gt, int t) {
  const size_t count = sorted.size();
  std::vector<double> precision(count);
  std::vector<double> recall(count);
  std::int64_t true_positives = 0;
  for (size_t i = 0; i < count; ++i) {
    if (sorted[i].matched & (1u << t)) ++true_positives;
    recall[i] = static_cast<double>(true_positives) / num_gt;
    precision[i] = static_cast<double>(true_positives) / static_cast<double>(i + 1);
  }
  // The precision envelope: the best precision reachable at this recall or a higher one.
  for (size_t i = count; i-- > 1;) precision[i - 1] = std::max(precision[i - 1], precision[i]);
  // Sample at the recall thresholds (numpy.searchsorted(recall, r, side="left")); once a
  // threshold is beyond the last recall, so are the rest, and they count 0.
  double sum = 0;
  size_t i = 0;
  for (int k = 0; k < kNumRecallThresholds; ++k) {
    const double threshold = RecallThreshold(k);
    while (i < count && recall[i] < threshold) ++i;
    if (i == count) break;
    sum += precision[i];
  }
  return sum / kNumRecallThresholds;
}

// The ground-truth instances of a frame: the ids present in the image, ascending
// (pycocotools keeps annotation order; ids are segslam's stable order), each with its
// category and area, and lookups by id.
struct FrameGroundTruth {
  std::vector<GroundTruthInstance> instances;
  std::vector<int> index_of_id = std::vector<int>(kNumIds, -1);
  std::vector<int> category_of_id = std::vector<int>(kNumIds, 0);  // 0 = background.
};

FrameGroundTruth CollectGroundTruth(const cv::Mat& gt_ids, const InstanceTable& gt_instances,
                                    int frame_index) {
  std::vector<std::int64_t> area_of_id(kNumIds, 0);
  for (int row = 0; row < gt_ids.rows; ++row) {
    const std::uint16_t* ids = gt_ids.ptr<std::uint16_t>(row);
    for (int col = 0; col < gt_ids.cols; ++col) ++area_of_id[ids[col]];
  }
  FrameGroundTruth gt;
  for (int id = 1; id < kNumIds; ++id) {
    if (area_of_id[id] == 0) continue;
    const InstanceInfo* info = gt_instances.Find(static_cast<std::uint16_t>(id));
    if (info == nullptr) {
      throw Error("segmentation metrics: frame " + std::to_string(frame_index) +
                  ": ground-truth id " + std::to_string(id) + " is not in the instance table");
    }
    gt.index_of_id[id] = static_cast<int>(gt.instances.size());
    gt.category_of_id[id] = info->category_id;
    gt.instances.push_back({static_cast<std::uint16_t>(id), info->category_id, area_of_id[id]});
  }
  return gt;
}

// Per detection: its area, its bounding box and its intersection with every ground-truth
// instance (the ground truth is a label image, so one pass over the mask gives all
// intersections).
struct DetectionOverlaps {
  DetectionOverlaps(const FrameSegmentation& prediction, const cv::Mat& gt_ids,
                    const FrameGroundTruth& gt)
      : gt_(gt) {
    const size_t count = prediction.instances.size();
    area.assign(count, 0);
    box.resize(count);
    intersection.assign(count, std::vector<std::int64_t>(gt.instances.size(), 0));
    for (size_t d = 0; d < count; ++d) {
      const cv::Mat& mask = prediction.instances[d].mask;
      // A detection covers a small part of the frame: scanning its box, not the frame.
      box[d] = cv::boundingRect(mask);
      for (int row = box[d].y; row < box[d].br().y; ++row) {
        const std::uint8_t* inside = mask.ptr<std::uint8_t>(row);
        const std::uint16_t* ids = gt_ids.ptr<std::uint16_t>(row);
        for (int col = box[d].x; col < box[d].br().x; ++col) {
          if (inside[col] == 0) continue;
          ++area[d];
          if (ids[col] != 0) ++intersection[d][gt.index_of_id[ids[col]]];
        }
      }
    }
  }

  // IoU of detection d and ground-truth instance g.
  double IoU(size_t d, size_t g) const {
    const std::int64_t overlap = intersection[d][g];
    const std::int64_t union_area = area[d] + gt_.instances[g].area - overlap;  // > 0: area > 0.
    return static_cast<double>(overlap) / static_cast<double>(union_area);
  }

  std::vector<std::int64_t> area;
  std::vector<cv::Rect> box;
  std::vector<std::vector<std::int64_t>> intersection;

 private:
  const FrameGroundTruth& gt_;
};

// Steps 1 and 2 of the header for one category: its detections by score, capped, each
// matched greedily to its ground truth at every IoU threshold, as COCOeval.evaluateImg.
CategoryMatches MatchCategory(const EvaluationOptions& options, int category,
                              const FrameGroundTruth& gt, const FrameSegmentation& prediction,
                              const std::vector<size_t>& by_score,
                              const DetectionOverlaps& overlaps) {
  std::vector<size_t> category_gt;  // Ascending id.
  for (size_t g = 0; g < gt.instances.size(); ++g) {
    if (gt.instances[g].category_id == category) category_gt.push_back(g);
  }
  std::vector<size_t> category_detections;
  for (size_t d : by_score) {
    if (prediction.instances[d].category_id != category) continue;
    if (static_cast<int>(category_detections.size()) == options.max_detections_per_frame) break;
    category_detections.push_back(d);
  }

  CategoryMatches matches;
  matches.num_gt = static_cast<int>(category_gt.size());
  matches.detections.resize(category_detections.size());
  for (size_t k = 0; k < category_detections.size(); ++k) {
    matches.detections[k].score = prediction.instances[category_detections[k]].score;
  }
  const std::array<double, 10>& thresholds = CocoIouThresholds();
  for (size_t t = 0; t < thresholds.size(); ++t) {
    std::vector<bool> gt_taken(category_gt.size(), false);
    for (size_t k = 0; k < category_detections.size(); ++k) {
      double best_iou = thresholds[t];
      int best = -1;
      for (size_t j = 0; j < category_gt.size(); ++j) {
        if (gt_taken[j]) continue;
        const double value = overlaps.IoU(category_detections[k], category_gt[j]);
        if (value < best_iou) continue;  // Equal IoU: the later instance replaces.
        best_iou = value;
        best = static_cast<int>(j);
      }
      if (best < 0) continue;  // A false positive at this threshold.
      gt_taken[best] = true;
      matches.detections[k].matched |= static_cast<std::uint16_t>(1u << t);
    }
  }
  return matches;
}

// For mIoU: the true positive, false positive and false negative pixels of each category
// that has any. The predicted class of every pixel is painted from the lowest score up so
// the highest score wins overlaps (ToIdImage's rule, painting categories instead of track
// ids so that equal track ids of different detections cannot mix classes).
std::map<int, PixelCounts> CountClassPixels(const cv::Mat& gt_ids, const FrameGroundTruth& gt,
                                            const FrameSegmentation& prediction,
                                            const std::vector<cv::Rect>& detection_box,
                                            const std::set<int>& categories) {
  cv::Mat predicted_class(gt_ids.size(), CV_16U, cv::Scalar(0));
  // Ascending score, stably: on equal scores the later instance is painted last and wins.
  std::vector<size_t> paint_order(prediction.instances.size());
  std::iota(paint_order.begin(), paint_order.end(), 0);
  std::stable_sort(paint_order.begin(), paint_order.end(), [&](size_t a, size_t b) {
    return prediction.instances[a].score < prediction.instances[b].score;
  });
  for (size_t d : paint_order) {
    const InstanceMask& instance = prediction.instances[d];
    predicted_class(detection_box[d]).setTo(instance.category_id, instance.mask(detection_box[d]));
  }
  // Counted per category in an array, which is cheaper than a map lookup per pixel, then
  // kept for the categories that have pixels.
  int max_category = 0;
  for (const int category : categories) max_category = std::max(max_category, category);
  std::vector<PixelCounts> pixels(static_cast<size_t>(max_category) + 1);
  for (int row = 0; row < gt_ids.rows; ++row) {
    const std::uint16_t* ids = gt_ids.ptr<std::uint16_t>(row);
    const std::uint16_t* predicted = predicted_class.ptr<std::uint16_t>(row);
    for (int col = 0; col < gt_ids.cols; ++col) {
      const int truth = gt.category_of_id[ids[col]];
      const int guess = predicted[col];
      if (truth == guess) {
        if (truth != 0) ++pixels[static_cast<size_t>(truth)].true_positive;
        continue;
      }
      if (truth != 0) ++pixels[static_cast<size_t>(truth)].false_negative;
      if (guess != 0) ++pixels[static_cast<size_t>(guess)].false_positive;
    }
  }
  std::map<int, PixelCounts> counts_by_category;
  for (const int category : categories) {
    const PixelCounts& counts = pixels[static_cast<size_t>(category)];
    if (counts.true_positive + counts.false_positive + counts.false_negative > 0) {
      counts_by_category[category] = counts;
    }
  }
  return counts_by_category;
}

FrameContribution ScoreFrameContribution(const EvaluationOptions& options, const cv::Mat& gt_ids,
                                         const InstanceTable& gt_instances,
                                         const FrameSegmentation& prediction) {
  CheckFrame(gt_ids, prediction);
  const FrameGroundTruth gt = CollectGroundTruth(gt_ids, gt_instances, prediction.frame_index);
  const DetectionOverlaps overlaps(prediction, gt_ids, gt);

  // The categories present on either side.
  std::set<int> categories;
  for (const GroundTruthInstance& instance : gt.instances) categories.insert(instance.category_id);
  for (const InstanceMask& instance : prediction.instances) categories.insert(instance.category_id);

  FrameContribution frame;
  frame.gt_instances = static_cast<int>(gt.instances.size());
  const std::vector<size_t> by_score = StableOrderByDescendingScore(
      prediction.instances.size(), [&](size_t i) { return prediction.instances[i].score; });
  for (int category : categories) {
    CategoryMatches& matches = frame.matches[category];
    matches = MatchCategory(options, category, gt, prediction, by_score, overlaps);
    frame.detections += static_cast<int>(matches.detections.size());
  }
  frame.pixels = CountClassPixels(gt_ids, gt, prediction, overlaps.box, categories);
  return frame;
}

// Steps 3 to 5 and the mIoU of the header from per-category matches and pixel counts.
SegmentationScores ComputeScores(const std::map<int, CategoryMatches>& matches,
                                 const std::map<int, PixelCounts>& pixels) {
  SegmentationScores scores;
  const std::array<double, 10>& thresholds = CocoIouThresholds();
  double sum_ap = 0;
  double sum_ap50 = 0;
  double sum_ap75 = 0;
  int categories_with_gt = 0;
  for (const auto& [category, category_matches] : matches) {
    if (category_matches.num_gt == 0) {
      scores.ap_per_category[category] = kNaN;
      scores.ap50_per_category[category] = kNaN;
      scores.ap75_per_category[category] = kNaN;
      continue;
    }
    const std::vector<ScoredDetection>& detections = category_matches.detections;
    const std::vector<size_t> order = StableOrderByDescendingScore(
        detections.size(), [&](size_t i) { return detections[i].score; });
    std::vector<ScoredDetection> sorted;
    sorted.reserve(order.size());
    for (size_t i : order) sorted.push_back(detections[i]);

    std::array<double, 10> ap_at{};
    for (size_t t = 0; t < thresholds.size(); ++t) {
      ap_at[t] = AveragePrecisionAt(sorted, category_matches.num_gt, static_cast<int>(t));
    }
    const double ap = std::accumulate(ap_at.begin(), ap_at.end(), 0.0) / thresholds.size();
    scores.ap_per_category[category] = ap;
    scores.ap50_per_category[category] = ap_at[kIou50Index];
    scores.ap75_per_category[category] = ap_at[kIou75Index];
    sum_ap += ap;
    sum_ap50 += ap_at[kIou50Index];
    sum_ap75 += ap_at[kIou75Index];
    ++categories_with_gt;
  }
  scores.mAP = categories_with_gt > 0 ? sum_ap / categories_with_gt : kNaN;
  scores.AP50 = categories_with_gt > 0 ? sum_ap50 / categories_with_gt : kNaN;
  scores.AP75 = categories_with_gt > 0 ? sum_ap75 / categories_with_gt : kNaN;

  double sum_iou = 0;
  for (const auto& [category, counts] : pixels) {
    const std::int64_t denominator =
        counts.true_positive + counts.false_positive + counts.false_negative;
    if (denominator == 0) continue;  // Not a class of these frames.
    const double iou = static_cast<double>(counts.true_positive) / static_cast<double>(denominator);
    scores.iou_per_category[category] = iou;
    scores.pixels_per_category[category] = counts;
    sum_iou += iou;
  }
  scores.mIoU = scores.iou_per_category.empty()
                    ? kNaN
                    : sum_iou / static_cast<double>(scores.iou_per_category.size());
  return scores;
}

nlohmann::json NumberOrNull(double value) {
  return std::isnan(value) ? nlohmann::json(nullptr) : nlohmann::json(value);
}

nlohmann::json ValueOrNull(const std::map<int, double>& values, int category) {
  const auto it = values.find(category);
  return it == values.end() ? nlohmann::json(nullptr) : NumberOrNull(it->second);
}

}  // namespace

const std::array<double, 10>& CocoIouThresholds() {
  // numpy.linspace(.5, .95, 10): i * ((.95 - .5) / 9) + .5, the last set to .95. Written
  // out (shortest round-trip literals) rather than computed so that no compiler
  // contraction into a fused multiply-add can move a threshold by an ulp.
  static const std::array<double, 10> kThresholds = {
      0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.8999999999999999, 0.95};
  return kThresholds;
}

bool EvaluationOptions::IsValid(std::string* error) const {
  if (max_detections_per_frame < 1) {
    if (error != nullptr) {
      *error = "max_detections_per_frame must be >= 1, got " +
               std::to_string(max_detections_per_frame);
    }
    return false;
  }
  return true;
}

nlohmann::json SegmentationScores::ToJson() const {
  nlohmann::json json;
  json["mAP"] = NumberOrNull(mAP);
  json["AP50"] = NumberOrNull(AP50);
  json["AP75"] = NumberOrNull(AP75);
  json["mIoU"] = NumberOrNull(mIoU);
  json["frames"] = frames;
  json["gt_instances"] = gt_instances;
  json["detections"] = detections;
  std::set<int> categories;
  for (const auto& entry : ap_per_category) categories.insert(entry.first);
  for (const auto& entry : iou_per_category) categories.insert(entry.first);
  nlohmann::json per_category = nlohmann::json::array();
  for (int category : categories) {
    const CocoCategory* coco = FindCocoCategory(category);
    nlohmann::json entry;
    entry["category_id"] = category;
    entry["category"] = coco != nullptr ? std::string(coco->name) : std::string();
    entry["ap"] = ValueOrNull(ap_per_category, category);
    entry["ap50"] = ValueOrNull(ap50_per_category, category);
    entry["ap75"] = ValueOrNull(ap75_per_category, category);
    entry["iou"] = ValueOrNull(iou_per_category, category);
    const auto counts = pixels_per_category.find(category);
    const PixelCounts pixels =
        counts != pixels_per_category.end() ? counts->second : PixelCounts{};
    entry["tp_pixels"] = pixels.true_positive;
    entry["fp_pixels"] = pixels.false_positive;
    entry["fn_pixels"] = pixels.false_negative;
    per_category.push_back(std::move(entry));
  }
  json["categories"] = std::move(per_category);
  return json;
}

SegmentationEvaluator::SegmentationEvaluator(const EvaluationOptions& options)
    : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error("segmentation metrics: " + error);
}

SegmentationScores SegmentationEvaluator::AddFrame(const cv::Mat& gt_ids,
                                                   const InstanceTable& gt_instances,
                                                   const FrameSegmentation& prediction) {
  FrameContribution frame = ScoreFrameContribution(options_, gt_ids, gt_instances, prediction);
  SegmentationScores frame_scores = ComputeScores(frame.matches, frame.pixels);
  frame_scores.frames = 1;
  frame_scores.gt_instances = frame.gt_instances;
  frame_scores.detections = frame.detections;

  // Append in frame order: step 3's stable sort then breaks score ties by frame.
  for (auto& [category, matches] : frame.matches) {
    detail::CategoryMatches& sequence = matches_[category];
    sequence.num_gt += matches.num_gt;
    sequence.detections.insert(sequence.detections.end(), matches.detections.begin(),
                               matches.detections.end());
  }
  for (const auto& [category, counts] : frame.pixels) {
    PixelCounts& sequence = pixels_[category];
    sequence.true_positive += counts.true_positive;
    sequence.false_positive += counts.false_positive;
    sequence.false_negative += counts.false_negative;
  }
  ++frames_;
  gt_instances_ += frame.gt_instances;
  detections_ += frame.detections;
  return frame_scores;
}

SegmentationScores SegmentationEvaluator::Scores() const {
  SegmentationScores scores = ComputeScores(matches_, pixels_);
  scores.frames = frames_;
  scores.gt_instances = gt_instances_;
  scores.detections = detections_;
  return scores;
}

SegmentationScores SegmentationEvaluator::ScoreFrame(const EvaluationOptions& options,
                                                     const cv::Mat& gt_ids,
                                                     const InstanceTable& gt_instances,
                                                     const FrameSegmentation& prediction) {
  SegmentationEvaluator evaluator(options);
  return evaluator.AddFrame(gt_ids, gt_instances, prediction);
}

}  // namespace segslam::seg
