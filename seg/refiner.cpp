#include "seg/refiner.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/statistics.h"
#include "seg/refiner_options.h"

namespace segslam::seg {
namespace {

// Bounding box, area and barycentre of a CV_8U mask (non-zero = inside).
struct RegionStats {
  cv::Rect bbox;
  int area_px = 0;
  double cx = 0, cy = 0;
};

// Builds RegionStats from a region's rows, top to bottom.
class RegionStatsAccumulator {
 public:
  // Adds the pixels x in [x_begin, x_end) of row y for which inside(row[x]) holds.
  template <typename Pixel, typename Inside>
  void AddRow(int y, const Pixel* row, int x_begin, int x_end, Inside inside) {
    int count = 0, first = -1, last = -1;
    std::int64_t sum_x = 0;
    for (int x = x_begin; x < x_end; ++x) {
      if (!inside(row[x])) continue;
      if (first < 0) first = x;
      last = x;
      ++count;
      sum_x += x;
    }
    if (count > 0) AddRowSpan(y, first, last, count, sum_x);
  }

  // AddRow for a CV_8U mask row (non-zero = inside), eight pixels at a time where they
  // are all outside or all inside.
  void AddMaskRow(int y, const std::uint8_t* row, int x_begin, int x_end) {
    constexpr std::uint64_t kOnes = 0x0101010101010101ull, kHighs = 0x8080808080808080ull;
    int count = 0, first = -1, last = -1;
    std::int64_t sum_x = 0;
    int x = x_begin;
    for (; x + 8 <= x_end; x += 8) {
      std::uint64_t word;
      std::memcpy(&word, row + x, 8);
      if (word == 0) continue;
      const bool has_zero_byte = ((word - kOnes) & ~word & kHighs) != 0;
      if (!has_zero_byte) {
        if (first < 0) first = x;
        last = x + 7;
        count += 8;
        sum_x += 8 * static_cast<std::int64_t>(x) + 28;
        continue;
      }
      for (int k = x; k < x + 8; ++k) {
        if (row[k] == 0) continue;
        if (first < 0) first = k;
        last = k;
        ++count;
        sum_x += k;
      }
    }
    for (; x < x_end; ++x) {
      if (row[x] == 0) continue;
      if (first < 0) first = x;
      last = x;
      ++count;
      sum_x += x;
    }
    if (count > 0) AddRowSpan(y, first, last, count, sum_x);
  }

  RegionStats Result() const {
    RegionStats s;
    if (area_px_ == 0) return s;
    s.area_px = area_px_;
    s.bbox = cv::Rect(x_min_, y_min_, x_max_ - x_min_ + 1, y_max_ - y_min_ + 1);
    s.cx = static_cast<double>(sum_x_) / area_px_;
    s.cy = static_cast<double>(sum_y_) / area_px_;
    return s;
  }

  // Row y holds `count` > 0 pixels of the region, the first at first_x, the last at
  // last_x; sum_x is the sum of their columns. Rows come top to bottom; one row may come
  // in several spans, left to right.
  void AddRowSpan(int y, int first_x, int last_x, int count, std::int64_t sum_x) {
    x_min_ = std::min(x_min_, first_x);
    x_max_ = std::max(x_max_, last_x);
    y_min_ = std::min(y_min_, y);
    y_max_ = y;
    area_px_ += count;
    sum_x_ += sum_x;
    sum_y_ += static_cast<std::int64_t>(y) * count;
  }

