#include "harness/slam_runner.h"

#include <algorithm>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <unordered_set>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/statistics.h"
#include "core/tracks.h"
#include "seg/external_masks.h"
#include "seg/simulated_segmenter.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

// Frames 0, 1, ..., count - 1 of a sequence in order. With `read_ahead`, each is read
// and decoded on another thread while the one before it is processed: decoding a frame's
// PNGs is about a sixth of a run's time. A read error is thrown by the Next() that would
// return the frame.
class FrameReader {
 public:
  FrameReader(const TumSequence& sequence, int count, bool read_ahead)
      : sequence_(sequence), count_(count), read_ahead_(read_ahead) {
    if (count_ > 0) next_ = Load(0);
  }

  RgbdFrame Next() {
    RgbdFrame frame = next_.get();
    if (++index_ < count_) next_ = Load(index_);
    return frame;
  }

 private:
  std::future<RgbdFrame> Load(int i) const {
    // Deferred: read by get(), on the calling thread.
    const std::launch policy = read_ahead_ ? std::launch::async : std::launch::deferred;
    return std::async(policy, [this, i] { return sequence_.LoadFrame(static_cast<size_t>(i)); });
  }

  const TumSequence& sequence_;
  int count_ = 0;
  bool read_ahead_ = true;
  int index_ = 0;
  std::future<RgbdFrame> next_;
};

// The segmenter the run's options name: the simulated one, an external masks folder, or
// none (nullptr) for the dataset's ground-truth masks.
std::unique_ptr<seg::Segmenter> MakeSegmenter(const TumSequence& sequence, const SlamRunOptions& options) {
  if (!options.segmenter.empty()) {
    if (options.masks != "gt") {
      throw Error("run: --segmenter " + options.segmenter + " and --masks " + options.masks +
                  " exclude each other (the simulated segmenter degrades the ground-truth masks)");
    }
    seg::SimulatedSegmenterOptions preset = seg::SimulatedSegmenterOptions::Preset(options.segmenter);
    preset.strength = options.segmenter_strength;
    return std::make_unique<seg::SimulatedSegmenter>(sequence.dir(), preset, options.segmenter_seed,
                                                     options.segmenter);
  }
  if (options.masks != "gt") {
    return std::make_unique<seg::ExternalMaskSegmenter>(options.masks, sequence,
                                                        static_cast<size_t>(std::max(0, options.max_frames)));
  }
  return nullptr;
}

// The instance masks of each frame as SLAM takes them, unrefined: the dataset's ground
// truth, or a segmenter's raw output. For the oracle, the ground truth's moving
// instances too.
class MaskSource {
 public:
  MaskSource(const TumSequence& sequence, const SlamRunOptions& options)
      : sequence_(sequence), segmenter_(MakeSegmenter(sequence, options)) {
    if (segmenter_ != nullptr) return;
    const fs::path table = sequence.dir() / "instances.json";
    if (!fs::exists(table)) {
      throw FileError(table, "missing: ground-truth masks need the dataset's instance table "
                             "(or give --masks DIR with external masks)");
    }
    table_ = InstanceTable::Read(table);
    for (const InstanceInfo& info : table_.instances()) {
      if (info.moveable) moveable_.insert(info.id);
    }
    if (options.mode == slam::SlamMode::kOracle) {
      const fs::path tracks = sequence.dir() / "tracks.json";
      if (!fs::exists(tracks)) {
        throw FileError(tracks, "missing: mode oracle takes which instances move from the ground-truth tracks");
      }
      moving_by_frame_.emplace();
      for (const ObjectTrack& track : ReadTracks(tracks)) {
        for (const TrackSample& sample : track.samples) {
          if (sample.moving) (*moving_by_frame_)[sample.frame].insert(track.instance_id);
        }
      }
    }
  }

  slam::FrameInstances Load(const RgbdFrame& frame) {
    if (segmenter_ != nullptr) {
      return mutual::ToFrameInstances(segmenter_->Segment(frame), frame.color_bgr.size());
    }
    slam::FrameInstances instances;
    const fs::path path = sequence_.dir() / "masks" / (sequence_.FrameStem(static_cast<size_t>(frame.index)) + ".png");
    instances.ids = sequence_.LoadInstanceMask(path);  // Checks its size.
    CheckMaskIds(instances.ids, table_, path.string());
    instances.moveable_ids = moveable_;
    if (moving_by_frame_.has_value()) {
      const auto moving = moving_by_frame_->find(frame.index);
      instances.known_moving_ids = moving != moving_by_frame_->end() ? moving->second
                                                                     : std::unordered_set<std::uint16_t>{};
    }
    return instances;
  }

