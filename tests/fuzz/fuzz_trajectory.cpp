// Fuzz target: TUM trajectories (core/pose.h, "timestamp tx ty tz qx qy qz qw" lines),
// as groundtruth.txt and every run's trajectory.txt are read. A trajectory that reads
// must hold finite stamps that increase and rigid poses, and interpolate between them.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/pose.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace segslam;
  const auto file = fuzz::WriteScratch("trajectory.txt", data, size);
  std::vector<StampedPose> poses;
  if (fuzz::Refused([&] { poses = ReadTumTrajectory(file); })) return 0;

  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto& pose = poses[i];
    if (!std::isfinite(pose.stamp_s) || !pose.T_wc.matrix().allFinite()) {
      fuzz::PropertyBroken("a trajectory with a non-finite value was accepted, line " + std::to_string(i + 1));
    }
    const double det = pose.T_wc.linear().determinant();
    if (std::abs(det - 1.0) > 1e-6) {
      fuzz::PropertyBroken("an accepted pose's rotation has determinant " + std::to_string(det));
    }
    if (i > 0) {
      const Eigen::Isometry3d mid = InterpolatePose(poses[i - 1].T_wc, pose.T_wc, 0.5);
      if (!mid.matrix().allFinite()) fuzz::PropertyBroken("interpolation gave a non-finite pose");
    }
  }
  return 0;
}
