#include "sim/world_renderer.h"

#include <mujoco/mujoco.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <array>
#include <cstring>
#include <mutex>

#include "core/error.h"
#include "sim/mjcf_builder.h"

namespace segslam::sim {
namespace {

// MuJoCo reports fatal errors through mju_user_error and then exits the process;
// turn them into exceptions instead (MuJoCo's C code is built with unwind tables).
[[noreturn]] void ThrowMujocoError(const char* message) {
  throw Error(std::string("MuJoCo: ") + message);
}

void InstallErrorHandler() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (mju_user_error == nullptr) mju_user_error = ThrowMujocoError;
  });
}

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};

// Compiles MJCF text through MuJoCo's virtual file system (no temporary files).
mjModel* CompileMjcf(const std::string& xml) {
  constexpr const char* kName = "segslam_world.xml";
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  if (mj_makeEmptyFileVFS(&vfs, kName, static_cast<int>(xml.size())) != 0) {
    throw Error("MuJoCo: cannot create the in-memory MJCF file");
  }
  const int index = mj_findFileVFS(&vfs, kName);
  std::memcpy(vfs.filedata[index], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(kName, &vfs, error, sizeof error);
  mj_deleteVFS(&vfs);
  if (m == nullptr) throw Error(std::string("MuJoCo cannot compile the world's MJCF: ") + error);
  return m;
}

}  // namespace

struct WorldRenderer::Impl {
  scenes::World world;
  RenderOptions options;
  MjcfModel mjcf;
  std::unique_ptr<GlContext> gl;
  std::unique_ptr<mjModel, ModelDeleter> model;
  std::unique_ptr<mjData, DataDeleter> data;
  mjvScene scene;
  mjrContext context;
  mjvOption vis_option;
  mjvCamera camera;
  bool scene_made = false;
  bool context_made = false;
  int width = 0;
  int height = 0;
  double near_m = 0;
  double far_m = 0;
  int camera_mocap = -1;
  std::vector<std::vector<int>> part_mocap;  // [object][part] -> mocap index
  std::vector<std::uint16_t> geom_instance;  // [model geom] -> instance id (0 = none)
  std::vector<int> geom_object;              // [model geom] -> object index, -1 = static
  std::vector<char> object_hidden;           // [object]
  // Read-back buffers (bottom-up rows, as GL gives them).
  std::vector<unsigned char> rgb;
  std::vector<float> depth;     // of the full scene
  std::vector<float> id_depth;  // of the id pass (instances only)
  std::array<Eigen::Vector3d, 4> frustum_side_normals;  // camera frame, unit

  ~Impl() {
    if (context_made) mjr_freeContext(&context);
    if (scene_made) mjv_freeScene(&scene);
  }

  void UploadTextures();
  void IndexBodies();
  void MakeRenderContext(GlBackend backend);
  void SetRenderOptions();
  void ComputeFrustum();
  void PrepareScene(const Eigen::Isometry3d& T_wc);
  bool OutsideView(const mjvGeom& geom, const Eigen::Isometry3d& T_cw) const;
  void ReadDepth(RenderedFrame* frame);
  void RenderInstanceIds(const mjrRect& viewport, bool have_full_depth, RenderedFrame* frame);
};