 private:
  const TumSequence& sequence_;
  std::unique_ptr<seg::Segmenter> segmenter_;
  InstanceTable table_;
  std::unordered_set<std::uint16_t> moveable_;
  // Oracle mode: frame index -> instances that moved since the frame before.
  std::optional<std::map<int, std::unordered_set<std::uint16_t>>> moving_by_frame_;
};


// A map reset voids the poses of the frames before it: they are in the frame of a map
// that no longer exists, so they count as lost, as ORB-SLAM2 forgets them.
void AddFrame(const slam::FrameResult& frame, SlamRunResult* result) {
  if (frame.map_reset) {
    for (slam::FrameResult& earlier : result->frames) earlier.status = slam::TrackingStatus::kLost;
    result->trajectory.clear();
  }
  if (frame.localized()) result->trajectory.push_back({frame.stamp_s, frame.T_wc});
  result->frames.push_back(frame);
}

// Mutual mode with a segmenter: the paper's loop, refined masks written and scored.
SlamRunResult RunMutualLoop(const TumSequence& sequence, const SlamRunOptions& options) {
  const std::unique_ptr<seg::Segmenter> segmenter = MakeSegmenter(sequence, options);
  mutual::MutualLoopOptions loop_options;
  loop_options.tracker = options.tracker;
  loop_options.refiner = options.refiner;
  mutual::MutualLoop loop(sequence.camera().intrinsics, *segmenter, loop_options);
  if (!options.map_in.empty()) {
    loop.LoadLongTermMap(slam::LoadLongTermMap(options.map_in), options.map_in.string());
  }

  // Scored when the sequence has ground-truth masks (a generated one; not a real TUM one).
  const fs::path gt_table_path = sequence.dir() / "instances.json";
  const fs::path gt_masks_dir = sequence.dir() / "masks";
  const bool score = fs::exists(gt_table_path) && fs::is_directory(gt_masks_dir);
  InstanceTable gt_table;
  if (score) gt_table = InstanceTable::Read(gt_table_path);
  seg::SegmentationEvaluator raw_scores, refined_scores;
  LoopSegmentationScores loop_scores;
  loop_scores.segmenter = segmenter->name();

  if (!options.refined_masks_dir.empty()) {
    std::error_code error;
    fs::create_directories(options.refined_masks_dir, error);
    if (error) throw FileError(options.refined_masks_dir, "cannot create: " + error.message());
    seg::WriteMaskFolderRecord(options.refined_masks_dir, sequence);
  }

  SlamRunResult result;
  const int total = options.max_frames > 0 ? std::min<int>(options.max_frames, static_cast<int>(sequence.size()))
                                           : static_cast<int>(sequence.size());
  FrameReader frames(sequence, total, options.read_ahead);
  for (int i = 0; i < total; ++i) {
    RgbdFrame frame = frames.Next();
    frame.index = i;
    const mutual::MutualFrameResult step = loop.ProcessFrame(frame);
    AddFrame(step.slam, &result);
    result.refine_ms.push_back(step.refine_ms);
    loop_scores.refined_from_previous += step.refined_from_previous;
    for (const seg::RegionDecision& decision : step.decisions) {
      ++loop_scores.decision_counts[static_cast<int>(decision.kind)];
    }
    const std::string stem = sequence.FrameStem(static_cast<size_t>(i));
    if (score) {
      const fs::path gt_path = gt_masks_dir / (stem + ".png");
      const cv::Mat gt_ids = sequence.LoadInstanceMask(gt_path);
      raw_scores.AddFrame(gt_ids, gt_table, step.initial);
      refined_scores.AddFrame(gt_ids, gt_table, step.refined);
    }
    if (!options.refined_masks_dir.empty()) {
      seg::WriteExternalMaskFiles(options.refined_masks_dir, stem,
                                  sequence.InstanceMaskAsStored(step.refined.ToIdImage(frame.color_bgr.size())),
                                  step.refined);
    }
    if (options.on_frame) options.on_frame(i + 1, total);
  }
  if (score) {
    loop_scores.raw = raw_scores.Scores();
    loop_scores.refined = refined_scores.Scores();
    loop_scores.refine_ms_median = result.refine_ms.empty() ? 0 : Median(result.refine_ms);
    result.segmentation = std::move(loop_scores);
  }
  result.long_term_map = loop.tracker().ExportLongTermMap(false);
  result.long_term_map.description = "segslam long-term map of " + sequence.dir().string() + ", mode mutual, " +
                                     "segmenter " + segmenter->name();
  result.keyframes = static_cast<int>(loop.tracker().map().keyframes().size());
  result.map_points = static_cast<int>(loop.tracker().map().NumGoodPoints());
  return result;
}

}  // namespace