 private:
  int x_min_ = std::numeric_limits<int>::max(), x_max_ = -1;
  int y_min_ = std::numeric_limits<int>::max(), y_max_ = -1;
  int area_px_ = 0;
  std::int64_t sum_x_ = 0, sum_y_ = 0;
};

// Whether the 32 bytes at p are all zero. Four scalar words: an array of them, copied
// at once, went through the stack.
inline bool AllZero32(const std::uint8_t* p) {
  std::uint64_t w0, w1, w2, w3;
  std::memcpy(&w0, p, 8);
  std::memcpy(&w1, p + 8, 8);
  std::memcpy(&w2, p + 16, 8);
  std::memcpy(&w3, p + 24, 8);
  return (w0 | w1 | w2 | w3) == 0;
}

// The first non-zero byte of row[begin, end), or end when there is none. A mask is
// mostly zero runs: they are skipped 32 bytes at a time.
int FirstNonZero(const std::uint8_t* row, int begin, int end) {
  int x = begin;
  while (x + 32 <= end && AllZero32(row + x)) x += 32;
  while (x < end && row[x] == 0) ++x;
  return x;
}

// The last non-zero byte of row[begin, end), or begin - 1 when there is none.
int LastNonZero(const std::uint8_t* row, int begin, int end) {
  int x = end;
  while (x - 32 >= begin && AllZero32(row + x - 32)) x -= 32;
  while (x > begin && row[x - 1] == 0) --x;
  return x - 1;
}

// Row-wise scan inside the instance's search box: each row from its first set pixel to
// its last.
RegionStats Measure(const InstanceMask& instance) {
  const cv::Rect box = SearchBox(instance);
  RegionStatsAccumulator region;
  for (int y = box.y; y < box.br().y; ++y) {
    const std::uint8_t* row = instance.mask.ptr<std::uint8_t>(y);
    const int first = FirstNonZero(row, box.x, box.br().x);
    if (first == box.br().x) continue;
    region.AddMaskRow(y, row, first, LastNonZero(row, first, box.br().x) + 1);
  }
  return region.Result();
}

void CheckInputImage(const cv::Mat& image, int type, const PinholeCamera& camera,
                     const char* what) {
  if (image.type() != type || image.cols != camera.width || image.rows != camera.height) {
    throw Error(std::string("refiner: ") + what + " must be " +
                (type == CV_32F ? "CV_32F" : "CV_8U") + " of the camera's size " +
                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
}

}  // namespace

bool RefinerOptions::IsValid(std::string* error) const {
  std::string problem = RefinerOptionRegistry().Check(*this);
  if (problem.empty() && w_barycenter == 0 && w_shape == 0) problem = "w_barycenter and w_shape must not both be 0";
  if (error != nullptr) *error = problem;
  return problem.empty();
}

// Z-buffer and label image (region index + 1) shared by all regions of one projection.
// Both are kept between calls; only `dirty` (the area the last call wrote) is reset.
struct ProjectionWorkspace {
  cv::Mat zbuf;   // CV_32F, +inf = empty
  cv::Mat label;  // CV_16U, 0 = empty
  cv::Rect dirty;
  std::vector<RegionStats> regions;  // per previous region: box, area, barycentre
  std::vector<cv::Rect> touched;
  // Per previous region: projected at the far limit (it had no depth at all).
  std::vector<bool> at_far_limit;
  std::vector<float> depths;         // room for a region's measured depths, for its median
  std::vector<cv::Point> missing;    // a region's pixels without depth
  std::vector<cv::Point> missing_below;  // those of the second row of a pair of rows
  // One row's points to splat, projected together (RegionSplatter::SplatRow): inputs
  // (ray's x, depth) and outputs (depth where it lands, and the pixel centres its
  // footprint covers there, columns x0..x1 by rows y0..y1, clipped to the image; empty
  // where it lands nowhere).
  struct RowBatch {
    std::vector<double> ray_x, depth;
    std::vector<float> z;
    std::vector<int> x0, x1, y0, y1;
    void Resize(int width) {
      for (auto* v : {&ray_x, &depth}) v->resize(width);
      z.resize(width);
      for (auto* v : {&x0, &x1, &y0, &y1}) v->resize(width);
    }
  };
  // Splatting by blocks: how many previous regions hold each pixel (2 = two or more),
  // valid inside their boxes. A pixel two regions share must project alike for both.
  cv::Mat sharers;  // CV_8U
  RowBatch row;     // single pixels of a row
  RowBatch below;   // single pixels of the row below it (splatting by blocks)
  RowBatch blocks;  // the 2x2 blocks of a pair of rows, one point each
};

namespace {

// Empties the z-buffer and label image where the last projection wrote (allocating them
// on first use or a new camera size) and sizes the per-region outputs.
void ResetWorkspace(int width, int height, size_t regions, ProjectionWorkspace* ws) {
  if (ws->zbuf.rows != height || ws->zbuf.cols != width) {
    ws->zbuf.create(height, width, CV_32F);
    ws->zbuf.setTo(std::numeric_limits<float>::infinity());
    ws->label.create(height, width, CV_16U);
    ws->label.setTo(0);
  } else if (!ws->dirty.empty()) {
    ws->zbuf(ws->dirty).setTo(std::numeric_limits<float>::infinity());
    ws->label(ws->dirty).setTo(0);
  }
  ws->dirty = cv::Rect();
  for (ProjectionWorkspace::RowBatch* batch : {&ws->row, &ws->below, &ws->blocks}) batch->Resize(width);
  ws->regions.assign(regions, RegionStats());
  ws->touched.assign(regions, cv::Rect());
  ws->at_far_limit.assign(regions, false);
}

bool HasDepth(float z) { return z > 0 && std::isfinite(z); }

// The largest measured depth of a depth image (the sensor's far limit, near enough),
// 0 when it measures nothing.
float FarthestDepth(const cv::Mat& depth_m) {
  float farthest = 0;
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* d = depth_m.ptr<float>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (HasDepth(d[u])) farthest = std::max(farthest, d[u]);
    }
  }
  return farthest;
}

// static_cast<int>(std::ceil(value)) for a value well inside int's range, in a few
// instructions: without SSE4.1, std::ceil on a float is a dozen.
int CeilToInt(float value) {
  const int truncated = static_cast<int>(value);  // towards zero: the ceiling of a negative value
  return truncated + (static_cast<float>(truncated) < value ? 1 : 0);
}

// Normalised image coordinates of each column (x) and row (y): the ray of pixel (u, v)
// is (x[u], y[v], 1).
struct PixelRays {
  explicit PixelRays(const PinholeCamera& camera) : x(camera.width), y(camera.height) {
    for (int u = 0; u < camera.width; ++u) x[u] = (u - camera.cx) / camera.fx;
    for (int v = 0; v < camera.height; ++v) y[v] = (v - camera.cy) / camera.fy;
  }
  std::vector<double> x, y;
};

// The constants of RegionSplatter's projection, X' = z R ray + t, then the footprint.
struct SplatConstants {
  double r[9];  // R, row-major
  double t[3];
  double fx, fy, cx, cy, fx_over_fy, fy_over_fx;
  double half_footprint, min_depth_m;
  int width, height;  // of the image, in pixels
};

// Projects the n pixels of one row: pixel i has the ray (ray_x[i], y, 1) and depth[i],
// and row_base = y R.col(1) + R.col(2). Its footprint is the axis-aligned box of the
// source pixel's image under the local warp Jacobian, for a surface fronto-parallel to
// the previous camera; it covers the pixel centres in [u - hx, u + hx) x [v - hy, v + hy).
// Branch-free over plain arrays, so the compiler vectorises it: the operations are those
// of projecting one pixel, in the same order, and none is fused (no FMA target), so every
// result is the same to the last bit whichever instruction set runs it. The arrays are
// parameters because GCC trusts __restrict on parameters only.
inline __attribute__((always_inline)) void ProjectRowBody(const SplatConstants& k,
                                                          const std::array<double, 3>& row_base, int n,
                                                          const double* __restrict ray_x,
                                                          const double* __restrict depth, float* __restrict z,
                                                          int* __restrict x0, int* __restrict x1,
                                                          int* __restrict y0, int* __restrict y1) {
  const double r0 = k.r[0], r1 = k.r[1], r3 = k.r[3], r4 = k.r[4], r6 = k.r[6], r7 = k.r[7];
  const double b0 = row_base[0], b1 = row_base[1], b2 = row_base[2];
  const double t0 = k.t[0], t1 = k.t[1], t2 = k.t[2];
  const double fx = k.fx, fy = k.fy, cx = k.cx, cy = k.cy;
  const double fx_over_fy = k.fx_over_fy, fy_over_fx = k.fy_over_fx;
  // A projection beyond these lands outside the image.
  const double u_limit = k.width + 0.5, v_limit = k.height + 0.5;
  const double half = k.half_footprint, min_depth = k.min_depth_m;
  // Footprint edges are clamped to a little outside the image before they are rounded,
  // which keeps the conversion to int defined and changes no pixel covered.
  const float u_low = -2.0f, u_high = static_cast<float>(k.width + 2);
  const float v_low = -2.0f, v_high = static_cast<float>(k.height + 2);
  const int last_x = k.width - 1, last_y = k.height - 1;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    const double dz = depth[i], rx = ray_x[i];
    const double X0 = dz * (r0 * rx + b0) + t0;
    const double X1 = dz * (r3 * rx + b1) + t1;
    const double X2 = dz * (r6 * rx + b2) + t2;
    const double inv_z = 1.0 / X2;
    const double xp = X0 * inv_z, yp = X1 * inv_z;
    const double up = fx * xp + cx, vp = fy * yp + cy;
    const double s = dz * inv_z;
    const double j00 = s * (r0 - xp * r6);
    const double j01 = s * fx_over_fy * (r1 - xp * r7);
    const double j10 = s * fy_over_fx * (r3 - yp * r6);
    const double j11 = s * (r4 - yp * r7);
    const bool lands = (X2 >= min_depth) & (up >= -1.5) & (vp >= -1.5) & (up <= u_limit) & (vp <= v_limit);
    // A pixel that lands nowhere is placed at NaN, which the clamps below turn into an
    // empty footprint left of the image. (A select of doubles on a comparison of doubles:
    // GCC vectorises it, where it turns selects of ints on it into branches.)
    const float pu = static_cast<float>(lands ? up : kNaN), pv = static_cast<float>(vp);
    const float hx = static_cast<float>(half * (std::abs(j00) + std::abs(j01)));
    const float hy = static_cast<float>(half * (std::abs(j10) + std::abs(j11)));
    // Clamped without a branch; the bound goes first, so that a NaN becomes the bound.
    const float left = std::min(u_high, std::max(u_low, pu - hx));
    const float right = std::min(u_high, std::max(u_low, pu + hx));
    const float top = std::min(v_high, std::max(v_low, pv - hy));
    const float bottom = std::min(v_high, std::max(v_low, pv + hy));
    z[i] = static_cast<float>(X2);
    x0[i] = std::max(0, CeilToInt(left));
    x1[i] = std::min(last_x, CeilToInt(right) - 1);
    y0[i] = std::max(0, CeilToInt(top));
    y1[i] = std::min(last_y, CeilToInt(bottom) - 1);
  }
}

void ProjectRowDefault(const SplatConstants& k, const std::array<double, 3>& row_base, int n,
                       ProjectionWorkspace::RowBatch* row) {
  ProjectRowBody(k, row_base, n, row->ray_x.data(), row->depth.data(), row->z.data(), row->x0.data(),
                 row->x1.data(), row->y0.data(), row->y1.data());
}

#if defined(__x86_64__)
// Four pixels at a time where the processor has AVX2 (no FMA: see ProjectRowBody).
__attribute__((target("avx2"))) void ProjectRowAvx2(const SplatConstants& k, const std::array<double, 3>& row_base,
                                                    int n, ProjectionWorkspace::RowBatch* row) {
  ProjectRowBody(k, row_base, n, row->ray_x.data(), row->depth.data(), row->z.data(), row->x0.data(),
                 row->x1.data(), row->y0.data(), row->y1.data());
}
#endif

void ProjectRow(const SplatConstants& k, const std::array<double, 3>& row_base, int n,
                ProjectionWorkspace::RowBatch* row) {
#if defined(__x86_64__)
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  if (has_avx2) return ProjectRowAvx2(k, row_base, n, row);
#endif
  ProjectRowDefault(k, row_base, n, row);
}

// Splats one region into the z-buffer under its label. Each pixel is moved by T into the
// current view, X' = z R ray + t, and written over the pixel centres its source pixel's
// footprint covers there, nearest first. Pixels without depth take the region's median
// depth; a region with no depth at all, the far limit (RefinerOptions). Within a region
// every write has the same label and the z-buffer keeps the nearest, so the order of the
// writes does not matter: pixels with depth are splatted in the one scan that also
// gathers the median, the others after it. A row's pixels are projected together
// (ProjectRow), then written one by one. With splat_interior_in_blocks, a 2x2 block of
// the region's own pixels on one surface is one point (SplatMeasuredInBlocks).
class RegionSplatter {
 public:
  RegionSplatter(const RefinerOptions& options, const PinholeCamera& camera, const PixelRays& rays,
                 const Eigen::Isometry3d& T, ProjectionWorkspace* ws)
      : options_(options),
        rays_(rays),
        ws_(ws),
        zbuf_data_(ws->zbuf.data),
        label_data_(ws->label.data),
        zbuf_step_(ws->zbuf.step[0]),
        label_step_(ws->label.step[0]) {
    for (int i = 0; i < 3; ++i) {
      k_.t[i] = T.translation()(i);
      for (int j = 0; j < 3; ++j) k_.r[3 * i + j] = T.linear()(i, j);
    }
    k_.fx = camera.fx;
    k_.fy = camera.fy;
    k_.cx = camera.cx;
    k_.cy = camera.cy;
    k_.fx_over_fy = camera.fx / camera.fy;
    k_.fy_over_fx = camera.fy / camera.fx;
    k_.half_footprint = 0.5 * options.splat_footprint_scale;
    k_.min_depth_m = options.min_depth_m;
    k_.width = camera.width;
    k_.height = camera.height;
    block_k_ = k_;
    block_k_.half_footprint = 2 * k_.half_footprint;  // a 2x2 block is twice a pixel's width
  }

