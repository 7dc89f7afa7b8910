// The plotting toolkit behind the report's figures (harness/report_figures.h), with OpenCV
// on BGR images (CV_8UC3): text and markers, antialiased polylines, nice axis ticks, the
// margins and frame of a plot with its grid and labels, and a legend placed where it
// hides the least. Internal to harness: the figures are the interface.
//
// Pixel coordinates are sub-pixel (cv::Point2d) wherever a shape is drawn with kShift
// fractional bits (Fixed()); pixel centres are at integer coordinates.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "harness/report_figures.h"

namespace segslam::harness::plot {

// ------------------------------------------------------------------ drawing primitives

inline constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
inline constexpr int kShift = 4;  // sub-pixel bits for cv::line & co.
inline constexpr double kSubPixel = 1 << kShift;
inline const cv::Scalar kWhite(255, 255, 255);
inline const cv::Scalar kBlack(0, 0, 0);
inline const cv::Scalar kGridColor(225, 225, 225);
inline const cv::Scalar kAxisTextColor(50, 50, 50);
inline constexpr double kTickFontScale = 0.45;
inline constexpr double kLabelFontScale = 0.55;
inline constexpr double kTitleFontScale = 0.7;
inline constexpr double kLegendFontScale = 0.5;

// `p` in the fixed-point pixels of OpenCV's drawing functions called with kShift.
cv::Point Fixed(const cv::Point2d& p);

enum class HAlign { kLeft, kCenter, kRight };
enum class VAlign { kTop, kMiddle, kBaseline };

// The size of `text` in kFont (height above the baseline).
cv::Size TextSize(const std::string& text, double scale, int thickness);

// `text` in kFont, antialiased, placed by `anchor` and the alignments.
void DrawText(cv::Mat& image, const std::string& text, cv::Point anchor, double scale, const cv::Scalar& color,
              int thickness, HAlign h, VAlign v);

// Text turned 90 degrees counter-clockwise (reading upwards), centred on `center`.
// Drawn dark on a white patch and merged by minimum, so it suits light backgrounds.
void DrawVerticalText(cv::Mat& image, const std::string& text, cv::Point center, double scale,
                      const cv::Scalar& color);

enum class Marker { kNone, kCircle, kSquare, kTriangle, kDiamond, kInvertedTriangle };

// A filled marker of about `size` pixels across with a thin dark rim.
void DrawMarker(cv::Mat& image, const cv::Point2d& center, Marker marker, const cv::Scalar& color, double size);

// An open antialiased polyline; vertices within a quarter pixel of the simplified path
// are dropped first (Douglas-Peucker), so densely sampled paths do not look beaded.
void DrawPolyline(cv::Mat& image, const std::vector<cv::Point2d>& points, const cv::Scalar& color, int thickness);

// ------------------------------------------------------------------ axes and ticks

// 1, 2 or 5 times a power of ten (the nearest on a log scale), so that `range` holds
// about `target_ticks` steps.
double NiceStep(double range, double target_ticks);

struct Ticks {
  std::vector<double> values;
  std::vector<std::string> labels;
};

// The multiples of `step` in [min, max], labelled with as many decimals as the step
// needs (and never "-0").
Ticks NiceTicks(double min, double max, double step);

// The width in pixels of the widest tick label.
int WidestLabel(const Ticks& ticks);

// Space around the plot area for the title, tick labels and axis labels.
struct Margins {
  int left = 0, right = 0, top = 0, bottom = 0;
};

Margins PlotMargins(bool has_title, int widest_y_label);

cv::Rect PlotArea(cv::Size size, const Margins& margins);

// Grid lines, frame, tick marks and labels, axis labels and title.
void DrawAxes(cv::Mat& image, const PlotAxes& axes, const Ticks& x_ticks, const Ticks& y_ticks,
              const std::string& x_label, const std::string& y_label, const std::string& title);

// ------------------------------------------------------------------ legend

struct LegendEntry {
  std::string label;
  cv::Scalar color;
  int line_thickness = 0;  // 0: no line sample
  Marker marker = Marker::kNone;
};

cv::Size LegendSize(const std::vector<LegendEntry>& entries);

// A white box with a line and/or marker sample and the label of each entry, a row each.
void DrawLegend(cv::Mat& image, cv::Point top_left, const std::vector<LegendEntry>& entries);

// The corner of the plot area where the legend covers the fewest data points
// (preference on ties: top right, top left, bottom right, bottom left).
cv::Point LegendCorner(const cv::Rect& area, cv::Size legend, const std::vector<cv::Point2d>& data_px,
                       size_t* covered_points);

// Where a legend goes: inside the plot area in the corner it hides nothing of, else to
// the right of the plot area (the caller then has to make room there first), this far
// from it.
inline constexpr int kOutsideLegendGapPx = 14;

// The points of a polyline every few pixels, so a legend over a long straight segment
// between two vertices counts as covering it.
void AppendDensified(const std::vector<cv::Point2d>& polyline_px, std::vector<cv::Point2d>* out);

cv::Mat WhiteCanvas(cv::Size size);

}  // namespace segslam::harness::plot
