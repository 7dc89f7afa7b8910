#include "harness/slam_runner.h"

#include <algorithm>
#include <future>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/instances.h"
#include "core/statistics.h"
#include "seg/external_masks.h"
#include "seg/ground_truth.h"
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

// The segmenter of the run's masks; none in plain mode.
std::unique_ptr<seg::Segmenter> MakeSegmenter(const TumSequence& sequence, const SlamRunOptions& options) {
  const MaskSource& masks = options.run.masks;
  if (!mutual::UsesMasks(options.run.mode)) return nullptr;
  switch (masks.kind) {
    case MaskSource::Kind::kNone:
      throw Error("mode " + options.run.ModeName() + " needs instance masks");
    case MaskSource::Kind::kGroundTruth:
      return std::make_unique<seg::GroundTruthSegmenter>(sequence);
    case MaskSource::Kind::kExternal:
      return std::make_unique<seg::ExternalMaskSegmenter>(masks.folder, sequence,
                                                          static_cast<size_t>(std::max(0, options.max_frames)));
    case MaskSource::Kind::kSimulated: {
      return std::make_unique<seg::SimulatedSegmenter>(sequence.dir(), masks.SimulatedOptions(), masks.seed,
                                                       PresetWithOverrides(masks.preset, masks.overrides));
    }
  }
  return nullptr;
}

// Raw and refined masks of the mutual loop against the sequence's ground truth, where it
// has one (a generated sequence; not a real TUM one).
class LoopSegmentationScorer {
 public:
  explicit LoopSegmentationScorer(const TumSequence& sequence) : sequence_(sequence) {
    const fs::path table = sequence.dir() / "instances.json";
    if (!fs::exists(table) || !fs::is_directory(sequence.dir() / "masks")) return;
    table_ = InstanceTable::Read(table);
    enabled_ = true;
  }
  void Add(const mutual::FrameStep& step, int frame_index) {
    if (!enabled_) return;
    const fs::path gt_path = sequence_.dir() / "masks" / (sequence_.FrameStem(static_cast<size_t>(frame_index)) + ".png");
    const cv::Mat gt_ids = sequence_.LoadInstanceMask(gt_path);
    raw_.AddFrame(gt_ids, table_, step.initial);
    refined_.AddFrame(gt_ids, table_, step.refined);
  }
  bool enabled() const { return enabled_; }
  seg::SegmentationScores raw() const { return raw_.Scores(); }
  seg::SegmentationScores refined() const { return refined_.Scores(); }

 private:
  const TumSequence& sequence_;
  bool enabled_ = false;
  InstanceTable table_;
  seg::SegmentationEvaluator raw_, refined_;
};

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
  const RunConfig& run = options.run;
  if (run.mode == mutual::SlamMode::kOracle && run.masks.kind != MaskSource::Kind::kGroundTruth) {
    throw Error("mode oracle takes the dataset's ground-truth masks, whose ids the ground-truth tracks name: "
                "no segmenter or external masks");
  }
  const std::unique_ptr<seg::Segmenter> segmenter = MakeSegmenter(sequence, options);
  std::optional<seg::GroundTruthMotion> motion;
  if (run.mode == mutual::SlamMode::kOracle) motion.emplace(sequence.dir());
  mutual::FramePipelineOptions pipeline_options;
  pipeline_options.mode = run.mode;
  pipeline_options.refine_masks = run.RefinesMasks();
  pipeline_options.tracker = options.tracker;
  pipeline_options.refiner = options.refiner;
  mutual::FramePipeline pipeline(sequence.camera().intrinsics, pipeline_options, segmenter.get(),
                                 motion ? &*motion : nullptr);
  if (!options.map_in.empty()) {
    pipeline.LoadLongTermMap(slam::LoadLongTermMap(options.map_in), options.map_in.string());
  }
  const bool refines = run.RefinesMasks();
  std::optional<LoopSegmentationScorer> scorer;
  LoopSegmentationScores loop_scores;
  if (refines) {
    scorer.emplace(sequence);
    loop_scores.segmenter = segmenter->name();
  }
  const bool write_refined = refines && !options.refined_masks_dir.empty();
  if (write_refined) {
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
    const mutual::FrameStep step = pipeline.ProcessFrame(frame);
    if (step.refined_in_loop) {
      result.refine_ms.push_back(step.refine_ms);
      loop_scores.refined_from_previous += step.refined_from_previous;
      for (const seg::RegionDecision& decision : step.decisions) {
        ++loop_scores.decision_counts[static_cast<int>(decision.kind)];
      }
      scorer->Add(step, i);
    }
    if (write_refined) {
      seg::WriteExternalMaskFiles(options.refined_masks_dir, sequence.FrameStem(static_cast<size_t>(i)),
                                  sequence.InstanceMaskAsStored(step.refined.ToIdImage(frame.color_bgr.size())),
                                  step.refined);
    }
    if (options.on_frame) options.on_frame(i + 1, total);
  }
  if (scorer.has_value() && scorer->enabled()) {
    loop_scores.raw = scorer->raw();
    loop_scores.refined = scorer->refined();
    loop_scores.refine_ms_median = result.refine_ms.empty() ? 0 : Median(result.refine_ms);
    result.segmentation = std::move(loop_scores);
  }
  result.frames = pipeline.frames();
  result.trajectory = pipeline.trajectory();
  result.long_term_map = pipeline.ExportLongTermMap();
  result.long_term_map.description = "segslam long-term map of " + sequence.dir().string() + ", mode " +
                                     run.ModeName() +
                                     (refines ? ", segmenter " + segmenter->name() : std::string());
  result.keyframes = static_cast<int>(pipeline.tracker().map().keyframes().size());
  result.map_points = static_cast<int>(pipeline.tracker().map().NumGoodPoints());
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
    line["retracked"] = frame.retracked;
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
