#include "harness/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <tuple>

#include <Eigen/SVD>
#include <fmt/format.h>

#include "core/error.h"
#include "core/statistics.h"

namespace segslam::harness {
namespace {

std::vector<double> StampsOf(const std::vector<StampedPose>& trajectory, const char* name) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const double stamp = trajectory[i].stamp_s;
    if (!std::isfinite(stamp) || !trajectory[i].T_wc.matrix().allFinite()) {
      throw Error(fmt::format("{} pose {} is not finite", name, i));
    }
    if (const double distance_m = trajectory[i].T_wc.translation().stableNorm(); !(distance_m <= kMaxPositionM)) {
      throw Error(fmt::format("{} pose {} (stamp {:.6f}) lies {:.3g} m from the origin; positions beyond {:g} m "
                              "(10,000 km) are refused: no trajectory on Earth reaches them, and their errors "
                              "overflow",
                              name, i, stamp, distance_m, kMaxPositionM));
    }
    if (i > 0 && !(stamp > stamps.back())) {
      throw Error(fmt::format("{} stamps do not strictly increase at pose {} ({:.6f} after "
                              "{:.6f})",
                              name, i, stamp, stamps.back()));
    }
    stamps.push_back(stamp);
  }
  return stamps;
}

std::string StampRange(const std::vector<double>& stamps) {
  if (stamps.empty()) return "no poses";
  return fmt::format("{} poses, {:.6f} to {:.6f} s", stamps.size(), stamps.front(),
                     stamps.back());
}

// evaluate_rpe.py's find_closest_index, step for step: a bisection that remembers the
// closest element it visits. Ties resolve to the element visited first, as there, which
// is why this is not std::lower_bound plus a comparison of the two neighbours.
std::size_t FindClosestIndex(const std::vector<double>& sorted, double t) {
  std::size_t begin = 0, end = sorted.size(), best = 0;
  double best_difference = std::abs(sorted[0] - t);
  while (begin < end) {
    const std::size_t middle = (begin + end) / 2;
    if (std::abs(sorted[middle] - t) < best_difference) {
      best_difference = std::abs(sorted[middle] - t);
      best = middle;
    }
    if (t == sorted[middle]) return middle;
    if (sorted[middle] > t) {
      end = middle;
    } else {
      begin = middle + 1;
    }
  }
  return best;
}

double RotationAngle(const Eigen::Matrix3d& R) {
  return std::acos(std::min(1.0, std::max(-1.0, (R.trace() - 1) / 2)));
}

}  // namespace

ErrorStatistics Scaled(ErrorStatistics s, double factor) {
  s.rmse *= factor;
  s.mean *= factor;
  s.median *= factor;
  s.std *= factor;
  s.min *= factor;
  s.max *= factor;
  return s;
}

ErrorStatistics ComputeErrorStatistics(const std::vector<double>& errors) {
  if (errors.empty()) throw Error("no errors to summarise");
  ErrorStatistics s;
  s.count = errors.size();
  const double n = static_cast<double>(errors.size());
  double sum = 0, sum_of_squares = 0;
  for (double e : errors) {
    sum += e;
    sum_of_squares += e * e;
  }
  s.rmse = std::sqrt(sum_of_squares / n);
  s.mean = sum / n;
  // Two passes, as numpy does: the one-pass formula loses digits when std << mean.
  double squared_deviations = 0;
  for (double e : errors) squared_deviations += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(squared_deviations / n);
  s.median = Median(errors);
  const auto [min, max] = std::minmax_element(errors.begin(), errors.end());
  s.min = *min;
  s.max = *max;
  return s;
}

