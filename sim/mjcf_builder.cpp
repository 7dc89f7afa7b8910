#include "sim/mjcf_builder.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace segslam::sim {
namespace {

// Shortest round-trip text of a double (MJCF numbers).
std::string Num(double v) { return fmt::format("{}", v); }
std::string Num(float v) { return fmt::format("{}", v); }

std::string Vec3(const Eigen::Vector3d& v) {
  return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z());
}

std::string Rgb(const Eigen::Vector3f& v) {
  return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z());
}

// "pos=... quat=..." of a rigid transform (MuJoCo quaternions are w x y z).
std::string PoseAttributes(const Eigen::Isometry3d& T) {
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  return fmt::format("pos=\"{}\" quat=\"{} {} {} {}\"", Vec3(T.translation()), Num(q.w()),
                     Num(q.x()), Num(q.y()), Num(q.z()));
}

const char* ShapeName(scenes::Shape shape) {
  switch (shape) {
    case scenes::Shape::kBox: return "box";
    case scenes::Shape::kCylinder: return "cylinder";
    case scenes::Shape::kCapsule: return "capsule";
    case scenes::Shape::kSphere: return "sphere";
    case scenes::Shape::kEllipsoid: return "ellipsoid";
    case scenes::Shape::kPlane: return "plane";
  }
  return "box";
}

// A box as 6 faces x 4 vertices with texture coordinates in texture copies, from
// `offset` at each face's top-left corner: vertical faces: u to the right seen from
// outside, v down (image up = +z); horizontal faces: u along +x, v along -y.
std::string BoxMeshAsset(const std::string& name, const Eigen::Vector3d& h,
                         const Eigen::Vector2d& tile, const Eigen::Vector2d& offset) {
  struct Face {
    Eigen::Vector3d normal, right, down;  // unit axes in the geom frame
  };
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  const std::array<Face, 6> faces = {{
      {X, Y, -Z}, {-X, -Y, -Z}, {Y, -X, -Z}, {-Y, X, -Z},  // vertical faces
      {Z, X, -Y}, {-Z, X, Y},                              // top, bottom
  }};
  std::ostringstream vertex, face, texcoord;
  int base = 0;
  for (const Face& f : faces) {
    // Half extents along the face's axes.
    const double hr = h.dot(f.right.cwiseAbs());
    const double hd = h.dot(f.down.cwiseAbs());
    const double hn = h.dot(f.normal.cwiseAbs());
    const Eigen::Vector3d centre = f.normal * hn;
    // Corners in order: top-left, top-right, bottom-right, bottom-left (seen from outside).
    const std::array<Eigen::Vector2d, 4> rd = {Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, -1),
                                               Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1)};
    for (const Eigen::Vector2d& c : rd) {
      const Eigen::Vector3d p = centre + f.right * (c.x() * hr) + f.down * (c.y() * hd);
      vertex << Vec3(p) << "  ";
      // Distance from the face's top-left corner along right and down, in copies.
      const double u = offset.x() + (c.x() + 1) * hr / tile.x();
      const double v = offset.y() + (c.y() + 1) * hd / tile.y();
      texcoord << Num(u) << " " << Num(v) << "  ";
    }
    // right x down = -normal, so (tl, tr, br) is clockwise seen from outside; emit
    // counter-clockwise triangles (tl, br, tr) and (tl, bl, br).
    face << base << " " << base + 2 << " " << base + 1 << "  " << base << " " << base + 3
         << " " << base + 2 << "  ";
    base += 4;
  }
  return fmt::format("    <mesh name=\"{}\" vertex=\"{}\" face=\"{}\" texcoord=\"{}\"/>\n", name,
                     vertex.str(), face.str(), texcoord.str());
}

// MuJoCo 2.2.2's mjrContext keeps the names of 100 textures (its arrays are sized 100,
// although mjMAXTEXTURE says 1000); the 101st and later overwrite the display lists'
// bases, and no texture is drawn any more.
constexpr size_t kMaxTextures = 100;

