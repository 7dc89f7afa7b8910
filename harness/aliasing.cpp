#include "harness/aliasing.h"

#include "core/error.h"
#include "core/pose.h"
#include "harness/pictures.h"
#include "slam/ransac_pnp.h"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

constexpr double kDegToRad = M_PI / 180.0;
// Ground truth is interpolated between two poses at most this far apart (TUM's motion
// capture runs at 100 Hz; a generated sequence has a pose at every frame's stamp).
constexpr double kMaxGroundTruthGapS = 0.1;
constexpr size_t kWorstPairsKept = 10;

// The pose at `stamp_s`: the ground truth's own at that stamp, or interpolated between
// the two around it when they lie at most kMaxGroundTruthGapS apart.
std::optional<Eigen::Isometry3d> GroundTruthAt(const std::vector<StampedPose>& groundtruth, double stamp_s) {
  const auto after = std::lower_bound(groundtruth.begin(), groundtruth.end(), stamp_s,
                                      [](const StampedPose& pose, double s) { return pose.stamp_s < s; });
  if (after != groundtruth.end() && std::abs(after->stamp_s - stamp_s) < 1e-6) return after->T_wc;
  // Before the first or after the last pose: nothing to interpolate between.
  if (after == groundtruth.begin() || after == groundtruth.end()) return std::nullopt;
  const StampedPose& before = *(after - 1);
  if (after->stamp_s - before.stamp_s > kMaxGroundTruthGapS) return std::nullopt;
  const double t = (stamp_s - before.stamp_s) / (after->stamp_s - before.stamp_s);
  return InterpolatePose(before.T_wc, after->T_wc, t);
}

double RotationAngleDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() / kDegToRad;
}

// Runs fn(k) for k in [0, count) on `threads` threads (the caller's among them), each
// index once; rethrows the first exception after all have stopped. `cancel` is checked
// before each item.
template <typename Fn>
void ParallelFor(int count, int threads, const std::atomic<bool>* cancel, Fn fn) {
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (;;) {
      if (failed.load()) return;
      const int k = next.fetch_add(1);
      if (k >= count) return;
      try {
        if (cancel != nullptr && cancel->load()) throw Error("aliasing measure: cancelled");
        fn(k);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, std::min(threads, count)); ++t) pool.emplace_back(work);
  work();
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

// Nearest and second-nearest of each query among `train` (N x 32 CV_8U rows) by Hamming
// distance; built for POPCNT where the CPU has it (the build targets plain x86-64).
struct NearestTwo {
  int best = -1;
  int best_distance = 257;
  int second_distance = 257;
};
__attribute__((target_clones("popcnt", "default"))) void FindNearestTwo(const cv::Mat& query, const cv::Mat& train,
                                                                          std::vector<NearestTwo>* nearest) {
  nearest->assign(static_cast<size_t>(query.rows), NearestTwo{});
  for (int q = 0; q < query.rows; ++q) {
    std::uint64_t qw[4];
    std::memcpy(qw, query.ptr<std::uint8_t>(q), sizeof(qw));
    NearestTwo& n = (*nearest)[static_cast<size_t>(q)];
    for (int t = 0; t < train.rows; ++t) {
      std::uint64_t tw[4];
      std::memcpy(tw, train.ptr<std::uint8_t>(t), sizeof(tw));
      const int d = __builtin_popcountll(qw[0] ^ tw[0]) + __builtin_popcountll(qw[1] ^ tw[1]) +
                    __builtin_popcountll(qw[2] ^ tw[2]) + __builtin_popcountll(qw[3] ^ tw[3]);
      if (d < n.best_distance) {
        n.second_distance = n.best_distance;
        n.best_distance = d;
        n.best = t;
      } else if (d < n.second_distance) {
        n.second_distance = d;
      }
    }
  }
}

// A sampled frame's features as the pair test uses them: as the "map" side (features
// with depth, their points in this camera's frame) and as the "current" side (pixels).
struct PairFeatures {
  cv::Mat query_descriptors;  // rows of features with depth
  std::vector<cv::Point3f> query_points_cam;
  std::vector<cv::Point2f> query_pixels;
  std::vector<std::uint16_t> query_instances;  // ground-truth instance under each, 0 = background
  cv::Mat train_descriptors;  // rows of all used features
  std::vector<cv::Point2f> train_pixels;
  std::vector<std::uint16_t> train_instances;
};

cv::Mat LoadMaskIfAny(const TumSequence& sequence, size_t index) {
  const fs::path masks = sequence.dir() / "masks";
  if (!fs::is_directory(masks)) return {};
  const fs::path png = masks / (sequence.FrameStem(index) + ".png");
  if (!fs::exists(png)) throw FileError(png, "missing: the sequence has masks/, and every frame needs its mask");
  return sequence.LoadInstanceMask(png);
}

PairFeatures ExtractPairFeatures(const AliasingOptions& options, const slam::OrbExtractor& extractor,
                                 const PinholeCamera& camera, const RgbdFrame& frame, const cv::Mat& ids) {
  cv::Mat gray;
  cv::cvtColor(frame.color_bgr, gray, cv::COLOR_BGR2GRAY);
  const slam::FrameFeatures features = extractor.Extract(gray, frame.depth_m, camera);
  PairFeatures out;
  std::vector<int> query_rows, train_rows;
  for (size_t k = 0; k < features.size(); ++k) {
    const cv::Point2f& pt = features.keypoints[k].pt;
    std::uint16_t instance = 0;
    if (!ids.empty()) {
      const int u = std::clamp(static_cast<int>(std::lround(pt.x)), 0, ids.cols - 1);
      const int v = std::clamp(static_cast<int>(std::lround(pt.y)), 0, ids.rows - 1);
      instance = ids.at<std::uint16_t>(v, u);
    }
    if (options.background_features_only && instance != 0) continue;
    train_rows.push_back(static_cast<int>(k));
    out.train_pixels.push_back(pt);
    out.train_instances.push_back(instance);
    if (features.HasDepth(k)) {
      query_rows.push_back(static_cast<int>(k));
      out.query_instances.push_back(instance);
      const Eigen::Vector3d& p = features.points_cam[k];
      out.query_points_cam.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                        static_cast<float>(p.z()));
      out.query_pixels.push_back(pt);
    }
  }
  auto rows = [&](const std::vector<int>& which) {
    cv::Mat m(static_cast<int>(which.size()), features.descriptors.cols, CV_8U);
    for (size_t r = 0; r < which.size(); ++r) features.descriptors.row(which[r]).copyTo(m.row(static_cast<int>(r)));
    return m;
  };
  out.query_descriptors = rows(query_rows);
  out.train_descriptors = rows(train_rows);
  return out;
}

