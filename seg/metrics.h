// Segmentation metrics of segslam: COCO mask AP (mAP, AP50, AP75) and semantic mIoU,
// over a whole sequence (SegmentationEvaluator) and for one frame (ScoreFrame).
//
// Inputs of one frame:
//   ground truth  a CV_16U instance-id image (0 = background, else an id of the
//                 sequence's InstanceTable, core/instances.h, which gives its COCO category);
//   prediction    a FrameSegmentation (seg/segmentation.h): instances with a COCO
//                 category, a score and a CV_8U frame-sized mask (any non-zero value is
//                 an instance pixel, as FrameSegmentation::ToIdImage reads it).
//
// ---- COCO AP, exactly as pycocotools' COCOeval (iouType "segm", areaRng "all",
//      maxDets 100) with every frame an image and no crowd or ignored annotations ----
// Ground truth of a frame: one instance per id present in the id image, with its
// category from the table. An instance with zero pixels in a frame is not ground truth
// in that frame (it is absent from COCO's annotations of that image).
// Mask IoU = |A ∩ B| / |A ∪ B| in pixels (pycocotools' rleIou as a double division).
// Per frame and category:
//   1. detections are sorted by descending score, stably (numpy mergesort of -score:
//      equal scores keep their order in FrameSegmentation::instances) and only the first
//      `max_detections_per_frame` are kept (pycocotools truncates per image AND category);
//   2. at each IoU threshold t, detections in that order are matched greedily: a
//      detection takes, among the ground truth instances not yet matched at t, the one
//      with the highest IoU, provided IoU >= t. Ground truth is scanned in ascending id
//      and a later instance with an IoU equal to the best so far replaces it (pycocotools'
//      `if ious[d, g] < iou: continue` keeps equal ones). Unmatched detections are FPs.
// Per category, over the sequence (or the one frame):
//   3. all kept detections, concatenated in frame order (the order of AddFrame calls,
//      which stands for pycocotools' sorted image ids) and within a frame in the order
//      of step 1, are sorted by descending score, stably (mergesort again);
//   4. at each t: cumulative TP and FP counts; recall_i = TP_i / num_gt,
//      precision_i = TP_i / (TP_i + FP_i); precision made non-increasing from the right
//      (precision_i = max over j >= i); sampled at the 101 recall thresholds
//      r_k = k * 0.01 (k = 0..100, r_100 = 1 exactly; numpy.linspace(0, 1, 101), a
//      product that is not always the double nearest k / 100: r_35 is
//      0.35000000000000003, so a recall of 7 / 20 does not reach it, as in pycocotools):
//      the precision at the first i with recall_i >= r_k, or 0 if there is none;
//      AP_t = mean of the 101 samples;
//   5. AP of the category = mean of AP_t over the 10 thresholds
//      t = 0.50, 0.55, ..., 0.95 (the doubles numpy.linspace(.5, .95, 10) yields; see
//      CocoIouThresholds()); AP50 / AP75 of the category = AP_t at t = 0.50 / 0.75.
//   mAP, AP50, AP75 = mean over the categories with at least one ground-truth instance
//   in the scored frames (pycocotools marks the others -1 and leaves them out). A
//   category with ground truth and no detections has AP 0. Detections of a category
//   without ground truth are therefore not penalised in AP (they are in mIoU).
// One deliberate difference: pycocotools divides TP / (TP + FP + 2^-52); TP + FP >= 1
// always holds, so segslam leaves the guard out (pycocotools' values are lower by at
// most ~2e-16, e.g. 0.9999999999999998 where segslam reports 1).
//
// ---- mIoU, semantic segmentation (VOC / Cityscapes accumulation) ----
// Each frame becomes two per-pixel class maps: ground truth = category of the pixel's
// instance id; prediction = category of the instance painted last when instances are
// painted in ascending score, stably (the overlap rule of FrameSegmentation::ToIdImage:
// the higher score wins, on equal scores the later instance). Background (id 0, or no
// predicted instance) is not a class. For every class c, over all scored frames:
//   TP_c = pixels with gt = c and prediction = c,
//   FP_c = pixels with prediction = c and gt != c (gt background or another class),
//   FN_c = pixels with gt = c and prediction != c;
//   IoU_c = TP_c / (TP_c + FP_c + FN_c), defined for the classes that occur in ground
//   truth or prediction in at least one scored frame (TP + FP + FN > 0).
// mIoU = unweighted mean of IoU_c over those classes. Pixel counts are summed over the
// sequence before dividing (the figure the paper's tables report per sequence), so a
// sequence's mIoU is not the mean of its frames' mIoU.
//
// Undefined values are NaN: mAP / AP50 / AP75 when no category has ground truth, a
// category's AP when it has no ground truth, mIoU when no class occurs at all.
#pragma once

