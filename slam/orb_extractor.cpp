#include "slam/orb_extractor.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/error.h"
#include "slam/fast_corners.h"

namespace segslam::slam {
namespace {

constexpr int kOrientationRadiusPx = OrbExtractor::kPatchSizePx / 2;

// A rectangle of the detection region [x0, x1) x [y0, y1) and the corners inside it:
// the indices [begin, end) of an array that keeps each node's corners together, in
// ascending order.
struct QuadNode {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int begin = 0, end = 0;

  int size() const { return end - begin; }
  bool CanSplit() const {
    // A node smaller than half a pixel both ways holds one integer position at most;
    // the guard only matters for duplicate positions, which splitting cannot separate.
    return size() > 1 && (x1 - x0 >= 0.5f || y1 - y0 >= 0.5f);
  }
};

// Sorts the indices [begin, end) by bucket, keeping their order within a bucket (a
// counting sort through `scratch`), and returns where each bucket starts; bucket_of(index)
// is in [0, kBuckets).
template <int kBuckets, typename BucketOf>
std::array<int, kBuckets + 1> GroupByBucket(int begin, int end, BucketOf bucket_of, std::vector<int>* indices,
                                            std::vector<int>* scratch) {
  std::array<int, kBuckets + 1> start{};
  for (int i = begin; i < end; ++i) ++start[bucket_of((*indices)[i]) + 1];
  start[0] = begin;
  for (int b = 0; b < kBuckets; ++b) start[b + 1] += start[b];
  std::array<int, kBuckets> next;
  std::copy(start.begin(), start.end() - 1, next.begin());
  for (int i = begin; i < end; ++i) (*scratch)[next[bucket_of((*indices)[i])]++] = (*indices)[i];
  std::copy(scratch->begin() + begin, scratch->begin() + end, indices->begin() + begin);
  return start;
}

void SplitNode(const QuadNode& node, const std::vector<FastCorner>& corners, std::vector<int>* indices,
               std::vector<int>* scratch, std::vector<QuadNode>* children) {
  const float mx = 0.5f * (node.x0 + node.x1);
  const float my = 0.5f * (node.y0 + node.y1);
  const std::array<int, 5> start = GroupByBucket<4>(
      node.begin, node.end,
      [&](int index) { return (corners[index].x >= mx ? 1 : 0) + (corners[index].y >= my ? 2 : 0); }, indices,
      scratch);
  const QuadNode quadrants[4] = {{node.x0, node.y0, mx, my, start[0], start[1]},
                                 {mx, node.y0, node.x1, my, start[1], start[2]},
                                 {node.x0, my, mx, node.y1, start[2], start[3]},
                                 {mx, my, node.x1, node.y1, start[3], start[4]}};
  for (const QuadNode& q : quadrants) {
    if (q.size() > 0) children->push_back(q);
  }
}

// Indices of at most `budget` corners: the quadtree is refined (every splittable node per
// round, the most crowded first once a full round could overshoot) until it has `budget`
// non-empty leaves, and each leaf keeps its strongest corner. Sparse areas thus keep their
// corners while dense areas keep only their best ones.
std::vector<int> DistributeByQuadtree(const std::vector<FastCorner>& corners, float x0, float y0,
                                      float x1, float y1, int budget) {
  if (budget <= 0 || corners.empty()) return {};
  // Start with near-square roots so that splits produce near-square cells.
  const int num_roots = std::max(1, static_cast<int>(std::lround((x1 - x0) / (y1 - y0))));
  const float root_width = (x1 - x0) / num_roots;
  const int count = static_cast<int>(corners.size());
  std::vector<int> indices(count);
  std::iota(indices.begin(), indices.end(), 0);
  std::vector<int> scratch(count);
  std::vector<int> root_of(count);
  for (int i = 0; i < count; ++i) {
    const int r = std::min(num_roots - 1, static_cast<int>((corners[i].x - x0) / root_width));
    root_of[i] = std::max(0, r);
  }
  std::vector<int> root_start(num_roots + 1, 0);
  for (int r : root_of) ++root_start[r + 1];
  for (int r = 0; r < num_roots; ++r) root_start[r + 1] += root_start[r];
  {
    std::vector<int> next(root_start.begin(), root_start.end() - 1);
    for (int i = 0; i < count; ++i) indices[next[root_of[i]]++] = i;
  }
  std::vector<QuadNode> nodes;
  for (int r = 0; r < num_roots; ++r) {
    const QuadNode root{x0 + r * root_width, y0, x0 + (r + 1) * root_width, y1, root_start[r], root_start[r + 1]};
    if (root.size() > 0) nodes.push_back(root);
  }

  std::vector<int> splittable;
  std::vector<bool> was_split;
  std::vector<QuadNode> children;
  std::vector<QuadNode> next;
  while (static_cast<int>(nodes.size()) < budget) {
    splittable.clear();
    for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
      if (nodes[n].CanSplit()) splittable.push_back(n);
    }
    if (splittable.empty()) break;
    const bool split_all = static_cast<int>(nodes.size() + 3 * splittable.size()) <= budget;
    if (!split_all) {
      std::stable_sort(splittable.begin(), splittable.end(),
                       [&nodes](int a, int b) { return nodes[a].size() > nodes[b].size(); });
    }
    was_split.assign(nodes.size(), false);
    children.clear();
    int node_count = static_cast<int>(nodes.size());
    for (int n : splittable) {
      const size_t before = children.size();
      SplitNode(nodes[n], corners, &indices, &scratch, &children);
      was_split[n] = true;
      node_count += static_cast<int>(children.size() - before) - 1;
      if (!split_all && node_count >= budget) break;
    }
    next.clear();
    for (size_t n = 0; n < nodes.size(); ++n) {
      if (!was_split[n]) next.push_back(nodes[n]);
    }
    next.insert(next.end(), children.begin(), children.end());
    nodes.swap(next);
  }