std::vector<StampAssociation> AssociateStamps(const std::vector<double>& first_stamps_s,
                                              const std::vector<double>& second_stamps_s,
                                              double max_difference_s, double offset_s) {
  if (!(max_difference_s > 0)) {
    throw Error(fmt::format("the association's maximum time difference must be positive, got {}",
                            max_difference_s));
  }
  // (difference, first, second): the order in which associate.py takes its candidates.
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t a = 0; a < first_stamps_s.size(); ++a) {
    const double first = first_stamps_s[a];
    auto within = [&](std::size_t b) {
      return std::abs(first - (second_stamps_s[b] + offset_s)) < max_difference_s;
    };
    // The candidates of one first stamp are contiguous among the sorted second stamps;
    // the window is found by bisection, then widened with the exact test so that rounding
    // in the bisection's bound cannot drop a candidate the script would keep.
    std::size_t b = static_cast<std::size_t>(
        std::lower_bound(second_stamps_s.begin(), second_stamps_s.end(),
                         first - offset_s - max_difference_s) -
        second_stamps_s.begin());
    while (b > 0 && within(b - 1)) --b;
    for (; b < second_stamps_s.size() &&
           second_stamps_s[b] + offset_s - first < max_difference_s * 2;
         ++b) {
      if (within(b)) {
        candidates.emplace_back(std::abs(first - (second_stamps_s[b] + offset_s)), a, b);
      }
    }
  }
  std::sort(candidates.begin(), candidates.end());

  std::vector<bool> first_used(first_stamps_s.size()), second_used(second_stamps_s.size());
  std::vector<StampAssociation> matches;
  for (const auto& [difference, a, b] : candidates) {
    if (first_used[a] || second_used[b]) continue;
    first_used[a] = second_used[b] = true;
    matches.push_back({a, b});
  }
  std::sort(matches.begin(), matches.end(),
            [](const StampAssociation& x, const StampAssociation& y) {
              return x.first_index < y.first_index;
            });
  return matches;
}

Eigen::Isometry3d AlignPointSets(const std::vector<Eigen::Vector3d>& model,
                                 const std::vector<Eigen::Vector3d>& data) {
  if (model.size() != data.size()) {
    throw Error(fmt::format("cannot align {} points to {} points", model.size(), data.size()));
  }
  if (model.size() < 3) {
    throw Error(fmt::format("cannot align {} point pairs: the rotation needs at least 3",
                            model.size()));
  }
  const double n = static_cast<double>(model.size());
  Eigen::Vector3d model_mean = Eigen::Vector3d::Zero(), data_mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < model.size(); ++i) {
    model_mean += model[i];
    data_mean += data[i];
  }
  model_mean /= n;
  data_mean /= n;
  Eigen::Matrix3d cross_covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < model.size(); ++i) {
    cross_covariance += (model[i] - model_mean) * (data[i] - data_mean).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross_covariance.transpose(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d Vt = svd.matrixV().transpose();
  Eigen::Matrix3d reflection_fix = Eigen::Matrix3d::Identity();
  if (U.determinant() * Vt.determinant() < 0) reflection_fix(2, 2) = -1;

  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = U * reflection_fix * Vt;
  T.translation() = data_mean - T.linear() * model_mean;
  return T;
}

AteResult ComputeAte(const std::vector<StampedPose>& ground_truth,
                     const std::vector<StampedPose>& estimate, const AteOptions& options) {
  const std::vector<double> gt_stamps = StampsOf(ground_truth, "ground-truth");
  const std::vector<double> est_stamps = StampsOf(estimate, "estimate");
  const std::vector<StampAssociation> matches =
      AssociateStamps(gt_stamps, est_stamps, options.max_difference_s);
  if (matches.empty()) {
    throw Error(fmt::format("no estimate stamp lies within {} s of a ground-truth stamp "
                            "(ground truth: {}; estimate: {})",
                            options.max_difference_s, StampRange(gt_stamps),
                            StampRange(est_stamps)));
  }
  const std::size_t needed = options.align ? 3 : 1;
  if (matches.size() < needed) {
    throw Error(fmt::format("only {} pose pair(s) associate within {} s; aligning the "
                            "trajectories needs at least {}",
                            matches.size(), options.max_difference_s, needed));
  }

  std::vector<Eigen::Vector3d> est_positions, gt_positions;
  for (const StampAssociation& m : matches) {
    gt_positions.push_back(ground_truth[m.first_index].T_wc.translation());
    est_positions.push_back(estimate[m.second_index].T_wc.translation());
  }

  AteResult result;
  if (options.align) result.T_gt_est = AlignPointSets(est_positions, gt_positions);
  std::vector<double> errors;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    AtePair pair;
    pair.stamp_gt_s = gt_stamps[matches[k].first_index];
    pair.stamp_est_s = est_stamps[matches[k].second_index];
    pair.position_gt = gt_positions[k];
    pair.position_est_aligned = result.T_gt_est * est_positions[k];
    pair.error_m = (pair.position_est_aligned - pair.position_gt).norm();
    errors.push_back(pair.error_m);
    result.pairs.push_back(pair);
  }
  for (const StampedPose& pose : estimate) {
    result.aligned_estimate.push_back({pose.stamp_s, result.T_gt_est * pose.T_wc});
  }
  result.translation_m = ComputeErrorStatistics(errors);
  return result;
}