  // Splats the region (inside bbox) under `id`; `far_limit` gives the depth for a region
  // measured nowhere. Returns the box of pixels written (empty when none) and sets
  // *at_far_limit when the far limit was used.
  template <typename FarLimit>
  cv::Rect Splat(const cv::Mat& mask, const cv::Rect& bbox, const cv::Mat& depth_m, std::uint16_t id,
                 FarLimit far_limit, bool* at_far_limit) {
    id_ = id;
    box_x0_ = ws_->zbuf.cols, box_y0_ = ws_->zbuf.rows, box_x1_ = -1, box_y1_ = -1;
    std::vector<float>& depths = ws_->depths;
    std::vector<cv::Point>& missing = ws_->missing;
    // Room for every pixel's depth, written by index: a push_back per pixel costs a
    // capacity test and a store of the vector's end.
    if (depths.size() < static_cast<std::size_t>(bbox.area())) depths.resize(bbox.area());
    depth_out_ = depths.data();
    depth_count_ = 0;
    missing.clear();
    const int measured = options_.splat_interior_in_blocks ? SplatMeasuredInBlocks(mask, bbox, depth_m)
                                                           : SplatMeasuredByPixel(mask, bbox, depth_m);
    if (missing.empty()) return Box();
    float fill_depth = 0;
    if (options_.fill_missing_depth_with_median && depth_count_ > 0) {
      fill_depth = KthSmallest(depths.data(), depth_count_, depth_count_ / 2);
    }
    const bool measured_nowhere = measured == 0;
    if (fill_depth <= 0 && options_.project_depthless_regions_at_far_limit && measured_nowhere) {
      fill_depth = far_limit();
      *at_far_limit = true;
    }
    if (fill_depth <= 0) return Box();
    // `missing` runs row by row, top to bottom.
    ProjectionWorkspace::RowBatch& row = ws_->row;
    for (size_t begin = 0; begin < missing.size();) {
      const int v = missing[begin].y;
      int n = 0;
      for (; begin < missing.size() && missing[begin].y == v; ++begin, ++n) {
        row.ray_x[n] = rays_.x[missing[begin].x];
        row.depth[n] = static_cast<double>(fill_depth);
      }
      SplatRow(k_, RowBase(rays_.y[v]), n, &row);
    }
    return Box();
  }

 private:
  // Splats the region's pixels with depth one by one, keeps their depths for the median
  // (when wanted) and lists those without depth in ws_->missing. Returns how many had
  // depth.
  int SplatMeasuredByPixel(const cv::Mat& mask, const cv::Rect& bbox, const cv::Mat& depth_m) {
    int measured = 0;
    for (int v = bbox.y; v < bbox.br().y; ++v) measured += SplatRowByPixel(mask, bbox, depth_m, v);
    return measured;
  }

  // Row v of the same, alone; returns how many of its pixels had depth.
  int SplatRowByPixel(const cv::Mat& mask, const cv::Rect& bbox, const cv::Mat& depth_m, int v) {
    const std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    const float* d = depth_m.ptr<float>(v);
    int n = 0;
    for (int u = bbox.x; u < bbox.br().x; ++u) GatherPixel(m, d, u, v, &ws_->row, &n, &ws_->missing);
    SplatRow(k_, RowBase(rays_.y[v]), n, &ws_->row);
    return n;
  }