  std::vector<int> selected;
  selected.reserve(nodes.size());
  for (const QuadNode& node : nodes) {
    selected.push_back(*std::max_element(
        indices.begin() + node.begin, indices.begin() + node.end,
        [&corners](int a, int b) { return corners[a].response < corners[b].response; }));
  }
  if (static_cast<int>(selected.size()) > budget) {
    // The last split round can overshoot by up to 3 leaves.
    std::nth_element(
        selected.begin(), selected.begin() + budget, selected.end(),
        [&corners](int a, int b) { return corners[a].response > corners[b].response; });
    selected.resize(budget);
  }
  std::sort(selected.begin(), selected.end());  // deterministic, row-major order
  return selected;
}

// FAST corners of one level inside `region`, found with the initial threshold over the
// whole region and again with the minimum threshold in each grid cell left empty (each
// search as cv::FAST over it, from one map of scores).
std::vector<FastCorner> DetectCornersInCells(const cv::Mat& level_image, const cv::Rect& region,
                                             const OrbExtractorOptions& options) {
  cv::Mat scores;
  ComputeFastScores(level_image, region, options.min_fast_threshold, &scores);
  std::vector<FastCorner> corners;
  AppendFastCorners(scores, region, options.initial_fast_threshold, &corners);
  if (options.min_fast_threshold >= options.initial_fast_threshold) return corners;

  const int cols = std::max(1, region.width / options.cell_size_px);
  const int rows = std::max(1, region.height / options.cell_size_px);
  auto cell_edge = [](int origin, int extent, int cells, int i) {
    return origin + static_cast<int>(static_cast<long>(extent) * i / cells);
  };
  std::vector<int> count(static_cast<size_t>(cols) * rows, 0);
  for (const FastCorner& c : corners) {
    // Inverse of cell_edge: the cell whose integer range [edge(i), edge(i+1)) holds c.
    int col = static_cast<int>(static_cast<long>(c.x - region.x) * cols / region.width);
    int row = static_cast<int>(static_cast<long>(c.y - region.y) * rows / region.height);
    while (col + 1 < cols && c.x >= cell_edge(region.x, region.width, cols, col + 1)) ++col;
    while (col > 0 && c.x < cell_edge(region.x, region.width, cols, col)) --col;
    while (row + 1 < rows && c.y >= cell_edge(region.y, region.height, rows, row + 1)) ++row;
    while (row > 0 && c.y < cell_edge(region.y, region.height, rows, row)) --row;
    ++count[static_cast<size_t>(row) * cols + col];
  }
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      if (count[static_cast<size_t>(row) * cols + col] > 0) continue;
      const int cx0 = cell_edge(region.x, region.width, cols, col);
      const int cx1 = cell_edge(region.x, region.width, cols, col + 1);
      const int cy0 = cell_edge(region.y, region.height, rows, row);
      const int cy1 = cell_edge(region.y, region.height, rows, row + 1);
      AppendFastCorners(scores, cv::Rect(cx0, cy0, cx1 - cx0, cy1 - cy0), options.min_fast_threshold,
                        &corners);
    }
  }
  return corners;
}

