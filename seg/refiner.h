// The paper's segmentation refinement (section III.D: eq. 1, eq. 2, Algorithm 1), in
// DESIGN.md's corrected form: the refined regions of frame t-1 are forward-projected
// into frame t with the previous depth and the relative pose, matched one-to-one to the
// initial regions of frame t, and each match keeps the more reliable of the two masks;
// instances the segmenter missed are added back from the projection.
//
// Conventions: poses are T_wc (camera-to-world, core/pose.h); `T_cur_prev` maps points
// of the previous camera frame into the current one. Depth images are CV_32F metres
// along the optical axis, 0 (or non-finite) = no measurement. Masks are CV_8U,
// frame-sized, non-zero = instance pixel (seg/segmentation.h).
//
// Interpretations of the paper (read with DESIGN.md, which is authoritative):
// - Relative pose: T_cur_prev = T_wc_current_coarse^-1 * T_wc_previous_fine (the
//   paper's R = R_c^-1 R_f, T = T_f - T_x is garbled).
// - Algorithm 1 line 4 reads In = Re_c AND Re_p (the paper writes Re_c AND Re_c) and
//   "replace Ra_c with Ra_p" means: replace the region Re_c by Re_p.
// - Ra_c = I/|Re_c| < Ra_p = I/|Re_p| holds exactly when |Re_c| > |Re_p|: the paper's
//   rule keeps the region whose pixels are better confirmed by the other one, i.e. it
//   repairs OVERSIZED current regions (its fig. (d)-(f)) and keeps a current region that
//   lost a part (it is fully confirmed, Ra_c = 1). Repairing lost parts is therefore an
//   extension here (`repair_missing_parts`, off by default = the paper's rule).
// - The paper matches each Re_p to its best Re_c independently; ids must be unique, so
//   matching is one-to-one, greedy by increasing S: the most certain pair is fixed
//   first, which is what the paper's per-Re_p "smallest S" does when no two Re_p compete;
//   Hungarian would minimise the sum and may trade one near-perfect match for two
//   mediocre ones. With ~10 regions and a threshold, conflicts are rare either way.
// - "#regions^{t-1} > #regions^t" compares the number of previous refined instances with
//   the number of current initial instances (AddUnmatchedRule::kPaperCountRule).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "core/camera.h"
#include "seg/segmentation.h"

namespace segslam::seg {

// When an unmatched projected region Re_p is added to the refined segmentation.
enum class AddUnmatchedRule {
  kNever,           // never add
  kPaperCountRule,  // add when frame t-1 had more regions than frame t (paper, Alg. 1)
  kAlways,          // add every unmatched projected region (per-region rule)
};

struct RefinerOptions {
  // --- Matching cost S = w_barycenter * d + w_shape * sqrt(|Re_c xor Re_p| /
  // (|Re_c| + |Re_p|)) (paper eq. 2), d = barycentre distance / image diagonal.
  // Weight of the barycentre distance, per image diagonal; >= 0. 1.0: a 40 px shift in
  // a 640x480 image (diagonal 800 px) costs 0.05, small next to the shape term, which
  // already grows with displacement; the distance term breaks ties between overlapping
  // candidates of similar shape.
  double w_barycenter = 1.0;
  // Weight of the shape term (in [0, 1]: 0 identical, 1 disjoint); >= 0. 1.0 makes S
  // read directly in "shape disagreement" units.
  double w_shape = 1.0;
  // A pair matches only if S < max_match_cost; > 0. 0.75: a region that lost half of
  // itself has shape term sqrt(0.5/1.5) = 0.58 and still matches with a ~0.1 diagonal
  // shift; disjoint regions (shape term 1) never match.
  double max_match_cost = 0.75;
  // Match only regions of the same COCO category (a chair cannot become a person).
  bool require_same_category = true;

