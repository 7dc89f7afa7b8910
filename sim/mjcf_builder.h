// Turns a scenes::World into MuJoCo MJCF text. Internal to sim/ (the renderer uses it);
// no MuJoCo type appears here, so tests can inspect the text without a GL context.
//
// Layout of the generated model:
//   - every static geom is a geom of the worldbody;
//   - every Part of every Object is a mocap body "obj<k>_part<j>" holding its geoms,
//     posed each frame by the renderer;
//   - the camera is a mocap body "segslam_camera" carrying camera "segslam_camera"
//     rotated 180 deg about x, so that the body pose is the optical-frame T_wc;
//   - each world texture i is a 2D texture "tex<i>" declared as a flat builtin of the
//     image's size; its pixels are copied into the model after compilation;
//   - a textured box becomes a mesh with per-face vertices and texture coordinates in
//     texture copies (tile_size_m per copy, image up = +z on vertical faces); a
//     textured plane uses texrepeat = plane size / tile size.
//   - near/far clipping: statistic extent 1, map znear = near_m, zfar = far_m.
//   - no contacts (contype = conaffinity = 0), no shadows unless asked, no MSAA
//     (offsamples 0, so that segmentation colours are never blended).
#pragma once

#include <string>
#include <vector>

#include "scenes/world.h"

namespace segslam::sim {

struct MjcfOptions {
  bool shadows = false;  // let directional lights cast shadows (costs ~2x render time)
  int shadow_size = 2048;  // shadow map size in pixels when shadows are on, > 0
};

struct MjcfModel {
  std::string xml;
  std::vector<std::string> texture_names;            // [world texture index]
  std::vector<std::vector<std::string>> part_bodies;  // [object index][part index]
  std::string camera_body;                             // mocap body carrying the camera
  std::string camera;                                  // the camera's name
};

// Names used in the model.
std::string TextureName(int texture_index);
std::string PartBodyName(int object_index, int part_index);

// Builds the model text. Throws segslam::Error for an invalid world (a material or
// texture index out of range, a non-positive size where one is required, a camera
// with non-positive size or clipping planes with near >= far).
MjcfModel BuildMjcf(const scenes::World& world, const MjcfOptions& options = {});

}  // namespace segslam::sim