// Orientation of the patch around (x, y) as the direction from its centre to its
// intensity centroid, in degrees [0, 360).
float IntensityCentroidAngle(const cv::Mat& image, int x, int y,
                             const std::vector<int>& half_widths) {
  const uchar* centre = image.ptr<uchar>(y) + x;
  const int step = static_cast<int>(image.step1());
  int m10 = 0;
  int m01 = 0;
  for (int u = -kOrientationRadiusPx; u <= kOrientationRadiusPx; ++u) m10 += u * centre[u];
  // Rows v and -v together: their x moments add, their y moments subtract.
  for (int v = 1; v <= kOrientationRadiusPx; ++v) {
    const int w = half_widths[v];
    const uchar* below = centre + v * step;
    const uchar* above = centre - v * step;
    int row_difference = 0;
    for (int u = -w; u <= w; ++u) {
      row_difference += below[u] - above[u];
      m10 += u * (below[u] + above[u]);
    }
    m01 += v * row_difference;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

void ValidateOptions(const OrbExtractorOptions& o) {
  auto fail = [](const std::string& what) { throw Error("OrbExtractorOptions: " + what); };
  if (o.max_features < 1) fail(fmt::format("max_features must be >= 1, got {}", o.max_features));
  if (!(o.scale_factor > 1.0f) || !std::isfinite(o.scale_factor)) {
    fail(fmt::format("scale_factor must be > 1, got {}", o.scale_factor));
  }
  if (o.levels < 1 || o.levels > 32) fail(fmt::format("levels must be 1..32, got {}", o.levels));
  if (o.initial_fast_threshold < 1 || o.initial_fast_threshold > 254 || o.min_fast_threshold < 1 ||
      o.min_fast_threshold > o.initial_fast_threshold) {
    fail(fmt::format("need 1 <= min_fast_threshold ({}) <= initial_fast_threshold ({}) <= 254",
                     o.min_fast_threshold, o.initial_fast_threshold));
  }
  if (o.cell_size_px < 8) fail(fmt::format("cell_size_px must be >= 8, got {}", o.cell_size_px));
  if (!(o.min_depth_m >= 0) || !(o.max_depth_m > o.min_depth_m)) {
    fail(
        fmt::format("need 0 <= min_depth_m ({}) < max_depth_m ({})", o.min_depth_m, o.max_depth_m));
  }
}

}  // namespace

OrbExtractor::OrbExtractor(const OrbExtractorOptions& options) : options_(options) {
  ValidateOptions(options_);
  const int levels = options_.levels;
  scale_factors_.resize(levels);
  level_sigma2_.resize(levels);
  inverse_level_sigma2_.resize(levels);
  for (int l = 0; l < levels; ++l) {
    scale_factors_[l] = static_cast<float>(std::pow(static_cast<double>(options_.scale_factor), l));
    level_sigma2_[l] = scale_factors_[l] * scale_factors_[l];
    inverse_level_sigma2_[l] = 1.0f / level_sigma2_[l];
  }

  // Budgets proportional to 1/scale^level (ORB-SLAM2's choice: in proportion to the level's
  // side length, not its area, which would starve the coarse levels).
  const double ratio = 1.0 / options_.scale_factor;
  const double first = options_.max_features * (1.0 - ratio) / (1.0 - std::pow(ratio, levels));
  features_per_level_.resize(levels);
  int assigned = 0;
  for (int l = 0; l + 1 < levels; ++l) {
    features_per_level_[l] = static_cast<int>(std::lround(first * std::pow(ratio, l)));
    assigned += features_per_level_[l];
  }
  features_per_level_[levels - 1] = std::max(0, options_.max_features - assigned);

  circle_half_widths_.resize(kOrientationRadiusPx + 1);
  for (int v = 0; v <= kOrientationRadiusPx; ++v) {
    circle_half_widths_[v] = static_cast<int>(std::lround(
        std::sqrt(static_cast<double>(kOrientationRadiusPx * kOrientationRadiusPx - v * v))));
  }
}

namespace {

void CheckExtractInput(const cv::Mat& gray, const cv::Mat& depth_m, const PinholeCamera& camera) {
  std::string reason;
  if (!camera.IsValid(&reason)) throw Error("OrbExtractor::Extract: invalid camera: " + reason);
  if (gray.empty() || gray.type() != CV_8UC1) {
    throw Error(fmt::format("OrbExtractor::Extract: image must be non-empty CV_8UC1, got type {}",
                            gray.empty() ? "empty" : cv::typeToString(gray.type())));
  }
  if (gray.cols != camera.width || gray.rows != camera.height) {
    throw Error(fmt::format("OrbExtractor::Extract: image is {}x{} but the camera is {}x{}",
                            gray.cols, gray.rows, camera.width, camera.height));
  }
  if (depth_m.empty()) return;
  if (depth_m.type() != CV_32FC1) {
    throw Error(fmt::format("OrbExtractor::Extract: depth must be CV_32FC1 metres, got {}",
                            cv::typeToString(depth_m.type())));
  }
  if (depth_m.size() != gray.size()) {
    throw Error(fmt::format("OrbExtractor::Extract: depth is {}x{} but the image is {}x{}",
                            depth_m.cols, depth_m.rows, gray.cols, gray.rows));
  }
}

// Gives each keypoint with a depth in [min_depth_m, max_depth_m] at its nearest pixel
// that depth and its back-projected point; the others keep 0 and the origin.
void AttachDepth(const cv::Mat& depth_m, const PinholeCamera& camera, const OrbExtractorOptions& options,
                 FrameFeatures* features) {
  const size_t n = features->keypoints.size();
  features->depth_m.assign(n, 0.0f);
  features->points_cam.assign(n, Eigen::Vector3d::Zero());
  if (depth_m.empty()) return;
  for (size_t i = 0; i < n; ++i) {
    const cv::Point2f& pt = features->keypoints[i].pt;
    const int x = std::clamp(cvRound(pt.x), 0, depth_m.cols - 1);
    const int y = std::clamp(cvRound(pt.y), 0, depth_m.rows - 1);
    const float d = depth_m.at<float>(y, x);
    // The comparisons are false for NaN, which thus counts as missing.
    if (d >= options.min_depth_m && d <= options.max_depth_m) {
      features->depth_m[i] = d;
      features->points_cam[i] = camera.BackProject(Eigen::Vector2d(pt.x, pt.y), d);
    }
  }
}

}  // namespace

std::vector<cv::KeyPoint> OrbExtractor::DetectLevel(const cv::Mat& level_image, int level) const {
  const cv::Rect region(kBorderPx, kBorderPx, level_image.cols - 2 * kBorderPx,
                        level_image.rows - 2 * kBorderPx);
  const std::vector<FastCorner> corners = DetectCornersInCells(level_image, region, options_);
  const std::vector<int> selected = DistributeByQuadtree(
      corners, static_cast<float>(region.x), static_cast<float>(region.y),
      static_cast<float>(region.x + region.width), static_cast<float>(region.y + region.height),
      features_per_level_[level]);
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(selected.size());
  for (int index : selected) {
    const FastCorner& c = corners[index];
    keypoints.emplace_back(cv::Point2f(static_cast<float>(c.x), static_cast<float>(c.y)),
                           static_cast<float>(kPatchSizePx),
                           IntensityCentroidAngle(level_image, c.x, c.y, circle_half_widths_), c.response, 0);
  }
  return keypoints;
}

FrameFeatures OrbExtractor::Extract(const cv::Mat& gray, const cv::Mat& depth_m,
                                    const PinholeCamera& camera) const {
  CheckExtractInput(gray, depth_m, camera);
  FrameFeatures features;
  std::vector<cv::Mat> level_descriptors;
  cv::Mat level_image = gray;
  // One instance per call: cv::ORB's compute is not documented as thread-safe.
  const cv::Ptr<cv::ORB> orb =
      cv::ORB::create(options_.max_features, options_.scale_factor, 1, kBorderPx, 0, 2,
                      cv::ORB::HARRIS_SCORE, kPatchSizePx, options_.initial_fast_threshold);
  for (int level = 0; level < options_.levels; ++level) {
    if (level > 0) {
      const cv::Size size(cvRound(gray.cols / scale_factors_[level]),
                          cvRound(gray.rows / scale_factors_[level]));
      if (size.width <= 2 * kBorderPx || size.height <= 2 * kBorderPx) break;
      cv::Mat next;
      cv::resize(level_image, next, size, 0, 0, cv::INTER_LINEAR);
      level_image = next;
    }
    if (level_image.cols <= 2 * kBorderPx || level_image.rows <= 2 * kBorderPx) break;

    std::vector<cv::KeyPoint> level_keypoints = DetectLevel(level_image, level);
    if (level_keypoints.empty()) continue;
    const size_t detected = level_keypoints.size();
    cv::Mat descriptors;
    orb->compute(level_image, level_keypoints, descriptors);
    if (level_keypoints.size() != detected || descriptors.rows != static_cast<int>(detected)) {
      // Cannot happen while kBorderPx matches cv::ORB's edge threshold; a silent
      // keypoint/descriptor mismatch would corrupt every match downstream.
      throw Error("OrbExtractor::Extract: cv::ORB dropped keypoints inside the border");
    }

    // Centre-aligned resizing maps level pixel x to level-0 pixel (x + 0.5) * W / W_l - 0.5.
    const float to_level0_x = static_cast<float>(gray.cols) / level_image.cols;
    const float to_level0_y = static_cast<float>(gray.rows) / level_image.rows;
    for (cv::KeyPoint& k : level_keypoints) {
      k.pt.x = (k.pt.x + 0.5f) * to_level0_x - 0.5f;
      k.pt.y = (k.pt.y + 0.5f) * to_level0_y - 0.5f;
      k.size = kPatchSizePx * scale_factors_[level];
      k.octave = level;
      features.keypoints.push_back(k);
    }
    level_descriptors.push_back(descriptors);
  }

  if (level_descriptors.empty()) {
    features.descriptors.create(0, 32, CV_8U);
  } else {
    cv::vconcat(level_descriptors, features.descriptors);
  }
  AttachDepth(depth_m, camera, options_, &features);
  return features;
}

}  // namespace segslam::slam
