#include "harness/report_figures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "harness/pictures.h"

namespace segslam::harness {
namespace {

// ------------------------------------------------------------------ drawing primitives

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kShift = 4;  // sub-pixel bits for cv::line & co.
constexpr double kSubPixel = 1 << kShift;
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGridColor(225, 225, 225);
const cv::Scalar kAxisTextColor(50, 50, 50);
constexpr double kTickFontScale = 0.45;
constexpr double kLabelFontScale = 0.55;
constexpr double kTitleFontScale = 0.7;
constexpr double kLegendFontScale = 0.5;

cv::Point Fixed(const cv::Point2d& p) {
  return {static_cast<int>(std::lround(p.x * kSubPixel)), static_cast<int>(std::lround(p.y * kSubPixel))};
}

enum class HAlign { kLeft, kCenter, kRight };
enum class VAlign { kTop, kMiddle, kBaseline };

cv::Size TextSize(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, thickness, &baseline);
}

void DrawText(cv::Mat& image, const std::string& text, cv::Point anchor, double scale, const cv::Scalar& color,
              int thickness, HAlign h, VAlign v) {
  const cv::Size size = TextSize(text, scale, thickness);
  const int x = anchor.x - (h == HAlign::kCenter ? size.width / 2 : h == HAlign::kRight ? size.width : 0);
  const int y = anchor.y + (v == VAlign::kTop ? size.height : v == VAlign::kMiddle ? size.height / 2 : 0);
  cv::putText(image, text, {x, y}, kFont, scale, color, thickness, cv::LINE_AA);
}

// Text turned 90 degrees counter-clockwise (reading upwards), centred on `center`.
// Drawn dark on a white patch and merged by minimum, so it suits light backgrounds.
void DrawVerticalText(cv::Mat& image, const std::string& text, cv::Point center, double scale,
                      const cv::Scalar& color) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, 1, &baseline);
  cv::Mat patch(size.height + baseline + 4, size.width + 4, CV_8UC3, kWhite);
  cv::putText(patch, text, {2, size.height + 2}, kFont, scale, color, 1, cv::LINE_AA);
  cv::rotate(patch, patch, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect where(center.x - patch.cols / 2, center.y - patch.rows / 2, patch.cols, patch.rows);
  where &= cv::Rect(0, 0, image.cols, image.rows);
  if (where.empty()) return;
  cv::Mat target = image(where);
  cv::min(target, patch(cv::Rect(0, 0, where.width, where.height)), target);
}

enum class Marker { kNone, kCircle, kSquare, kTriangle, kDiamond, kInvertedTriangle };

// A filled marker of about `size` pixels across with a thin dark rim.
void DrawMarker(cv::Mat& image, const cv::Point2d& center, Marker marker, const cv::Scalar& color, double size) {
  const double r = size / 2;
  std::vector<cv::Point2d> corners;
  switch (marker) {
    case Marker::kNone: return;
    case Marker::kCircle:
      cv::circle(image, Fixed(center), static_cast<int>(std::lround(r * kSubPixel)), color, cv::FILLED, cv::LINE_AA,
                 kShift);
      cv::circle(image, Fixed(center), static_cast<int>(std::lround(r * kSubPixel)), kBlack, 1, cv::LINE_AA, kShift);
      return;
    case Marker::kSquare:
      corners = {{-r, -r}, {r, -r}, {r, r}, {-r, r}};
      break;
    case Marker::kTriangle:
      corners = {{0, -1.2 * r}, {1.1 * r, 0.8 * r}, {-1.1 * r, 0.8 * r}};
      break;
    case Marker::kInvertedTriangle:
      corners = {{0, 1.2 * r}, {1.1 * r, -0.8 * r}, {-1.1 * r, -0.8 * r}};
      break;
    case Marker::kDiamond:
      corners = {{0, -1.3 * r}, {1.3 * r, 0}, {0, 1.3 * r}, {-1.3 * r, 0}};
      break;
  }
  std::vector<cv::Point> polygon;
  for (const cv::Point2d& corner : corners) polygon.push_back(Fixed(center + corner));
  cv::fillPoly(image, std::vector<std::vector<cv::Point>>{polygon}, color, cv::LINE_AA, kShift);
  cv::polylines(image, std::vector<std::vector<cv::Point>>{polygon}, true, kBlack, 1, cv::LINE_AA, kShift);
}