  // The same, by pairs of rows: a 2x2 block inside the region and on one surface is one
  // point (its centre, its mean depth, a footprint twice as wide); every other pixel
  // goes alone. Returns how many pixels had depth.
  int SplatMeasuredInBlocks(const cv::Mat& mask, const cv::Rect& bbox, const cv::Mat& depth_m) {
    ProjectionWorkspace::RowBatch& row = ws_->row;
    ProjectionWorkspace::RowBatch& below = ws_->below;
    ProjectionWorkspace::RowBatch& blocks = ws_->blocks;
    std::vector<cv::Point>& missing_below = ws_->missing_below;
    const bool want_median = options_.fill_missing_depth_with_median;
    const float same_surface = static_cast<float>(1.0 + options_.depth_tolerance);
    const double* const column_ray_x = rays_.x.data();
    int measured = 0;
    for (int v = bbox.y; v < bbox.br().y; v += 2) {
      if (v + 1 == bbox.br().y) {  // a last row without a pair
        measured += SplatRowByPixel(mask, bbox, depth_m, v);
        break;
      }
      const std::uint8_t* m0 = mask.ptr<std::uint8_t>(v);
      const std::uint8_t* m1 = mask.ptr<std::uint8_t>(v + 1);
      const std::uint8_t* shared0 = ws_->sharers.ptr<std::uint8_t>(v);
      const std::uint8_t* shared1 = ws_->sharers.ptr<std::uint8_t>(v + 1);
      const float* d0 = depth_m.ptr<float>(v);
      const float* d1 = depth_m.ptr<float>(v + 1);
      missing_below.clear();
      int n0 = 0, n1 = 0, blocks_here = 0;
      int u = bbox.x;
      for (; u + 1 < bbox.br().x; u += 2) {
        // Only this region's own pixels: a pixel another region shares goes alone, so
        // that it lands at the same depth for both and the tie rule decides it.
        const bool own_block = m0[u] && m0[u + 1] && m1[u] && m1[u + 1] && shared0[u] == 1 &&
                               shared0[u + 1] == 1 && shared1[u] == 1 && shared1[u + 1] == 1;
        if (own_block) {
          const float z00 = d0[u], z01 = d0[u + 1], z10 = d1[u], z11 = d1[u + 1];
          const bool all_measured = HasDepth(z00) && HasDepth(z01) && HasDepth(z10) && HasDepth(z11);
          const float nearest = std::min(std::min(z00, z01), std::min(z10, z11));
          const float farthest = std::max(std::max(z00, z01), std::max(z10, z11));
          if (all_measured && farthest <= nearest * same_surface) {
            if (want_median) {
              for (float z : {z00, z01, z10, z11}) depth_out_[depth_count_++] = z;
            }
            blocks.ray_x[blocks_here] = 0.5 * (column_ray_x[u] + column_ray_x[u + 1]);
            blocks.depth[blocks_here] =
                0.25 * (static_cast<double>(z00) + static_cast<double>(z01) + static_cast<double>(z10) +
                        static_cast<double>(z11));
            ++blocks_here;
            continue;
          }
        }
        for (int x : {u, u + 1}) {
          GatherPixel(m0, d0, x, v, &row, &n0, &ws_->missing);
          GatherPixel(m1, d1, x, v + 1, &below, &n1, &missing_below);
        }
      }
      if (u < bbox.br().x) {  // an odd last column
        GatherPixel(m0, d0, u, v, &row, &n0, &ws_->missing);
        GatherPixel(m1, d1, u, v + 1, &below, &n1, &missing_below);
      }
      // `missing` stays in row order: the lower row's pixels follow the upper row's.
      ws_->missing.insert(ws_->missing.end(), missing_below.begin(), missing_below.end());
      measured += n0 + n1 + 4 * blocks_here;
      SplatRow(k_, RowBase(rays_.y[v]), n0, &row);
      SplatRow(k_, RowBase(rays_.y[v + 1]), n1, &below);
      SplatRow(block_k_, RowBase(0.5 * (rays_.y[v] + rays_.y[v + 1])), blocks_here, &blocks);
    }
    return measured;
  }

  // Adds pixel (u, v) of the region (mask row m, depth row d) to `batch` when it has
  // depth (keeping the depth for the median when wanted), to `missing` when it has none.
  inline __attribute__((always_inline)) void GatherPixel(const std::uint8_t* m, const float* d, int u, int v,
                                                         ProjectionWorkspace::RowBatch* batch, int* n,
                                                         std::vector<cv::Point>* missing) {
    if (!m[u]) return;
    const float z = d[u];
    if (!HasDepth(z)) {
      missing->emplace_back(u, v);
      return;
    }
    if (options_.fill_missing_depth_with_median) depth_out_[depth_count_++] = z;
    batch->ray_x[*n] = rays_.x[u];
    batch->depth[*n] = static_cast<double>(z);
    ++*n;
  }

  // Projects a row's n gathered points (constants k, row_base as RowBase gives) and
  // writes each where it lands, nearest first.
  void SplatRow(const SplatConstants& k, const std::array<double, 3>& row_base, int n,
                ProjectionWorkspace::RowBatch* batch) {
    if (n == 0) return;
    const ProjectionWorkspace::RowBatch& row = *batch;
    ProjectRow(k, row_base, n, batch);
    for (int i = 0; i < n; ++i) {
      const int x0 = row.x0[i], x1 = row.x1[i], y0 = row.y0[i], y1 = row.y1[i];
      // One pixel, nearly all at footprint scale 1 and a frame's motion, is tested first.
      const bool one_pixel = x0 == x1 && y0 == y1;
      if (!one_pixel && (x0 > x1 || y0 > y1)) continue;
      box_x0_ = std::min(box_x0_, x0);
      box_x1_ = std::max(box_x1_, x1);
      box_y0_ = std::min(box_y0_, y0);
      box_y1_ = std::max(box_y1_, y1);
      if (one_pixel) {
        WriteIfNearer(x0, y0, row.z[i]);
        continue;
      }
      // Two pixels wide and at most two high (a block's footprint, nearly always): a
      // pair of pixels on each row, without the loops' unpredictable ends. A row written
      // twice (y0 = y1) is written alike.
      if (x1 == x0 + 1 && y1 - y0 <= 1) {
        WritePairIfNearer(x0, y0, row.z[i]);
        WritePairIfNearer(x0, y1, row.z[i]);
        continue;
      }
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) WriteIfNearer(x, y, row.z[i]);
      }
    }
  }

  // Writes depth z and the region's label at (x, y) when nearer than what is there.
  // Without a branch, which overlapping regions make unpredictable: the new and old
  // values are blended bitwise (GCC compiles a select of floats into a branch).
  inline __attribute__((always_inline)) void WriteIfNearer(int x, int y, float z) {
    float* zbuf = reinterpret_cast<float*>(zbuf_data_ + y * zbuf_step_) + x;
    std::uint16_t* label = reinterpret_cast<std::uint16_t*>(label_data_ + y * label_step_) + x;
    const bool nearer = z <= *zbuf;
    const std::uint32_t take = 0u - static_cast<std::uint32_t>(nearer);  // all ones or zero
    std::uint32_t new_bits, old_bits;
    std::memcpy(&new_bits, &z, sizeof z);
    std::memcpy(&old_bits, zbuf, sizeof z);
    const std::uint32_t bits = (new_bits & take) | (old_bits & ~take);
    std::memcpy(zbuf, &bits, sizeof bits);
    *label = static_cast<std::uint16_t>((id_ & take) | (*label & ~take));
  }

  // WriteIfNearer at (x, y) and (x + 1, y) at once. Every depth here is positive or +inf
  // (points nearer than min_depth_m > 0 are dropped, the reset writes +inf, closing takes
  // means), and such floats order as their bits do, so they are compared as integers.
  inline __attribute__((always_inline)) void WritePairIfNearer(int x, int y, float z) {
    using Bits2 = std::uint32_t __attribute__((vector_size(8)));
    using Labels2 = std::uint16_t __attribute__((vector_size(4)));
    std::uint8_t* zbuf = zbuf_data_ + y * zbuf_step_ + x * sizeof(float);
    std::uint8_t* label = label_data_ + y * label_step_ + x * sizeof(std::uint16_t);
    std::uint32_t z_bits;
    std::memcpy(&z_bits, &z, sizeof z);
    const Bits2 new_bits = {z_bits, z_bits};
    Bits2 old_bits;
    Labels2 old_labels;
    std::memcpy(&old_bits, zbuf, sizeof old_bits);
    std::memcpy(&old_labels, label, sizeof old_labels);
    const Bits2 take = new_bits <= old_bits;  // per pixel, all ones or zero
    const Bits2 bits = (new_bits & take) | (old_bits & ~take);
    const Labels2 take_label = __builtin_convertvector(take, Labels2);
    const Labels2 new_labels = {id_, id_};
    const Labels2 labels = (new_labels & take_label) | (old_labels & ~take_label);
    std::memcpy(zbuf, &bits, sizeof bits);
    std::memcpy(label, &labels, sizeof labels);
  }

  // R's second and third columns for a row of rays (x, ray_y, 1): R (x, ray_y, 1) =
  // x R.col(0) + this.
  std::array<double, 3> RowBase(double ray_y) const {
    return {k_.r[1] * ray_y + k_.r[2], k_.r[4] * ray_y + k_.r[5], k_.r[7] * ray_y + k_.r[8]};
  }

  cv::Rect Box() const {
    if (box_x1_ < 0) return cv::Rect();
    return cv::Rect(box_x0_, box_y0_, box_x1_ - box_x0_ + 1, box_y1_ - box_y0_ + 1);
  }

  const RefinerOptions& options_;
  const PixelRays& rays_;
  SplatConstants k_;
  SplatConstants block_k_;  // the same with a 2x2 block's footprint
  ProjectionWorkspace* ws_;
  std::uint8_t* zbuf_data_;
  std::uint8_t* label_data_;
  const std::size_t zbuf_step_, label_step_;
  std::uint16_t id_ = 0;
  float* depth_out_ = nullptr;  // ws_->depths' storage: the region's measured depths
  std::size_t depth_count_ = 0;
  int box_x0_ = 0, box_y0_ = 0, box_x1_ = -1, box_y1_ = -1;
};