// The id pass draws only the geoms of instances, in MuJoCo's segmentation colours
// (lighting and textures off, colour = segid + 1 = r + 256 g + 65536 b). Static
// scenery covers most of the image and is id 0 anyway, so leaving it out makes this
// pass several times cheaper on a software rasteriser. Occlusion by scenery is restored
// by comparing with the full scene's depth buffer (`depth`, from the colour pass): the
// same triangles rasterised with the same transforms give bit-identical depth, so an
// instance pixel whose depth is not the full scene's depth is hidden behind scenery.
void WorldRenderer::Impl::RenderInstanceIds(const mjrRect& viewport, bool have_full_depth,
                                            RenderedFrame* frame) {
  const int full_ngeom = scene.ngeom;
  std::vector<mjvGeom> all_geoms(scene.geoms, scene.geoms + full_ngeom);
  std::vector<std::uint16_t> segid_instance(1, 0);  // [segid + 1] -> instance id
  int kept = 0;
  for (int i = 0; i < full_ngeom; ++i) {
    const mjvGeom& g = all_geoms[i];
    const bool is_instance = g.objtype == mjOBJ_GEOM && g.objid >= 0 && geom_instance[g.objid] != 0;
    // Without a full-scene depth to compare with, every geom must be drawn.
    if (!is_instance && have_full_depth) continue;
    scene.geoms[kept] = g;
    scene.geoms[kept].segid = kept;
    scene.geoms[kept].rgba[3] = 1.0f;  // opaque: nothing may be blended
    segid_instance.push_back(is_instance ? geom_instance[g.objid] : 0);
    ++kept;
  }
  scene.ngeom = kept;
  scene.flags[mjRND_SEGMENT] = 1;
  scene.flags[mjRND_IDCOLOR] = 1;
  mjr_render(viewport, &scene, &context);
  scene.flags[mjRND_SEGMENT] = 0;
  scene.flags[mjRND_IDCOLOR] = 0;
  std::copy(all_geoms.begin(), all_geoms.end(), scene.geoms);
  scene.ngeom = full_ngeom;

  if (have_full_depth) {
    id_depth.resize(depth.size());
    mjr_readPixels(rgb.data(), id_depth.data(), viewport, &context);
  } else {
    mjr_readPixels(rgb.data(), depth.data(), viewport, &context);
    ReadDepth(frame);
  }
  // Depth buffers hold 24-bit values; a few quanta of slack absorb float conversion.
  constexpr float kSameDepth = 4.0f / (1 << 24);
  frame->instance_ids.create(height, width, CV_16U);
  for (int r = 0; r < height; ++r) {
    const size_t row = static_cast<size_t>(height - 1 - r) * width;
    const unsigned char* src = rgb.data() + 3 * row;
    std::uint16_t* dst = frame->instance_ids.ptr<std::uint16_t>(r);
    for (int c = 0; c < width; ++c) {
      const unsigned v = src[3 * c] + 256u * src[3 * c + 1] + 65536u * src[3 * c + 2];
      std::uint16_t id = v < segid_instance.size() ? segid_instance[v] : 0;
      if (id != 0 && have_full_depth && std::abs(id_depth[row + c] - depth[row + c]) > kSameDepth) {
        id = 0;
      }
      dst[c] = id;
    }
  }
}

void WorldRenderer::Impl::UploadTextures() {
  mjModel* m = model.get();
  for (size_t i = 0; i < world.textures.size(); ++i) {
    const int id = mj_name2id(m, mjOBJ_TEXTURE, mjcf.texture_names[i].c_str());
    const cv::Mat& bgr = world.textures[i].image_bgr;
    if (id < 0 || m->tex_width[id] != bgr.cols || m->tex_height[id] != bgr.rows) {
      throw Error(fmt::format("MuJoCo: texture '{}' missing or of unexpected size",
                              mjcf.texture_names[i]));
    }
    // tex_rgb rows are in image order (row 0 = the top of the picture, as MuJoCo loads
    // PNG files), RGB bytes.
    cv::Mat rgb_view(bgr.rows, bgr.cols, CV_8UC3, m->tex_rgb + m->tex_adr[id]);
    cv::cvtColor(bgr, rgb_view, cv::COLOR_BGR2RGB);
  }
}

// Whether a geom's bounding sphere lies wholly outside the camera's view frustum.
// MuJoCo hands every geom of the model to GL; a city has thousands, most of them
// behind or beside the camera, and llvmpipe spends its time transforming their
// vertices. Dropping them first changes no pixel.
bool WorldRenderer::Impl::OutsideView(const mjvGeom& geom, const Eigen::Isometry3d& T_cw) const {
  if (geom.objtype != mjOBJ_GEOM || geom.objid < 0) return false;
  const double radius = model->geom_rbound[geom.objid];
  if (radius <= 0) return false;  // planes: unbounded for MuJoCo, always drawn
  const Eigen::Vector3d p = T_cw * Eigen::Vector3d(geom.pos[0], geom.pos[1], geom.pos[2]);
  if (p.z() + radius < near_m || p.z() - radius > far_m) return true;
  // Side planes through the optical centre; normals point out of the frustum.
  for (const Eigen::Vector3d& normal : frustum_side_normals) {
    if (normal.dot(p) > radius) return true;
  }
  return false;
}