// Distance from p to the segment a-b (to a, when a and b coincide).
double DistanceToSegment(const cv::Point2d& p, const cv::Point2d& a, const cv::Point2d& b) {
  const cv::Point2d ab = b - a;
  const double length2 = ab.dot(ab);
  const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  const cv::Point2d d = p - (a + t * ab);
  return std::hypot(d.x, d.y);
}

// Douglas-Peucker with distances to segments, so closed loops (first point = last)
// keep their shape; cv::approxPolyDP's open-curve mode collapses them.
std::vector<cv::Point2d> SimplifyPolyline(const std::vector<cv::Point2d>& points, double tolerance_px) {
  if (points.size() < 3) return points;
  std::vector<bool> keep(points.size(), false);
  keep.front() = keep.back() = true;
  std::vector<std::pair<size_t, size_t>> spans = {{0, points.size() - 1}};
  while (!spans.empty()) {
    const auto [first, last] = spans.back();
    spans.pop_back();
    double farthest = -1;
    size_t farthest_index = first;
    for (size_t i = first + 1; i < last; ++i) {
      const double distance = DistanceToSegment(points[i], points[first], points[last]);
      if (distance > farthest) {
        farthest = distance;
        farthest_index = i;
      }
    }
    if (farthest > tolerance_px) {
      keep[farthest_index] = true;
      spans.emplace_back(first, farthest_index);
      spans.emplace_back(farthest_index, last);
    }
  }
  std::vector<cv::Point2d> kept;
  for (size_t i = 0; i < points.size(); ++i) {
    if (keep[i]) kept.push_back(points[i]);
  }
  return kept;
}

void DrawPolyline(cv::Mat& image, const std::vector<cv::Point2d>& points, const cv::Scalar& color, int thickness) {
  if (points.size() < 2) return;
  // Densely sampled paths have many vertices a pixel apart, and every antialiased joint
  // darkens the line a little: the line looks beaded. Vertices within a quarter pixel
  // of the simplified path add nothing visible, so they are dropped first.
  const std::vector<cv::Point2d> simplified = SimplifyPolyline(points, 0.25);
  std::vector<cv::Point> fixed;
  fixed.reserve(simplified.size());
  for (const cv::Point2d& p : simplified) fixed.push_back(Fixed(p));
  cv::polylines(image, std::vector<std::vector<cv::Point>>{fixed}, false, color, thickness, cv::LINE_AA, kShift);
}

// ------------------------------------------------------------------ axes and ticks

// 1, 2 or 5 times a power of ten (the nearest on a log scale), so that `range` holds
// about `target_ticks` steps.
double NiceStep(double range, double target_ticks) {
  const double raw = range / std::max(1.0, target_ticks);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  return (r < 1.42 ? 1 : r < 3.17 ? 2 : r < 7.08 ? 5 : 10) * magnitude;
}

std::vector<double> TicksInRange(double min, double max, double step) {
  std::vector<double> ticks;
  const long first = static_cast<long>(std::ceil(min / step - 1e-9));
  const long last = static_cast<long>(std::floor(max / step + 1e-9));
  for (long k = first; k <= last; ++k) ticks.push_back(k * step);
  return ticks;
}

// As many decimals as the step needs, and never "-0".
std::string FormatTick(double value, double step) {
  const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  if (std::abs(value) < step * 1e-6) value = 0;
  return fmt::format("{:.{}f}", value, decimals);
}

struct Ticks {
  std::vector<double> values;
  std::vector<std::string> labels;
};

Ticks NiceTicks(double min, double max, double step) {
  Ticks ticks;
  ticks.values = TicksInRange(min, max, step);
  for (double v : ticks.values) ticks.labels.push_back(FormatTick(v, step));
  return ticks;
}

int WidestLabel(const Ticks& ticks) {
  int widest = 0;
  for (const std::string& label : ticks.labels) widest = std::max(widest, TextSize(label, kTickFontScale, 1).width);
  return widest;
}

// Space around the plot area for the title, tick labels and axis labels.
struct Margins {
  int left = 0, right = 0, top = 0, bottom = 0;
};

Margins PlotMargins(bool has_title, int widest_y_label) {
  Margins margins;
  margins.top = has_title ? 52 : 22;
  margins.bottom = 62;
  margins.left = 14 + 22 + widest_y_label + 12;  // edge, axis label, tick labels, tick marks
  margins.right = 28;
  return margins;
}

cv::Rect PlotArea(cv::Size size, const Margins& margins) {
  return {margins.left, margins.top, size.width - margins.left - margins.right,
          size.height - margins.top - margins.bottom};
}