// The verification of one pair: ratio-test matches of a's features with depth among b's
// features (each of b's used once, by its nearest), then RANSAC PnP of a's points on b's
// pixels.
struct PairVerification {
  std::vector<std::pair<int, int>> matches;  // (a query row, b train row)
  std::vector<int> inliers;                  // indices into matches
  std::optional<Eigen::Isometry3d> T_b_a;    // the PnP pose: a's camera frame into b's
};

PairVerification VerifyPair(const AliasingOptions& options, const PinholeCamera& camera, const PairFeatures& a,
                            const PairFeatures& b) {
  PairVerification result;
  if (a.query_descriptors.empty() || b.train_descriptors.rows < 2) return result;
  std::vector<NearestTwo> nearest;
  FindNearestTwo(a.query_descriptors, b.train_descriptors, &nearest);
  // One query per train feature, the nearest (the lower query row on a tie).
  std::vector<int> owner(static_cast<size_t>(b.train_descriptors.rows), -1);
  for (size_t q = 0; q < nearest.size(); ++q) {
    const NearestTwo& n = nearest[q];
    if (n.best < 0 || n.best_distance > options.max_descriptor_distance ||
        !(n.best_distance < options.ratio * n.second_distance)) {
      continue;
    }
    // The same object at both places is not a look-alike of itself.
    const std::uint16_t instance = a.query_instances[q];
    if (instance != 0 && instance == b.train_instances[static_cast<size_t>(n.best)]) continue;
    int& o = owner[static_cast<size_t>(n.best)];
    if (o < 0 || n.best_distance < nearest[static_cast<size_t>(o)].best_distance) o = static_cast<int>(q);
  }
  for (size_t q = 0; q < nearest.size(); ++q) {
    const int t = nearest[q].best;
    if (t >= 0 && owner[static_cast<size_t>(t)] == static_cast<int>(q)) result.matches.emplace_back(static_cast<int>(q), t);
  }
  if (result.matches.size() < 4) return result;
  std::vector<cv::Point3f> points;
  std::vector<cv::Point2f> pixels;
  for (const auto& [q, t] : result.matches) {
    points.push_back(a.query_points_cam[static_cast<size_t>(q)]);
    pixels.push_back(b.train_pixels[static_cast<size_t>(t)]);
  }
  const std::optional<slam::PnpConsensus> consensus =
      slam::SolveRansacPnp(points, pixels, camera, options.ransac_samples, 4, options.ransac_max_error_px);
  if (consensus) {
    result.inliers = consensus->inliers;
    result.T_b_a = consensus->T_cw;
  }
  return result;
}

