// The report's pictures drawn on a frame (harness/report_figures.h): raw vs refined masks
// beside the ground truth (the paper's Fig. 5) and the features of a frame kept or
// dropped by the judgement (Fig. 6), with the choice of the frame that shows it best.
#include "harness/report_figures.h"

#include <algorithm>
#include <array>
#include <map>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "harness/pictures.h"
#include "harness/plot_toolkit.h"

namespace segslam::harness {

using namespace plot;

// ------------------------------------------------------------------ masks (Fig. 5)

namespace {

void CheckImage(const cv::Mat& image, int type, cv::Size size, const std::string& what) {
  if (image.type() != type) {
    throw Error(fmt::format("{} must be {}, not {}", what, CvTypeName(type), CvTypeName(image.type())));
  }
  if (image.size() != size) {
    throw Error(fmt::format("{} is {}x{}, the frame {}x{}", what, image.cols, image.rows, size.width, size.height));
  }
}

// A dark tag with the instance's class at the top-left of its bounding box.
void LabelInstances(cv::Mat& image, const cv::Mat& ids, const std::map<std::uint16_t, std::string>& labels) {
  for (const auto& [id, label] : labels) {
    const cv::Mat mask = ids == id;
    const cv::Rect box = cv::boundingRect(mask);
    if (box.empty()) continue;
    const cv::Size text = TextSize(label, 0.45, 1);
    cv::Rect tag(box.x, box.y - text.height - 8, text.width + 8, text.height + 8);
    if (tag.y < 0) tag.y = box.y;
    tag.x = std::clamp(tag.x, 0, std::max(0, image.cols - tag.width));
    cv::rectangle(image, tag, cv::Scalar(30, 30, 30), cv::FILLED);
    DrawText(image, label, {tag.x + 4, tag.y + 4}, 0.45, kWhite, 1, HAlign::kLeft, VAlign::kTop);
  }
}

std::map<std::uint16_t, std::string> SegmentationLabels(const seg::FrameSegmentation& segmentation) {
  std::map<std::uint16_t, std::string> labels;
  for (const seg::InstanceMask& instance : segmentation.instances) {
    const CocoCategory* category = FindCocoCategory(instance.category_id);
    labels[instance.track_id] = category != nullptr ? std::string(category->name)
                                                    : fmt::format("class {}", instance.category_id);
  }
  return labels;
}

cv::Mat WithWhiteBorder(const cv::Mat& image, int border_px) {
  cv::Mat bordered;
  cv::copyMakeBorder(image, bordered, border_px, border_px, border_px, border_px, cv::BORDER_CONSTANT, kWhite);
  return bordered;
}

}  // namespace

cv::Mat DrawMaskComparison(const cv::Mat& color_bgr, const cv::Mat& ground_truth_ids,
                           const InstanceTable& instance_table, const seg::FrameSegmentation& raw,
                           const seg::FrameSegmentation& refined) {
  if (color_bgr.type() != CV_8UC3 || color_bgr.empty()) {
    throw Error("mask comparison: the frame must be CV_8UC3, not " + CvTypeName(color_bgr.type()));
  }
  const cv::Size size = color_bgr.size();
  CheckImage(ground_truth_ids, CV_16U, size, "mask comparison: ground-truth ids");
  for (const auto* segmentation : {&raw, &refined}) {
    for (const seg::InstanceMask& instance : segmentation->instances) {
      CheckImage(instance.mask, CV_8U, size, fmt::format("mask comparison: mask of instance {}", instance.track_id));
    }
  }
  // Ground-truth labels for the ids present in this frame.
  std::map<std::uint16_t, std::string> truth_labels;
  for (auto it = ground_truth_ids.begin<std::uint16_t>(); it != ground_truth_ids.end<std::uint16_t>(); ++it) {
    if (*it != 0) truth_labels.emplace(*it, std::string());
  }
  for (auto& [id, label] : truth_labels) {
    const InstanceInfo* info = instance_table.Find(id);
    label = info != nullptr ? info->category_name : fmt::format("id {}", id);
  }
  const cv::Mat raw_ids = raw.ToIdImage(size);
  const cv::Mat refined_ids = refined.ToIdImage(size);
  cv::Mat truth_panel = OverlayPicture(color_bgr, ground_truth_ids);
  cv::Mat raw_panel = OverlayPicture(color_bgr, raw_ids);
  cv::Mat refined_panel = OverlayPicture(color_bgr, refined_ids);
  LabelInstances(truth_panel, ground_truth_ids, truth_labels);
  LabelInstances(raw_panel, raw_ids, SegmentationLabels(raw));
  LabelInstances(refined_panel, refined_ids, SegmentationLabels(refined));
  constexpr int kBorderPx = 3;
  return WithWhiteBorder(CaptionedRow({WithWhiteBorder(truth_panel, kBorderPx), WithWhiteBorder(raw_panel, kBorderPx),
                                       WithWhiteBorder(refined_panel, kBorderPx)},
                                      {" ground truth", " raw", " refined"}),
                         kBorderPx);
}

// ------------------------------------------------------------------ features (Fig. 6)

cv::Scalar FeatureKindColor(slam::FeatureKind kind) {
  switch (kind) {
    case slam::FeatureKind::kUsed: return {0, 200, 0};
    case slam::FeatureKind::kDroppedMoving: return {0, 0, 235};
    case slam::FeatureKind::kDroppedMoveable: return {0, 150, 255};
    case slam::FeatureKind::kOutlier: return {160, 160, 160};
    case slam::FeatureKind::kUnmatched: return {255, 255, 255};
  }
  return {255, 0, 255};
}

namespace {

const cv::Scalar kMovingOutlineColor(255, 0, 255);  // magenta: apart from every feature colour

std::string FeatureKindLegend(slam::FeatureKind kind) {
  switch (kind) {
    case slam::FeatureKind::kUsed: return "used in fine pose";
    case slam::FeatureKind::kDroppedMoving: return "dropped: moving instance";
    case slam::FeatureKind::kDroppedMoveable: return "dropped: moveable class";
    case slam::FeatureKind::kOutlier: return "outlier";
    case slam::FeatureKind::kUnmatched: return "unmatched";
  }
  return "?";
}

constexpr double kFeatureRadiusPx = 3.2;

// A feature's dark rim (a disc one pixel larger than its dot). Drawn for all features of
// a kind before their dots, so close neighbours' rims do not cut into each other's dots.
void DrawFeatureRim(cv::Mat& image, const cv::Point2f& pixel, slam::FeatureKind kind) {
  if (kind == slam::FeatureKind::kUnmatched) return;  // a ring, no rim
  cv::circle(image, Fixed(cv::Point2d(pixel.x, pixel.y)), static_cast<int>((kFeatureRadiusPx + 1) * kSubPixel), kBlack,
             cv::FILLED, cv::LINE_AA, kShift);
}

void DrawFeatureDot(cv::Mat& image, const cv::Point2f& pixel, slam::FeatureKind kind) {
  const cv::Point center = Fixed(cv::Point2d(pixel.x, pixel.y));
  const int radius = static_cast<int>(kFeatureRadiusPx * kSubPixel);
  const bool hollow = kind == slam::FeatureKind::kUnmatched;
  cv::circle(image, center, radius, FeatureKindColor(kind), hollow ? 1 : cv::FILLED, cv::LINE_AA, kShift);
}

void DrawFeature(cv::Mat& image, const cv::Point2f& pixel, slam::FeatureKind kind) {
  DrawFeatureRim(image, pixel, kind);
  DrawFeatureDot(image, pixel, kind);
}

// The frame a little desaturated, so coloured dots stand out.
cv::Mat Desaturated(const cv::Mat& color_bgr) {
  cv::Mat gray, gray_bgr, frame;
  cv::cvtColor(color_bgr, gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(gray, gray_bgr, cv::COLOR_GRAY2BGR);
  cv::addWeighted(color_bgr, 0.45, gray_bgr, 0.55, 0, frame);
  return frame;
}

// Outlines and names each instance judged moving that is in view; returns how many.
int OutlineMovingInstances(const cv::Mat& instance_ids, const std::vector<slam::InstanceJudgement>& judgements,
                           cv::Mat& frame) {
  int outlined = 0;
  for (const slam::InstanceJudgement& judgement : judgements) {
    if (!judgement.moving) continue;
    const cv::Mat mask = instance_ids == judgement.id;
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    if (contours.empty()) continue;
    ++outlined;
    cv::drawContours(frame, contours, -1, kMovingOutlineColor, 2, cv::LINE_AA);
    const cv::Rect box = cv::boundingRect(mask);
    const std::string label = fmt::format("moving #{}", judgement.id);
    const cv::Size text = TextSize(label, 0.45, 1);
    cv::Rect tag(box.x, std::max(0, box.y - text.height - 8), text.width + 8, text.height + 8);
    tag.x = std::clamp(tag.x, 0, std::max(0, frame.cols - tag.width));
    cv::rectangle(frame, tag, kMovingOutlineColor, cv::FILLED);
    DrawText(frame, label, {tag.x + 4, tag.y + 4}, 0.45, kWhite, 1, HAlign::kLeft, VAlign::kTop);
  }
  return outlined;
}

// Draws the features, the informative kinds last so they are on top; returns the count
// of each kind.
std::map<slam::FeatureKind, int> DrawFeatures(const std::vector<slam::FeatureRecord>& records, cv::Mat& frame) {
  const std::array<slam::FeatureKind, 5> kDrawOrder = {slam::FeatureKind::kUnmatched, slam::FeatureKind::kOutlier,
                                                       slam::FeatureKind::kUsed, slam::FeatureKind::kDroppedMoveable,
                                                       slam::FeatureKind::kDroppedMoving};
  std::map<slam::FeatureKind, int> counts;
  for (const slam::FeatureKind kind : kDrawOrder) {
    for (const slam::FeatureRecord& record : records) {
      if (record.kind != kind) continue;
      ++counts[kind];
      DrawFeatureRim(frame, record.pixel, kind);
    }
    for (const slam::FeatureRecord& record : records) {
      if (record.kind == kind) DrawFeatureDot(frame, record.pixel, kind);
    }
  }
  return counts;
}

// One entry of the feature picture's legend: a feature kind's sample dot, or (no kind)
// the moving outline.
struct FeatureLegendEntry {
  std::string text;
  std::optional<slam::FeatureKind> kind;
};

// The frame above a white strip with `title`, then the entries, wrapped. A frame
// narrower than the longest entry gets a white band on its right.
cv::Mat WithFeatureLegend(const cv::Mat& frame, const std::vector<FeatureLegendEntry>& entries,
                          const std::string& title) {
  constexpr int kEntryGapPx = 22, kSamplePx = 18, kRowPx = 24, kSidePx = 10;
  int picture_width = frame.cols;
  for (const FeatureLegendEntry& entry : entries) {
    picture_width = std::max(picture_width, 2 * kSidePx + kSamplePx + 6 + TextSize(entry.text, kLegendFontScale, 1).width);
  }
  if (!title.empty()) {
    picture_width = std::max(picture_width, 2 * kSidePx + TextSize(title, kLabelFontScale, 1).width);
  }
  std::vector<cv::Point> positions;  // x in pixels, y the row
  int u = kSidePx, row = 0;
  for (const FeatureLegendEntry& entry : entries) {
    const int width = kSamplePx + 6 + TextSize(entry.text, kLegendFontScale, 1).width;
    if (u > kSidePx && u + width > picture_width - kSidePx) {
      u = kSidePx;
      ++row;
    }
    positions.emplace_back(u, row);
    u += width + kEntryGapPx;
  }
  const int title_px = title.empty() ? 0 : 30;
  const int strip_px = title_px + (row + 1) * kRowPx + 12;
  cv::Mat picture(frame.rows + strip_px, picture_width, CV_8UC3, kWhite);
  frame.copyTo(picture(cv::Rect(0, 0, frame.cols, frame.rows)));
  const int strip_top = frame.rows + 6;
  if (!title.empty()) {
    DrawText(picture, title, {kSidePx, strip_top + 4}, kLabelFontScale, kBlack, 1, HAlign::kLeft, VAlign::kTop);
  }
  // The dots of the legend sit on a mid-grey chip so white and grey dots are visible.
  for (size_t k = 0; k < entries.size(); ++k) {
    const int v = strip_top + title_px + positions[k].y * kRowPx + kRowPx / 2;
    const cv::Point2d sample(positions[k].x + kSamplePx / 2.0, v);
    cv::rectangle(picture, cv::Rect(positions[k].x, v - kSamplePx / 2, kSamplePx, kSamplePx), cv::Scalar(110, 110, 110),
                  cv::FILLED);
    if (entries[k].kind.has_value()) {
      DrawFeature(picture, cv::Point2f(static_cast<float>(sample.x), static_cast<float>(sample.y)), *entries[k].kind);
    } else {
      cv::rectangle(picture, cv::Rect(positions[k].x + 3, v - kSamplePx / 2 + 3, kSamplePx - 6, kSamplePx - 6),
                    kMovingOutlineColor, 2);
    }
    DrawText(picture, entries[k].text, {positions[k].x + kSamplePx + 6, v}, kLegendFontScale, kBlack, 1, HAlign::kLeft,
             VAlign::kMiddle);
  }
  return picture;
}

}  // namespace

cv::Mat DrawFeatureKinds(const cv::Mat& color_bgr, const cv::Mat& instance_ids, const slam::FrameResult& result,
                         const std::string& title) {
  if (color_bgr.type() != CV_8UC3 || color_bgr.empty()) {
    throw Error("feature picture: the frame must be CV_8UC3, not " + CvTypeName(color_bgr.type()));
  }
  if (!instance_ids.empty()) CheckImage(instance_ids, CV_16U, color_bgr.size(), "feature picture: instance ids");

  cv::Mat frame = Desaturated(color_bgr);
  const int moving_instances = instance_ids.empty() ? 0 : OutlineMovingInstances(instance_ids, result.instances, frame);
  std::map<slam::FeatureKind, int> counts = DrawFeatures(result.feature_records, frame);

  std::vector<FeatureLegendEntry> entries;
  for (const slam::FeatureKind kind : {slam::FeatureKind::kUsed, slam::FeatureKind::kDroppedMoving,
                                       slam::FeatureKind::kDroppedMoveable, slam::FeatureKind::kOutlier,
                                       slam::FeatureKind::kUnmatched}) {
    entries.push_back({fmt::format("{} ({})", FeatureKindLegend(kind), counts[kind]), kind});
  }
  entries.push_back({fmt::format("instance judged moving ({})", moving_instances), std::nullopt});
  return WithFeatureLegend(frame, entries, title);
}

std::optional<std::size_t> PickFeatureFigureFrame(const std::vector<slam::FrameResult>& results) {
  std::optional<std::size_t> best;
  std::pair<int, int> best_counts{-1, -1};  // (dropped moving, dropped moveable)
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (results[i].feature_records.empty()) continue;
    std::pair<int, int> counts{0, 0};
    for (const slam::FeatureRecord& record : results[i].feature_records) {
      counts.first += record.kind == slam::FeatureKind::kDroppedMoving;
      counts.second += record.kind == slam::FeatureKind::kDroppedMoveable;
    }
    if (counts > best_counts) {
      best_counts = counts;
      best = i;
    }
  }
  return best;
}

}  // namespace segslam::harness