// Grid lines, frame, tick marks and labels, axis labels and title.
void DrawAxes(cv::Mat& image, const PlotAxes& axes, const Ticks& x_ticks, const Ticks& y_ticks,
              const std::string& x_label, const std::string& y_label, const std::string& title) {
  const cv::Rect& area = axes.area;
  const int left = area.x, right = area.x + area.width, top = area.y, bottom = area.y + area.height;
  for (size_t k = 0; k < x_ticks.values.size(); ++k) {
    const int u = static_cast<int>(std::lround(axes.ToPixel(x_ticks.values[k], 0).x));
    if (u < left || u > right) continue;
    cv::line(image, {u, top}, {u, bottom}, kGridColor, 1);
    cv::line(image, {u, bottom}, {u, bottom + 5}, kBlack, 1);
    DrawText(image, x_ticks.labels[k], {u, bottom + 9}, kTickFontScale, kAxisTextColor, 1, HAlign::kCenter,
             VAlign::kTop);
  }
  for (size_t k = 0; k < y_ticks.values.size(); ++k) {
    const int v = static_cast<int>(std::lround(axes.ToPixel(0, y_ticks.values[k]).y));
    if (v < top || v > bottom) continue;
    cv::line(image, {left, v}, {right, v}, kGridColor, 1);
    cv::line(image, {left - 5, v}, {left, v}, kBlack, 1);
    DrawText(image, y_ticks.labels[k], {left - 9, v}, kTickFontScale, kAxisTextColor, 1, HAlign::kRight,
             VAlign::kMiddle);
  }
  cv::rectangle(image, {left, top}, {right, bottom}, kBlack, 1);
  if (!x_label.empty()) {
    DrawText(image, x_label, {left + area.width / 2, image.rows - 14}, kLabelFontScale, kBlack, 1, HAlign::kCenter,
             VAlign::kBaseline);
  }
  if (!y_label.empty()) DrawVerticalText(image, y_label, {16, top + area.height / 2}, kLabelFontScale, kBlack);
  if (!title.empty()) {
    DrawText(image, title, {left + area.width / 2, 16}, kTitleFontScale, kBlack, 2, HAlign::kCenter, VAlign::kTop);
  }
}

// ------------------------------------------------------------------ legend

struct LegendEntry {
  std::string label;
  cv::Scalar color;
  int line_thickness = 0;  // 0: no line sample
  Marker marker = Marker::kNone;
};

constexpr int kLegendRowPx = 24;
constexpr int kLegendSamplePx = 34;
constexpr int kLegendPaddingPx = 10;

cv::Size LegendSize(const std::vector<LegendEntry>& entries) {
  int widest = 0;
  for (const LegendEntry& entry : entries) widest = std::max(widest, TextSize(entry.label, kLegendFontScale, 1).width);
  return {2 * kLegendPaddingPx + kLegendSamplePx + 8 + widest,
          2 * kLegendPaddingPx + static_cast<int>(entries.size()) * kLegendRowPx - 6};
}

void DrawLegend(cv::Mat& image, cv::Point top_left, const std::vector<LegendEntry>& entries) {
  const cv::Size size = LegendSize(entries);
  const cv::Rect box(top_left, size);
  cv::rectangle(image, box, kWhite, cv::FILLED);
  cv::rectangle(image, box, cv::Scalar(160, 160, 160), 1);
  for (size_t k = 0; k < entries.size(); ++k) {
    const LegendEntry& entry = entries[k];
    const int v = top_left.y + kLegendPaddingPx + static_cast<int>(k) * kLegendRowPx + 9;
    const int u0 = top_left.x + kLegendPaddingPx;
    if (entry.line_thickness > 0) {
      cv::line(image, {u0, v}, {u0 + kLegendSamplePx, v}, entry.color, entry.line_thickness, cv::LINE_AA);
    }
    DrawMarker(image, cv::Point2d(u0 + kLegendSamplePx / 2.0, v), entry.marker, entry.color, 9);
    DrawText(image, entry.label, {u0 + kLegendSamplePx + 8, v}, kLegendFontScale, kBlack, 1, HAlign::kLeft,
             VAlign::kMiddle);
  }
}