void CheckWorld(const scenes::World& world) {
  const scenes::CameraSpec& c = world.camera;
  if (c.width <= 0 || c.height <= 0) {
    throw Error(fmt::format("world '{}': camera size {}x{} must be positive", world.name,
                            c.width, c.height));
  }
  if (!(c.fovy_deg > 0 && c.fovy_deg < 180)) {
    throw Error(fmt::format("world '{}': camera fovy_deg {} not in (0, 180)", world.name,
                            c.fovy_deg));
  }
  if (!(c.near_m > 0 && c.far_m > c.near_m)) {
    throw Error(fmt::format("world '{}': camera clipping near {} far {} need 0 < near < far",
                            world.name, c.near_m, c.far_m));
  }
  for (size_t i = 0; i < world.materials.size(); ++i) {
    const int t = world.materials[i].texture;
    if (t < -1 || t >= static_cast<int>(world.textures.size())) {
      throw Error(fmt::format("world '{}': material {} has texture index {} out of range",
                              world.name, i, t));
    }
  }
  if (world.textures.size() > kMaxTextures) {
    throw Error(fmt::format("world '{}': {} textures, more than MuJoCo's renderer holds ({}); "
                            "pack pictures into fewer textures",
                            world.name, world.textures.size(), kMaxTextures));
  }
  for (size_t i = 0; i < world.textures.size(); ++i) {
    const scenes::Texture& t = world.textures[i];
    if (t.image_bgr.empty() || t.image_bgr.type() != CV_8UC3) {
      throw Error(fmt::format("world '{}': texture {} ('{}') is not a non-empty CV_8UC3 image",
                              world.name, i, t.name));
    }
    if (!(t.tile_size_m.x() > 0 && t.tile_size_m.y() > 0)) {
      throw Error(fmt::format("world '{}': texture {} ('{}') tile size must be positive",
                              world.name, i, t.name));
    }
  }
}

// One MJCF <material>; texrepeat: texture copies across the geom (see BuildMjcf).
std::string MaterialXml(const std::string& name, const scenes::Material& mat,
                        const Eigen::Vector2d& texrepeat) {
  std::string tex;
  if (mat.texture >= 0) {
    tex = fmt::format(" texture=\"{}\" texrepeat=\"{} {}\" texuniform=\"false\"",
                      TextureName(mat.texture), Num(texrepeat.x()), Num(texrepeat.y()));
  }
  return fmt::format(
      "    <material name=\"{}\"{} rgba=\"{} {} {} {}\" specular=\"{}\" shininess=\"{}\" "
      "reflectance=\"0\" emission=\"0\"/>\n",
      name, tex, Num(mat.rgba[0]), Num(mat.rgba[1]), Num(mat.rgba[2]), Num(mat.rgba[3]),
      Num(mat.specular), Num(mat.shininess));
}

// The size attribute of a geom, in MJCF's per-type layout.
std::string GeomSize(const scenes::Geom& g) {
  switch (g.shape) {
    case scenes::Shape::kBox:
    case scenes::Shape::kEllipsoid: return Vec3(g.size);
    case scenes::Shape::kCylinder:
    case scenes::Shape::kCapsule: return Num(g.size.x()) + " " + Num(g.size.y());
    case scenes::Shape::kSphere: return Num(g.size.x());
    case scenes::Shape::kPlane:
      // Third value: spacing of the grid MuJoCo draws the plane with (metres).
      return Num(g.size.x()) + " " + Num(g.size.y()) + " 1";
  }
  return Vec3(g.size);
}

// The <asset> section, which grows as geoms are written: a textured box becomes a mesh
// with texture coordinates of its own, a textured plane a material with its own repeat.
class AssetSection {
 public:
  explicit AssetSection(const scenes::World& world) : world_(world) {}

  // One texture per world texture (its pixels are uploaded by the renderer); returns
  // their names.
  std::vector<std::string> AddTextures() {
    std::vector<std::string> names;
    for (size_t i = 0; i < world_.textures.size(); ++i) {
      const cv::Mat& img = world_.textures[i].image_bgr;
      names.push_back(TextureName(static_cast<int>(i)));
      xml_ << fmt::format(
          "    <texture name=\"{}\" type=\"2d\" builtin=\"flat\" width=\"{}\" height=\"{}\" "
          "rgb1=\"1 1 1\" rgb2=\"1 1 1\"/>\n",
          names.back(), img.cols, img.rows);
    }
    return names;
  }

