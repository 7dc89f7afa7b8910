#include "mutual/slam_mode.h"

#include "core/error.h"

namespace segslam::mutual {

std::string ToString(SlamMode mode) {
  switch (mode) {
    case SlamMode::kPlain: return "plain";
    case SlamMode::kMaskMoveable: return "mask-moveable";
    case SlamMode::kMutual: return "mutual";
    case SlamMode::kMutualSparse: return "mutual-sparse";
    case SlamMode::kOracle: return "oracle";
  }
  return "?";
}

const std::vector<std::string>& SlamModeNames() {
  static const std::vector<std::string> names = {ToString(SlamMode::kPlain), ToString(SlamMode::kMaskMoveable),
                                                 ToString(SlamMode::kMutual), ToString(SlamMode::kMutualSparse),
                                                 ToString(SlamMode::kOracle)};
  return names;
}

const std::vector<std::string>& PaperModeNames() {
  static const std::vector<std::string> names = {ToString(SlamMode::kPlain), ToString(SlamMode::kMaskMoveable),
                                                 ToString(SlamMode::kMutual)};
  return names;
}

SlamMode ParseSlamMode(const std::string& name) {
  for (const SlamMode mode :
       {SlamMode::kPlain, SlamMode::kMaskMoveable, SlamMode::kMutual, SlamMode::kMutualSparse, SlamMode::kOracle}) {
    if (name == ToString(mode)) return mode;
  }
  throw Error("unknown SLAM mode '" + name + "' (expected plain, mask-moveable, mutual, mutual-sparse or oracle)");
}

}  // namespace segslam::mutual