// Whether each of the four labels at `row` equals the label left of it and the one
// above it (`above`, the same columns of the row above).
bool SameAsLeftAndAbove(const std::uint16_t* row, const std::uint16_t* above) {
  std::uint64_t here, left, up;
  std::memcpy(&here, row, 8);
  std::memcpy(&left, row - 1, 8);
  std::memcpy(&up, above, 8);
  return ((here ^ left) | (here ^ up)) == 0;
}

// Whether the four labels at `labels` all equal the label repeated in `four_ids`.
bool FourLabelsAre(const std::uint16_t* labels, std::uint64_t four_ids) {
  std::uint64_t here;
  std::memcpy(&here, labels, 8);
  return here == four_ids;
}

// Depth-aware closing inside `area`: a pixel that is empty, or shows something farther
// than the region on both of its sides (left and right, or above and below), is a crack
// in that region and takes its label and mean depth.
void CloseCracks(const RefinerOptions& options, const cv::Rect& area, cv::Mat* zbuf,
                 cv::Mat* label) {
  const float tol = static_cast<float>(1.0 + options.depth_tolerance);
  const cv::Rect inner = area & cv::Rect(1, 1, zbuf->cols - 2, zbuf->rows - 2);
  for (int iteration = 0; iteration < options.hole_fill_iterations; ++iteration) {
    int filled = 0;
    for (int y = inner.y; y < inner.br().y; ++y) {
      float* zr = zbuf->ptr<float>(y);
      std::uint16_t* lr = label->ptr<std::uint16_t>(y);
      const std::uint16_t* lu = label->ptr<std::uint16_t>(y - 1);
      const std::uint16_t* ld = label->ptr<std::uint16_t>(y + 1);
      const float* zu = zbuf->ptr<float>(y - 1);
      const float* zd = zbuf->ptr<float>(y + 1);
      for (int x = inner.x; x < inner.br().x; ++x) {
        // Four pixels at a time: one labelled as its left and upper neighbours is no
        // crack by either rule, and the run is skipped (most pixels, inside a region or
        // outside all).
        while (x + 4 <= inner.br().x && SameAsLeftAndAbove(lr + x, lu + x)) x += 4;
        if (x >= inner.br().x) break;
        std::uint16_t l = 0;
        float z = 0;
        if (lr[x - 1] != 0 && lr[x - 1] == lr[x + 1] && lr[x - 1] != lr[x]) {
          l = lr[x - 1];
          z = 0.5f * (zr[x - 1] + zr[x + 1]);
        } else if (lu[x] != 0 && lu[x] == ld[x] && lu[x] != lr[x]) {
          l = lu[x];
          z = 0.5f * (zu[x] + zd[x]);
        } else {
          continue;
        }
        if (lr[x] == 0 || zr[x] > z * tol) {
          lr[x] = l;
          zr[x] = z;
          ++filled;
        }
      }
    }
    if (filled == 0) break;
  }
}

// Unlabels the projected pixels (inside `area`) behind what the current depth image
// measures there, when there is one (something now stands in front of the region), and
// measures the box, area and barycentre of each region's pixels left, in one scan: a run
// of pixels of one label adds to its region at once. Closing stays inside the box a
// region wrote, so `area`, the union of those boxes, holds every labelled pixel.
std::vector<RegionStats> DropOccludedAndMeasure(const RefinerOptions& options, const cv::Mat& current_depth_m,
                                                const cv::Rect& area, const cv::Mat& zbuf, size_t regions,
                                                cv::Mat* label) {
  const float keep = static_cast<float>(1.0 - options.occlusion_tolerance);
  const bool drop = !current_depth_m.empty();
  std::vector<RegionStatsAccumulator> accumulators(regions);
  for (int y = area.y; y < area.br().y; ++y) {
    const float* zr = zbuf.ptr<float>(y);
    const float* dr = drop ? current_depth_m.ptr<float>(y) : nullptr;
    std::uint16_t* lr = label->ptr<std::uint16_t>(y);
    if (drop) {
      // A select, not a branch, so that GCC vectorises the loop.
      for (int x = area.x; x < area.br().x; ++x) {
        const bool occluded = (lr[x] != 0) & (dr[x] > 0) & (dr[x] < keep * zr[x]);
        lr[x] = occluded ? 0 : lr[x];
      }
    }
    for (int x = area.x; x < area.br().x;) {
      const std::uint16_t id = lr[x];
      const int start = x;
      // Runs are long (a region's width, or the empty space between regions): four
      // labels are compared at a time.
      const std::uint64_t four_ids = 0x0001000100010001ull * id;
      while (x + 4 <= area.br().x && FourLabelsAre(lr + x, four_ids)) x += 4;
      while (x < area.br().x && lr[x] == id) ++x;
      if (id == 0) continue;
      const std::int64_t length = x - start;
      accumulators[id - 1].AddRowSpan(y, start, x - 1, static_cast<int>(length), length * (start + x - 1) / 2);
    }
  }
  std::vector<RegionStats> stats;
  stats.reserve(regions);
  for (const RegionStatsAccumulator& accumulator : accumulators) stats.push_back(accumulator.Result());
  return stats;
}

// count[i] += (mask[i] != 0), saturated at 2; vectorised (the arrays do not overlap).
void AddHolders(const std::uint8_t* __restrict mask, std::uint8_t* __restrict count, int n) {
  for (int i = 0; i < n; ++i) {
    const std::uint8_t sum = static_cast<std::uint8_t>(count[i] + (mask[i] != 0 ? 1 : 0));
    count[i] = sum < 2 ? sum : 2;
  }
}

// Counts, for each pixel inside the previous regions' boxes, how many of the regions hold
// it (2 standing for two or more) into ws->sharers.
void CountSharers(const FrameSegmentation& previous_refined, const std::vector<RegionStats>& source_stats,
                  ProjectionWorkspace* ws) {
  cv::Rect box;
  for (const RegionStats& stats : source_stats) {
    if (stats.area_px > 0) box = box.empty() ? stats.bbox : (box | stats.bbox);
  }
  if (ws->sharers.size() != ws->label.size()) ws->sharers.create(ws->label.size(), CV_8U);
  if (box.empty()) return;
  ws->sharers(box).setTo(0);
  for (size_t i = 0; i < source_stats.size(); ++i) {
    const cv::Rect& bbox = source_stats[i].bbox;
    if (source_stats[i].area_px == 0) continue;
    for (int v = bbox.y; v < bbox.br().y; ++v) {
      AddHolders(previous_refined.instances[i].mask.ptr<std::uint8_t>(v) + bbox.x,
                 ws->sharers.ptr<std::uint8_t>(v) + bbox.x, bbox.width);
    }
  }
}