std::vector<double> PositionErrorPerFrame(const std::vector<StampedPose>& ground_truth,
                                          const std::vector<StampedPose>& estimate, double max_difference_s) {
  std::vector<double> errors(ground_truth.size(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<StampAssociation> matches = AssociateStamps(
      StampsOf(ground_truth, "ground-truth"), StampsOf(estimate, "estimate"), max_difference_s);
  for (const StampAssociation& match : matches) {
    const Eigen::Vector3d difference =
        estimate[match.second_index].T_wc.translation() - ground_truth[match.first_index].T_wc.translation();
    errors[match.first_index] = difference.norm();
  }
  return errors;
}

namespace {

// Throws unless each trajectory has 2 poses and they overlap in time by the script's
// test: map each estimate stamp to its closest ground-truth stamp and back; if all land
// on one estimate stamp, they do not overlap.
void CheckRpeOverlap(const std::vector<double>& gt_stamps, const std::vector<double>& est_stamps) {
  if (gt_stamps.size() < 2 || est_stamps.size() < 2) {
    throw Error(fmt::format("RPE needs at least 2 poses in each trajectory (ground truth: {}; "
                            "estimate: {})",
                            StampRange(gt_stamps), StampRange(est_stamps)));
  }
  std::set<std::size_t> estimate_stamps_reached;
  for (double stamp : est_stamps) {
    const double closest_gt = gt_stamps[FindClosestIndex(gt_stamps, stamp)];
    estimate_stamps_reached.insert(FindClosestIndex(est_stamps, closest_gt));
  }
  if (estimate_stamps_reached.size() < 2) {
    throw Error(fmt::format("the estimate and the ground truth barely overlap in time "
                            "(ground truth: {}; estimate: {})",
                            StampRange(gt_stamps), StampRange(est_stamps)));
  }
}

// Index pairs (i, j) of estimate poses delta apart (seconds or frames): j is the pose
// closest to delta after i. A partner that is the last pose is dropped, as the script
// does: it is also where the search ends up when nothing lies delta ahead.
std::vector<std::pair<std::size_t, std::size_t>> EstimatePairsDeltaApart(const std::vector<double>& est_stamps,
                                                                         const RpeOptions& options) {
  std::vector<double> index_est;
  if (options.unit == RpeDeltaUnit::kSeconds) {
    index_est = est_stamps;
  } else {
    index_est.resize(est_stamps.size());
    std::iota(index_est.begin(), index_est.end(), 0.0);
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < index_est.size(); ++i) {
    const std::size_t j = FindClosestIndex(index_est, index_est[i] + options.delta);
    if (j != index_est.size() - 1) pairs.emplace_back(i, j);
  }
  return pairs;
}

}  // namespace

RpeResult ComputeRpe(const std::vector<StampedPose>& ground_truth,
                     const std::vector<StampedPose>& estimate, const RpeOptions& options) {
  if (!(options.delta > 0) || !std::isfinite(options.delta)) {
    throw Error(fmt::format("the RPE delta must be positive, got {}", options.delta));
  }
  const std::vector<double> gt_stamps = StampsOf(ground_truth, "ground-truth");
  const std::vector<double> est_stamps = StampsOf(estimate, "estimate");
  CheckRpeOverlap(gt_stamps, est_stamps);
  const double span = options.unit == RpeDeltaUnit::kSeconds ? est_stamps.back() - est_stamps.front()
                                                             : static_cast<double>(est_stamps.size() - 1);
  if (span < options.delta) {
    throw Error(options.unit == RpeDeltaUnit::kSeconds
                    ? fmt::format("RPE needs poses at least the delta of {:g} s apart; the estimate spans {:.3f} s",
                                  options.delta, span)
                    : fmt::format("RPE needs poses at least the delta of {:g} frames apart; the estimate has {} poses",
                                  options.delta, est_stamps.size()));
  }
  const std::vector<std::pair<std::size_t, std::size_t>> pairs = EstimatePairsDeltaApart(est_stamps, options);

  // Both ends of a pair need a ground-truth pose within twice the median interval.
  std::vector<double> gt_intervals;
  for (std::size_t k = 1; k < gt_stamps.size(); ++k) {
    gt_intervals.push_back(gt_stamps[k] - gt_stamps[k - 1]);
  }
  const double max_gt_time_difference = 2 * Median(gt_intervals);

  RpeResult result;
  std::vector<double> translation_errors, rotation_errors;
  for (const auto& [i, j] : pairs) {
    const std::size_t gt_i = FindClosestIndex(gt_stamps, est_stamps[i]);
    const std::size_t gt_j = FindClosestIndex(gt_stamps, est_stamps[j]);
    if (std::abs(gt_stamps[gt_i] - est_stamps[i]) > max_gt_time_difference ||
        std::abs(gt_stamps[gt_j] - est_stamps[j]) > max_gt_time_difference) {
      continue;
    }
    const Eigen::Isometry3d est_motion = estimate[i].T_wc.inverse() * estimate[j].T_wc;
    const Eigen::Isometry3d gt_motion = ground_truth[gt_i].T_wc.inverse() * ground_truth[gt_j].T_wc;
    // The script's order, ominus(ominus(est_j, est_i), ominus(gt_j, gt_i)); its rotation
    // angle equals that of gt_motion^-1 * est_motion (Sturm et al.'s definition), but its
    // translation is expressed in a different frame and its norm differs.
    const Eigen::Isometry3d error = est_motion * gt_motion.inverse();
    RpePair pair;
    pair.stamp_est_0_s = est_stamps[i];
    pair.stamp_est_1_s = est_stamps[j];
    pair.stamp_gt_0_s = gt_stamps[gt_i];
    pair.stamp_gt_1_s = gt_stamps[gt_j];
    pair.translation_error_m = error.translation().norm();
    pair.rotation_error_rad = RotationAngle(error.linear());
    translation_errors.push_back(pair.translation_error_m);
    rotation_errors.push_back(pair.rotation_error_rad);
    result.pairs.push_back(pair);
  }
  if (result.pairs.size() < 2) {
    throw Error(fmt::format("only {} pose pair(s) {} {} apart have ground truth within {:.4f} s; "
                            "RPE needs at least 2",
                            result.pairs.size(), options.delta,
                            options.unit == RpeDeltaUnit::kSeconds ? "s" : "frames",
                            max_gt_time_difference));
  }
  result.translation_m = ComputeErrorStatistics(translation_errors);
  result.rotation_rad = ComputeErrorStatistics(rotation_errors);
  return result;
}

TrajectoryEvaluation EvaluateTrajectoryFiles(const std::filesystem::path& ground_truth_file,
                                             const std::filesystem::path& estimate_file,
                                             const AteOptions& ate_options,
                                             const RpeOptions& rpe_options) {
  const std::vector<StampedPose> ground_truth = ReadTumTrajectory(ground_truth_file);
  const std::vector<StampedPose> estimate = ReadTumTrajectory(estimate_file);
  const std::string origin = ground_truth_file.string() + " vs " + estimate_file.string();
  TrajectoryEvaluation evaluation;
  try {
    evaluation.ate = ComputeAte(ground_truth, estimate, ate_options);
  } catch (const Error& e) {
    throw Error(origin + ": ATE: " + e.what());
  }
  // The ATE needs pose pairs at one stamp, the RPE pairs delta apart: a trajectory
  // shorter than the delta has the one and not the other.
  try {
    evaluation.rpe = ComputeRpe(ground_truth, estimate, rpe_options);
  } catch (const Error& e) {
    evaluation.rpe_missing_reason = e.what();
  }
  return evaluation;
}

}  // namespace segslam::harness