int NearestRank(const std::vector<int>& sorted, double percent) {
  if (sorted.empty()) return 0;
  const double rank = std::ceil(percent / 100.0 * static_cast<double>(sorted.size()));
  const size_t index = static_cast<size_t>(std::clamp(rank, 1.0, static_cast<double>(sorted.size()))) - 1;
  return sorted[index];
}

// Sequence indices of the frames to sample, with their poses.
std::vector<std::pair<int, Eigen::Isometry3d>> SampleFrames(const AliasingOptions& options,
                                                            const TumSequence& sequence) {
  std::vector<std::pair<int, Eigen::Isometry3d>> sampled;
  for (size_t i = 0; i < sequence.size(); ++i) {
    const std::optional<Eigen::Isometry3d> T_wc = GroundTruthAt(sequence.groundtruth(), sequence.entries()[i].rgb_stamp_s);
    if (!T_wc) continue;
    if (!sampled.empty()) {
      const Eigen::Isometry3d& last = sampled.back().second;
      const double moved_m = (T_wc->translation() - last.translation()).norm();
      const int frames_since = static_cast<int>(i) - sampled.back().first;
      const bool waited = options.sample_every_frames > 0 && frames_since >= options.sample_every_frames;
      if (!waited && moved_m < options.sample_spacing_m && RotationAngleDeg(last, *T_wc) < options.sample_turn_deg) {
        continue;
      }
    }
    sampled.emplace_back(static_cast<int>(i), *T_wc);
  }
  return sampled;
}

}  // namespace

bool CommonViewOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (pixel_stride < 1) return fail("common_view.pixel_stride must be >= 1");
  if (!(depth_tolerance_m >= 0)) return fail("common_view.depth_tolerance_m must be >= 0");
  if (!(depth_tolerance_share >= 0 && depth_tolerance_share < 1)) {
    return fail("common_view.depth_tolerance_share must lie in [0, 1)");
  }
  if (!(min_common_share > 0 && min_common_share < 1)) return fail("common_view.min_common_share must lie in (0, 1)");
  if (!(far_apart_m >= 0)) return fail("common_view.far_apart_m must be >= 0");
  return true;
}

GroundTruthView MakeGroundTruthView(const CommonViewOptions& options, const PinholeCamera& camera,
                                    const Eigen::Isometry3d& T_wc, const cv::Mat& depth_m,
                                    const cv::Mat& instance_ids) {
  if (depth_m.type() != CV_32F || depth_m.cols != camera.width || depth_m.rows != camera.height) {
    throw Error(fmt::format("common view: depth must be CV_32F {}x{}", camera.width, camera.height));
  }
  if (!instance_ids.empty() && (instance_ids.type() != CV_16U || instance_ids.size() != depth_m.size())) {
    throw Error(fmt::format("common view: instance ids must be CV_16U {}x{}", camera.width, camera.height));
  }
  GroundTruthView view;
  view.T_wc = T_wc;
  view.depth_m = depth_m;
  const int stride = options.pixel_stride;
  for (int v = stride / 2; v < depth_m.rows; v += stride) {
    for (int u = stride / 2; u < depth_m.cols; u += stride) {
      const float d = depth_m.at<float>(v, u);
      if (!(d > 0) || !std::isfinite(d)) continue;
      if (!instance_ids.empty() && instance_ids.at<std::uint16_t>(v, u) != 0) continue;
      view.points_w.push_back(T_wc * camera.BackProject(Eigen::Vector2d(u, v), d));
    }
  }
  return view;
}