  // --- Forward projection (paper eq. 1) and hole closing.
  // Previous-region pixels without depth take the region's median depth (true) or are
  // skipped (false). True: sensor depth drops out on edges and dark/shiny parts; skipping
  // punches holes larger than closing can fill and shrinks Re_p, which biases the
  // area-ratio decision. Objects are shallow next to their distance, so the median is
  // within a pixel or so for inter-frame motion.
  bool fill_missing_depth_with_median = true;
  // A previous region with no depth at all (beyond the sensor's far limit: cars and
  // people down a long street) is projected at the farthest depth measured in the
  // previous frame (true) or not projected (false, the paper). Its true depth is at
  // least that far, so the camera's translation moves it at most as much as it moves the
  // far limit, and rotation, which is exact at any depth, does the rest; without it such
  // regions are "new" in every frame (docs/tuning.md).
  bool project_depthless_regions_at_far_limit = true;
  // Each projected point is splatted into an axis-aligned footprint: the image of its
  // source pixel under the local warp Jacobian (fronto-parallel assumption), times this
  // factor; in [0.5, 3]. 1.0 tiles the target exactly for translation, rotation and
  // scaling of a plane (hole-free without dilation; pixel-exact under pure shifts).
  double splat_footprint_scale = 1.0;
  // A region's inside is splatted 2x2 pixels at a time (true): a block whose four pixels
  // belong to the region and lie on one surface (depths within depth_tolerance) is one
  // point at its centre and mean depth with a footprint twice as wide, a quarter of the
  // projections and footprints. Its edges, depth edges and pixels without depth go pixel
  // by pixel, so the outline is splatted as finely as before. False: every pixel alone.
  bool splat_interior_in_blocks = true;
  // Passes of depth-aware hole filling after splatting: a pixel that is empty, or shows
  // something farther (by more than depth_tolerance) than a region on both of its sides
  // (left/right or up/down), takes that region; in [0, 8]. 2 closes the 1-2 px cracks
  // left by slanted surfaces, whose depth gradient the footprint ignores.
  int hole_fill_iterations = 2;
  // Relative depth tolerance of the z-buffer's hole filling (see above); in [0, 1).
  // 0.05: an order above RGB-D noise (~1% at 3 m) yet separates objects 15 cm apart at
  // 3 m.
  double depth_tolerance = 0.05;
  // Relative depth margin by which the current depth must lie in front of a projected
  // pixel to hide it (RefinerInput::current_depth_m); in [0, 1). 0.1: above RGB-D noise
  // and the projection's own depth error, below the gap between a walker and what is
  // behind.
  double occlusion_tolerance = 0.1;
  // Projected points nearer than this (metres, > 0) are dropped (behind/at the camera).
  double min_depth_m = 0.05;
  // Projected regions smaller than this (pixels, >= 0) are not added back. 1: far
  // objects are 2-60 px, and once only confirmed tracks are added
  // (min_detections_to_add) a small projection is as good evidence of a missed instance
  // as a large one (docs/tuning.md).
  int min_projected_area_px = 1;
  // The same for a region projected at the far limit (it had no depth, see
  // project_depthless_regions_at_far_limit), pixels >= 0. 16: far objects that shrink
  // below what the segmenter finds left 1-15 px ghosts at an assumed depth.
  int min_far_projected_area_px = 16;
  // Projected regions smaller than this (pixels, >= 0) are not matched. 1: far objects
  // (traffic lights, pedestrians down the street) are 2-60 px; left unmatched they
  // became "new" every frame and lost their track.
  int min_matched_area_px = 1;

