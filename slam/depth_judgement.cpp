// The moving/static judgement from depth (TrackerOptions::judge_by_depth), beyond the
// paper: where the paper needs re-found ORB features with depth on an object a baseline
// apart (seldom four on a car 15 m away), an RGB-D frame has depth on every pixel of it.
//
// A still object's interior depth pixels, carried into another frame by the camera's own
// motion (the background's pose), land where that frame measured the same depth. A
// moving one's do not: receding, the depth there is farther now (checked forward, the
// remembered frame's samples into this frame); approaching, it was farther then (checked
// backward, this frame's samples into the remembered one); moving across, both find
// what lay behind. A point that lands behind nearer depth is hidden, and counts neither
// way. So a frame contradicts a share of the samples, and that share over the threshold
// is a frame that sees the instance move. The frames' verdicts add up along the
// instance's track id as log-odds of moving.
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "slam/tracker_internal.h"

namespace segslam::slam {
namespace {

struct Region {
  int min_u = std::numeric_limits<int>::max();
  int min_v = std::numeric_limits<int>::max();
  int max_u = -1;
  int max_v = -1;
  int area = 0;
};

// Each instance's bounding box and pixel count, from every `step`-th pixel of every
// `step`-th row (area in those pixels): enough to space the samples, at a fraction of a
// pass over the whole image.
std::map<std::uint16_t, Region> InstanceRegions(const cv::Mat& ids, int step) {
  std::map<std::uint16_t, Region> regions;
  std::uint16_t last_id = 0;
  Region* last = nullptr;
  for (int v = 0; v < ids.rows; v += step) {
    const std::uint16_t* row = ids.ptr<std::uint16_t>(v);
    // Run by run of one id: a region is updated once per run, not once per pixel.
    for (int u = 0; u < ids.cols;) {
      const std::uint16_t id = row[u];
      const int first = u;
      do {
        u += step;
      } while (u < ids.cols && row[u] == id);
      if (id == 0) continue;
      if (last == nullptr || id != last_id) {
        last = &regions[id];
        last_id = id;
      }
      last->min_u = std::min(last->min_u, first);
      last->max_u = std::max(last->max_u, u - step);
      last->min_v = std::min(last->min_v, v);
      last->max_v = std::max(last->max_v, v);
      last->area += (u - first) / step;
    }
  }
  return regions;
}

}  // namespace

void Tracker::Impl::SampleInstanceDepth(const cv::Mat& ids) {
  current.depth_samples_c.clear();
  const DepthJudgementOptions& o = options.depth_judgement;
  const int m = o.interior_margin_px;
  const cv::Mat& depth = current.depth_m;
  constexpr int kRegionStep = 2;
  for (auto [id, region] : InstanceRegions(ids, kRegionStep)) {
    // The box found on the coarse grid, widened by what the grid may have missed.
    region.min_u = std::max(0, region.min_u - kRegionStep + 1);
    region.min_v = std::max(0, region.min_v - kRegionStep + 1);
    region.max_u = std::min(ids.cols - 1, region.max_u + kRegionStep - 1);
    region.max_v = std::min(ids.rows - 1, region.max_v + kRegionStep - 1);
    const double area = double(region.area) * kRegionStep * kRegionStep;
    // A grid fine enough for about samples_per_instance of the region's pixels.
    const int stride = std::max(1, static_cast<int>(std::floor(std::sqrt(area / o.samples_per_instance))));
    std::vector<Eigen::Vector3d>& samples = current.depth_samples_c[id];
    for (int v = std::max(region.min_v, m); v <= std::min(region.max_v, ids.rows - 1 - m); v += stride) {
      const std::uint16_t* id_row = ids.ptr<std::uint16_t>(v);
      const float* depth_row = depth.ptr<float>(v);
      for (int u = std::max(region.min_u, m); u <= std::min(region.max_u, ids.cols - 1 - m); u += stride) {
        if (id_row[u] != id) continue;
        const float z = depth_row[u];
        if (!(z > 0) || z > o.max_depth_m) continue;
        bool interior = true;
        for (const auto& [du, dv] : {std::pair{-m, 0}, std::pair{m, 0}, std::pair{0, -m}, std::pair{0, m}}) {
          if (ids.at<std::uint16_t>(v + dv, u + du) != id || !OnSameSurface(depth.at<float>(v + dv, u + du), z)) {
            interior = false;
            break;
          }
        }
        if (interior) samples.push_back(camera.BackProject(Eigen::Vector2d(u, v), z));
      }
    }
  }
}

void Tracker::Impl::VoteAgainstDepth(const std::vector<Eigen::Vector3d>& points_w, const Eigen::Isometry3d& T_cw,
                                     const cv::Mat& depth_m, const Eigen::Vector3d& offset_w,
                                     DepthVotes* votes) const {
  for (const Eigen::Vector3d& point_w : points_w) {
    const Eigen::Vector3d p_c = T_cw * (point_w + offset_w);
    if (p_c.z() <= 0 || p_c.z() > options.depth_judgement.max_depth_m) continue;
    const Eigen::Vector2d uv = camera.Project(p_c);
    const int u = static_cast<int>(std::lround(uv.x()));
    const int v = static_cast<int>(std::lround(uv.y()));
    if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) continue;
    const float measured = depth_m.at<float>(v, u);
    if (!(measured > 0)) continue;
    const double excess = measured - p_c.z();  // > 0: the depth there lies beyond the point
    const double threshold = MovingDistanceThreshold(p_c.z());
    if (excess > threshold) {
      ++votes->moving;
    } else if (excess >= -threshold) {
      ++votes->still;
    }
  }
}

