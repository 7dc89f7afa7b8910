// The ground truth of a generated sequence as the bench feeds it to the frame pipeline:
// its instance masks as a segmenter that is never wrong, and which instances truly move
// in each frame (the oracle's verdicts). Both read what `segslam generate` writes
// (docs/formats.md): masks/<stem>.png with instances.json, and tracks.json.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <unordered_set>

#include "core/tum_dataset.h"
#include "seg/external_masks.h"
#include "seg/segmenter.h"

namespace segslam::seg {

// The sequence's ground-truth instance masks: each instance its true id as track id,
// its true COCO category, score 1.
class GroundTruthSegmenter : public Segmenter {
 public:
  // Throws segslam::Error naming instances.json when it is missing or unreadable.
  explicit GroundTruthSegmenter(const TumSequence& sequence);

  // Throws segslam::Error naming the mask file when it is unreadable, of the wrong type
  // or size, or holds an id instances.json lacks.
  FrameSegmentation Segment(const RgbdFrame& frame) override;
  std::string name() const override { return "gt"; }

 private:
  TumSequence sequence_;
  std::map<std::uint16_t, ExternalDetection> categories_;  // instance id -> category, score 1
};

// Which instances move in each frame of a generated sequence (tracks.json: "moving" since
// the frame before).
class GroundTruthMotion {
 public:
  // Throws segslam::Error naming tracks.json when it is missing or malformed.
  explicit GroundTruthMotion(const std::filesystem::path& sequence_dir);

  // The ids that moved since frame `frame_index - 1`; empty where none did.
  const std::unordered_set<std::uint16_t>& MovingIds(int frame_index) const;

 private:
  std::map<int, std::unordered_set<std::uint16_t>> moving_by_frame_;
  std::unordered_set<std::uint16_t> none_;
};

}  // namespace segslam::seg