// The projection proper: forward-splats each previous region with its depth and motion
// (its own when estimated, else the camera's) into one z-buffer, closes the cracks the
// splatting leaves, drops what the current depth shows occluded, and measures each
// projected region. Fills ws->label, ws->zbuf and ws->regions.
void ProjectInto(const RefinerOptions& options, const PinholeCamera& camera,
                 const FrameSegmentation& previous_refined, const cv::Mat& previous_depth_m,
                 const Eigen::Isometry3d& T_cur_prev,
                 const std::map<std::uint16_t, Eigen::Isometry3d>& instance_motion_prev,
                 const cv::Mat& current_depth_m, ProjectionWorkspace* ws) {
  CheckInputImage(previous_depth_m, CV_32F, camera, "previous depth");
  if (!current_depth_m.empty()) CheckInputImage(current_depth_m, CV_32F, camera, "current depth");
  // Every input is checked before the workspace is touched: an error half-way would leave
  // splatted labels behind for the next frame.
  for (const InstanceMask& instance : previous_refined.instances) {
    CheckInputImage(instance.mask, CV_8U, camera, "previous instance mask");
  }
  const size_t n = previous_refined.instances.size();
  ResetWorkspace(camera.width, camera.height, n, ws);
  if (n == 0) return;

  const PixelRays rays(camera);
  std::optional<float> far_limit;  // FarthestDepth(previous_depth_m), when first needed
  cv::Rect all_touched;
  // Where regions overlap (a segmenter's table mask that takes in the keyboard on it),
  // a shared pixel projects to the same place at the same depth for both. Splatting the
  // larger regions first and letting ties go to the later one gives it to the smaller,
  // more specific region; first-come ties erased such a keyboard from the projection.
  std::vector<RegionStats> source_stats(n);
  for (size_t i = 0; i < n; ++i) source_stats[i] = Measure(previous_refined.instances[i]);
  std::vector<size_t> larger_first(n);
  std::iota(larger_first.begin(), larger_first.end(), size_t{0});
  std::stable_sort(larger_first.begin(), larger_first.end(), [&](size_t a, size_t b) {
    return source_stats[a].area_px > source_stats[b].area_px;
  });
  if (options.splat_interior_in_blocks) CountSharers(previous_refined, source_stats, ws);
  for (const size_t i : larger_first) {
    const InstanceMask& instance = previous_refined.instances[i];
    const RegionStats& stats = source_stats[i];
    if (stats.area_px == 0) continue;
    const auto motion = instance_motion_prev.find(instance.track_id);
    const Eigen::Isometry3d& T =
        motion != instance_motion_prev.end() ? motion->second : T_cur_prev;
    const auto far_limit_depth = [&] {
      if (!far_limit) far_limit = FarthestDepth(previous_depth_m);
      return *far_limit;
    };
    bool at_far_limit = false;
    ws->touched[i] = RegionSplatter(options, camera, rays, T, ws)
                         .Splat(instance.mask, stats.bbox, previous_depth_m, static_cast<std::uint16_t>(i + 1),
                                far_limit_depth, &at_far_limit);
    ws->at_far_limit[i] = at_far_limit;
    if (!ws->touched[i].empty()) {
      all_touched = all_touched.empty() ? ws->touched[i] : (all_touched | ws->touched[i]);
    }
  }

  CloseCracks(options, all_touched, &ws->zbuf, &ws->label);
  ws->dirty = all_touched;
  if (!all_touched.empty()) {
    ws->regions = DropOccludedAndMeasure(options, current_depth_m, all_touched, ws->zbuf, n, &ws->label);
  }
}

// Frame-sized CV_8U mask of projected region i.
cv::Mat RegionMask(const ProjectionWorkspace& ws, size_t i) {
  cv::Mat mask(ws.label.size(), CV_8U, cv::Scalar(0));
  const cv::Rect& box = ws.regions[i].bbox;
  const std::uint16_t id = static_cast<std::uint16_t>(i + 1);
  for (int y = box.y; y < box.br().y; ++y) {
    const std::uint16_t* lr = ws.label.ptr<std::uint16_t>(y);
    std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (int x = box.x; x < box.br().x; ++x) m[x] = lr[x] == id;
  }
  return mask;
}

// Pixels of projected region i that are set in `mask` (with box `mask_box`).
int IntersectionWithLabel(const ProjectionWorkspace& ws, size_t i, const cv::Mat& mask,
                          const cv::Rect& mask_box) {
  const cv::Rect r = ws.regions[i].bbox & mask_box;
  const std::uint16_t id = static_cast<std::uint16_t>(i + 1);
  int count = 0;
  for (int y = r.y; y < r.y + r.height; ++y) {
    const std::uint16_t* lr = ws.label.ptr<std::uint16_t>(y);
    const std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (int x = r.x; x < r.x + r.width; ++x) count += (lr[x] == id) & (m[x] != 0);
  }
  return count;
}

// A projected previous region p matched to a current region c.
struct RegionMatch {
  double cost = 0;  // S of the paper's eq. 2
  int p = -1;
  int c = -1;
  int intersection = 0;  // pixels the two regions share
};