  // One material per world material, texrepeat 1: boxes as meshes carry their own
  // texture coordinates.
  void AddMaterials() {
    for (size_t i = 0; i < world_.materials.size(); ++i) {
      xml_ << MaterialXml(fmt::format("mat{}", i), world_.materials[i], Eigen::Vector2d(1, 1));
    }
  }

  // A <geom> element, adding what it needs to the assets.
  std::string Geom(const scenes::Geom& g, const std::string& indent) {
    const int id = geom_count_++;
    if (g.material < 0 || g.material >= static_cast<int>(world_.materials.size())) {
      throw Error(fmt::format("world '{}': geom {} has material index {} out of range",
                              world_.name, id, g.material));
    }
    const scenes::Material& mat = world_.materials[g.material];
    const bool textured = mat.texture >= 0;
    const std::string pose = PoseAttributes(g.T_parent_geom);
    if (textured && g.shape == scenes::Shape::kBox) {
      const std::string mesh = fmt::format("box{}", id);
      const Eigen::Vector2d tile = mat.texture_tile_m.x() > 0 ? mat.texture_tile_m : world_.textures[mat.texture].tile_size_m;
      xml_ << BoxMeshAsset(mesh, g.size, tile, mat.texture_origin);
      return fmt::format("{}<geom type=\"mesh\" mesh=\"{}\" material=\"mat{}\" {}/>\n", indent,
                         mesh, g.material, pose);
    }
    std::string material = fmt::format("mat{}", g.material);
    if (textured && g.shape == scenes::Shape::kPlane && mat.texture_tile_m.x() > 0) {
      // A plane repeats its material's whole texture; a window of one is for boxes only.
      throw Error(fmt::format("world '{}': plane geom {} has material '{}' with a texture window (boxes only)",
                              world_.name, id, mat.name));
    }
    if (textured && g.shape == scenes::Shape::kPlane) {
      const Eigen::Vector2d& tile = world_.textures[mat.texture].tile_size_m;
      material = fmt::format("mat{}_plane{}", g.material, id);
      xml_ << MaterialXml(material, mat,
                          Eigen::Vector2d(2 * g.size.x() / tile.x(), 2 * g.size.y() / tile.y()));
    }
    return fmt::format("{}<geom type=\"{}\" size=\"{}\" material=\"{}\" {}/>\n", indent,
                       ShapeName(g.shape), GeomSize(g), material, pose);
  }

  std::string Xml() const { return "  <asset>\n" + xml_.str() + "  </asset>\n"; }

 private:
  const scenes::World& world_;
  std::ostringstream xml_;
  int geom_count_ = 0;
};

// A mocap body per object part, named by PartBodyName, each holding its geoms. They start
// far below the ground; the renderer poses (or hides) every part per frame.
std::string ObjectBodies(const scenes::World& world, AssetSection* assets,
                         std::vector<std::vector<std::string>>* part_bodies) {
  std::ostringstream body;
  part_bodies->assign(world.objects.size(), {});
  for (size_t k = 0; k < world.objects.size(); ++k) {
    const scenes::Object& obj = world.objects[k];
    for (size_t j = 0; j < obj.parts.size(); ++j) {
      const std::string name = PartBodyName(static_cast<int>(k), static_cast<int>(j));
      (*part_bodies)[k].push_back(name);
      body << fmt::format("    <body name=\"{}\" mocap=\"true\" pos=\"0 0 -1e4\">\n", name);
      for (const scenes::Geom& g : obj.parts[j].geoms) body << assets->Geom(g, "      ");
      body << "    </body>\n";
    }
  }
  return body.str();
}

std::string LightsXml(const std::vector<scenes::Light>& lights, const MjcfOptions& options) {
  std::ostringstream xml;
  for (const scenes::Light& l : lights) {
    xml << fmt::format(
        "    <light directional=\"{}\" pos=\"{}\" dir=\"{}\" diffuse=\"{}\" ambient=\"{}\" "
        "specular=\"{}\" castshadow=\"{}\"{}/>\n",
        l.directional ? "true" : "false", Vec3(l.position), Vec3(l.direction.normalized()),
        Rgb(l.diffuse), Rgb(l.ambient), Rgb(l.specular), options.shadows ? "true" : "false",
        // MuJoCo's lights are 45-degree spotlights by default; a ceiling lamp lights the
        // whole room, so positional lights become point lights (GL's cutoff 180).
        l.directional ? "" : " cutoff=\"180\" exponent=\"0\"");
  }
  return xml.str();
}

