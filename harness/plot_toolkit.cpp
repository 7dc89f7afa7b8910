// The plotting toolkit (harness/plot_toolkit.h), and the plot types and output that
// harness/report_figures.h declares for every figure: PlotAxes, SeriesColor, WriteFigure.
#include "harness/plot_toolkit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"

namespace segslam::harness {
namespace plot {
namespace {

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

constexpr int kLegendRowPx = 24;
constexpr int kLegendSamplePx = 34;
constexpr int kLegendPaddingPx = 10;

}  // namespace

// ------------------------------------------------------------------ drawing primitives

cv::Point Fixed(const cv::Point2d& p) {
  return {static_cast<int>(std::lround(p.x * kSubPixel)), static_cast<int>(std::lround(p.y * kSubPixel))};
}

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

double NiceStep(double range, double target_ticks) {
  const double raw = range / std::max(1.0, target_ticks);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  return (r < 1.42 ? 1 : r < 3.17 ? 2 : r < 7.08 ? 5 : 10) * magnitude;
}

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

}  // namespace plot

// ------------------------------------------------------------------ report_figures.h

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

void WriteFigure(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.type() != CV_8UC3 || image.empty()) {
    throw FileError(path, "a figure must be a non-empty CV_8UC3 image, not " + CvTypeName(image.type()));
  }
  if (path.extension() != ".png") throw FileError(path, "figures are written as .png");
  WriteImageAtomically(path, image, {cv::IMWRITE_PNG_COMPRESSION, 6});
}

}  // namespace segslam::harness