#include "core/instances.h"
#include "seg/segmentation.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace segslam::seg {

// The 10 COCO IoU thresholds 0.50:0.05:0.95 as the doubles numpy.linspace(.5, .95, 10)
// produces (i * 0.05 + 0.5; the ninth is 0.8999999999999999, the third exactly 0.6),
// so that an IoU lying on a threshold is decided as pycocotools decides it.
const std::array<double, 10>& CocoIouThresholds();

struct EvaluationOptions {
  // Detections kept per frame and category, the highest-scored first (COCO's maxDets;
  // 100 is the value of the published mask AP). >= 1.
  int max_detections_per_frame = 100;

  // False (and a reason in *error when given) if a value is out of range.
  bool IsValid(std::string* error) const;
};

// Pixel counts of one class, summed over the scored frames (see the mIoU definition).
struct PixelCounts {
  std::int64_t true_positive = 0;
  std::int64_t false_positive = 0;
  std::int64_t false_negative = 0;
};

struct SegmentationScores {
  double mAP = 0;   // COCO AP @[0.50:0.95], mean over categories with ground truth; NaN if none.
  double AP50 = 0;  // The same at IoU 0.50 only.
  double AP75 = 0;  // The same at IoU 0.75 only.
  double mIoU = 0;  // Semantic mIoU over the classes that occur; NaN if none.

  // Per COCO category id, for every category with ground truth or detections in the
  // scored frames; NaN for a category without ground truth (left out of the means).
  std::map<int, double> ap_per_category;
  std::map<int, double> ap50_per_category;
  std::map<int, double> ap75_per_category;
  // Per COCO category id, IoU_c for every class that occurs (never NaN).
  std::map<int, double> iou_per_category;
  std::map<int, PixelCounts> pixels_per_category;

  int frames = 0;        // Frames scored.
  int gt_instances = 0;  // Ground-truth instances summed over frames (an instance seen in
                         // 10 frames counts 10 times), those with >= 1 pixel.
  int detections = 0;    // Predicted instances scored, after the per-frame cap.

  // {"mAP", "AP50", "AP75", "mIoU", "frames", "gt_instances", "detections",
  //  "categories": [{"category_id", "category", "ap", "ap50", "ap75", "iou",
  //                  "tp_pixels", "fp_pixels", "fn_pixels"}, ...] sorted by id}.
  // NaN and absent per-category values are written as null.
  nlohmann::json ToJson() const;
};

namespace detail {
// What AP needs of one detection once it is matched in its frame.
struct ScoredDetection {
  float score = 0;
  std::uint16_t matched = 0;  // Bit t set: a TP at CocoIouThresholds()[t].
};
// The AP input of one category over a frame or a sequence.
struct CategoryMatches {
  int num_gt = 0;                           // Ground-truth instances (frame-instances).
  std::vector<ScoredDetection> detections;  // Frame order, then step 1's order.
};
}  // namespace detail

// Accumulates frames of one sequence and scores them together. Not copyable (it holds
// the sequence's state); cheap to keep: per category the scores and match flags of its
// detections, and per class three pixel counts.
class SegmentationEvaluator {
 public:
  // Throws segslam::Error if `options` is not valid.
  explicit SegmentationEvaluator(const EvaluationOptions& options = {});
  SegmentationEvaluator(const SegmentationEvaluator&) = delete;
  SegmentationEvaluator& operator=(const SegmentationEvaluator&) = delete;

  // Scores one frame, adds it to the sequence and returns the frame's own scores (the
  // same as ScoreFrame). Throws segslam::Error, adding nothing, if `gt_ids` is not a
  // non-empty CV_16U image, holds an id missing from `gt_instances`, or a predicted
  // instance's mask is not CV_8U of the same size, its category is not a COCO id or its
  // score is not finite.
  SegmentationScores AddFrame(const cv::Mat& gt_ids, const InstanceTable& gt_instances,
                              const FrameSegmentation& prediction);

  // Scores of all frames added so far (NaN everywhere when none).
  SegmentationScores Scores() const;

  // Scores of one frame on its own; throws as AddFrame does.
  static SegmentationScores ScoreFrame(const EvaluationOptions& options, const cv::Mat& gt_ids,
                                       const InstanceTable& gt_instances,
                                       const FrameSegmentation& prediction);

 private:
  EvaluationOptions options_;
  int frames_ = 0;
  int gt_instances_ = 0;
  int detections_ = 0;
  std::map<int, detail::CategoryMatches> matches_;  // By COCO category id.
  std::map<int, PixelCounts> pixels_;               // By COCO category id.
};

}  // namespace segslam::seg
