#include "harness/slam_runner.h"

#include <algorithm>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "seg/external_masks.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

// The instance masks of each frame, from the dataset's ground truth or an external folder.
class MaskSource {
 public:
  MaskSource(const TumSequence& sequence, const std::string& masks) : sequence_(sequence) {
    if (masks == "gt") {
      const fs::path table = sequence.dir() / "instances.json";
      if (!fs::exists(table)) {
        throw FileError(table, "missing: ground-truth masks need the dataset's instance table "
                               "(or give --masks DIR with external masks)");
      }
      const InstanceTable instances = InstanceTable::Read(table);
      for (const InstanceInfo& info : instances.instances()) {
        if (info.moveable) moveable_.insert(info.id);
      }
      table_ = instances;
    } else {
      external_ = std::make_unique<seg::ExternalMaskSegmenter>(masks, sequence);
    }
  }

  slam::FrameInstances Load(const RgbdFrame& frame) {
    slam::FrameInstances instances;
    if (external_ == nullptr) {
      const fs::path path = sequence_.dir() / "masks" /
                            (fs::path(sequence_.entries()[static_cast<size_t>(frame.index)].rgb_file).stem().string() + ".png");
      instances.ids = ReadInstanceMask(path);
      if (instances.ids.size() != frame.color_bgr.size()) {
        throw FileError(path, "mask size differs from the frame's");
      }
      CheckMaskIds(instances.ids, table_, path.string());
      instances.moveable_ids = moveable_;
      return instances;
    }
    const seg::FrameSegmentation segmentation = external_->Segment(frame);
    instances.ids = segmentation.ToIdImage(frame.color_bgr.size());
    for (const seg::InstanceMask& instance : segmentation.instances) {
      if (IsMoveableCategory(instance.category_id)) instances.moveable_ids.insert(instance.track_id);
    }
    return instances;
  }

 private:
  const TumSequence& sequence_;
  InstanceTable table_;
  std::unordered_set<std::uint16_t> moveable_;
  std::unique_ptr<seg::ExternalMaskSegmenter> external_;
};

}  // namespace

double SlamRunResult::LocalizedShare() const {
  if (frames.empty()) return 0;
  const auto localized = std::count_if(frames.begin(), frames.end(), [](const auto& f) { return f.localized(); });
  return double(localized) / double(frames.size());
}

double SlamRunResult::MedianTrackingMs() const {
  std::vector<double> times;
  for (const auto& frame : frames) times.push_back(frame.timings.TrackingMs());
  if (times.empty()) return 0;
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  return times[times.size() / 2];
}

SlamRunResult RunSlamOnSequence(const TumSequence& sequence, const SlamRunOptions& options) {
  slam::Tracker tracker(sequence.camera().intrinsics, options.tracker);
  if (!options.map_in.empty()) {
    tracker.LoadLongTermMap(slam::LoadLongTermMap(options.map_in), options.map_in.string());
  }
  std::unique_ptr<MaskSource> masks;
  if (options.mode != slam::SlamMode::kPlain) masks = std::make_unique<MaskSource>(sequence, options.masks);

  SlamRunResult result;
  const int total = options.max_frames > 0 ? std::min<int>(options.max_frames, static_cast<int>(sequence.size()))
                                           : static_cast<int>(sequence.size());
  for (int i = 0; i < total; ++i) {
    const RgbdFrame frame = sequence.LoadFrame(static_cast<size_t>(i));
    slam::FrameInstances instances;
    if (masks != nullptr) instances = masks->Load(frame);
    const slam::FrameResult frame_result = tracker.Track(frame, masks ? &instances : nullptr, options.mode);
    if (frame_result.localized()) result.trajectory.push_back({frame.stamp_s, frame_result.T_wc});
    result.frames.push_back(frame_result);
    if (options.on_frame) options.on_frame(i + 1, total);
  }
  // The plain baseline knows no instances, so its long-term map is everything it mapped;
  // mask-moveable never mapped a moveable object; mutual keeps the background only.
  result.long_term_map = tracker.ExportLongTermMap(options.mode != slam::SlamMode::kMutual);
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
    line["features"] = frame.num_features;
    line["features_with_depth"] = frame.num_features_with_depth;
    line["coarse_inliers"] = frame.num_coarse_inliers;
    line["fine_inliers"] = frame.num_fine_inliers;
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