double SeenShare(const CommonViewOptions& options, const PinholeCamera& camera, double depth_range_m,
                 const GroundTruthView& from, const GroundTruthView& to) {
  if (from.points_w.empty()) return 0.0;
  const Eigen::Isometry3d T_cw = to.T_wc.inverse();
  int seen = 0;
  for (const Eigen::Vector3d& p_w : from.points_w) {
    const Eigen::Vector3d p = T_cw * p_w;
    if (p.z() <= 0) continue;
    const Eigen::Vector2d pixel = camera.Project(p);
    if (!camera.InImage(pixel)) continue;
    const int u = static_cast<int>(std::lround(pixel.x()));
    const int v = static_cast<int>(std::lround(pixel.y()));
    const float d = to.depth_m.at<float>(v, u);
    if (d > 0) {
      const double tolerance = std::max(options.depth_tolerance_m, options.depth_tolerance_share * p.z());
      if (std::abs(d - p.z()) <= tolerance) ++seen;
    } else if (p.z() > depth_range_m) {
      ++seen;  // beyond what the sensor reads: cannot be ruled out
    }
  }
  return static_cast<double>(seen) / static_cast<double>(from.points_w.size());
}

ViewOverlap MeasureOverlap(const CommonViewOptions& options, const PinholeCamera& camera, double depth_range_m,
                           const GroundTruthView& a, const GroundTruthView& b) {
  return {SeenShare(options, camera, depth_range_m, a, b), SeenShare(options, camera, depth_range_m, b, a)};
}

bool AliasingOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (!(sample_spacing_m > 0)) return fail("sample_spacing_m must be > 0");
  if (!(sample_turn_deg > 0)) return fail("sample_turn_deg must be > 0");
  if (sample_every_frames < 0) return fail("sample_every_frames must be >= 0");
  if (!common_view.IsValid(error)) return false;
  if (!(ratio > 0 && ratio <= 1)) return fail("ratio must lie in (0, 1]");
  if (max_descriptor_distance < 0 || max_descriptor_distance > 256) {
    return fail("max_descriptor_distance must lie in [0, 256]");
  }
  if (ransac_samples < 1) return fail("ransac_samples must be >= 1");
  if (!(ransac_max_error_px > 0)) return fail("ransac_max_error_px must be > 0");
  if (!(true_place_tolerance_m > 0)) return fail("true_place_tolerance_m must be > 0");
  if (threads < 0) return fail("threads must be >= 0");
  return true;
}

nlohmann::json AliasingOptions::ToJson() const {
  return {{"sample_spacing_m", sample_spacing_m},
          {"sample_turn_deg", sample_turn_deg},
          {"sample_every_frames", sample_every_frames},
          {"pixel_stride", common_view.pixel_stride},
          {"depth_tolerance_m", common_view.depth_tolerance_m},
          {"depth_tolerance_share", common_view.depth_tolerance_share},
          {"min_common_share", common_view.min_common_share},
          {"far_apart_m", common_view.far_apart_m},
          {"orb_features", orb.max_features},
          {"ratio", ratio},
          {"max_descriptor_distance", max_descriptor_distance},
          {"ransac_samples", ransac_samples},
          {"ransac_max_error_px", ransac_max_error_px},
          {"true_place_tolerance_m", true_place_tolerance_m},
          {"background_features_only", background_features_only},
          {"loop_acceptance_matches", kLoopAcceptanceMatches}};
}

nlohmann::json AliasingSummary::ToJson() const {
  nlohmann::json worst = nlohmann::json::array();
  for (const AliasingPair& p : worst_pairs) {
    worst.push_back({{"frame_a", p.frame_a},
                     {"frame_b", p.frame_b},
                     {"stamp_a_s", p.stamp_a_s},
                     {"stamp_b_s", p.stamp_b_s},
                     {"distance_m", p.distance_m},
                     {"common_share", p.common_share},
                     {"ratio_matches", p.ratio_matches},
                     {"verified_matches", p.verified_matches},
                     {"no_common_view", p.no_common_view},
                     {"true_place", p.true_place},
                     {"pose_error_m", p.pose_error_m}});
  }
  return {{"sequence", sequence},
          {"frames", frames},
          {"sampled_frames", sampled_frames},
          {"pairs_tested", pairs_tested},
          {"pairs_no_common_view", pairs_no_common_view},
          {"pairs_measured", pairs_measured},
          {"max_verified_matches", max_verified_matches},
          {"p50", p50},
          {"p90", p90},
          {"p99", p99},
          {"pairs_at_or_above_acceptance", pairs_at_or_above_acceptance},
          {"worst_pairs", worst}};
}

