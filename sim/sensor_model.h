// Makes a perfect render look like a Kinect-like RGB-D sensor: depth noise growing with
// depth squared, disparity quantization, a valid depth range, dropout on depth edges,
// RGB noise and optional motion blur.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>

#include "core/camera.h"
#include "scenes/scenario.h"
#include "sim/world_renderer.h"

namespace segslam::sim {

// Deterministic: the noise of a frame depends only on (seed, pass_index, frame_index),
// never on thread order or on other frames. Stateless after construction, so one
// instance may be shared by threads.
class SensorModel {
 public:
  // Stereo baseline of the disparity model (Kinect-like), metres.
  static constexpr double kBaselineM = 0.075;
  // Disparity resolution of the quantization, pixels.
  static constexpr double kDisparityStepPx = 1.0 / 8.0;
  // A pixel is on a depth edge when the depth range of its 3x3 neighbourhood exceeds
  // this share of its depth.
  static constexpr double kEdgeRelativeRange = 0.05;

  // `camera`: intrinsics of the frames (fx gives the disparity scale, the centre the
  // motion-blur probe). `kind_default_max_depth_m`: the far limit used when
  // spec.max_depth_m is 0 (e.g. 10 m indoors, 40 m outdoors). `fps`: frame rate, for
  // the motion blur (share of the frame interval the shutter is open).
  SensorModel(const scenes::SensorSpec& spec, const PinholeCamera& camera,
              double kind_default_max_depth_m, double fps);

  // Applies the model in place. `T_wc_prev` and `T_wc` (camera-to-world, optical frame,
  // previous and current frame) are used only for motion blur. A disabled spec leaves
  // the frame untouched. Empty images in `frame` are skipped.
  void Apply(std::uint64_t seed, int pass_index, int frame_index,
             const Eigen::Isometry3d& T_wc_prev, const Eigen::Isometry3d& T_wc,
             RenderedFrame* frame) const;

  // The far limit in use, metres.
  double max_depth_m() const { return max_depth_m_; }

 private:
  scenes::SensorSpec spec_;
  PinholeCamera camera_;
  double max_depth_m_;
  double fps_;
};

}  // namespace segslam::sim