// Poses the camera, runs kinematics and fills MuJoCo's abstract scene with the
// geoms that can be seen (hidden objects and geoms outside the view removed,
// segmentation ids renumbered).
void WorldRenderer::Impl::PrepareScene(const Eigen::Isometry3d& T_wc) {
  mjModel* m = model.get();
  mjData* d = data.get();
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_camlight(m, d);
  mjv_updateScene(m, d, &vis_option, nullptr, &camera, mjCAT_STATIC | mjCAT_DYNAMIC, &scene);
  const Eigen::Isometry3d T_cw = T_wc.inverse();
  int kept = 0;
  for (int i = 0; i < scene.ngeom; ++i) {
    const mjvGeom& g = scene.geoms[i];
    if (g.objtype == mjOBJ_GEOM && g.objid >= 0) {
      const int object = geom_object[g.objid];
      if (object >= 0 && object_hidden[object]) continue;
    }
    if (OutsideView(g, T_cw)) continue;
    if (kept != i) scene.geoms[kept] = g;
    scene.geoms[kept].segid = kept;
    ++kept;
  }
  scene.ngeom = kept;
}

// Metric depth from the non-linear depth buffer, flipped to top-down rows.
void WorldRenderer::Impl::ReadDepth(RenderedFrame* frame) {
  cv::Mat buffer(height, width, CV_32F, depth.data());
  cv::Mat out(height, width, CV_32F);
  const float n = static_cast<float>(near_m), f = static_cast<float>(far_m);
  for (int r = 0; r < height; ++r) {
    const float* src = buffer.ptr<float>(height - 1 - r);
    float* dst = out.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      const float z = src[c];
      dst[c] = z >= 1.0f ? 0.0f : n * f / (f - z * (f - n));
    }
  }
  frame->depth_m = out;
}

// Mocap indices of the camera and of every object part, and which object (and instance)
// each model geom belongs to.
void WorldRenderer::Impl::IndexBodies() {
  const mjModel* m = model.get();
  const int camera_body = mj_name2id(m, mjOBJ_BODY, mjcf.camera_body.c_str());
  camera_mocap = camera_body >= 0 ? m->body_mocapid[camera_body] : -1;
  if (camera_mocap < 0) throw Error("MuJoCo: the camera body is not a mocap body");
  geom_instance.assign(m->ngeom, 0);
  geom_object.assign(m->ngeom, -1);
  std::vector<int> body_object(m->nbody, -1);
  part_mocap.resize(world.objects.size());
  for (size_t k = 0; k < world.objects.size(); ++k) {
    for (const std::string& name : mjcf.part_bodies[k]) {
      const int body = mj_name2id(m, mjOBJ_BODY, name.c_str());
      if (body < 0 || m->body_mocapid[body] < 0) {
        throw Error("MuJoCo: part body '" + name + "' missing or not mocap");
      }
      part_mocap[k].push_back(m->body_mocapid[body]);
      body_object[body] = static_cast<int>(k);
    }
  }
  for (int g = 0; g < m->ngeom; ++g) {
    const int object = body_object[m->geom_bodyid[g]];
    geom_object[g] = object;
    if (object >= 0) geom_instance[g] = world.objects[object].instance_id;
  }
  object_hidden.assign(world.objects.size(), 1);
}

// The GL context, then MuJoCo's render context drawing into its off-screen buffer.
void WorldRenderer::Impl::MakeRenderContext(GlBackend backend) {
  const mjModel* m = model.get();
  gl = std::make_unique<GlContext>(backend, width, height);
  mjv_defaultScene(&scene);
  mjv_makeScene(m, &scene, m->ngeom + 16);
  scene_made = true;
  mjr_defaultContext(&context);
  mjr_makeContext(m, &context, mjFONTSCALE_50);
  context_made = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &context);
  if (context.currentBuffer != mjFB_OFFSCREEN) {
    throw Error("MuJoCo: the off-screen framebuffer is not available");
  }
  if (context.offWidth < width || context.offHeight < height) {
    throw Error("MuJoCo: off-screen buffer smaller than the camera image");
  }
}

