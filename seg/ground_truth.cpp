#include "seg/ground_truth.h"

#include "core/error.h"
#include "core/instances.h"
#include "core/tracks.h"

namespace segslam::seg {

namespace fs = std::filesystem;

GroundTruthSegmenter::GroundTruthSegmenter(const TumSequence& sequence) : sequence_(sequence) {
  const fs::path table_path = sequence.dir() / "instances.json";
  if (!fs::exists(table_path)) {
    throw FileError(table_path, "missing: ground-truth masks need the dataset's instance table "
                                "(or give --masks DIR with external masks)");
  }
  const InstanceTable table = InstanceTable::Read(table_path);
  for (const InstanceInfo& info : table.instances()) {
    categories_[info.id] = ExternalDetection{info.category_id, 1.0f};
  }
}

FrameSegmentation GroundTruthSegmenter::Segment(const RgbdFrame& frame) {
  if (frame.index < 0) throw FileError(sequence_.dir(), "negative frame index " + std::to_string(frame.index));
  const fs::path path = sequence_.dir() / "masks" / (sequence_.FrameStem(static_cast<size_t>(frame.index)) + ".png");
  const cv::Mat ids = sequence_.LoadInstanceMask(path);  // Checks its type and size.
  const cv::Size frame_size = !frame.color_bgr.empty() ? frame.color_bgr.size() : ids.size();
  return ExternalMasksToSegmentation(ids, categories_, frame_size, frame.index,
                                     path.string() + " (table " + (sequence_.dir() / "instances.json").string() + ")");
}

GroundTruthMotion::GroundTruthMotion(const fs::path& sequence_dir) {
  const fs::path tracks = sequence_dir / "tracks.json";
  if (!fs::exists(tracks)) {
    throw FileError(tracks, "missing: mode oracle takes which instances move from the ground-truth tracks");
  }
  for (const ObjectTrack& track : ReadTracks(tracks)) {
    for (const TrackSample& sample : track.samples) {
      if (sample.moving) moving_by_frame_[sample.frame].insert(track.instance_id);
    }
  }
}

const std::unordered_set<std::uint16_t>& GroundTruthMotion::MovingIds(int frame_index) const {
  const auto found = moving_by_frame_.find(frame_index);
  return found != moving_by_frame_.end() ? found->second : none_;
}

}  // namespace segslam::seg
