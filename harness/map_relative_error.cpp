#include "harness/map_relative_error.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"

namespace segslam::harness {

namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

// A pass-1 frame that can serve as a place: its true and its estimated pose (T_wc).
struct Place {
  std::size_t estimate_index = 0;  // into pass 1's estimate
  Eigen::Isometry3d T_wc_true = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_wc_estimated = Eigen::Isometry3d::Identity();
};

std::vector<double> StampsOf(const std::vector<StampedPose>& poses) {
  std::vector<double> stamps;
  stamps.reserve(poses.size());
  for (const StampedPose& pose : poses) stamps.push_back(pose.stamp_s);
  return stamps;
}

// Pass 1's estimated frames with their ground truth, paired as ComputeAte pairs them;
// an estimated frame without ground truth cannot be found by position and is no place.
std::vector<Place> PassOnePlaces(const std::vector<StampedPose>& ground_truth, const std::vector<StampedPose>& estimate,
                                 double max_difference_s) {
  std::vector<Place> places;
  for (const StampAssociation& pair : AssociateStamps(StampsOf(ground_truth), StampsOf(estimate), max_difference_s)) {
    places.push_back({pair.second_index, ground_truth[pair.first_index].T_wc, estimate[pair.second_index].T_wc});
  }
  return places;
}

// The pose whose stamp is nearest to `stamp_s`, if within `max_difference_s`; `poses`
// sorted by stamp.
const StampedPose* PoseAtStamp(const std::vector<StampedPose>& poses, double stamp_s, double max_difference_s) {
  const auto above = std::lower_bound(poses.begin(), poses.end(), stamp_s,
                                      [](const StampedPose& pose, double stamp) { return pose.stamp_s < stamp; });
  const StampedPose* nearest = nullptr;
  double nearest_difference = max_difference_s;
  for (auto it : {above, above == poses.begin() ? poses.end() : above - 1}) {
    if (it == poses.end()) continue;
    const double difference = std::abs(it->stamp_s - stamp_s);
    if (difference < nearest_difference) {
      nearest = &*it;
      nearest_difference = difference;
    }
  }
  return nearest;
}

// The place whose true camera position is nearest to `position` (see the header for why
// position only); null when `places` is empty.
const Place* NearestPlace(const std::vector<Place>& places, const Eigen::Vector3d& position) {
  const Place* nearest = nullptr;
  double nearest_distance = std::numeric_limits<double>::infinity();
  for (const Place& place : places) {
    const double distance = (place.T_wc_true.translation() - position).norm();
    if (distance < nearest_distance) {
      nearest = &place;
      nearest_distance = distance;
    }
  }
  return nearest;
}

// Angle of a rotation in radians, in [0, pi]; through the quaternion, which keeps small
// angles accurate (acos of the trace does not).
double RotationAngleRad(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return 2 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

// E = (T̂1_j^-1 T̂2_i)^-1 (T1_j^-1 T2_i): camera i in camera j's frame, estimated against
// true; the header says why.
void ScoreFrame(const Place& place, const Eigen::Isometry3d& T_wc2_true, const Eigen::Isometry3d& T_wc2_estimated,
                MapRelativeFrame* frame) {
  const Eigen::Isometry3d T_j_i_estimated = place.T_wc_estimated.inverse() * T_wc2_estimated;
  const Eigen::Isometry3d T_j_i_true = place.T_wc_true.inverse() * T_wc2_true;
  const Eigen::Isometry3d error = T_j_i_estimated.inverse() * T_j_i_true;
  frame->translation_error_m = error.translation().norm();
  frame->rotation_error_deg = RotationAngleRad(error.linear()) * kDegreesPerRadian;
}

}  // namespace

std::string MapRelativeOptions::Check() const {
  if (!(max_difference_s > 0)) return fmt::format("max_difference_s must be > 0, not {}", max_difference_s);
  if (!(max_place_distance_m > 0)) return fmt::format("max_place_distance_m must be > 0, not {}", max_place_distance_m);
  if (!(within_translation_m > 0)) return fmt::format("within_translation_m must be > 0, not {}", within_translation_m);
  if (!(within_rotation_deg > 0)) return fmt::format("within_rotation_deg must be > 0, not {}", within_rotation_deg);
  return "";
}

double MapRelativeResult::WithinShare() const {
  return frames_with_place > 0 ? double(frames_within) / frames_with_place : std::numeric_limits<double>::quiet_NaN();
}

MapRelativeResult ComputeMapRelativeError(const std::vector<StampedPose>& pass1_ground_truth,
                                          const std::vector<StampedPose>& pass1_estimate,
                                          const std::vector<double>& pass2_frame_stamps_s,
                                          const std::vector<StampedPose>& pass2_ground_truth,
                                          const std::vector<StampedPose>& pass2_estimate,
                                          const MapRelativeOptions& options) {
  if (const std::string error = options.Check(); !error.empty()) throw Error("map-relative error: " + error);
  const std::vector<Place> places = PassOnePlaces(pass1_ground_truth, pass1_estimate, options.max_difference_s);

  MapRelativeResult result;
  result.options = options;
  std::vector<double> translation_errors_m, rotation_errors_deg;
  for (const double stamp_s : pass2_frame_stamps_s) {
    MapRelativeFrame frame;
    frame.stamp_s = stamp_s;
    const StampedPose* truth = PoseAtStamp(pass2_ground_truth, stamp_s, options.max_difference_s);
    frame.has_ground_truth = truth != nullptr;
    const Place* place = truth != nullptr ? NearestPlace(places, truth->T_wc.translation()) : nullptr;
    if (place != nullptr) {
      frame.place_index = place->estimate_index;
      frame.place_distance_m = (place->T_wc_true.translation() - truth->T_wc.translation()).norm();
      frame.has_place = frame.place_distance_m <= options.max_place_distance_m;
    }
    const StampedPose* estimate = PoseAtStamp(pass2_estimate, stamp_s, options.max_difference_s);
    frame.has_estimate = estimate != nullptr;

    // Count it; score it where it has both a place and a pose.
    if (!frame.has_ground_truth) {
      ++result.frames_without_ground_truth;
    } else if (!frame.has_place) {
      ++result.frames_without_place;
    } else {
      ++result.frames_with_place;
      if (!frame.has_estimate) {
        ++result.frames_unestimated;
      } else {
        ScoreFrame(*place, truth->T_wc, estimate->T_wc, &frame);
        translation_errors_m.push_back(frame.translation_error_m);
        rotation_errors_deg.push_back(frame.rotation_error_deg);
        frame.within = frame.translation_error_m <= options.within_translation_m &&
                       frame.rotation_error_deg <= options.within_rotation_deg;
        result.frames_within += frame.within;
      }
    }
    result.frames.push_back(frame);
  }
  if (!translation_errors_m.empty()) {
    result.translation_m = ComputeErrorStatistics(translation_errors_m);
    result.rotation_deg = ComputeErrorStatistics(rotation_errors_deg);
  }
  return result;
}

}  // namespace segslam::harness