double SlamRunResult::LocalizedShare() const {
  if (frames.empty()) return 0;
  const auto localized = std::count_if(frames.begin(), frames.end(), [](const auto& f) { return f.localized_on_map(); });
  return double(localized) / double(frames.size());
}

double SlamRunResult::MedianTrackingMs() const {
  std::vector<double> times;
  for (const auto& frame : frames) times.push_back(frame.timings.TrackingMs());
  return times.empty() ? 0 : Median(std::move(times));
}

SlamRunResult RunSlamOnSequence(const TumSequence& sequence, const SlamRunOptions& options) {
  if (options.mode == slam::SlamMode::kOracle && (!options.segmenter.empty() || options.masks != "gt")) {
    throw Error("mode oracle takes the dataset's ground-truth masks, whose ids the ground-truth tracks name: "
                "no segmenter or external masks");
  }
  if (options.mode == slam::SlamMode::kMutual && (!options.segmenter.empty() || options.masks != "gt")) {
    return RunMutualLoop(sequence, options);
  }
  slam::Tracker tracker(sequence.camera().intrinsics, options.tracker);
  if (!options.map_in.empty()) {
    tracker.LoadLongTermMap(slam::LoadLongTermMap(options.map_in), options.map_in.string());
  }
  std::unique_ptr<MaskSource> masks;
  if (options.mode != slam::SlamMode::kPlain) masks = std::make_unique<MaskSource>(sequence, options);

  SlamRunResult result;
  const int total = options.max_frames > 0 ? std::min<int>(options.max_frames, static_cast<int>(sequence.size()))
                                           : static_cast<int>(sequence.size());
  FrameReader frames(sequence, total, options.read_ahead);
  for (int i = 0; i < total; ++i) {
    const RgbdFrame frame = frames.Next();
    slam::FrameInstances instances;
    if (masks != nullptr) instances = masks->Load(frame);
    const slam::FrameResult frame_result = tracker.Track(frame, masks ? &instances : nullptr, options.mode);
    AddFrame(frame_result, &result);
    if (options.on_frame) options.on_frame(i + 1, total);
  }
  // The plain baseline knows no instances, so its long-term map is everything it mapped;
  // mask-moveable never mapped a moveable object; mutual and the oracle keep the
  // background only.
  const bool knows_instances = options.mode == slam::SlamMode::kMutual || options.mode == slam::SlamMode::kOracle;
  result.long_term_map = tracker.ExportLongTermMap(!knows_instances);
  result.long_term_map.description = "segslam long-term map of " + sequence.dir().string() + ", mode " +
                                     slam::ToString(options.mode);
  result.keyframes = static_cast<int>(tracker.map().keyframes().size());
  result.map_points = static_cast<int>(tracker.map().NumGoodPoints());
  return result;
}

void WriteFrameLog(const fs::path& path, const std::vector<slam::FrameResult>& frames) {
  std::ostringstream out;
  for (const slam::FrameResult& frame : frames) {
    nlohmann::json line;
    line["frame"] = frame.frame_index;
    line["stamp"] = frame.stamp_s;
    line["status"] = slam::ToString(frame.status);
    line["keyframe"] = frame.keyframe;
    line["map_reset"] = frame.map_reset;
    line["features"] = frame.num_features;
    line["features_with_depth"] = frame.num_features_with_depth;
    line["coarse_inliers"] = frame.num_coarse_inliers;
    line["fine_inliers"] = frame.num_fine_inliers;
    if (frame.num_long_term_inliers >= 0) {  // localization on a loaded map
      line["long_term_inliers"] = frame.num_long_term_inliers;
      line["on_long_term_map"] = frame.on_long_term_map;
    }
    const slam::FrameTimings& t = frame.timings;
    line["timings_ms"] = {{"features", t.features_ms}, {"coarse", t.coarse_ms}, {"judge", t.judge_ms},
                          {"fine", t.fine_ms},         {"map_update", t.map_update_ms},
                          {"bundle_adjustment", t.bundle_adjustment_ms}};
    nlohmann::json instances = nlohmann::json::array();
    for (const slam::InstanceJudgement& j : frame.instances) {
      instances.push_back({{"id", j.id}, {"moveable", j.moveable_class}, {"judged", j.judged},
                           {"moving", j.moving}, {"features", j.num_features}, {"measured", j.num_points},
                           {"moving_points", j.num_moving_points}, {"moving_share", j.moving_share}});
    }
    line["instances"] = instances;
    out << line.dump() << '\n';
  }
  WriteFileAtomically(path, out.str());
}

}  // namespace segslam::harness