DepthVotes Tracker::Impl::VoteOnDisplacement(std::uint16_t id, const Eigen::Isometry3d& T_wc,
                                             const InstanceSnapshot& past, const Eigen::Vector3d& displacement_w) const {
  DepthVotes votes;
  // Forward: the remembered frame's samples of this track, moved, into this frame.
  if (const auto found = past.depth_samples_w.find(id); found != past.depth_samples_w.end()) {
    VoteAgainstDepth(found->second, T_wc.inverse(), current.depth_m, displacement_w, &votes);
  }
  // Backward: this frame's samples, moved back, into the remembered frame.
  if (const auto found = current.depth_samples_c.find(id); found != current.depth_samples_c.end()) {
    std::vector<Eigen::Vector3d> points_w;
    points_w.reserve(found->second.size());
    for (const Eigen::Vector3d& p_c : found->second) points_w.push_back(T_wc * p_c);
    VoteAgainstDepth(points_w, past.T_wc.inverse(), past.depth_m, -displacement_w, &votes);
  }
  return votes;
}

DepthVotes Tracker::Impl::MeasureDepthMotion(std::uint16_t id, const Eigen::Isometry3d& T_wc,
                                             const InstanceSnapshot& past, InstanceJudgement* judgement) const {
  const DepthVotes votes = VoteOnDisplacement(id, T_wc, past, Eigen::Vector3d::Zero());
  judgement->num_points = votes.measured();
  judgement->num_moving_points = votes.moving;
  judgement->moving_share = votes.measured() > 0 ? double(votes.moving) / votes.measured() : 0;
  return votes;
}

// The sparse features see what depth cannot, a surface sliding within its own plane;
// but descriptors alias on repeated structure (a car's two wheels, a row of windows),
// and a still object's feature matched to its twin a wheelbase along reads as a large
// displacement. The two are told apart by moving the instance's depth samples as the
// features say it moved: a real slide keeps them on the surface (its ends aside), while
// an alias pushes a good part of them past the object's end, onto what lies behind.
// The displacement since `past` is the features' median velocity over that time (their
// own spans differ: map points are older than the remembered frame).
bool Tracker::Impl::DepthRefutesSparseMotion(std::uint16_t id, const Eigen::Isometry3d& T_wc,
                                             const InstanceSnapshot& past, const MotionEvidence& evidence,
                                             const DepthVotes& still) const {
  if (evidence.displacements.empty()) return false;
  const Eigen::Vector3d displacement_w = evidence.MedianVelocity() * (current.stamp_s - past.stamp_s);
  const DepthVotes moved = VoteOnDisplacement(id, T_wc, past, displacement_w);
  // Only two measured hypotheses are compared; the samples each counts differ (some
  // leave the view, some land hidden), so their shares are.
  const int enough = options.depth_judgement.min_samples;
  if (still.measured() < enough || moved.measured() < enough) return false;
  return double(moved.moving) / moved.measured() > double(still.moving) / still.measured();
}

bool Tracker::Impl::DepthSeesMotion(const DepthVotes& votes, const InstanceJudgement& judgement) const {
  const DepthJudgementOptions& o = options.depth_judgement;
  const bool evidence_enough_to_move =
      judgement.moveable_class || votes.measured() >= options.min_points_to_move_fixed_class;
  return votes.measured() >= o.min_samples && evidence_enough_to_move &&
         double(votes.moving) >= o.moving_share * votes.measured();
}

void Tracker::Impl::DecideFromDepth(const DepthVotes& votes, bool full_baseline, bool sees_motion,
                                    InstanceJudgement* judgement, InstanceMotionMemory* memory) const {
  const DepthJudgementOptions& o = options.depth_judgement;
  // An instance unmeasured for longer than moving_memory_s starts afresh: its track id
  // may now be another object's, and what it did then says little of now.
  if (current.stamp_s - memory->last_measured_stamp_s > options.moving_memory_s + 1e-9) {
    memory->moving_log_odds = 0;
    memory->static_frames = 0;
  }
  const bool measured = votes.measured() >= o.min_samples;
  if (sees_motion) {
    // A still past does not outweigh a frame that sees motion: a parked car that pulls
    // out must leave the pose at once; a false alarm only keeps a still one out a while.
    memory->last_measured_stamp_s = current.stamp_s;
    memory->moving_log_odds = std::min(o.max_log_odds, std::max(0.0, memory->moving_log_odds) + o.moving_log_odds);
    memory->static_frames = 0;
  } else if (measured && full_baseline) {
    // Over less than a baseline a walker moves less than the depth noise: only a frame
    // a full baseline apart can see it still.
    memory->last_measured_stamp_s = current.stamp_s;
    memory->moving_log_odds = std::max(-o.max_log_odds, memory->moving_log_odds - o.static_log_odds);
    ++memory->static_frames;
  }
  judgement->moving = memory->moving_log_odds > 0;
  judgement->judged = memory->moving_log_odds != 0;
}

}  // namespace segslam::slam
