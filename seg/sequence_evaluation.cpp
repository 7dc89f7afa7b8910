#include "seg/sequence_evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/statistics.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;

// The ground-truth instance of a region: the id it overlaps most in `gt_ids`.
std::uint16_t DominantGroundTruthId(const cv::Mat& region, const cv::Mat& gt_ids) {
  std::map<std::uint16_t, int> votes;
  for (int v = 0; v < region.rows; ++v) {
    const std::uint8_t* in = region.ptr<std::uint8_t>(v);
    const std::uint16_t* gt = gt_ids.ptr<std::uint16_t>(v);
    for (int u = 0; u < region.cols; ++u) {
      if (in[u] && gt[u]) ++votes[gt[u]];
    }
  }
  std::uint16_t best = 0;
  int best_votes = 0;
  for (const auto& [id, count] : votes) {
    if (count > best_votes) best = id, best_votes = count;
  }
  return best;
}

// The sample of frame `frame` in a track (ordered by frame, possibly sparse), or null.
const TrackSample* SampleAt(const ObjectTrack& track, int frame) {
  const auto it = std::lower_bound(track.samples.begin(), track.samples.end(), frame,
                                   [](const TrackSample& sample, int f) { return sample.frame < f; });
  return it != track.samples.end() && it->frame == frame ? &*it : nullptr;
}

}  // namespace

std::map<std::uint16_t, Eigen::Isometry3d> GroundTruthRegionMotions(const FrameSegmentation& previous_refined,
                                                                    const cv::Mat& previous_gt,
                                                                    const TrackIndex& track_of, int frame,
                                                                    const Eigen::Isometry3d& T_wc_previous,
                                                                    const Eigen::Isometry3d& T_wc_current) {
  std::map<std::uint16_t, Eigen::Isometry3d> motions;
  for (const auto& region : previous_refined.instances) {
    const std::uint16_t gt_id = DominantGroundTruthId(region.mask, previous_gt);
    const auto it = track_of.find(gt_id);
    if (gt_id == 0 || it == track_of.end()) continue;
    const TrackSample* before = SampleAt(*it->second, frame - 1);
    const TrackSample* now = SampleAt(*it->second, frame);
    if (before == nullptr || now == nullptr || !before->present || !now->present) continue;
    motions[region.track_id] =
        T_wc_current.inverse() * now->T_world_object * before->T_world_object.inverse() * T_wc_previous;
  }
  return motions;
}

SequenceSegEval EvaluateSequenceWithGroundTruthPoses(const SegEvalOptions& options,
                                                      const fs::path& dir,
                                                      Segmenter& segmenter) {
  const TumSequence sequence = TumSequence::Open(dir);
  if (!sequence.has_groundtruth() || sequence.groundtruth().size() != sequence.size()) {
    throw FileError(dir / "groundtruth.txt",
                    "seg-eval needs one ground-truth pose per frame (--poses gt)");
  }
  // Pose i is frame i's: at its stamp (a motion-capture trajectory at its own rate,
  // cut to the same count, would pair poses with the wrong frames).
  for (size_t i = 0; i < sequence.size(); ++i) {
    const double frame_stamp = sequence.entries()[i].rgb_stamp_s;
    if (std::abs(sequence.groundtruth()[i].stamp_s - frame_stamp) > 1e-3) {
      throw FileError(dir / "groundtruth.txt",
                      fmt::format("pose {} is at {:.6f} s, frame {} at {:.6f} s: seg-eval needs one ground-truth "
                                  "pose per frame, at the frame's stamp (--poses gt)",
                                  i, sequence.groundtruth()[i].stamp_s, i, frame_stamp));
    }
  }
  const InstanceTable instances = InstanceTable::Read(dir / "instances.json");
  std::optional<TrackIndex> track_of;
  std::vector<ObjectTrack> tracks;
  if (options.object_motion && fs::exists(dir / "tracks.json")) {
    tracks = ReadTracks(dir / "tracks.json");
    track_of.emplace();
    for (const auto& track : tracks) (*track_of)[track.instance_id] = &track;
  }

  SegmentationRefiner refiner(options.refiner);
  SegmentationEvaluator raw_scores, refined_scores, raw_confident_scores;
  const PinholeCamera& camera = sequence.camera().intrinsics;
  std::vector<double> refine_ms;
  SequenceSegEval result;
  result.name = dir.filename().string();

  std::optional<FrameSegmentation> previous_refined;
  cv::Mat previous_depth, previous_gt;
  RgbdFrame frame;
  FrameSegmentation initial;
  RefinementResult refinement;
  cv::Mat gt_ids;
  for (size_t i = 0; i < sequence.size(); ++i) {
    frame = sequence.LoadFrame(i);
    frame.index = static_cast<int>(i);
    gt_ids = sequence.LoadInstanceMask(
        dir / "masks" / (sequence.FrameStem(i) + ".png"));
    initial = segmenter.Segment(frame);

    RefinerInput input;
    input.previous_refined = previous_refined ? &*previous_refined : nullptr;
    input.previous_depth_m = previous_depth;
    input.current_depth_m = frame.depth_m;
    input.T_wc_previous_fine = sequence.groundtruth()[i > 0 ? i - 1 : 0].T_wc;
    input.T_wc_current_coarse = sequence.groundtruth()[i].T_wc;
    input.current_initial = initial;
    input.camera = camera;
    // Moving objects are projected with their own ground-truth motion.
    if (previous_refined && track_of) {
      input.instance_motion_prev = GroundTruthRegionMotions(*previous_refined, previous_gt, *track_of, static_cast<int>(i),
                                                            input.T_wc_previous_fine, input.T_wc_current_coarse);
    }
    const auto refine_start = std::chrono::steady_clock::now();
    refinement = refiner.Refine(input);
    refine_ms.push_back(std::chrono::duration<double, std::milli>(
                            std::chrono::steady_clock::now() - refine_start).count());
    for (const RegionDecision& d : refinement.decisions) {
      ++result.decision_counts[static_cast<int>(d.kind)];
    }

    raw_scores.AddFrame(gt_ids, instances, initial);
    FrameSegmentation confident = initial;
    confident.instances.erase(std::remove_if(confident.instances.begin(), confident.instances.end(),
                                             [&](const InstanceMask& m) {
                                               return m.score < options.refiner.min_new_region_score;
                                             }),
                              confident.instances.end());
    raw_confident_scores.AddFrame(gt_ids, instances, confident);
    refined_scores.AddFrame(gt_ids, instances, refinement.refined);
    previous_refined = refinement.refined;
    previous_depth = frame.depth_m;
    previous_gt = gt_ids;
    if (options.on_frame) {
      options.on_frame(static_cast<int>(i + 1), static_cast<int>(sequence.size()));
    }
  }

  result.frames = static_cast<int>(sequence.size());
  result.raw = raw_scores.Scores();
  result.refined = refined_scores.Scores();
  result.raw_confident = raw_confident_scores.Scores();
  result.raw_confident_min_score = options.refiner.min_new_region_score;
  result.refine_ms_median = refine_ms.empty() ? 0 : Median(refine_ms);
  result.last_color_bgr = frame.color_bgr;
  result.last_gt_ids = gt_ids;
  result.last_initial = std::move(initial);
  result.last_refined = std::move(refinement.refined);
  return result;
}

}  // namespace segslam::seg
