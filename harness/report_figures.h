// The report's figures, drawn with OpenCV as BGR images (CV_8UC3) a person would put in a
// paper: top-view trajectories (the paper's Fig. 4), line plots of sweeps, raw vs refined
// masks (Fig. 5), and the features of a frame kept or dropped by the judgement (Fig. 6).
//
// Pure functions over plain data: they know nothing of how runs are orchestrated. Each
// returns the image; WriteFigure() writes one atomically. Inputs that cannot be drawn
// (mismatched sizes, wrong image types) throw segslam::Error saying what is wrong.
//
// The plots are in report_figures.cpp, the pictures drawn on a frame (Figs. 5 and 6) in
// frame_figures.cpp; both draw with the toolkit of harness/plot_toolkit.h, whose .cpp
// also holds PlotAxes, SeriesColor and WriteFigure.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/instances.h"
#include "core/pose.h"
#include "seg/segmentation.h"
#include "slam/tracker.h"

namespace segslam::harness {

// Where plot coordinates land in a figure's pixels (for callers that annotate a figure,
// and for tests). The y axis points up: larger y is higher in the image.
struct PlotAxes {
  cv::Rect area;  // the plot area (inside the frame), pixels
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;  // the data range shown
  // Sub-pixel position of (x, y); pixel centres are at integer coordinates.
  cv::Point2d ToPixel(double x, double y) const;
  double PixelsPerUnitX() const { return area.width / (x_max - x_min); }
  double PixelsPerUnitY() const { return area.height / (y_max - y_min); }
};

struct Figure {
  cv::Mat image;  // CV_8UC3 BGR
  PlotAxes axes;
};

// Distinct colours (Okabe-Ito, readable by colour-blind readers) for series 0, 1, ...,
// cycling after seven. Ground truth is always kGroundTruthColor.
cv::Scalar SeriesColor(std::size_t index);
inline const cv::Scalar kGroundTruthColor(40, 40, 40);

// ------------------------------------------------------------------ trajectories (Fig. 4)

struct NamedTrajectory {
  std::string name;                // legend entry, e.g. "mutual"
  std::vector<StampedPose> poses;  // T_wc in the ground truth's world frame, stamps increasing
};

struct TopViewOptions {
  std::string title;
  cv::Size size{900, 760};  // whole figure, pixels (height: the most, see shrink_to_fit)
  // Consecutive poses more than gap_factor times the trajectory's median frame interval
  // apart in time are not joined: frames were lost there, and the plot shows a gap.
  double gap_factor = 2.5;
  // Padding around the trajectories, as a share of their larger extent.
  double padding = 0.06;
  // Lower the figure (never below 320 pixels) when the trajectories are wider than
  // high, so equal axis scales do not leave empty bands above and below them.
  bool shrink_to_fit = true;
  bool IsValid(std::string* error) const;
};

// The x-y (ground-plane; world z is up) projection of `ground_truth` and `estimates`
// with equal scale on both axes, a metric grid with labelled ticks, a legend, a start
// marker (circle) and an end marker (square) per trajectory, and the title. Estimates
// must already be in the ground truth's frame (e.g. AteResult::aligned_estimate).
// Empty trajectories are listed in the legend but draw nothing. Throws segslam::Error on
// invalid options or when no trajectory has a pose.
Figure DrawTopView(const TopViewOptions& options, const NamedTrajectory& ground_truth,
                   const std::vector<NamedTrajectory>& estimates);

// ------------------------------------------------------------------ line plots (sweeps)

struct PlotSeries {
  std::string name;           // legend entry
  std::vector<double> y;      // one per x value; NaN = no value (the line breaks there)
  std::vector<double> y_min;  // error bars: empty, or one per x value (NaN = no bar)
  std::vector<double> y_max;
};

struct LinePlotOptions {
  std::string title;
  std::string x_label;  // e.g. "moving cars"
  std::string y_label;  // e.g. "ATE RMSE [m]"
  cv::Size size{900, 600};
  // Start the y axis at 0 when every value is non-negative (errors, counts).
  bool y_from_zero = true;
  // A marker per point; off for dense series (a value per frame), which are lines only.
  bool markers = true;
  bool IsValid(std::string* error) const;
};

// Lines with a marker per point (a different shape per series; options.markers), vertical min/max error
// bars with caps, slightly offset per series so bars of equal x stay apart. The x ticks
// are the x values themselves when there are at most 12 of them, else a nice grid.
// Throws segslam::Error on invalid options, no x values, x not strictly increasing, or a
// series whose vectors do not have one value per x.
Figure DrawLinePlot(const LinePlotOptions& options, const std::vector<double>& x,
                    const std::vector<PlotSeries>& series);

// ------------------------------------------------------------------ masks (Fig. 5)

// "ground truth | raw | refined": the frame three times with instances tinted and
// outlined (OverlayPicture) and a class label on each instance; ground-truth classes
// come from `instance_table`, the segmentations' from their COCO category ids.
// `color_bgr` is CV_8UC3, `ground_truth_ids` CV_16U of the same size, masks frame-sized.
// Throws segslam::Error on wrong types or sizes.
cv::Mat DrawMaskComparison(const cv::Mat& color_bgr, const cv::Mat& ground_truth_ids,
                           const InstanceTable& instance_table, const seg::FrameSegmentation& raw,
                           const seg::FrameSegmentation& refined);

// ------------------------------------------------------------------ features (Fig. 6)

// Colour of each feature kind in DrawFeatureKinds: green used, red dropped (moving),
// orange dropped (moveable), grey outlier, white (hollow) unmatched.
cv::Scalar FeatureKindColor(slam::FeatureKind kind);

// The frame with its features (FrameResult::feature_records) as dots coloured by kind,
// every instance judged moving outlined (from `instance_ids`, CV_16U, the masks the
// judgement used), and a legend strip with the count of each kind and `title` below the
// frame (the picture is the frame's width, or wider when the legend needs it). Throws
// segslam::Error on wrong image types or sizes.
cv::Mat DrawFeatureKinds(const cv::Mat& color_bgr, const cv::Mat& instance_ids,
                         const slam::FrameResult& result, const std::string& title);

// The index into `results` of the frame that shows the judgement best: most features
// dropped as moving; ties (and runs with none) go to the most features dropped as
// moveable, then to the earlier frame. nullopt when no result has feature records.
std::optional<std::size_t> PickFeatureFigureFrame(const std::vector<slam::FrameResult>& results);

// ------------------------------------------------------------------ output

// Writes `image` (CV_8UC3) as PNG atomically. Throws segslam::Error naming the file.
void WriteFigure(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace segslam::harness