// The corner of the plot area where the legend covers the fewest data points
// (preference on ties: top right, top left, bottom right, bottom left).
cv::Point LegendCorner(const cv::Rect& area, cv::Size legend, const std::vector<cv::Point2d>& data_px,
                       size_t* covered_points) {
  constexpr int kInset = 10;
  const std::array<cv::Point, 4> corners = {
      cv::Point(area.x + area.width - kInset - legend.width, area.y + kInset),
      cv::Point(area.x + kInset, area.y + kInset),
      cv::Point(area.x + area.width - kInset - legend.width, area.y + area.height - kInset - legend.height),
      cv::Point(area.x + kInset, area.y + area.height - kInset - legend.height)};
  cv::Point best = corners[0];
  size_t fewest = std::numeric_limits<size_t>::max();
  for (const cv::Point& corner : corners) {
    // A margin around the box, so lines passing just outside it do not touch it.
    const cv::Rect2d covered(corner.x - 6, corner.y - 6, legend.width + 12, legend.height + 12);
    const size_t count = static_cast<size_t>(
        std::count_if(data_px.begin(), data_px.end(), [&](const cv::Point2d& p) { return covered.contains(p); }));
    if (count < fewest) {
      fewest = count;
      best = corner;
    }
  }
  *covered_points = fewest;
  return best;
}

// Where a legend goes: inside the plot area in the corner it hides nothing of, else to
// the right of the plot area (the caller then has to make room there first).
constexpr int kOutsideLegendGapPx = 14;

// The points of a polyline every few pixels, so a legend over a long straight segment
// between two vertices counts as covering it.
void AppendDensified(const std::vector<cv::Point2d>& polyline_px, std::vector<cv::Point2d>* out) {
  for (size_t i = 0; i < polyline_px.size(); ++i) {
    out->push_back(polyline_px[i]);
    if (i + 1 == polyline_px.size()) break;
    const cv::Point2d step = polyline_px[i + 1] - polyline_px[i];
    const int pieces = static_cast<int>(std::ceil(std::hypot(step.x, step.y) / 3.0));
    for (int k = 1; k < pieces; ++k) out->push_back(polyline_px[i] + step * (double(k) / pieces));
  }
}

cv::Mat WhiteCanvas(cv::Size size) { return cv::Mat(size, CV_8UC3, kWhite); }

// ------------------------------------------------------------------ trajectories

// Ground-plane polylines of one trajectory, split where frames were lost.
std::vector<std::vector<cv::Point2d>> GroundPlaneSegments(const std::vector<StampedPose>& poses,
                                                          double gap_factor) {
  std::vector<std::vector<cv::Point2d>> segments;
  if (poses.empty()) return segments;
  std::vector<double> intervals;
  for (size_t i = 1; i < poses.size(); ++i) intervals.push_back(poses[i].stamp_s - poses[i - 1].stamp_s);
  double median_interval = 0;
  if (!intervals.empty()) {
    std::vector<double> sorted = intervals;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    median_interval = sorted[sorted.size() / 2];
  }
  segments.emplace_back();
  for (size_t i = 0; i < poses.size(); ++i) {
    if (i > 0 && median_interval > 0 && intervals[i - 1] > gap_factor * median_interval) segments.emplace_back();
    const Eigen::Vector3d& t = poses[i].T_wc.translation();
    segments.back().emplace_back(t.x(), t.y());
  }
  return segments;
}

}  // namespace

cv::Point2d PlotAxes::ToPixel(double x, double y) const {
  return {area.x + (x - x_min) / (x_max - x_min) * area.width,
          area.y + (y_max - y) / (y_max - y_min) * area.height};
}

cv::Scalar SeriesColor(std::size_t index) {
  // Okabe & Ito's palette without its yellow (too faint on white), as BGR.
  static const std::array<cv::Scalar, 7> kPalette = {
      cv::Scalar(178, 114, 0),    // blue
      cv::Scalar(0, 94, 213),     // vermillion
      cv::Scalar(115, 158, 0),    // bluish green
      cv::Scalar(0, 159, 230),    // orange
      cv::Scalar(167, 121, 204),  // reddish purple
      cv::Scalar(233, 180, 86),   // sky blue
      cv::Scalar(0, 0, 0)};       // black
  return kPalette[index % kPalette.size()];
}

bool TopViewOptions::IsValid(std::string* error) const {
  std::string problem;
  if (size.width < 200 || size.height < 200) problem = "size must be at least 200x200 pixels";
  else if (!(gap_factor > 1)) problem = "gap_factor must be > 1";
  else if (!(padding >= 0 && padding < 1)) problem = "padding must be in [0, 1)";
  if (error != nullptr) *error = problem;
  return problem.empty();
}