  // --- Decisions (Algorithm 1).
  // The paper replaces Re_c by Re_p whenever I/|Re_c| < I/|Re_p|, i.e. whenever the
  // current region is the larger. That fires on most good regions (a projection loses
  // slivers of thin parts, lags objects that grow, come out from behind an occluder or
  // in at the border), and refined masks drift; three guards make the rule safe
  // (docs/tuning.md has the figures):
  // (1) the ratios count a pixel of one region as in the other when it lies within
  //     boundary_tolerance_px of it, in [0, 16]; 0 = exact (the paper). 2: projection
  //     with noisy depth is accurate to 1-2 px;
  // (2) replace only when I/|Re_p| - I/|Re_c| > replace_min_ratio_gap, in [0, 1); 0 =
  //     the paper. 0.45: a segmenter's bleeding seldom reaches 0.3 once the tolerance is
  //     granted, while a correct region that grew often passes 0.15, so the rule acts
  //     only on gross over-segmentation (blobs into a neighbour);
  // (3) "replace" keeps the current region's pixels within boundary_tolerance_px of
  //     Re_p (Re_c AND dilate(Re_p)) instead of taking Re_p itself
  //     (trim_instead_of_replace; needs a tolerance > 0): the oversized part is cut off
  //     while the current boundary, sharper than a projection, stays.
  double replace_min_ratio_gap = 0.45;
  int boundary_tolerance_px = 2;
  bool trim_instead_of_replace = true;
  // Extension (off = the trim above): a trim keeps the cut-off pixels whose current depth
  // lies within the projected region's depth range, widened by depth_tolerance (needs
  // RefinerInput::current_depth_m). The segmenter's bleeding lands mostly on what lies
  // behind an object, while a region that really grew (an object stepping in at the
  // border or out from behind another) keeps its depth, which the plain trim cut back to
  // the last frame's extent.
  bool trim_keeps_region_depth = true;
  // Extension (off = paper): also replace Re_c by Re_p when Re_c lies inside the
  // projection (I/|Re_c| >= repair_min_current_inside) but covers too little of it
  // (I/|Re_p| < repair_max_projected_covered): the current segment lost a part.
  bool repair_missing_parts = false;
  double repair_min_current_inside = 0.95;    // in (0, 1]
  double repair_max_projected_covered = 0.9;  // in (0, 1]
  // When an unmatched projected region is added (with its previous track id and
  // category). kAlways, a deviation: the paper's count rule (#regions^{t-1} >
  // #regions^t) seldom holds when the segmenter also makes false positives, which hide
  // a missed instance from the count; the score decay below ends a ghost within 5
  // frames.
  AddUnmatchedRule add_unmatched = AddUnmatchedRule::kAlways;
  // ...and only for a track that the segmenter has detected (matched or new) in at
  // least this many frames, >= 1 (1 = any track). 2, as trackers confirm a track after
  // a second hit: a false positive of the segmenter is seldom detected twice, and carried
  // on by projection it cost pixels and precision for up to 5 frames. Tracks of a
  // previous segmentation that this refiner did not make count as confirmed.
  int min_detections_to_add = 2;
  // An added region's score is its previous score times this decay, in (0, 1]; 0.8: a
  // region carried by projection alone loses confidence each frame...
  double added_score_decay = 0.8;
  // ...and is no longer added once that score falls below this, in [0, 1]. 0.3: with
  // decay 0.8 a score-1 instance survives 5 frames of being missed (~0.2 s at 30 Hz),
  // so a ghost of a vanished object does not live forever.
  double min_added_score = 0.3;
  // --- Scores of the refined regions (extension; the paper does not say; the
  // defaults leave the segmenter's scores alone, which measured best).
  // A matched region (kept or replaced) scores max(its current score,
  // matched_previous_score_weight * the previous region's score), in [0, 1]; 0 = the
  // current score.
  double matched_previous_score_weight = 0.0;
  // A current region without match (and with a previous frame to match against) scores
  // its current score times this factor, in (0, 1]; 1 = unchanged: far objects without
  // depth have no projection and are "new" in every frame, and a lower factor ranked them
  // below false positives.
  double new_region_score_factor = 1.0;
  // A new region (as above) scoring below this after the factor is dropped (reported
  // as kDropped with its current_index), in [0, 1]; 0 = never dropped. 0.35 (an
  // extension, temporal consistency): a region with neither support from the previous
  // frame nor confidence is most likely a false positive, whose pixels cost mIoU. The
  // first frame and clean input (scores 1) are unaffected.
  double min_new_region_score = 0.35;