// One-to-one matches between the projected previous regions and the current regions,
// indexed by current region (nullopt: unmatched). Of the pairs whose S (paper eq. 2) is
// under max_match_cost, the lowest S is taken first (ties: lower indices first, so the
// result is deterministic).
std::vector<std::optional<RegionMatch>> MatchRegions(const RefinerOptions& options,
                                                     const PinholeCamera& camera,
                                                     const FrameSegmentation& previous,
                                                     const ProjectionWorkspace& ws,
                                                     const FrameSegmentation& current,
                                                     const std::vector<RegionStats>& cur_stats) {
  const std::vector<RegionStats>& prev_stats = ws.regions;
  std::vector<RegionMatch> candidates;
  const double diagonal = std::hypot(camera.width, camera.height);
  for (size_t p = 0; p < previous.instances.size(); ++p) {
    if (prev_stats[p].area_px < std::max(1, options.min_matched_area_px)) continue;
    for (size_t c = 0; c < current.instances.size(); ++c) {
      if (cur_stats[c].area_px == 0) continue;
      if (options.require_same_category &&
          previous.instances[p].category_id != current.instances[c].category_id) {
        continue;
      }
      const int inter =
          (prev_stats[p].bbox & cur_stats[c].bbox).empty()
              ? 0
              : IntersectionWithLabel(ws, p, current.instances[c].mask, cur_stats[c].bbox);
      const double sum = prev_stats[p].area_px + cur_stats[c].area_px;
      const double xor_area = sum - 2.0 * inter;
      const double dist = std::hypot(prev_stats[p].cx - cur_stats[c].cx,
                                     prev_stats[p].cy - cur_stats[c].cy) / diagonal;
      const double cost =
          options.w_barycenter * dist + options.w_shape * std::sqrt(xor_area / sum);
      if (cost < options.max_match_cost) {
        candidates.push_back({cost, static_cast<int>(p), static_cast<int>(c), inter});
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const RegionMatch& a, const RegionMatch& b) {
    if (a.cost != b.cost) return a.cost < b.cost;
    return a.p != b.p ? a.p < b.p : a.c < b.c;
  });
  std::vector<std::optional<RegionMatch>> match_of_cur(current.instances.size());
  std::vector<bool> previous_taken(previous.instances.size(), false);
  for (const RegionMatch& k : candidates) {
    if (match_of_cur[k.c] || previous_taken[k.p]) continue;
    match_of_cur[k.c] = k;
    previous_taken[k.p] = true;
  }
  return match_of_cur;
}

// Sets in *trimmed (over roi) the pixels of current_mask that the trim cut off but whose
// current depth lies within projected region p's depth range, widened by depth_tolerance
// (RefinerOptions::trim_keeps_region_depth).
void KeepCutPixelsAtRegionDepth(const RefinerOptions& options, const ProjectionWorkspace& ws, size_t p,
                                const cv::Mat& current_depth_m, const cv::Mat& current_mask, const cv::Rect& roi,
                                cv::Mat* trimmed) {
  const std::uint16_t id = static_cast<std::uint16_t>(p + 1);
  float z_min = std::numeric_limits<float>::infinity(), z_max = 0;
  for (int y = roi.y; y < roi.br().y; ++y) {
    const std::uint16_t* label = ws.label.ptr<std::uint16_t>(y);
    const float* z = ws.zbuf.ptr<float>(y);
    for (int x = roi.x; x < roi.br().x; ++x) {
      if (label[x] == id && HasDepth(z[x])) {
        z_min = std::min(z_min, z[x]);
        z_max = std::max(z_max, z[x]);
      }
    }
  }
  if (!(z_max > 0)) return;
  const double low = z_min * (1 - options.depth_tolerance), high = z_max * (1 + options.depth_tolerance);
  for (int y = 0; y < roi.height; ++y) {
    const float* depth = current_depth_m.ptr<float>(roi.y + y) + roi.x;
    const std::uint8_t* current = current_mask.ptr<std::uint8_t>(roi.y + y) + roi.x;
    std::uint8_t* kept = trimmed->ptr<std::uint8_t>(y);
    for (int x = 0; x < roi.width; ++x) {
      if (current[x] != 0 && kept[x] == 0 && HasDepth(depth[x]) && depth[x] >= low && depth[x] <= high) kept[x] = 255;
    }
  }
}

// Algorithm 1 for a matched pair. *instance (a copy of the current region) keeps its
// mask, or takes the projected region's: where it spills past the projection that it
// covers (shrink; or it is trimmed to the projection, trim_instead_of_replace), or where
// it lies inside a projection it covers only in part (repair of a missed part). It takes
// the previous track id and at least a share of the previous score. *decision says why.
void RefineMatchedRegion(const RefinerOptions& options, const PinholeCamera& camera,
                         const ProjectionWorkspace& ws, const RegionMatch& match,
                         const RegionStats& cur_stats, const InstanceMask& previous,
                         const cv::Mat& current_depth_m, InstanceMask* instance, RegionDecision* decision) {
  const size_t p = static_cast<size_t>(match.p);
  const RegionStats& prev_stats = ws.regions[p];
  // Ratios up to the boundary tolerance: a pixel of one region counts as confirmed by
  // the other when it lies within boundary_tolerance_px of it.
  const int tol = options.boundary_tolerance_px;
  double ra_c = static_cast<double>(match.intersection) / cur_stats.area_px;
  double ra_p = static_cast<double>(match.intersection) / prev_stats.area_px;
  cv::Mat trimmed;
  cv::Rect roi;
  if (tol > 0) {
    roi = cur_stats.bbox | prev_stats.bbox;
    roi.x -= tol;
    roi.y -= tol;
    roi.width += 2 * tol;
    roi.height += 2 * tol;
    roi &= cv::Rect(0, 0, camera.width, camera.height);
    const cv::Mat mc = instance->mask(roi) != 0;
    // The projected region within the box, without a frame-sized mask of it.
    const cv::Mat mp = ws.label(roi) == static_cast<double>(p + 1);
    const cv::Mat kernel =
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * tol + 1, 2 * tol + 1));
    cv::Mat mc_wide, mp_wide;
    cv::dilate(mc, mc_wide, kernel);
    cv::dilate(mp, mp_wide, kernel);
    trimmed = mc & mp_wide;
    ra_c = static_cast<double>(cv::countNonZero(trimmed)) / cur_stats.area_px;
    ra_p = static_cast<double>(cv::countNonZero(mp & mc_wide)) / prev_stats.area_px;
  }
  const bool shrink = ra_p - ra_c > options.replace_min_ratio_gap;  // paper: gap 0
  const bool repair = options.repair_missing_parts &&
                      ra_c >= options.repair_min_current_inside &&
                      ra_p < options.repair_max_projected_covered;
  const bool replace = shrink || repair;
  decision->kind = replace ? RegionDecision::Kind::kReplaced : RegionDecision::Kind::kKept;
  decision->previous_index = match.p;
  decision->cost = match.cost;
  decision->ratio_current = ra_c;
  decision->ratio_projected = ra_p;
  decision->projected_area_px = prev_stats.area_px;
  instance->track_id = previous.track_id;
  if (shrink && !repair && options.trim_instead_of_replace && !trimmed.empty()) {
    if (options.trim_keeps_region_depth && !current_depth_m.empty()) {
      KeepCutPixelsAtRegionDepth(options, ws, p, current_depth_m, instance->mask, roi, &trimmed);
    }
    cv::Mat mask(instance->mask.size(), CV_8U, cv::Scalar(0));
    mask(roi).setTo(1, trimmed);
    instance->mask = mask;
    instance->bounds = roi;
  } else if (replace) {
    instance->mask = RegionMask(ws, p);
    instance->bounds = prev_stats.bbox;
  } else {
    instance->bounds = cur_stats.bbox;
  }
  instance->score = std::max(
      instance->score,
      static_cast<float>(options.matched_previous_score_weight * previous.score));
}

}  // namespace

std::vector<ProjectedRegion> ProjectRegions(
    const RefinerOptions& options, const PinholeCamera& camera,
    const FrameSegmentation& previous_refined, const cv::Mat& previous_depth_m,
    const Eigen::Isometry3d& T_cur_prev,
    const std::map<std::uint16_t, Eigen::Isometry3d>& instance_motion_prev) {
  ProjectionWorkspace ws;
  ProjectInto(options, camera, previous_refined, previous_depth_m, T_cur_prev,
              instance_motion_prev, cv::Mat(), &ws);
  std::vector<ProjectedRegion> out(previous_refined.instances.size());
  for (size_t i = 0; i < out.size(); ++i) {
    out[i].mask = RegionMask(ws, i);
    out[i].area_px = ws.regions[i].area_px;
    out[i].bbox = ws.regions[i].bbox;
  }
  return out;
}

const char* ToString(RegionDecision::Kind kind) {
  switch (kind) {
    case RegionDecision::Kind::kNew: return "new";
    case RegionDecision::Kind::kKept: return "kept";
    case RegionDecision::Kind::kReplaced: return "replaced";
    case RegionDecision::Kind::kAdded: return "added";
    case RegionDecision::Kind::kDropped: return "dropped";
  }
  return "unknown";
}

std::string RefinementResult::BriefReport() const {
  int counts[5] = {0, 0, 0, 0, 0};
  for (const RegionDecision& d : decisions) ++counts[static_cast<int>(d.kind)];
  std::ostringstream s;
  s << "kept " << counts[1] << " replaced " << counts[2] << " new " << counts[0]
    << " added " << counts[3] << " dropped " << counts[4];
  return s.str();
}