namespace {

// The box of every position on the ground plane (x, y), metres.
struct GroundBounds {
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
};

GroundBounds TrajectoryBounds(const std::string& origin, const std::vector<const NamedTrajectory*>& trajectories) {
  GroundBounds b;
  for (const NamedTrajectory* trajectory : trajectories) {
    for (const StampedPose& pose : trajectory->poses) {
      const Eigen::Vector3d& t = pose.T_wc.translation();
      if (!t.allFinite()) throw Error(origin + ": trajectory '" + trajectory->name + "' has a non-finite position");
      b.x_lo = std::min(b.x_lo, t.x());
      b.x_hi = std::max(b.x_hi, t.x());
      b.y_lo = std::min(b.y_lo, t.y());
      b.y_hi = std::max(b.y_hi, t.y());
    }
  }
  if (!(b.x_lo <= b.x_hi)) throw Error(origin + ": no trajectory has a pose");
  return b;
}

// Trajectory k of a top view: 0 is the ground truth, drawn thicker, under the estimates.
cv::Scalar TopViewColor(size_t k) { return k == 0 ? kGroundTruthColor : SeriesColor(k - 1); }
int TopViewThickness(size_t k) { return k == 0 ? 3 : 2; }

// Equal scale on both axes: the axis with room to spare shows more, centred on the data.
// With shrink_to_fit the figure is no taller than the trajectories need: the plot area
// takes their aspect.
PlotAxes TopViewAxes(const TopViewOptions& options, const GroundBounds& b, double pad, const Margins& margins,
                     cv::Size* figure_size) {
  *figure_size = options.size;
  if (options.shrink_to_fit) {
    const int width_px = PlotArea(*figure_size, margins).width;
    const double needed_height_px = width_px * (b.y_hi - b.y_lo + 2 * pad) / (b.x_hi - b.x_lo + 2 * pad);
    const int needed_figure_px = static_cast<int>(std::ceil(needed_height_px)) + margins.top + margins.bottom;
    figure_size->height = std::clamp(needed_figure_px, std::min(options.size.height, 320), options.size.height);
  }
  PlotAxes axes;
  axes.area = PlotArea(*figure_size, margins);
  const double scale_px_per_m =
      std::min(axes.area.width / (b.x_hi - b.x_lo + 2 * pad), axes.area.height / (b.y_hi - b.y_lo + 2 * pad));
  const double x_center = (b.x_lo + b.x_hi) / 2, y_center = (b.y_lo + b.y_hi) / 2;
  axes.x_min = x_center - axes.area.width / (2 * scale_px_per_m);
  axes.x_max = x_center + axes.area.width / (2 * scale_px_per_m);
  axes.y_min = y_center - axes.area.height / (2 * scale_px_per_m);
  axes.y_max = y_center + axes.area.height / (2 * scale_px_per_m);
  return axes;
}

using GroundSegments = std::vector<std::vector<cv::Point2d>>;  // pieces between gaps, metres

// Every pixel the trajectories pass through, for placing the legend off them.
std::vector<cv::Point2d> TrajectoryPixels(const PlotAxes& axes, const std::vector<GroundSegments>& segments_of) {
  std::vector<cv::Point2d> pixels;
  for (const GroundSegments& segments : segments_of) {
    for (const auto& segment : segments) {
      std::vector<cv::Point2d> polyline;
      for (const cv::Point2d& p : segment) polyline.push_back(axes.ToPixel(p.x, p.y));
      AppendDensified(polyline, &pixels);
    }
  }
  return pixels;
}

// The trajectories clipped to the plot area, in order (ground truth first, under the
// estimates), then start and end markers on top of every line.
void DrawTrajectories(const PlotAxes& axes, const std::vector<const NamedTrajectory*>& trajectories,
                      const std::vector<GroundSegments>& segments_of, cv::Mat& image) {
  const cv::Rect area = axes.area;
  cv::Mat plot = image(area);
  for (size_t k = 0; k < trajectories.size(); ++k) {
    for (const auto& segment : segments_of[k]) {
      std::vector<cv::Point2d> pixels;
      for (const cv::Point2d& p : segment) pixels.push_back(axes.ToPixel(p.x, p.y) - cv::Point2d(area.x, area.y));
      DrawPolyline(plot, pixels, TopViewColor(k), TopViewThickness(k));
      // A single pose between two gaps is still visible.
      if (pixels.size() == 1) {
        cv::circle(plot, Fixed(pixels[0]), static_cast<int>(TopViewThickness(k) * kSubPixel), TopViewColor(k),
                   cv::FILLED, cv::LINE_AA, kShift);
      }
    }
  }
  for (size_t k = 0; k < trajectories.size(); ++k) {
    const auto& poses = trajectories[k]->poses;
    if (poses.empty()) continue;
    const Eigen::Vector3d& first = poses.front().T_wc.translation();
    const Eigen::Vector3d& last = poses.back().T_wc.translation();
    DrawMarker(image, axes.ToPixel(first.x(), first.y()), Marker::kCircle, TopViewColor(k), 11);
    DrawMarker(image, axes.ToPixel(last.x(), last.y()), Marker::kSquare, TopViewColor(k), 9);
  }
}

}  // namespace

