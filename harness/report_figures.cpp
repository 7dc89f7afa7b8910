// The report's plots (harness/report_figures.h): top views of trajectories (the paper's
// Fig. 4) and line plots (sweeps, errors frame by frame), drawn with the plotting toolkit
// of harness/plot_toolkit.h. The pictures drawn on a frame are in frame_figures.cpp.
#include "harness/report_figures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"
#include "harness/plot_toolkit.h"

namespace segslam::harness {

using namespace plot;

// ------------------------------------------------------------------ trajectories (Fig. 4)

bool TopViewOptions::IsValid(std::string* error) const {
  std::string problem;
  if (size.width < 200 || size.height < 200) problem = "size must be at least 200x200 pixels";
  else if (!(gap_factor > 1)) problem = "gap_factor must be > 1";
  else if (!(padding >= 0 && padding < 1)) problem = "padding must be in [0, 1)";
  if (error != nullptr) *error = problem;
  return problem.empty();
}

namespace {

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

}  // namespace segslam::harness