SegmentationRefiner::~SegmentationRefiner() = default;

SegmentationRefiner::SegmentationRefiner(RefinerOptions options)
    : options_(std::move(options)), workspace_(std::make_unique<ProjectionWorkspace>()) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error("refiner options: " + error);
}

std::uint16_t SegmentationRefiner::FreshId() {
  if (next_track_id_ == std::numeric_limits<std::uint16_t>::max()) {
    throw Error("refiner: track ids exhausted (65534 tracks)");
  }
  return next_track_id_++;
}

namespace {

// Unmatched projections of previous regions: each is added back (the instance the
// segmenter missed, carried by its projection, its score decayed) when the add rule
// allows it, else dropped. The paper's count rule adds only when the previous frame had
// more regions than the current one.
void AddBackUnmatchedProjections(const RefinerOptions& options, const FrameSegmentation& previous,
                                 const std::vector<bool>& previous_matched, bool count_rule_holds,
                                 const std::map<std::uint16_t, int>& detections_of_track,
                                 const ProjectionWorkspace& ws, RefinementResult* result) {
  for (size_t p = 0; p < previous.instances.size(); ++p) {
    if (previous_matched[p]) continue;
    const InstanceMask& prev = previous.instances[p];
    const auto detections = detections_of_track.find(prev.track_id);
    const bool confirmed = detections == detections_of_track.end() ||
                           detections->second >= options.min_detections_to_add;
    RegionDecision d;
    d.previous_index = static_cast<int>(p);
    d.track_id = prev.track_id;
    d.projected_area_px = ws.regions[p].area_px;
    const float score = static_cast<float>(prev.score * options.added_score_decay);
    const bool rule = options.add_unmatched == AddUnmatchedRule::kAlways ||
                      (options.add_unmatched == AddUnmatchedRule::kPaperCountRule && count_rule_holds);
    const int min_area = ws.at_far_limit[p] ? options.min_far_projected_area_px : options.min_projected_area_px;
    const bool add = rule && confirmed && ws.regions[p].area_px >= std::max(1, min_area) &&
                     score >= options.min_added_score;
    d.kind = add ? RegionDecision::Kind::kAdded : RegionDecision::Kind::kDropped;
    if (add) {
      InstanceMask instance;
      instance.track_id = prev.track_id;
      instance.category_id = prev.category_id;
      instance.score = score;
      instance.mask = RegionMask(ws, p);
      instance.bounds = ws.regions[p].bbox;
      result->refined.instances.push_back(std::move(instance));
    }
    result->decisions.push_back(d);
  }
}

}  // namespace

void SegmentationRefiner::ReserveIdsOf(const FrameSegmentation& previous) {
  for (const InstanceMask& p : previous.instances) {
    if (p.track_id >= next_track_id_ && p.track_id < 0xffff) {
      next_track_id_ = static_cast<std::uint16_t>(p.track_id + 1);
    }
  }
}

void SegmentationRefiner::CountDetections(const RefinementResult& result) {
  std::map<std::uint16_t, int> counts;
  for (const RegionDecision& d : result.decisions) {
    if (d.kind == RegionDecision::Kind::kDropped) continue;
    const auto before = detections_of_track_.find(d.track_id);
    // A carried track that this refiner did not make has an unknown past: confirmed.
    const int past = before != detections_of_track_.end() ? before->second : options_.min_detections_to_add;
    if (d.kind == RegionDecision::Kind::kNew) {
      counts[d.track_id] = 1;
    } else if (d.kind == RegionDecision::Kind::kAdded) {
      counts[d.track_id] = past;
    } else {
      counts[d.track_id] = past + 1;
    }
  }
  detections_of_track_ = std::move(counts);
}

RefinementResult SegmentationRefiner::AllNew(const FrameSegmentation& current) {
  RefinementResult result;
  result.refined.frame_index = current.frame_index;
  for (size_t c = 0; c < current.instances.size(); ++c) {
    InstanceMask instance = current.instances[c];
    instance.track_id = FreshId();
    RegionDecision d;
    d.kind = RegionDecision::Kind::kNew;
    d.track_id = instance.track_id;
    d.current_index = static_cast<int>(c);
    result.decisions.push_back(d);
    result.refined.instances.push_back(std::move(instance));
  }
  return result;
}

RefinementResult SegmentationRefiner::Refine(const RefinerInput& in) {
  std::string error;
  if (!in.camera.IsValid(&error)) throw Error("refiner camera: " + error);
  const FrameSegmentation& current = in.current_initial;
  for (const InstanceMask& instance : current.instances) {
    CheckInputImage(instance.mask, CV_8U, in.camera, "current instance mask");
  }
  // Ids handed out elsewhere (a loaded previous segmentation) are never reused.
  if (in.previous_refined) ReserveIdsOf(*in.previous_refined);
  // First frame (or no depth to project with): every region is new.
  if (!in.previous_refined || in.previous_depth_m.empty()) {
    RefinementResult result = AllNew(current);
    CountDetections(result);
    return result;
  }

  const FrameSegmentation& previous = *in.previous_refined;
  const Eigen::Isometry3d T_cur_prev = in.T_wc_current_coarse.inverse() * in.T_wc_previous_fine;
  ProjectInto(options_, in.camera, previous, in.previous_depth_m, T_cur_prev, in.instance_motion_prev,
              in.current_depth_m, workspace_.get());
  const ProjectionWorkspace& ws = *workspace_;

  const size_t n_cur = current.instances.size();
  std::vector<RegionStats> cur_stats(n_cur);
  for (size_t c = 0; c < n_cur; ++c) cur_stats[c] = Measure(current.instances[c]);
  const std::vector<std::optional<RegionMatch>> match_of_cur =
      MatchRegions(options_, in.camera, previous, ws, current, cur_stats);

  // Current regions: keep or replace (Algorithm 1), or new.
  RefinementResult result;
  result.refined.frame_index = current.frame_index;
  std::vector<bool> previous_matched(previous.instances.size(), false);
  for (size_t c = 0; c < n_cur; ++c) {
    InstanceMask instance = current.instances[c];
    RegionDecision d;
    d.current_index = static_cast<int>(c);
    if (const std::optional<RegionMatch>& match = match_of_cur[c]) {
      previous_matched[static_cast<size_t>(match->p)] = true;
      RefineMatchedRegion(options_, in.camera, ws, *match, cur_stats[c],
                          previous.instances[static_cast<size_t>(match->p)], in.current_depth_m, &instance, &d);
    } else {
      d.kind = RegionDecision::Kind::kNew;
      instance.score = static_cast<float>(instance.score * options_.new_region_score_factor);
      if (instance.score < options_.min_new_region_score) {
        // No track id: dropped regions would use them up (65534) on a long sequence of
        // low-scoring detections.
        d.kind = RegionDecision::Kind::kDropped;
        d.track_id = 0;
        result.decisions.push_back(d);
        continue;
      }
      instance.track_id = FreshId();
      instance.bounds = cur_stats[c].bbox;
    }
    d.track_id = instance.track_id;
    result.decisions.push_back(d);
    result.refined.instances.push_back(std::move(instance));
  }

  AddBackUnmatchedProjections(options_, previous, previous_matched, previous.instances.size() > n_cur,
                              detections_of_track_, ws, &result);
  CountDetections(result);
  return result;
}

}  // namespace segslam::seg