Figure DrawTopView(const TopViewOptions& options, const NamedTrajectory& ground_truth,
                   const std::vector<NamedTrajectory>& estimates) {
  const std::string origin = "top-view plot '" + options.title + "'";
  std::string problem;
  if (!options.IsValid(&problem)) throw Error(origin + ": " + problem);
  std::vector<const NamedTrajectory*> trajectories = {&ground_truth};
  for (const NamedTrajectory& estimate : estimates) trajectories.push_back(&estimate);
  const GroundBounds bounds = TrajectoryBounds(origin, trajectories);
  std::vector<GroundSegments> segments_of;
  for (const NamedTrajectory* trajectory : trajectories) {
    segments_of.push_back(GroundPlaneSegments(trajectory->poses, options.gap_factor));
  }

  std::vector<LegendEntry> legend;
  for (size_t k = 0; k < trajectories.size(); ++k) {
    legend.push_back({trajectories[k]->name, TopViewColor(k), TopViewThickness(k), Marker::kNone});
  }
  const cv::Scalar marker_grey(150, 150, 150);
  legend.push_back({"start", marker_grey, 0, Marker::kCircle});
  legend.push_back({"end", marker_grey, 0, Marker::kSquare});

  // The legend goes inside the plot where it covers no trajectory, else to the right.
  const double extent = std::max({bounds.x_hi - bounds.x_lo, bounds.y_hi - bounds.y_lo, 0.1});
  const double pad = options.padding * extent;
  const Ticks provisional_y = NiceTicks(bounds.y_lo - extent, bounds.y_hi + extent, NiceStep(extent, 6));
  Margins margins = PlotMargins(!options.title.empty(), WidestLabel(provisional_y));
  cv::Size figure_size;
  PlotAxes axes = TopViewAxes(options, bounds, pad, margins, &figure_size);
  const cv::Size legend_size = LegendSize(legend);
  size_t covered_points = 0;
  cv::Point legend_at = LegendCorner(axes.area, legend_size, TrajectoryPixels(axes, segments_of), &covered_points);
  if (covered_points > 0) {
    margins.right += legend_size.width + kOutsideLegendGapPx;
    axes = TopViewAxes(options, bounds, pad, margins, &figure_size);
    legend_at = {axes.area.x + axes.area.width + kOutsideLegendGapPx, axes.area.y};
  }
  // One grid step for both axes, about every 90 pixels, so the grid is made of squares.
  const double longer_side_px = std::max(axes.area.width, axes.area.height);
  const double step = NiceStep(longer_side_px / axes.PixelsPerUnitX(), longer_side_px / 90.0);

  Figure figure;
  figure.axes = axes;
  figure.image = WhiteCanvas(figure_size);
  DrawAxes(figure.image, axes, NiceTicks(axes.x_min, axes.x_max, step), NiceTicks(axes.y_min, axes.y_max, step),
           "x [m]", "y [m]", options.title);
  DrawTrajectories(axes, trajectories, segments_of, figure.image);
  DrawLegend(figure.image, legend_at, legend);
  return figure;
}

// ------------------------------------------------------------------ line plots

bool LinePlotOptions::IsValid(std::string* error) const {
  std::string problem;
  if (size.width < 200 || size.height < 200) problem = "size must be at least 200x200 pixels";
  if (error != nullptr) *error = problem;
  return problem.empty();
}

namespace {

// Throws unless x is finite and strictly increasing and every series has one value per x
// (y_min and y_max may also be empty).
void CheckLinePlotInput(const std::string& origin, const std::vector<double>& x,
                        const std::vector<PlotSeries>& series) {
  if (x.empty()) throw Error(origin + ": no x values");
  for (size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) throw Error(origin + ": x value " + std::to_string(i) + " is not finite");
    if (i > 0 && !(x[i] > x[i - 1])) throw Error(origin + ": x values must strictly increase");
  }
  for (const PlotSeries& s : series) {
    const auto check = [&](const std::vector<double>& values, const char* what, bool may_be_empty) {
      if (values.size() == x.size() || (may_be_empty && values.empty())) return;
      throw Error(fmt::format("{}: series '{}' has {} {} values for {} x values", origin, s.name, values.size(), what,
                              x.size()));
    };
    check(s.y, "y", false);
    check(s.y_min, "y_min", true);
    check(s.y_max, "y_max", true);
  }
}