// Everything before the assets: compiler, simulation options, rendering settings and
// defaults.
std::string HeaderXml(const scenes::World& world, const MjcfOptions& options) {
  const scenes::CameraSpec& cam = world.camera;
  std::ostringstream xml;
  xml << fmt::format("<mujoco model=\"{}\">\n", world.name.empty() ? "segslam" : world.name);
  xml << "  <compiler angle=\"radian\"/>\n";
  // Nothing is simulated: every part is a mocap body posed per frame. Without contacts,
  // the compiler's forward pass skips collision detection, whose broad phase takes stack
  // in proportion to the number of bodies: a crowded city (90 pedestrians, two passes of
  // traffic) overflowed MuJoCo's default stack at load time.
  xml << "  <option timestep=\"0.01\">\n    <flag contact=\"disable\"/>\n  </option>\n";
  // extent 1: the near/far planes are znear/zfar in metres exactly.
  xml << "  <statistic extent=\"1\" center=\"0 0 0\"/>\n";
  xml << "  <visual>\n";
  xml << fmt::format("    <global offwidth=\"{}\" offheight=\"{}\" fovy=\"{}\"/>\n", cam.width,
                     cam.height, Num(cam.fovy_deg));
  // Tessellation of cylinders, capsules, spheres and ellipsoids: MuJoCo's defaults
  // (28 slices, 16 stacks, 4x4 quads per box face) made the city vertex-bound on llvmpipe
  // (60 ms per colour pass); 12 x 8 keeps trees and people round at 640x480 in 30 ms.
  xml << fmt::format("    <quality shadowsize=\"{}\" offsamples=\"0\" numslices=\"12\" "
                     "numstacks=\"8\" numquads=\"1\"/>\n",
                     options.shadows ? options.shadow_size : 0);
  xml << fmt::format("    <map znear=\"{}\" zfar=\"{}\" haze=\"0\"/>\n", Num(cam.near_m),
                     Num(cam.far_m));
  // The head light only when the world brings no light of its own.
  xml << fmt::format("    <headlight active=\"{}\"/>\n", world.lights.empty() ? 1 : 0);
  xml << "  </visual>\n";
  xml << "  <default>\n    <geom contype=\"0\" conaffinity=\"0\" group=\"0\"/>\n  </default>\n";
  return xml.str();
}

}  // namespace

std::string TextureName(int texture_index) { return fmt::format("tex{}", texture_index); }
std::string PartBodyName(int object_index, int part_index) {
  return fmt::format("obj{}_part{}", object_index, part_index);
}

MjcfModel BuildMjcf(const scenes::World& world, const MjcfOptions& options) {
  CheckWorld(world);
  MjcfModel out;
  AssetSection assets(world);
  out.texture_names = assets.AddTextures();
  assets.AddMaterials();

  std::ostringstream body;  // worldbody content
  for (const scenes::Geom& g : world.static_geoms) body << assets.Geom(g, "    ");
  body << ObjectBodies(world, &assets, &out.part_bodies);
  out.camera_body = "segslam_camera";
  out.camera = "segslam_camera";
  // The optical frame (x right, y down, z forward) is MuJoCo's camera frame (looking
  // along -z, y up) rotated 180 deg about x: quaternion (w x y z) = (0 1 0 0).
  body << fmt::format(
      "    <body name=\"{}\" mocap=\"true\">\n"
      "      <camera name=\"{}\" fovy=\"{}\" pos=\"0 0 0\" quat=\"0 1 0 0\"/>\n"
      "    </body>\n",
      out.camera_body, out.camera, Num(world.camera.fovy_deg));

  out.xml = HeaderXml(world, options) + assets.Xml() + "  <worldbody>\n" +
            LightsXml(world.lights, options) + body.str() + "  </worldbody>\n</mujoco>\n";
  return out;
}

}  // namespace segslam::sim