// No decorations: only geoms of static and dynamic bodies, no frames, labels, light or
// camera markers; no reflections, skybox, fog or (unless asked) shadows. The view is the
// model's camera.
void WorldRenderer::Impl::SetRenderOptions() {
  mjv_defaultOption(&vis_option);
  for (int i = 0; i < mjNVISFLAG; ++i) vis_option.flags[i] = 0;
  vis_option.flags[mjVIS_STATIC] = 1;
  vis_option.flags[mjVIS_TEXTURE] = 1;
  vis_option.frame = mjFRAME_NONE;
  vis_option.label = mjLABEL_NONE;
  for (int i = 0; i < mjNGROUP; ++i) vis_option.geomgroup[i] = 1;
  scene.flags[mjRND_SHADOW] = options.shadows ? 1 : 0;
  scene.flags[mjRND_WIREFRAME] = 0;
  scene.flags[mjRND_REFLECTION] = 0;
  scene.flags[mjRND_ADDITIVE] = 0;
  scene.flags[mjRND_SKYBOX] = 0;
  scene.flags[mjRND_FOG] = 0;
  scene.flags[mjRND_HAZE] = 0;
  scene.flags[mjRND_SEGMENT] = 0;
  scene.flags[mjRND_IDCOLOR] = 0;
  scene.flags[mjRND_CULL_FACE] = 1;  // closed geoms: back faces are never seen
  mjv_defaultCamera(&camera);
  camera.type = mjCAMERA_FIXED;
  camera.fixedcamid = mj_name2id(model.get(), mjOBJ_CAMERA, mjcf.camera.c_str());
}

// Frustum side planes of the optical frame, a little wider than the image so that
// rounding never drops a geom that touches the border.
void WorldRenderer::Impl::ComputeFrustum() {
  const PinholeCamera intrinsics = PinholeCamera::FromVerticalFov(width, height, world.camera.fovy_deg);
  const double tan_x = 1.02 * 0.5 * width / intrinsics.fx;
  const double tan_y = 1.02 * 0.5 * height / intrinsics.fy;
  frustum_side_normals = {Eigen::Vector3d(1, 0, -tan_x).normalized(), Eigen::Vector3d(-1, 0, -tan_x).normalized(),
                          Eigen::Vector3d(0, 1, -tan_y).normalized(), Eigen::Vector3d(0, -1, -tan_y).normalized()};
}

WorldRenderer::WorldRenderer(const scenes::World& world, GlBackend backend,
                             RenderOptions options)
    : impl_(std::make_unique<Impl>()) {
  InstallErrorHandler();
  Impl& s = *impl_;
  s.world = world;
  s.options = options;
  MjcfOptions mjcf_options;
  mjcf_options.shadows = options.shadows;
  s.mjcf = BuildMjcf(world, mjcf_options);
  s.width = world.camera.width;
  s.height = world.camera.height;

  s.model.reset(CompileMjcf(s.mjcf.xml));
  s.data.reset(mj_makeData(s.model.get()));
  s.near_m = s.model->vis.map.znear * s.model->stat.extent;
  s.far_m = s.model->vis.map.zfar * s.model->stat.extent;
  s.UploadTextures();
  s.IndexBodies();
  s.MakeRenderContext(backend);
  s.SetRenderOptions();
  s.ComputeFrustum();
  s.rgb.resize(static_cast<size_t>(s.width) * s.height * 3);
  s.depth.resize(static_cast<size_t>(s.width) * s.height);
}

WorldRenderer::~WorldRenderer() {
  // MuJoCo's GL objects must be freed while their context is current.
  if (impl_ && impl_->gl) {
    try {
      impl_->gl->MakeCurrent();
    } catch (const Error&) {
    }
  }
}

PinholeCamera WorldRenderer::intrinsics() const {
  const scenes::CameraSpec& c = impl_->world.camera;
  return PinholeCamera::FromVerticalFov(c.width, c.height, c.fovy_deg);
}