bool AnyErrorBar(const std::vector<PlotSeries>& series) {
  return std::any_of(series.begin(), series.end(),
                     [](const PlotSeries& s) { return !s.y_min.empty() || !s.y_max.empty(); });
}

// The line plot's axes: y a nice range over every finite value (bars included) with a
// little headroom, so the top marker does not sit on the frame; x the values with 6 %
// to spare on each side.
PlotAxes LinePlotAxes(const LinePlotOptions& options, const std::vector<double>& x,
                      const std::vector<PlotSeries>& series, double* y_step) {
  double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
  for (const PlotSeries& s : series) {
    for (const auto* values : {&s.y, &s.y_min, &s.y_max}) {
      for (double v : *values) {
        if (!std::isfinite(v)) continue;
        y_lo = std::min(y_lo, v);
        y_hi = std::max(y_hi, v);
      }
    }
  }
  if (!(y_lo <= y_hi)) {
    y_lo = 0;
    y_hi = 1;
  }
  if (options.y_from_zero && y_lo >= 0) y_lo = 0;
  if (y_hi - y_lo < 1e-12) y_hi = y_lo + (y_lo == 0 ? 1 : std::abs(y_lo) * 0.1);

  *y_step = NiceStep(y_hi - y_lo, 6);
  PlotAxes axes;
  axes.y_min = std::floor(y_lo / *y_step + 1e-9) * *y_step;
  axes.y_max = std::ceil((y_hi + 0.04 * (y_hi - y_lo)) / *y_step - 1e-9) * *y_step;
  const double x_span = x.size() > 1 ? x.back() - x.front() : 2.0;
  axes.x_min = x.front() - 0.06 * x_span;
  axes.x_max = x.back() + 0.06 * x_span;
  return axes;
}

// x ticks: the values themselves for a short sweep, else a nice grid.
Ticks LinePlotXTicks(const PlotAxes& axes, const std::vector<double>& x) {
  Ticks ticks;
  if (x.size() > 12) {
    const double x_span = x.size() > 1 ? x.back() - x.front() : 2.0;
    return NiceTicks(axes.x_min, axes.x_max, NiceStep(x_span, 8));
  }
  for (double v : x) {
    ticks.values.push_back(v);
    ticks.labels.push_back(fmt::format("{:g}", v));
  }
  return ticks;
}

constexpr std::array<Marker, 5> kSeriesMarkers = {Marker::kCircle, Marker::kSquare, Marker::kTriangle,
                                                  Marker::kDiamond, Marker::kInvertedTriangle};

// One series in pixels: line pieces (broken at missing values), markers, error bars.
struct SeriesPixels {
  std::vector<std::vector<cv::Point2d>> lines;
  std::vector<cv::Point2d> markers;
  std::vector<std::pair<cv::Point2d, cv::Point2d>> bars;  // bottom, top
};

std::vector<SeriesPixels> SeriesToPixels(const PlotAxes& axes, bool markers, const std::vector<double>& x,
                                         const std::vector<PlotSeries>& series) {
  const bool any_error_bar = AnyErrorBar(series);
  std::vector<SeriesPixels> all(series.size());
  for (size_t k = 0; k < series.size(); ++k) {
    const PlotSeries& s = series[k];
    SeriesPixels& pixels = all[k];
    // Series side by side at each x when bars are drawn, so they do not hide each other.
    const double dodge_px = any_error_bar ? (k - (series.size() - 1) / 2.0) * 7.0 : 0.0;
    const auto at = [&](size_t i, double y) { return axes.ToPixel(x[i], y) + cv::Point2d(dodge_px, 0); };
    pixels.lines.emplace_back();
    for (size_t i = 0; i < x.size(); ++i) {
      if (!std::isfinite(s.y[i])) {
        pixels.lines.emplace_back();
        continue;
      }
      pixels.lines.back().push_back(at(i, s.y[i]));
      if (markers) pixels.markers.push_back(at(i, s.y[i]));
      const double lo = s.y_min.empty() ? NAN : s.y_min[i];
      const double hi = s.y_max.empty() ? NAN : s.y_max[i];
      if (std::isfinite(lo) || std::isfinite(hi)) {
        pixels.bars.emplace_back(at(i, std::isfinite(lo) ? lo : s.y[i]), at(i, std::isfinite(hi) ? hi : s.y[i]));
      }
    }
  }
  return all;
}