AliasingSummary MeasureAliasing(const AliasingOptions& options, const TumSequence& sequence,
                                const AliasingProgress& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (std::string problem; !options.IsValid(&problem)) throw Error("aliasing measure: " + problem);
  if (!sequence.has_groundtruth()) {
    throw FileError(sequence.dir() / "groundtruth.txt", "missing: the aliasing measure decides from ground truth "
                                                         "which views share nothing");
  }
  const PinholeCamera& camera = sequence.camera().intrinsics;
  const int threads =
      options.threads > 0 ? options.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::mutex progress_mutex;
  auto report = [&](const std::string& stage, int done, int total) {
    if (!progress) return;
    std::lock_guard<std::mutex> lock(progress_mutex);
    progress(stage, done, total);
  };

  // Each sampled frame once: its features and its ground-truth view.
  const std::vector<std::pair<int, Eigen::Isometry3d>> sampled = SampleFrames(options, sequence);
  const int n = static_cast<int>(sampled.size());
  const slam::OrbExtractor extractor(options.orb);
  std::vector<PairFeatures> features(static_cast<size_t>(n));
  std::vector<GroundTruthView> views(static_cast<size_t>(n));
  std::vector<float> max_depth(static_cast<size_t>(n), 0.0f);
  std::atomic<int> frames_done{0};
  report("frames", 0, n);
  ParallelFor(n, threads, options.cancel, [&](int k) {
    const auto& [index, T_wc] = sampled[static_cast<size_t>(k)];
    const RgbdFrame frame = sequence.LoadFrame(static_cast<size_t>(index));
    const cv::Mat ids = LoadMaskIfAny(sequence, static_cast<size_t>(index));
    features[static_cast<size_t>(k)] = ExtractPairFeatures(options, extractor, camera, frame, ids);
    views[static_cast<size_t>(k)] = MakeGroundTruthView(options.common_view, camera, T_wc, frame.depth_m, ids);
    double max_value = 0;
    cv::minMaxLoc(frame.depth_m, nullptr, &max_value);
    max_depth[static_cast<size_t>(k)] = static_cast<float>(max_value);
    report("frames", ++frames_done, n);
  });
  // The farthest depth the sensor reported anywhere along the route: beyond it a pixel
  // without depth may hide anything (SeenShare).
  const double depth_range_m = n > 0 ? *std::max_element(max_depth.begin(), max_depth.end()) : 0.0;

  // Every pair once; the pair list is fixed before the threads take from it, and each
  // result goes to its own slot, so the outcome does not depend on the threads.
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(static_cast<size_t>(n) * static_cast<size_t>(std::max(0, n - 1)) / 2);
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) pairs.emplace_back(a, b);
  }
  std::vector<std::optional<AliasingPair>> results(pairs.size());
  std::atomic<int> pairs_done{0};
  const int pair_count = static_cast<int>(pairs.size());
  const int report_every = std::max(1, pair_count / 200);
  report("pairs", 0, pair_count);
  ParallelFor(pair_count, threads, options.cancel, [&](int k) {
    const auto [a, b] = pairs[static_cast<size_t>(k)];
    const GroundTruthView& view_a = views[static_cast<size_t>(a)];
    const GroundTruthView& view_b = views[static_cast<size_t>(b)];
    const ViewOverlap overlap = MeasureOverlap(options.common_view, camera, depth_range_m, view_a, view_b);
    const double distance_m = (view_a.T_wc.translation() - view_b.T_wc.translation()).norm();
    const bool no_common_view = overlap.Share() < options.common_view.min_common_share;
    const bool far_apart = options.common_view.far_apart_m > 0 && distance_m >= options.common_view.far_apart_m;
    if (no_common_view || far_apart) {
      const PairVerification verification =
          VerifyPair(options, camera, features[static_cast<size_t>(a)], features[static_cast<size_t>(b)]);
      AliasingPair pair;
      pair.frame_a = sampled[static_cast<size_t>(a)].first;
      pair.frame_b = sampled[static_cast<size_t>(b)].first;
      pair.stamp_a_s = sequence.entries()[static_cast<size_t>(pair.frame_a)].rgb_stamp_s;
      pair.stamp_b_s = sequence.entries()[static_cast<size_t>(pair.frame_b)].rgb_stamp_s;
      pair.distance_m = distance_m;
      pair.no_common_view = no_common_view;
      pair.common_share = overlap.Share();
      pair.ratio_matches = static_cast<int>(verification.matches.size());
      pair.verified_matches = static_cast<int>(verification.inliers.size());
      if (verification.T_b_a) {
        // Camera b's centre in a's frame: where PnP puts it, and where it is.
        const Eigen::Vector3d estimated = verification.T_b_a->inverse().translation();
        const Eigen::Vector3d truth = (view_a.T_wc.inverse() * view_b.T_wc).translation();
        pair.pose_error_m = (estimated - truth).norm();
        pair.true_place = pair.pose_error_m < options.true_place_tolerance_m;
        if (pair.true_place) pair.verified_matches = 0;
      }
      results[static_cast<size_t>(k)] = pair;
    }
    const int done = ++pairs_done;
    if (done % report_every == 0 || done == pair_count) report("pairs", done, pair_count);
  });

  AliasingSummary summary;
  summary.sequence = sequence.dir().string();
  summary.frames = static_cast<int>(sequence.size());
  summary.sampled_frames = n;
  summary.pairs_tested = static_cast<std::int64_t>(pairs.size());
  std::vector<int> verified;
  std::vector<AliasingPair> measured;
  for (const std::optional<AliasingPair>& result : results) {
    if (!result) continue;
    if (result->no_common_view) ++summary.pairs_no_common_view;
    verified.push_back(result->verified_matches);
    measured.push_back(*result);
    if (result->verified_matches >= kLoopAcceptanceMatches) ++summary.pairs_at_or_above_acceptance;
  }
  summary.pairs_measured = static_cast<std::int64_t>(measured.size());
  std::sort(verified.begin(), verified.end());
  if (!verified.empty()) summary.max_verified_matches = verified.back();
  summary.p50 = NearestRank(verified, 50);
  summary.p90 = NearestRank(verified, 90);
  summary.p99 = NearestRank(verified, 99);
  // `measured` is in pair order (a, then b), so a stable sort keeps ties in that order.
  std::stable_sort(measured.begin(), measured.end(), [](const AliasingPair& x, const AliasingPair& y) {
    return x.verified_matches > y.verified_matches;
  });
  if (measured.size() > kWorstPairsKept) measured.resize(kWorstPairsKept);
  summary.worst_pairs = std::move(measured);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