  // False (and the reason in *error when given) for a value outside its range
  // (seg/refiner_options.h) or weights that are both 0.
  bool IsValid(std::string* error) const;
};

// One previous region forward-projected into the current frame.
struct ProjectedRegion {
  cv::Mat mask;      // CV_8U, current frame size, 1 = visible projected pixel
  int area_px = 0;   // number of mask pixels
  cv::Rect bbox;     // bounding box of the mask pixels (empty when area_px == 0)
};

// Forward-projects every region of `previous_refined` (paper eq. 1) into the current
// frame: each pixel with depth (or the region's median depth, see options) is
// back-projected, moved by `T_cur_prev` (or by instance_motion_prev[track_id] when the
// instance has its own motion: T_cur_prev of that object's points), projected, and
// splatted into a z-buffer shared by ALL regions, so a region behind another is hidden
// where the front one lands; where two regions share a pixel (overlapping masks), the
// smaller one gets it. Cracks are then closed depth-aware (see options).
// Returns one ProjectedRegion per previous instance, in order. `previous_depth_m` is
// CV_32F of the camera's size; masks must be CV_8U of the camera's size (asserted).
std::vector<ProjectedRegion> ProjectRegions(
    const RefinerOptions& options, const PinholeCamera& camera,
    const FrameSegmentation& previous_refined, const cv::Mat& previous_depth_m,
    const Eigen::Isometry3d& T_cur_prev,
    const std::map<std::uint16_t, Eigen::Isometry3d>& instance_motion_prev = {});

struct RefinerInput {
  // Refined segmentation of frame t-1; nullptr on the first frame (then the initial
  // instances get fresh ids and are returned as refined). Not owned.
  const FrameSegmentation* previous_refined = nullptr;
  cv::Mat previous_depth_m;  // CV_32F metres of frame t-1, 0 = none
  // Optional, CV_32F metres of frame t: projected pixels that something nearer now hides
  // (by more than occlusion_tolerance) are dropped, so a person who walks behind another
  // is not given back the part the other now covers.
  cv::Mat current_depth_m;
  Eigen::Isometry3d T_wc_previous_fine = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_wc_current_coarse = Eigen::Isometry3d::Identity();
  FrameSegmentation current_initial;  // the segmenter's instances of frame t
  PinholeCamera camera;
  // Optional: previous track id -> T_cur_prev of that object's points (camera motion
  // and object motion together); instances absent here move with the camera.
  std::map<std::uint16_t, Eigen::Isometry3d> instance_motion_prev;
};

// What happened to one region, for reports.
struct RegionDecision {
  enum class Kind {
    kNew,       // current region without match: fresh track id
    kKept,      // matched; current mask kept, previous track id
    kReplaced,  // matched; mask replaced by the projection, previous track id
    kAdded,     // unmatched projection added (missed detection), previous track id
    kDropped,   // unmatched projection not added (or too small / too low score), or
                // a new current region under min_new_region_score
  };
  Kind kind = Kind::kNew;
  std::uint16_t track_id = 0;   // id in the refined output (kDropped: the previous id; 0 for a new region)
  int current_index = -1;       // index in current_initial.instances, -1 if none
  int previous_index = -1;      // index in previous_refined->instances, -1 if none
  double cost = -1;             // S of the match, -1 if unmatched
  double ratio_current = -1;    // I / |Re_c| of the match (up to boundary_tolerance_px)
  double ratio_projected = -1;  // I / |Re_p| of the match (up to boundary_tolerance_px)
  int projected_area_px = -1;   // |Re_p|, -1 if no projection involved
};

const char* ToString(RegionDecision::Kind kind);

struct RefinementResult {
  // Current instances in input order (refined mask, stable track id; new regions
  // under min_new_region_score left out), then added ones. Kept masks share pixel data
  // with the input (cv::Mat reference counting). Every instance's bounds hold its pixels
  // (seg/segmentation.h), so the next frame's refinement reads only inside them.
  FrameSegmentation refined;
  std::vector<RegionDecision> decisions;  // one per current region, then per projection
  std::string BriefReport() const;        // e.g. "kept 3 replaced 1 new 0 added 1 ..."
};

struct ProjectionWorkspace;  // seg/refiner.cpp

// Stateful across frames: hands out track ids (next id only grows). Not copyable.
class SegmentationRefiner {
 public:
  explicit SegmentationRefiner(RefinerOptions options = {});
  ~SegmentationRefiner();
  SegmentationRefiner(const SegmentationRefiner&) = delete;
  SegmentationRefiner& operator=(const SegmentationRefiner&) = delete;

  // Refines in.current_initial (Algorithm 1). The current instances' own track ids are
  // ignored: ids come from the match (previous id) or from this refiner (fresh id).
  // Throws segslam::Error on invalid options, camera, or image sizes/types.
  RefinementResult Refine(const RefinerInput& in);

  const RefinerOptions& options() const { return options_; }

 private:
  std::uint16_t FreshId();
  // Fresh ids start after every id of `previous`.
  void ReserveIdsOf(const FrameSegmentation& previous);
  // Every region of `current` new, with a fresh id: the first frame, or no depth.
  RefinementResult AllNew(const FrameSegmentation& current);

  // Frames in which the segmenter detected each track of the last refined output (see
  // min_detections_to_add); added regions do not count.
  void CountDetections(const RefinementResult& result);

  RefinerOptions options_;
  std::uint16_t next_track_id_ = 1;
  std::map<std::uint16_t, int> detections_of_track_;
  // Z-buffer and label image reused across frames (only the touched area is reset).
  std::unique_ptr<ProjectionWorkspace> workspace_;
};

}  // namespace segslam::seg