// Every pixel the lines and bars pass through, for placing the legend off them.
std::vector<cv::Point2d> DataPixels(const std::vector<SeriesPixels>& all) {
  std::vector<cv::Point2d> pixels;
  for (const SeriesPixels& one : all) {
    for (const auto& line : one.lines) AppendDensified(line, &pixels);
    for (const auto& [bottom, top] : one.bars) AppendDensified({bottom, top}, &pixels);
  }
  return pixels;
}

// Lines and capped error bars of every series, then the markers over all of them.
void DrawSeries(const std::vector<SeriesPixels>& all, cv::Mat& image) {
  for (size_t k = 0; k < all.size(); ++k) {
    const cv::Scalar color = SeriesColor(k);
    for (const auto& line : all[k].lines) DrawPolyline(image, line, color, 2);
    for (const auto& [bottom, top] : all[k].bars) {
      cv::line(image, Fixed(bottom), Fixed(top), color, 1, cv::LINE_AA, kShift);
      for (const cv::Point2d& end : {bottom, top}) {
        cv::line(image, Fixed(end - cv::Point2d(4, 0)), Fixed(end + cv::Point2d(4, 0)), color, 1, cv::LINE_AA,
                 kShift);
      }
    }
  }
  for (size_t k = 0; k < all.size(); ++k) {
    for (const cv::Point2d& marker : all[k].markers) {
      DrawMarker(image, marker, kSeriesMarkers[k % kSeriesMarkers.size()], SeriesColor(k), 9);
    }
  }
}

}  // namespace

Figure DrawLinePlot(const LinePlotOptions& options, const std::vector<double>& x,
                    const std::vector<PlotSeries>& series) {
  const std::string origin = "line plot '" + options.title + "'";
  std::string problem;
  if (!options.IsValid(&problem)) throw Error(origin + ": " + problem);
  CheckLinePlotInput(origin, x, series);

  double y_step = 0;
  PlotAxes axes = LinePlotAxes(options, x, series, &y_step);
  const Ticks y_ticks = NiceTicks(axes.y_min, axes.y_max, y_step);
  const Ticks x_ticks = LinePlotXTicks(axes, x);
  std::vector<LegendEntry> legend;
  for (size_t k = 0; k < series.size(); ++k) {
    const Marker marker = options.markers ? kSeriesMarkers[k % kSeriesMarkers.size()] : Marker::kNone;
    legend.push_back({series[k].name, SeriesColor(k), 2, marker});
  }

  // The legend goes inside the plot where it covers no data, else to the right of it.
  Margins margins = PlotMargins(!options.title.empty(), WidestLabel(y_ticks));
  axes.area = PlotArea(options.size, margins);
  const cv::Size legend_size = LegendSize(legend);
  size_t covered_points = 0;
  cv::Point legend_at = LegendCorner(axes.area, legend_size,
                                     DataPixels(SeriesToPixels(axes, options.markers, x, series)), &covered_points);
  if (covered_points > 0) {
    margins.right += legend_size.width + kOutsideLegendGapPx;
    axes.area = PlotArea(options.size, margins);
    legend_at = {axes.area.x + axes.area.width + kOutsideLegendGapPx, axes.area.y};
  }

  Figure figure;
  figure.axes = axes;
  figure.image = WhiteCanvas(options.size);
  DrawAxes(figure.image, axes, x_ticks, y_ticks, options.x_label, options.y_label, options.title);
  DrawSeries(SeriesToPixels(axes, options.markers, x, series), figure.image);
  if (!legend.empty()) DrawLegend(figure.image, legend_at, legend);
  return figure;
}

// ------------------------------------------------------------------ masks

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

// ------------------------------------------------------------------ features

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

}  // namespace

namespace {

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

// ------------------------------------------------------------------ output

void WriteFigure(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.type() != CV_8UC3 || image.empty()) {
    throw FileError(path, "a figure must be a non-empty CV_8UC3 image, not " + CvTypeName(image.type()));
  }
  if (path.extension() != ".png") throw FileError(path, "figures are written as .png");
  WriteImageAtomically(path, image, {cv::IMWRITE_PNG_COMPRESSION, 6});
}

}  // namespace segslam::harness
