// Trajectory accuracy as the TUM RGB-D benchmark's scripts compute it (Sturm et al.,
// IROS 2012; rgbd_benchmark_tools: associate.py, evaluate_ate.py, evaluate_rpe.py), so
// that numbers from segslam can be put next to published ones. Replicated from the
// scripts' logic, including their quirks, and checked against the numbers they print for
// TUM's fr1/xyz RGBDSLAM example (tests/harness/trajectory_metrics_test.cpp).
//
// Where segslam deliberately differs from the scripts:
// - evaluate_ate.py needs 2 associated pairs; ComputeAte needs 3 when aligning, because
//   Horn's rotation is undetermined for 2 points (any rotation about their line fits).
// - evaluate_rpe.py, with more than --max_pairs (10000) pairs, evaluates a random sample;
//   ComputeRpe always evaluates every pair.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/pose.h"

namespace segslam::harness {

// Summary of a list of errors with numpy's conventions: median of an even count is the
// mean of the two middle values, std is the population standard deviation (ddof 0).
struct ErrorStatistics {
  std::size_t count = 0;
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
};

// Throws segslam::Error for an empty list.
ErrorStatistics ComputeErrorStatistics(const std::vector<double>& errors);

// Every statistic multiplied by `factor` (e.g. radians to degrees); count unchanged.
ErrorStatistics Scaled(ErrorStatistics statistics, double factor);

// Indices into two stamp lists joined as associate.py does: every pair with
// |first - (second + offset)| < max_difference is a candidate; candidates are taken in
// order of increasing difference (ties by first, then second stamp), each stamp at most
// once; the result is sorted by first stamp.
struct StampAssociation {
  std::size_t first_index = 0;
  std::size_t second_index = 0;
};
std::vector<StampAssociation> AssociateStamps(const std::vector<double>& first_stamps_s,
                                              const std::vector<double>& second_stamps_s,
                                              double max_difference_s, double offset_s = 0);

// The rigid transform T (rotation and translation, no scale) minimising
// sum |T * model_i - data_i|^2: Horn's closed form as evaluate_ate.py's align() computes
// it, the rotation from the SVD of the cross-covariance of the centred point sets with
// the sign of the last singular direction flipped when needed to exclude reflections.
// Throws segslam::Error if the lists differ in length or hold fewer than 3 points.
Eigen::Isometry3d AlignPointSets(const std::vector<Eigen::Vector3d>& model,
                                 const std::vector<Eigen::Vector3d>& data);

struct AteOptions {
  double max_difference_s = 0.02;  // association radius (evaluate_ate.py's default)
  // False: compare in the given frames (identity alignment), for example an estimate
  // relocalized in a map whose frame is the ground truth's.
  bool align = true;
};

struct AtePair {
  double stamp_gt_s = 0;
  double stamp_est_s = 0;
  Eigen::Vector3d position_gt = Eigen::Vector3d::Zero();
  Eigen::Vector3d position_est_aligned = Eigen::Vector3d::Zero();
  double error_m = 0;
};

struct AteResult {
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();  // applied to the estimate
  std::vector<AtePair> pairs;                // associated pairs, by ground-truth stamp
  std::vector<StampedPose> aligned_estimate;  // every estimate pose moved by T_gt_est
  ErrorStatistics translation_m;
};

// Positions further than this from the origin are refused (10,000 km): no trajectory on
// Earth comes near, and squared distances of far larger ones overflow to inf and NaN.
constexpr double kMaxPositionM = 1e7;

// Absolute trajectory error as evaluate_ate.py: associate positions by stamp, align the
// estimate to the ground truth (unless options.align is false), and summarise the
// distances. Both trajectories must have strictly increasing stamps and positions within
// kMaxPositionM of the origin. Throws segslam::Error when no stamps associate, or too few
// for the alignment (3; 1 without).
AteResult ComputeAte(const std::vector<StampedPose>& ground_truth,
                     const std::vector<StampedPose>& estimate, const AteOptions& options = {});

// The position error of `estimate` at each ground-truth pose, in the given frames (no
// alignment: align the estimate first where it needs it), associated as ComputeAte
// associates; NaN at ground-truth poses no estimate pose associates with. All NaN when
// none does. For plots of where along a run its error builds up.
std::vector<double> PositionErrorPerFrame(const std::vector<StampedPose>& ground_truth,
                                          const std::vector<StampedPose>& estimate,
                                          double max_difference_s = AteOptions{}.max_difference_s);

enum class RpeDeltaUnit { kSeconds, kFrames };

struct RpeOptions {
  double delta = 1;                            // evaluate_rpe.py --delta
  RpeDeltaUnit unit = RpeDeltaUnit::kSeconds;  // --delta_unit s or f
};

struct RpePair {
  double stamp_est_0_s = 0, stamp_est_1_s = 0;  // the estimate's pose pair
  double stamp_gt_0_s = 0, stamp_gt_1_s = 0;    // the ground-truth poses used for them
  double translation_error_m = 0;
  double rotation_error_rad = 0;
};

struct RpeResult {
  std::vector<RpePair> pairs;
  ErrorStatistics translation_m;
  ErrorStatistics rotation_rad;
};

// Relative pose error as `evaluate_rpe.py --fixed_delta`: for each estimate pose i, the
// pose j closest to (stamp_i + delta) seconds or to (i + delta) frames, skipped when j
// is the last pose; both matched to the closest ground-truth stamps, skipped when either
// is further than twice the median ground-truth interval; error
// E = (est_i^-1 est_j) (gt_i^-1 gt_j)^-1, summarised as |translation(E)| and the angle of
// rotation(E). Both trajectories must have strictly increasing stamps and positions within
// kMaxPositionM of the origin. Throws
// segslam::Error when the stamps barely overlap or fewer than 2 pairs remain.
RpeResult ComputeRpe(const std::vector<StampedPose>& ground_truth,
                     const std::vector<StampedPose>& estimate, const RpeOptions& options = {});

struct TrajectoryEvaluation {
  AteResult ate;
  // Absent where the trajectories give too few pose pairs delta apart (a sequence shorter
  // than the delta, say), with the reason.
  std::optional<RpeResult> rpe;
  std::string rpe_missing_reason;
};

// Reads both TUM trajectory files and computes ATE and, where it can, RPE. Errors about
// the pair (no overlap, too few pairs for the ATE) name both files.
TrajectoryEvaluation EvaluateTrajectoryFiles(const std::filesystem::path& ground_truth_file,
                                             const std::filesystem::path& estimate_file,
                                             const AteOptions& ate_options,
                                             const RpeOptions& rpe_options);

}  // namespace segslam::harness
