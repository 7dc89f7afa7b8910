// The systems the bench compares (DESIGN.md "Baselines"). Each is one way through the
// frame pipeline (mutual/frame_pipeline.h), which is the only place a mode is acted on.
#pragma once

#include <string>
#include <vector>

namespace segslam::mutual {

enum class SlamMode {
  kPlain,         // no masks at all (ORB-SLAM2-like)
  kMaskMoveable,  // every feature on a moveable-class instance dropped (DynaSLAM-like)
  kMutual,        // the paper's loop: moving/static judgement per instance, from the
                  // depth of its pixels (slam::TrackerOptions::judge_by_depth)
  kMutualSparse,  // the same loop judging from re-found sparse features, as the paper does
  kOracle,        // mutual with the ground truth's verdicts (seg::GroundTruthMotion):
                  // mutual as it would run if its judgement were never wrong
};

std::string ToString(SlamMode mode);
// Every mode's name, the baselines first: the order of the paper's tables.
const std::vector<std::string>& SlamModeNames();
// The modes of the paper's tables, which a scenario runs unless told otherwise (the
// oracle needs the ground truth and is asked for by name).
const std::vector<std::string>& PaperModeNames();
// Throws segslam::Error listing the valid names.
SlamMode ParseSlamMode(const std::string& name);

// Which instance masks a mode reads: none for plain.
inline bool UsesMasks(SlamMode mode) { return mode != SlamMode::kPlain; }
// Whether a mode judges instances moving or static (and so keeps only the background in
// its long-term map).
inline bool JudgesInstances(SlamMode mode) {
  return mode == SlamMode::kMutual || mode == SlamMode::kMutualSparse || mode == SlamMode::kOracle;
}
// Whether a mode runs the paper's whole loop, refining the segmenter's masks with SLAM.
inline bool IsMutualLoop(SlamMode mode) { return mode == SlamMode::kMutual || mode == SlamMode::kMutualSparse; }

}  // namespace segslam::mutual