void WorldRenderer::SetPartPoses(const std::vector<std::vector<Eigen::Isometry3d>>& poses) {
  Impl& s = *impl_;
  if (poses.size() != s.world.objects.size()) {
    throw Error(fmt::format("SetPartPoses: {} objects given, the world has {}", poses.size(),
                            s.world.objects.size()));
  }
  mjData* d = s.data.get();
  for (size_t k = 0; k < poses.size(); ++k) {
    if (poses[k].empty()) {
      s.object_hidden[k] = 1;
      continue;
    }
    if (poses[k].size() != s.part_mocap[k].size()) {
      throw Error(fmt::format("SetPartPoses: object {} has {} parts, {} poses given", k,
                              s.part_mocap[k].size(), poses[k].size()));
    }
    s.object_hidden[k] = 0;
    for (size_t j = 0; j < poses[k].size(); ++j) {
      const int id = s.part_mocap[k][j];
      const Eigen::Vector3d t = poses[k][j].translation();
      Eigen::Quaterniond q(poses[k][j].linear());
      q.normalize();
      mjtNum* pos = d->mocap_pos + 3 * id;
      mjtNum* quat = d->mocap_quat + 4 * id;
      pos[0] = t.x(); pos[1] = t.y(); pos[2] = t.z();
      quat[0] = q.w(); quat[1] = q.x(); quat[2] = q.y(); quat[3] = q.z();
    }
  }
}

void WorldRenderer::SetScene(scenes::Pass pass, double stamp_s) {
  std::vector<std::vector<Eigen::Isometry3d>> poses;
  poses.reserve(impl_->world.objects.size());
  for (const scenes::Object& object : impl_->world.objects) {
    poses.push_back(scenes::PartPosesAt(object, pass, stamp_s));
  }
  SetPartPoses(poses);
}

RenderedFrame WorldRenderer::RenderFrom(const Eigen::Isometry3d& T_wc) {
  Impl& s = *impl_;
  mjData* d = s.data.get();
  // The camera body is the optical frame; its camera is rotated into MuJoCo's convention.
  {
    const Eigen::Vector3d t = T_wc.translation();
    Eigen::Quaterniond q(T_wc.linear());
    q.normalize();
    mjtNum* pos = d->mocap_pos + 3 * s.camera_mocap;
    mjtNum* quat = d->mocap_quat + 4 * s.camera_mocap;
    pos[0] = t.x(); pos[1] = t.y(); pos[2] = t.z();
    quat[0] = q.w(); quat[1] = q.x(); quat[2] = q.y(); quat[3] = q.z();
  }
  s.PrepareScene(T_wc);
  const mjrRect viewport = {0, 0, s.width, s.height};
  RenderedFrame frame;
  const bool ids = s.options.render_ids;
  const bool color = s.options.render_color || !ids;  // depth needs at least one pass

  if (color) {
    s.scene.flags[mjRND_SEGMENT] = 0;
    s.scene.flags[mjRND_IDCOLOR] = 0;
    mjr_render(viewport, &s.scene, &s.context);
    mjr_readPixels(s.options.render_color ? s.rgb.data() : nullptr, s.depth.data(), viewport,
                   &s.context);
    s.ReadDepth(&frame);
    if (s.options.render_color) {
      cv::Mat rgb(s.height, s.width, CV_8UC3, s.rgb.data());
      cv::Mat flipped;
      cv::flip(rgb, flipped, 0);
      cv::cvtColor(flipped, frame.color_bgr, cv::COLOR_RGB2BGR);
    }
  }
  if (ids) s.RenderInstanceIds(viewport, color, &frame);
  // Where nothing was hit, the sky colour.
  if (!frame.color_bgr.empty()) {
    const Eigen::Vector3f& sky = s.world.sky_rgb;
    const cv::Vec3b sky_bgr(cv::saturate_cast<uchar>(sky.z() * 255.f),
                            cv::saturate_cast<uchar>(sky.y() * 255.f),
                            cv::saturate_cast<uchar>(sky.x() * 255.f));
    frame.color_bgr.setTo(sky_bgr, frame.depth_m == 0);
  }
  return frame;
}

RenderedFrame WorldRenderer::Render(scenes::Pass pass, double stamp_s) {
  SetScene(pass, stamp_s);
  return RenderFrom(scenes::CameraPoseAt(impl_->world, pass, stamp_s));
}

std::string WorldRenderer::gl_renderer() const { return impl_->gl->renderer(); }
const std::string& WorldRenderer::mjcf() const { return impl_->mjcf.xml; }
int WorldRenderer::geom_count() const { return impl_->model->ngeom; }

}  // namespace segslam::sim
