// Perceptual aliasing of a sequence: how many ORB matches between two views that share
// no static content survive a ratio test and RANSAC PnP with depth, the check a loop
// detector makes of a candidate. ORB-SLAM2's loop closing accepts a candidate at about
// 20 such inliers (kLoopAcceptanceMatches); a world whose distant places pass that check
// invites a false loop closure or relocalization. `segslam bench aliasing` reports the
// measure per pass, `segslam generate` records its summary in manifest.json. Method,
// thresholds and why: docs/aliasing.md.
//
// "Share no static view" is decided from ground truth alone (GroundTruthView,
// SeenShare): a grid of background pixels with depth of one frame, moved into the other
// with the ground-truth poses, is seen there when it lands inside the image, in front of
// the camera, where the other frame's depth agrees. This needs no model of the world, so
// it holds for the office, the city and a real TUM sequence (without masks every pixel
// counts as background).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

#include "core/camera.h"
#include "core/tum_dataset.h"
#include "slam/orb_extractor.h"

namespace segslam::harness {

// The inliers at which ORB-SLAM2's loop closing accepts a candidate (LoopClosing::
// ComputeSim3 asks for 20 Sim3 inliers; relocalization then needs 50 after tracking):
// a pair of views with no common view at or above it would be taken for a loop.
constexpr int kLoopAcceptanceMatches = 20;

struct CommonViewOptions {
  // Pixels sampled on a grid with this step (px, >= 1); 8 gives 4800 points at 640x480.
  int pixel_stride = 8;
  // A point is seen by the other frame when that frame's depth at its pixel agrees with
  // the point's depth there within max(depth_tolerance_m, depth_tolerance_share * depth):
  // sensor noise (2-3 % at range), not the metres an occluder stands in front.
  double depth_tolerance_m = 0.1;
  double depth_tolerance_share = 0.05;  // [0, 1)
  // Two frames share no view when fewer than this share of either frame's sampled
  // points is seen by the other (both ways). 0.5 % of 4800 points is 24 points, about 1500
  // pixels: too little for 20 true matches among 1000 features spread over
  // the image, and more than the handful of points that depth noise at an occluding edge
  // lets through. (0, 1).
  double min_common_share = 0.005;
  // Pairs whose cameras stand at least this far apart are measured too, whatever they
  // share far off: down a straight avenue every frame sees, tiny and without depth, the
  // facades the frames 200 m on see up close, so no pair of it shares "no view", yet a
  // loop detector there is as exposed to look-alikes. (The figures took pairs 40 m
  // apart.) 0: only pairs with no common view. >= 0.
  double far_apart_m = 40.0;

  bool IsValid(std::string* error) const;
};

// One frame's ground truth for the common-view test.
struct GroundTruthView {
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  cv::Mat depth_m;                        // CV_32F metres, 0 = no depth (the frame's own)
  std::vector<Eigen::Vector3d> points_w;  // the sampled background pixels with depth, in world
};

// The view of a frame: `depth_m` CV_32F metres (0 = none); `instance_ids` CV_16U of the
// same size with 0 = static background, or empty (every pixel is background: a real
// sequence without masks). Throws segslam::Error on wrong types or sizes.
GroundTruthView MakeGroundTruthView(const CommonViewOptions& options, const PinholeCamera& camera,
                                    const Eigen::Isometry3d& T_wc, const cv::Mat& depth_m,
                                    const cv::Mat& instance_ids);

// The share (0..1) of `from`'s points that `to` sees: in its image and in front of it,
// with to's depth there agreeing (see CommonViewOptions). Where `to` has no depth, the
// point counts as seen when it lies beyond `depth_range_m` (the farthest depth the
// sensor reports): the sensor reads nothing there, so it cannot be ruled out, and
// calling such a pair "no common view" would count true matches on distant facades as
// aliasing. Nearer than that, a pixel without depth is a dropout and proves nothing.
// 0 when `from` has no points.
double SeenShare(const CommonViewOptions& options, const PinholeCamera& camera, double depth_range_m,
                 const GroundTruthView& from, const GroundTruthView& to);

// Both ways; the pair shares a view when either share reaches min_common_share.
struct ViewOverlap {
  double share_ab = 0;  // of a's points seen by b
  double share_ba = 0;
  double Share() const { return share_ab > share_ba ? share_ab : share_ba; }
};
ViewOverlap MeasureOverlap(const CommonViewOptions& options, const PinholeCamera& camera, double depth_range_m,
                           const GroundTruthView& a, const GroundTruthView& b);

struct AliasingOptions {
  // Frames are sampled along the ground truth: the first with a pose, then each frame
  // once the camera has moved sample_spacing_m or turned sample_turn_deg since the last
  // sampled one (> 0). All pairs of sampled frames are tested, so the work grows with
  // the square of the route length over the spacing: a 200 m city route at 2 m is about
  // 100 frames and 5000 pairs (14 s on one core), at 1 m 170 frames and 14 000 pairs
  // (44 s). Finer sampling finds more look-alike pairs (docs/aliasing.md).
  double sample_spacing_m = 2.0;
  double sample_turn_deg = 15.0;
  // ... or once this many frames have passed (0: never), so that a camera that moves
  // little (an office's hand-held sequence) is still sampled along its whole length.
  int sample_every_frames = 30;
  CommonViewOptions common_view;
  // The SLAM core's extractor settings (1000 features, 8 levels of 1.2).
  slam::OrbExtractorOptions orb;
  // Lowe's ratio test on Hamming distances: the nearest of frame b's descriptors must be
  // nearer than ratio * the second nearest (ORB-SLAM2: 0.75 in loop and relocalization
  // searches, 0.6-0.9 elsewhere; the tracker here: 0.8). (0, 1].
  float ratio = 0.8f;
  // And no farther than this (of 256 bits): the tracker's max_descriptor_distance.
  int max_descriptor_distance = 100;
  // RANSAC PnP (slam::SolveRansacPnp, AP3P on samples of four): at most this many
  // samples, as ORB-SLAM2's loop closing draws per candidate (Sim3Solver: 300). A
  // consensus of a third of the matches is found with probability 0.97, a quarter 0.69,
  // a fifth 0.38; the relocalization's 2000 raise those to 1, 0.9996 and 0.96 at about
  // six times the cost (a sample takes ~15 us in OpenCV). A match is an inlier within
  // max_error_px. OpenCV's RANSAC draws from a fixed seed on each call, so the same
  // matches give the same inliers.
  int ransac_samples = 300;
  float ransac_max_error_px = 4.0f;
  // A consensus whose pose puts camera b within this of its true place relative to a
  // (m) is the same place seen from afar, a true match, not a look-alike: such a pair
  // counts 0 verified matches (AliasingPair::true_place). > 0.
  double true_place_tolerance_m = 1.0;
  // false: every feature counts, as a loop detector sees them, but a match between two
  // features on the same instance does not: the same object seen at both places (a car
  // the camera follows) is common content, where a second truck in the same livery is a
  // look-alike. true: features on ground-truth background (mask 0) only. Without masks
  // every feature counts either way.
  bool background_features_only = false;
  int threads = 0;                            // worker threads; 0 = all cores
  const std::atomic<bool>* cancel = nullptr;  // set to true to stop (throws "cancelled")