cv::Mat AliasingPairPicture(const AliasingOptions& options, const TumSequence& sequence, const AliasingPair& pair) {
  const PinholeCamera& camera = sequence.camera().intrinsics;
  const slam::OrbExtractor extractor(options.orb);
  const RgbdFrame frame_a = sequence.LoadFrame(static_cast<size_t>(pair.frame_a));
  const RgbdFrame frame_b = sequence.LoadFrame(static_cast<size_t>(pair.frame_b));
  const PairFeatures a = ExtractPairFeatures(options, extractor, camera, frame_a,
                                             LoadMaskIfAny(sequence, static_cast<size_t>(pair.frame_a)));
  const PairFeatures b = ExtractPairFeatures(options, extractor, camera, frame_b,
                                             LoadMaskIfAny(sequence, static_cast<size_t>(pair.frame_b)));
  const PairVerification verification = VerifyPair(options, camera, a, b);

  const std::string caption_a = fmt::format("frame {} ({:.3f} s)", pair.frame_a, pair.stamp_a_s);
  const std::string caption_b =
      fmt::format("frame {} ({:.3f} s): {} verified of {} ratio matches, {:.1f} m away", pair.frame_b, pair.stamp_b_s,
                  verification.inliers.size(), verification.matches.size(), pair.distance_m);
  cv::Mat row = CaptionedRow({frame_a.color_bgr, frame_b.color_bgr}, {caption_a, caption_b});
  const float offset = static_cast<float>(frame_a.color_bgr.cols);
  const int thickness = std::max(1, camera.width / 640);
  for (size_t k = 0; k < verification.inliers.size(); ++k) {
    const auto& [q, t] = verification.matches[static_cast<size_t>(verification.inliers[k])];
    const cv::Point2f pa = a.query_pixels[static_cast<size_t>(q)];
    const cv::Point2f pb = b.train_pixels[static_cast<size_t>(t)] + cv::Point2f(offset, 0);
    // A colour per match, from its rank, so neighbouring lines can be told apart.
    const double hue = std::fmod(static_cast<double>(k) * 47.0, 180.0);
    cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(hue, 255, 255)), bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
    const cv::Scalar colour(c[0], c[1], c[2]);
    cv::line(row, pa, pb, colour, thickness, cv::LINE_AA);
    cv::circle(row, pa, 3 * thickness, colour, thickness, cv::LINE_AA);
    cv::circle(row, pb, 3 * thickness, colour, thickness, cv::LINE_AA);
  }
  return row;
}

}  // namespace segslam::harness
