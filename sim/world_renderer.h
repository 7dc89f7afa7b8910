// Off-screen rendering of a scenes::World with MuJoCo: colour, metric depth and
// instance ids from a camera in the optical convention (x right, y down, z forward).
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <vector>

#include "core/camera.h"
#include "scenes/world.h"
#include "sim/gl_context.h"

namespace segslam::sim {

struct RenderedFrame {
  cv::Mat color_bgr;     // CV_8UC3, BGR; the world's sky colour where nothing was hit
  cv::Mat depth_m;       // CV_32F, metres along the optical axis, 0 where nothing was hit
  cv::Mat instance_ids;  // CV_16U, Object::instance_id, 0 = background / static scenery
};

struct RenderOptions {
  bool shadows = false;      // directional lights cast shadows (about 2x the colour pass time)
  bool render_color = true;  // render the colour image; false leaves color_bgr empty
  bool render_ids = true;    // render instance ids; false leaves instance_ids empty
  // Depth is always rendered (from the id pass when there is one, else the colour pass).
};

// Owns a GL context, the MuJoCo model built from the world (see mjcf_builder.h) and
// MuJoCo's scene and render context. All calls must come from the thread that
// constructed it (or call MakeCurrent-equivalent by constructing per thread). Not
// copyable. Rendering the same scene twice gives identical bytes.
class WorldRenderer {
 public:
  // Throws segslam::Error when the world is invalid, the MJCF does not compile (the
  // message carries MuJoCo's reason), or the GL back-end is unavailable.
  WorldRenderer(const scenes::World& world, GlBackend backend, RenderOptions options = {});
  ~WorldRenderer();
  WorldRenderer(const WorldRenderer&) = delete;
  WorldRenderer& operator=(const WorldRenderer&) = delete;

  // PinholeCamera::FromVerticalFov(world.camera.width, height, fovy_deg).
  PinholeCamera intrinsics() const;

  // Places every object's parts for time `stamp_s` of `pass` (scenes::PartPosesAt);
  // objects absent from the pass are removed from the rendered scene (no colour, no
  // depth, no id).
  void SetScene(scenes::Pass pass, double stamp_s);
  // Lower level: world poses of the parts of each object, in world.objects order and
  // part order; an empty vector hides that object. Throws segslam::Error if the sizes
  // do not match the world.
  void SetPartPoses(const std::vector<std::vector<Eigen::Isometry3d>>& part_poses);

  // Renders the current scene from camera pose T_wc (optical frame, camera-to-world).
  RenderedFrame RenderFrom(const Eigen::Isometry3d& T_wc);
  // SetScene(pass, stamp_s) then RenderFrom(scenes::CameraPoseAt(world, pass, stamp_s)).
  RenderedFrame Render(scenes::Pass pass, double stamp_s);

  std::string gl_renderer() const;
  const std::string& mjcf() const;  // the generated model text, for debugging
  int geom_count() const;           // geoms in the compiled model

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace segslam::sim