  bool IsValid(std::string* error) const;
  nlohmann::json ToJson() const;  // the effective settings, for reports
};

// One measured pair of sampled frames: no common view, or far apart.
struct AliasingPair {
  int frame_a = 0;  // sequence indices, a < b; a's features with depth give the 3D points
  int frame_b = 0;
  double stamp_a_s = 0, stamp_b_s = 0;
  double distance_m = 0;      // ground truth, between the camera centres
  bool no_common_view = false;  // else measured as far apart
  double common_share = 0;    // ViewOverlap::Share()
  int ratio_matches = 0;      // pass the ratio test and the distance limit
  // RANSAC PnP inliers among them at a wrong pose: 0 when the pose is within
  // true_place_tolerance_m of the truth (true_place).
  int verified_matches = 0;
  bool true_place = false;
  // How far from its true place the PnP pose puts camera b (m); -1 without a pose.
  double pose_error_m = -1;
};

struct AliasingSummary {
  std::string sequence;  // folder
  int frames = 0;
  int sampled_frames = 0;
  std::int64_t pairs_tested = 0;        // all pairs of sampled frames
  std::int64_t pairs_no_common_view = 0;
  std::int64_t pairs_measured = 0;  // no common view, or at least far_apart_m apart
  // Over the measured pairs (0 when there are none).
  int max_verified_matches = 0;
  int p50 = 0, p90 = 0, p99 = 0;  // nearest-rank percentiles of verified matches
  std::int64_t pairs_at_or_above_acceptance = 0;  // verified >= kLoopAcceptanceMatches
  std::vector<AliasingPair> worst_pairs;  // the most verified first (ties: lower a, b), at most 10
  double seconds = 0;

  nlohmann::json ToJson() const;
};

// stage: "frames" (load, features, ground truth view) or "pairs".
using AliasingProgress = std::function<void(const std::string& stage, int done, int total)>;

// Measures one sequence. Needs groundtruth.txt: a frame's pose is the ground truth's at
// its stamp, or interpolated between the two around it when they lie at most 0.1 s
// apart, else the frame is skipped. masks/<rgb stem>.png are used when the sequence has
// masks/ (every frame then needs one).
// Throws segslam::Error on invalid options, a sequence without ground truth, unreadable
// images or masks, and cancellation. Deterministic: the same sequence and options give
// the same summary whatever the thread count.
AliasingSummary MeasureAliasing(const AliasingOptions& options, const TumSequence& sequence,
                                const AliasingProgress& progress = {});

// The two frames of `pair` side by side with the verified matches drawn between them,
// and a caption line (frames, ground-truth distance, verified matches).
cv::Mat AliasingPairPicture(const AliasingOptions& options, const TumSequence& sequence, const AliasingPair& pair);

}  // namespace segslam::harness
