// A TUM fr3-like office: a textured room, desks with monitors and clutter, chairs,
// people walking around the desk or sitting at it, and a hand-held camera moving as in
// TUM's xyz / static / rpy / halfsphere sequences.
//
// Room frame: origin on the floor at the room centre, x toward the back wall the camera
// faces, y left, z up. The main desk stands near the back wall; the camera is in front
// of it.
#include "scenes/builder.h"
#include "scenes/person.h"
#include "scenes/textures.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace segslam::scenes {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

constexpr double kDeskHeightM = 0.75;
constexpr double kDeg = M_PI / 180.0;
constexpr double kChairFootprintM = 0.31;  // the five-star base

Vec3 At(const Vec2& p, double z) { return Vec3(p.x(), p.y(), z); }

// A rectangle of a surface things stand on (desk top or floor strip), room frame.
struct Surface {
  Vec2 centre;
  Vec2 half;       // along the surface's own axes
  double yaw = 0;  // of the surface's axes
  double z = 0;
};

// A footprint taken on a surface.
struct Spot {
  Vec2 p;
  double radius;
};

class OfficeBuilder {
 public:
  explicit OfficeBuilder(const Scenario& s) : s_(s), spec_(s.office), b_(&world_) {
    X_ = spec_.room_size_m[0];
    Y_ = spec_.room_size_m[1];
    Z_ = spec_.room_size_m[2];
    desk_ = Vec2(X_ / 2 - 2.1, 0.0);
  }

  World Build() {
    world_.name = s_.name;
    world_.kind = "office";
    world_.seed = s_.seed;
    world_.camera = s_.camera;
    world_.sky_rgb = Eigen::Vector3f(0.2f, 0.2f, 0.2f);
    world_.frames_per_pass = {spec_.frames, spec_.frames};
    MakeLook();
    MakeRoom();
    MakeCamera();
    MakeDesks();
    MakeSitters();
    MakeClutter();
    RecordSittersArmObstacles();
    MakeWalkers();
    MakeLights();
    RecordSecondPassChanges(&world_, candidates_);
    return std::move(world_);
  }

 private:
  std::mt19937_64 Rng(const std::string& tag, std::uint64_t i = 0) const {
    return std::mt19937_64(SubSeed(s_.seed, tag, i));
  }
  int Mat(const std::string& name, int texture, Eigen::Vector4f rgba = Eigen::Vector4f(1, 1, 1, 1), float spec = 0.1f) {
    return b_.AddMaterial(name, texture, rgba, spec);
  }
  int Tex(const std::string& name, cv::Mat img, double u, double v) {
    return b_.AddTexture(name, std::move(img), Vec2(u, v));
  }
  void Static(const Geom& g) { world_.static_geoms.push_back(g); }

  // ---- Materials ---------------------------------------------------------------------
  void MakeLook() {
    const std::uint64_t seed = s_.seed;
    wall_ = Mat("wall", Tex("wall", WallTexture(SubSeed(seed, "wall")), 2.0, 2.0));
    carpet_ = Mat("carpet", Tex("carpet", CarpetTexture(SubSeed(seed, "carpet")), 2.0, 2.0));
    ceiling_ = Mat("ceiling", Tex("ceiling", CeilingTexture(SubSeed(seed, "ceiling")), 2.4, 2.4));
    const int wood_t = Tex("wood", WoodTexture(SubSeed(seed, "wood")), 1.6, 1.6);
    wood_ = Mat("desk_wood", wood_t);
    door_ = Mat("door_wood", wood_t, Eigen::Vector4f(0.7f, 0.6f, 0.5f, 1));
    whiteboard_ = Mat("whiteboard", Tex("whiteboard", WhiteboardTexture(SubSeed(seed, "whiteboard")), 2.0, 1.0), Eigen::Vector4f(1, 1, 1, 1), 0.4f);
    spines_ = Mat("spines", Tex("spines", SpinesTexture(SubSeed(seed, "spines")), 0.9, 0.32));
    for (int i = 0; i < 6; ++i) {
      posters_.push_back(Mat("poster", Tex("poster_" + std::to_string(i), PosterTexture(SubSeed(seed, "poster", i)), 0.6, 0.8)));
    }
    for (int i = 0; i < 4; ++i) {
      screens_.push_back(Mat("screen", Tex("screen_" + std::to_string(i), ScreenTexture(SubSeed(seed, "screen", i)), 0.52, 0.32), Eigen::Vector4f(1, 1, 1, 1), 0.5f));
    }
    keyboard_ = Mat("keyboard", Tex("keyboard", KeyboardTexture(SubSeed(seed, "keyboard")), 0.44, 0.14));
    for (int i = 0; i < 4; ++i) {
      prints_.push_back(Tex("print_" + std::to_string(i), PrintTexture(SubSeed(seed, "print", i)), 0.25, 0.12));
    }
    for (int i = 0; i < 5; ++i) {
      clothes_.push_back(Tex("cloth_" + std::to_string(i), ClothTexture(SubSeed(seed, "cloth", i), i), 0.5, 0.5));
    }
    skin_t_ = Tex("skin", SkinTexture(SubSeed(seed, "skin")), 0.2, 0.2);
    black_ = Mat("black_plastic", -1, Eigen::Vector4f(0.06f, 0.06f, 0.07f, 1), 0.3f);
    grey_ = Mat("grey_plastic", -1, Eigen::Vector4f(0.45f, 0.46f, 0.48f, 1), 0.3f);
    metal_ = Mat("metal", -1, Eigen::Vector4f(0.7f, 0.72f, 0.74f, 1), 0.6f);
    fabric_ = Mat("chair_fabric", clothes_[4], Eigen::Vector4f(0.25f, 0.28f, 0.4f, 1));
    light_ = Mat("ceiling_light", -1, Eigen::Vector4f(1, 1, 0.97f, 1), 0.9f);
    window_ = Mat("window_view", Tex("window_view", FacadeTexture(SubSeed(seed, "view"), FacadeStyle::kBrick, 3, 4), 2.6, 2.0), Eigen::Vector4f(1.15f, 1.15f, 1.2f, 1));
    plant_ = Mat("leaves", -1, Eigen::Vector4f(0.15f, 0.45f, 0.15f, 1));
  }

  // ---- Room --------------------------------------------------------------------------
  void MakeRoom() {
    std::mt19937_64 rng = Rng("room");
    const double t = 0.05;  // half wall thickness
    Static(MakeBox(Vec3(0, 0, -t), Vec3(X_ / 2, Y_ / 2, t), carpet_));
    Static(MakeBox(Vec3(0, 0, Z_ + t), Vec3(X_ / 2, Y_ / 2, t), ceiling_));
    Static(MakeBox(Vec3(X_ / 2 + t, 0, Z_ / 2), Vec3(t, Y_ / 2 + 2 * t, Z_ / 2), wall_));
    Static(MakeBox(Vec3(-X_ / 2 - t, 0, Z_ / 2), Vec3(t, Y_ / 2 + 2 * t, Z_ / 2), wall_));
    Static(MakeBox(Vec3(0, Y_ / 2 + t, Z_ / 2), Vec3(X_ / 2, t, Z_ / 2), wall_));
    Static(MakeBox(Vec3(0, -Y_ / 2 - t, Z_ / 2), Vec3(X_ / 2, t, Z_ / 2), wall_));
    // Baseboards.
    Static(MakeBox(Vec3(X_ / 2 - 0.01, 0, 0.05), Vec3(0.01, Y_ / 2, 0.05), grey_));
    Static(MakeBox(Vec3(0, Y_ / 2 - 0.01, 0.05), Vec3(X_ / 2, 0.01, 0.05), grey_));
    Static(MakeBox(Vec3(0, -Y_ / 2 + 0.01, 0.05), Vec3(X_ / 2, 0.01, 0.05), grey_));

    // Back wall (behind the desk): whiteboard, a bookshelf and posters.
    const double bx = X_ / 2 - 0.015;
    Static(MakeBox(Vec3(bx, -0.4, 1.5), Vec3(0.015, 1.0, 0.55), whiteboard_, M_PI));
    Static(MakeBox(Vec3(bx - 0.03, -0.4, 0.93), Vec3(0.04, 0.8, 0.015), grey_));  // marker tray
    const double shelf_y = std::min(1.9, Y_ / 2 - 0.6);
    MakeShelf(Vec2(X_ / 2 - 0.18, shelf_y), M_PI);
    Static(MakeBox(Vec3(bx, -1.85, 1.55), Vec3(0.01, 0.3, 0.4), posters_[0], M_PI));
    // Left wall: window with a view, a radiator, posters; right wall: door, posters.
    const double ly = Y_ / 2 - 0.015;
    Static(MakeBox(Vec3(-0.3, ly, 1.55), Vec3(1.3, 0.015, 0.8), window_, -M_PI / 2));
    for (double x : {-1.6, -0.3, 1.0}) Static(MakeBox(Vec3(x, ly - 0.02, 1.55), Vec3(0.04, 0.03, 0.82), grey_));
    Static(MakeBox(Vec3(-0.3, ly - 0.05, 0.45), Vec3(1.0, 0.05, 0.3), grey_));
    Static(MakeBox(Vec3(X_ / 2 - 0.9, ly, 1.6), Vec3(0.3, 0.01, 0.4), posters_[1], -M_PI / 2));
    const double ry = -Y_ / 2 + 0.015;
    Static(MakeBox(Vec3(-X_ / 2 + 1.2, ry, 1.05), Vec3(0.5, 0.02, 1.05), door_, M_PI / 2));
    Static(MakeBox(Vec3(-X_ / 2 + 1.55, ry + 0.05, 1.0), Vec3(0.08, 0.03, 0.015), metal_));
    for (int i = 0; i < 3; ++i) {
      Static(MakeBox(Vec3(-X_ / 2 + 2.4 + 1.1 * i + Uniform(rng, -0.2, 0.2), ry, Uniform(rng, 1.4, 1.7)),
                     Vec3(0.3, 0.01, 0.4), posters_[2 + i], M_PI / 2));
    }
    // Camera side wall: a poster and a cabinet, visible in rpy and halfsphere motions.
    Static(MakeBox(Vec3(-X_ / 2 + 0.015, 0.8, 1.5), Vec3(0.01, 0.3, 0.4), posters_[5]));
    // Ceiling lights.
    for (const Vec2& p : LightSpots()) Static(MakeBox(At(p, Z_ - 0.02), Vec3(0.6, 0.3, 0.02), light_));
    // A potted plant in the back corner (a fixed COCO object).
    Object& plant = b_.AddObject("potted plant");
    plant.parts.push_back(Part{"plant", {}});
    plant.parts[0].geoms.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.2), Vec3(0.17, 0.2, 0), door_));
    plant.parts[0].geoms.push_back(MakeShape(Shape::kEllipsoid, Vec3(0, 0, 0.75), Vec3(0.3, 0.3, 0.4), plant_));
    plant.parts[0].geoms.push_back(MakeShape(Shape::kEllipsoid, Vec3(0.08, -0.05, 1.05), Vec3(0.2, 0.22, 0.3), plant_));
    for (Placement& p : plant.placement) p.T_world_object = PoseXYZYaw(Vec3(X_ / 2 - 0.35, -Y_ / 2 + 0.35, 0), 0);
  }

  std::vector<Vec2> LightSpots() const {
    return {Vec2(desk_.x() - 1.2, 1.2), Vec2(desk_.x() - 1.2, -1.2), Vec2(desk_.x() + 0.8, 0.0)};
  }

  void MakeShelf(const Vec2& p, double yaw) {
    // A 1.2 m wide, 1.9 m tall bookshelf, books and binders on four boards.
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).matrix();
    auto put = [&](Vec3 local, Vec3 half, int mat) {
      Static(MakeShape(Shape::kBox, At(p, 0) + R * local, half, mat, R));
    };
    put(Vec3(0.16, 0, 0.95), Vec3(0.01, 0.6, 0.95), wood_);
    for (double y : {-0.6, 0.6}) put(Vec3(0, y, 0.95), Vec3(0.17, 0.015, 0.95), wood_);
    for (int k = 0; k < 5; ++k) put(Vec3(0, 0, 0.02 + 0.45 * k), Vec3(0.17, 0.6, 0.015), wood_);
    for (int k = 0; k < 4; ++k) put(Vec3(-0.02, 0, 0.035 + 0.45 * k + 0.16), Vec3(0.14, 0.57, 0.16), spines_);
  }

  // ---- Furniture and objects -------------------------------------------------------------
  Object& Rigid(const std::string& category, const Eigen::Isometry3d& T) {
    Object& o = b_.AddObject(category);
    o.parts.push_back(Part{category, {}});
    for (Placement& p : o.placement) p.T_world_object = T;
    return o;
  }

  // The desks: the main one facing the camera, others along the side walls.
  void MakeDesks() {
    std::vector<Surface> desks;
    desks.push_back({desk_, Vec2(0.4, 1.0), 0.0, kDeskHeightM});
    if (spec_.desks >= 2) desks.push_back({Vec2(desk_.x() - 0.3, Y_ / 2 - 0.45), Vec2(0.4, 0.8), M_PI / 2, kDeskHeightM});
    if (spec_.desks >= 3) desks.push_back({Vec2(desk_.x() - 0.3, -Y_ / 2 + 0.45), Vec2(0.4, 0.8), -M_PI / 2, kDeskHeightM});
    if (spec_.desks >= 4) desks.push_back({Vec2(-X_ / 2 + 0.45, -Y_ / 2 + 1.6), Vec2(0.4, 0.8), M_PI, kDeskHeightM});
    for (std::size_t d = 0; d < desks.size(); ++d) {
      const Surface& s = desks[d];
      Object& table = Rigid("dining table", PoseXYZYaw(At(s.centre, 0), s.yaw));
      auto& g = table.parts[0].geoms;
      g.push_back(MakeBox(Vec3(0, 0, kDeskHeightM - 0.015), Vec3(s.half.x(), s.half.y(), 0.015), wood_));
      for (double x : {-1.0, 1.0}) {
        for (double y : {-1.0, 1.0}) {
          g.push_back(MakeBox(Vec3(x * (s.half.x() - 0.04), y * (s.half.y() - 0.04), (kDeskHeightM - 0.03) / 2),
                              Vec3(0.025, 0.025, (kDeskHeightM - 0.03) / 2), metal_));
        }
      }
      // A modesty panel on the wall desks, on the wall side; the main desk has none, as
      // its sitters' legs go under it from the back (+x).
      if (d > 0) g.push_back(MakeBox(Vec3(s.half.x() - 0.05, 0, 0.45), Vec3(0.01, s.half.y() - 0.06, 0.25), wood_));
      // Monitors at the back edge facing the front (the main desk: at both ends, so
      // the people behind stay visible), a keyboard and a mouse in front of each.
      const std::vector<double> ys = d == 0 ? std::vector<double>{-0.72, 0.72} : std::vector<double>{0.0};
      for (double y : ys) {
        const Eigen::Isometry3d T_desk = PoseXYZYaw(At(s.centre, 0), s.yaw);
        const double turn = d == 0 ? (y > 0 ? -0.25 : 0.25) : 0.0;  // angled toward the middle
        MakeMonitor(T_desk * PoseXYZYaw(Vec3(0.15, y, kDeskHeightM), M_PI + turn));
        fixed_items_.push_back({"keyboard", T_desk * PoseXYZYaw(Vec3(-0.12, y, kDeskHeightM), M_PI)});
        fixed_items_.push_back({"mouse", T_desk * PoseXYZYaw(Vec3(-0.12, y + (y > 0 ? -0.3 : 0.3), kDeskHeightM), M_PI)});
      }
      desk_surfaces_.push_back(s);
      // Taken spots: monitors and keyboards (in surface coordinates).
      for (double y : ys) {
        taken_[d].push_back({Vec2(0.15, y), 0.3});
        taken_[d].push_back({Vec2(-0.12, y), 0.25});
        taken_[d].push_back({Vec2(-0.12, y + (y > 0 ? -0.3 : 0.3)), 0.08});
      }
    }
    // Floor strip along the right wall for bags and the like.
    desk_surfaces_.push_back({Vec2(0.3, -Y_ / 2 + 0.35), Vec2(1.8, 0.2), 0.0, 0.0});
  }

  void MakeMonitor(const Eigen::Isometry3d& T) {
    Object& o = Rigid("tv", T);
    auto& g = o.parts[0].geoms;
    std::mt19937_64 rng = Rng("monitor", world_.objects.size());
    const int screen = screens_[UniformInt(rng, 0, static_cast<int>(screens_.size()) - 1)];
    g.push_back(MakeBox(Vec3(0, 0, 0.01), Vec3(0.1, 0.12, 0.01), black_));               // foot
    g.push_back(MakeBox(Vec3(-0.03, 0, 0.17), Vec3(0.015, 0.03, 0.16), black_));          // neck
    g.push_back(MakeBox(Vec3(0, 0, 0.38), Vec3(0.025, 0.28, 0.175), black_));             // housing
    g.push_back(MakeBox(Vec3(0.026, 0, 0.385), Vec3(0.002, 0.26, 0.16), screen));        // screen
  }

  // Chairs behind the main desk, with a sitter on each.
  void MakeSitters() {
    std::mt19937_64 rng = Rng("sitters");
    const int n = spec_.people_sitting;
    for (int k = 0; k < n; ++k) {
      const double y = n == 1 ? 0.0 : -0.45 + 0.9 * k / (n - 1);
      // Facing the camera (-x); the seat centre is under the sitter's pelvis.
      const Eigen::Isometry3d T = PoseXYZYaw(Vec3(desk_.x() + 0.75, y * (n > 2 ? 1.4 : 1.0), 0), M_PI);
      MakeChair(T, /*changeable=*/false);
      Object& person = MakePerson(rng);
      person.articulation = Articulation::kSitter;
      for (Placement& p : person.placement) p.T_world_object = T;
    }
  }

  // What each sitter's arms must keep out of in each pass, once every desk item and
  // its pass-2 place are known: the boxes bounding the geoms within reach of the desks,
  // monitors, keyboards, mice and the sitter's chair (arm rests), in its frame. Small items
  // (cups, phones, books) are left out: beside them the forearm finds narrow gaps, and
  // the least fold would jump between a gap and the clear range above (a known gap: a
  // forearm may pass through a cup).
  void RecordSittersArmObstacles() {
    static const std::set<std::string> kArmObstacles = {"dining table", "tv", "keyboard", "mouse", "chair"};
    constexpr double kReachM = 1.0;  // from between the shoulders to a fingertip, largest body_scale
    for (Object& sitter : world_.objects) {
      if (sitter.articulation != Articulation::kSitter) continue;
      for (int pass = 0; pass < 2; ++pass) {
        Placement& seat = sitter.placement[pass];
        seat.arm_obstacles.clear();
        const Eigen::Isometry3d T_sitter_world = seat.T_world_object.inverse();
        const Eigen::Vector3d shoulders(0, 0, 1.0);
        for (const Object& o : world_.objects) {
          const Placement& p = o.placement[pass];
          if (o.articulation != Articulation::kRigid || !p.present || p.moving) continue;
          if (!kArmObstacles.count(o.category_name)) continue;
          // Of the chairs, the sitter's own (its arm rests); a neighbour's is beyond them.
          const bool own_chair = (p.T_world_object.translation() - seat.T_world_object.translation()).norm() < 1e-6;
          if (o.category_name == "chair" && !own_chair) continue;
          for (const Part& part : o.parts) {
            for (const Geom& g : part.geoms) {
              if (g.shape == Shape::kPlane) continue;
              Geom box = g;
              box.shape = Shape::kBox;
              box.T_parent_geom = T_sitter_world * p.T_world_object * g.T_parent_geom;
              if (g.shape == Shape::kCylinder) box.size = Vec3(g.size.x(), g.size.x(), g.size.y());
              if (g.shape == Shape::kCapsule) box.size = Vec3(g.size.x(), g.size.x(), g.size.y() + g.size.x());
              if (g.shape == Shape::kSphere) box.size = Vec3::Constant(g.size.x());
              ReachDownToTheSeat(&box);
              if ((box.T_parent_geom.translation() - shoulders).norm() - box.size.norm() < kReachM) {
                seat.arm_obstacles.push_back(box);
              }
            }
          }
        }
      }
    }
  }

  // A sitter's forearms point forward and up (SitJoints) and must meet the desk and what
  // stands on it from above: a forearm slipping under the desk top would be "clear" too, and the
  // least fold that clears would jump between under and over the desk. So an upright
  // box's underside counts down to the seat.
  static void ReachDownToTheSeat(Geom* box) {
    constexpr double kSeatTopM = 0.48;
    if (std::abs(box->T_parent_geom.linear()(2, 2)) < 0.999) return;  // tilted: left as it is
    const double top = box->T_parent_geom.translation().z() + box->size.z();
    const double bottom = box->T_parent_geom.translation().z() - box->size.z();
    if (bottom <= kSeatTopM || top <= kSeatTopM) return;
    box->size.z() = 0.5 * (top - kSeatTopM);
    box->T_parent_geom.translation().z() = 0.5 * (top + kSeatTopM);
  }

  void MakeChair(const Eigen::Isometry3d& T, bool changeable) {
    Object& o = Rigid("chair", T);
    auto& g = o.parts[0].geoms;
    g.push_back(MakeBox(Vec3(0.05, 0, 0.44), Vec3(0.23, 0.23, 0.04), fabric_));           // seat
    g.push_back(MakeBox(Vec3(-0.2, 0, 0.78), Vec3(0.04, 0.22, 0.25), fabric_));           // back
    g.push_back(MakeShape(Shape::kCylinder, Vec3(0.02, 0, 0.25), Vec3(0.03, 0.16, 0), metal_));
    for (int i = 0; i < 5; ++i) {
      const double a = 2 * M_PI * i / 5;
      const Vec3 tip(0.02 + 0.28 * std::cos(a), 0.28 * std::sin(a), 0.05);
      g.push_back(MakeRod(Vec3(0.02, 0, 0.08), tip, 0.018, black_));
      g.push_back(MakeShape(Shape::kSphere, tip - Vec3(0, 0, 0.025), Vec3(0.025, 0, 0), black_));
    }
    for (double y : {-0.24, 0.24}) g.push_back(MakeBox(Vec3(0.02, y, 0.62), Vec3(0.15, 0.02, 0.02), black_));  // arm rests
    if (changeable) changeable_.push_back({static_cast<int>(world_.objects.size()) - 1, kChairFootprintM});
  }

  Object& MakePerson(std::mt19937_64& rng) {
    Object& o = b_.AddObject("person");
    o.body_scale = Uniform(rng, 0.94, 1.06);
    o.gait_phase_offset = Uniform(rng, 0, 1);
    PersonLook look;
    const float skin = static_cast<float>(Uniform(rng, 0.4, 0.95));
    look.skin = Mat("skin", skin_t_, Eigen::Vector4f(skin, skin * 0.78f, skin * 0.64f, 1));
    const float hair = static_cast<float>(Uniform(rng, 0.05, 0.4));
    look.hair = Mat("hair", -1, Eigen::Vector4f(hair, hair * 0.75f, hair * 0.5f, 1));
    auto cloth = [&] {
      return Mat("cloth", clothes_[UniformInt(rng, 0, 4)],
                 Eigen::Vector4f(static_cast<float>(Uniform(rng, 0.15, 1)), static_cast<float>(Uniform(rng, 0.15, 1)),
                                 static_cast<float>(Uniform(rng, 0.15, 1)), 1));
    };
    look.shirt = cloth();
    look.pants = cloth();
    look.shoes = black_;
    o.parts = MakePersonParts(look, o.body_scale);
    return o;
  }

  // ---- Clutter and pass-2 changes ---------------------------------------------------------
  struct Item {
    std::string category;
    Eigen::Isometry3d T;
  };

  // Geometry of a small moveable item; returns the footprint radius.
  double ItemGeoms(std::mt19937_64& rng, const std::string& c, std::vector<Geom>& g) {
    const int print = Mat("print", prints_[UniformInt(rng, 0, 3)], Eigen::Vector4f(1, 1, 1, 1), 0.4f);
    const Eigen::Vector4f colour(static_cast<float>(Uniform(rng, 0.2, 1)), static_cast<float>(Uniform(rng, 0.2, 1)),
                                 static_cast<float>(Uniform(rng, 0.2, 1)), 1);
    const int plain = Mat(c, -1, colour, 0.3f);
    if (c == "cup") {
      g.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.05), Vec3(0.042, 0.05, 0), print));
      g.push_back(MakeBox(Vec3(0.05, 0, 0.055), Vec3(0.012, 0.006, 0.03), print));
      return 0.07;
    }
    if (c == "bottle") {
      g.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.09), Vec3(0.035, 0.09, 0), print));
      g.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.2), Vec3(0.014, 0.03, 0), plain));
      g.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.235), Vec3(0.016, 0.008, 0), black_));
      return 0.05;
    }
    if (c == "book") {
      g.push_back(MakeBox(Vec3(0, 0, 0.02), Vec3(0.11, 0.075, 0.02), print));
      g.push_back(MakeBox(Vec3(0.002, 0.002, 0.02), Vec3(0.105, 0.07, 0.018), spines_));
      return 0.14;
    }
    if (c == "laptop") {
      g.push_back(MakeBox(Vec3(0, 0, 0.01), Vec3(0.12, 0.17, 0.01), grey_));
      g.push_back(MakeBox(Vec3(-0.02, 0, 0.012), Vec3(0.07, 0.14, 0.002), keyboard_));
      Geom lid = MakeBox(Vec3(-0.13, 0, 0.12), Vec3(0.005, 0.17, 0.11), grey_);
      lid.T_parent_geom.linear() = Eigen::AngleAxisd(-15 * kDeg, Vec3::UnitY()).matrix();
      g.push_back(lid);
      Geom screen = MakeBox(Vec3(-0.123, 0, 0.12), Vec3(0.002, 0.155, 0.095), screens_[UniformInt(rng, 0, 3)]);
      screen.T_parent_geom.linear() = lid.T_parent_geom.linear();
      g.push_back(screen);
      return 0.2;
    }
    if (c == "cell phone") {
      g.push_back(MakeBox(Vec3(0, 0, 0.005), Vec3(0.075, 0.036, 0.005), black_));
      g.push_back(MakeBox(Vec3(0, 0, 0.0105), Vec3(0.068, 0.032, 0.0005), screens_[UniformInt(rng, 0, 3)]));
      return 0.08;
    }
    if (c == "remote") {
      g.push_back(MakeBox(Vec3(0, 0, 0.012), Vec3(0.09, 0.025, 0.012), black_));
      for (int i = 0; i < 4; ++i) g.push_back(MakeBox(Vec3(-0.05 + 0.03 * i, 0, 0.025), Vec3(0.006, 0.012, 0.002), plain));
      return 0.09;
    }
    if (c == "bowl") {
      g.push_back(MakeShape(Shape::kEllipsoid, Vec3(0, 0, 0.035), Vec3(0.08, 0.08, 0.035), print));
      return 0.09;
    }
    if (c == "teddy bear") {
      g.push_back(MakeShape(Shape::kSphere, Vec3(0, 0, 0.08), Vec3(0.08, 0, 0), plain));
      g.push_back(MakeShape(Shape::kSphere, Vec3(0, 0, 0.19), Vec3(0.06, 0, 0), plain));
      for (double y : {-0.04, 0.04}) g.push_back(MakeShape(Shape::kSphere, Vec3(0, y, 0.245), Vec3(0.02, 0, 0), plain));
      g.push_back(MakeShape(Shape::kSphere, Vec3(0.055, 0, 0.185), Vec3(0.018, 0, 0), black_));
      return 0.1;
    }
    if (c == "backpack" || c == "handbag") {
      const double h = c == "backpack" ? 0.22 : 0.13;
      g.push_back(MakeBox(Vec3(0, 0, h), Vec3(0.1, 0.16, h), plain));
      g.push_back(MakeBox(Vec3(0.105, 0, h * 0.8), Vec3(0.01, 0.12, h * 0.5), print));
      g.push_back(MakeRod(Vec3(0, -0.08, 2 * h), Vec3(0, 0.08, 2 * h + 0.06), 0.012, black_));
      return 0.2;
    }
    if (c == "keyboard") {
      g.push_back(MakeBox(Vec3(0, 0, 0.012), Vec3(0.07, 0.22, 0.012), keyboard_));
      return 0.24;
    }
    // mouse
    g.push_back(MakeShape(Shape::kEllipsoid, Vec3(0, 0, 0.017), Vec3(0.055, 0.032, 0.017), plain));
    return 0.07;
  }

  // A free spot on a surface for a footprint of `radius`; the room-frame pose.
  bool FreeSpot(std::mt19937_64& rng, int surface, double radius, Eigen::Isometry3d* T) {
    const Surface& s = desk_surfaces_[surface];
    for (int attempt = 0; attempt < 200; ++attempt) {
      const Vec2 p(Uniform(rng, -s.half.x() + radius, s.half.x() - radius),
                   Uniform(rng, -s.half.y() + radius, s.half.y() - radius));
      bool ok = true;
      for (const Spot& q : taken_[surface]) ok &= (p - q.p).norm() >= radius + q.radius;
      if (!ok) continue;
      taken_[surface].push_back({p, radius});
      const Eigen::Isometry3d T_surface = PoseXYZYaw(At(s.centre, s.z), s.yaw);
      *T = T_surface * PoseXYZYaw(At(p, 0), Uniform(rng, -M_PI, M_PI));
      return true;
    }
    return false;
  }

  // An item on a free spot of a suitable surface, present in pass 1 (or 2 only).
  bool AddItem(std::mt19937_64& rng, const std::string& category, bool pass2_only) {
    const bool on_floor = category == "backpack" || category == "handbag";
    std::vector<Geom> geoms;
    const double radius = ItemGeoms(rng, category, geoms);
    Eigen::Isometry3d T;
    const int floor = static_cast<int>(desk_surfaces_.size()) - 1;
    bool found = false;
    for (int tries = 0; tries < 8 && !found; ++tries) {
      const int surface = on_floor ? floor : UniformInt(rng, 0, floor - 1);
      found = FreeSpot(rng, surface, radius, &T);
    }
    if (!found) return false;
    Object& o = Rigid(category, T);
    o.parts[0].geoms = std::move(geoms);
    if (pass2_only) {
      o.placement[0].present = false;
    } else {
      changeable_.push_back({static_cast<int>(world_.objects.size()) - 1, radius});
    }
    return true;
  }

  void MakeClutter() {
    std::mt19937_64 rng = Rng("clutter");
    // Keyboards and mice in front of the monitors come first, then random items, up to
    // the budget of moveable objects (sitters' chairs count too).
    int budget = spec_.moveable_objects - spec_.people_sitting;
    for (const Item& item : fixed_items_) {
      if (budget <= 0) break;
      std::vector<Geom> geoms;
      const double radius = ItemGeoms(rng, item.category, geoms);
      Object& o = Rigid(item.category, item.T);
      o.parts[0].geoms = std::move(geoms);
      changeable_.push_back({static_cast<int>(world_.objects.size()) - 1, radius});
      --budget;
    }
    // One spare chair pushed under the side desk.
    if (budget > 0 && spec_.desks >= 2) {
      MakeChair(PoseXYZYaw(Vec3(desk_.x() - 0.3, Y_ / 2 - 0.85, 0), M_PI / 2), /*changeable=*/true);
      --budget;
    }
    static const char* kCatalog[] = {"cup", "bottle", "book", "laptop", "cell phone", "book", "cup",
                                     "remote", "bowl", "teddy bear", "backpack", "handbag", "bottle"};
    for (int k = 0; budget > 0 && k < 10 * spec_.moveable_objects + 20; ++k) {
      if (AddItem(rng, kCatalog[UniformInt(rng, 0, 12)], false)) --budget;
    }
    // Pass 2: relocate, remove, add.
    candidates_ = static_cast<int>(changeable_.size());
    const ChangePlan plan = PlanSecondPass(candidates_, s_.pass2, rng);
    for (int k : plan.relocated) {
      Object& o = world_.objects[changeable_[k].object];
      Eigen::Isometry3d T;
      if (o.category_name == "chair") {
        // Chairs are pushed elsewhere on the floor, clear of the walkers' loop.
        T = PoseXYZYaw(Vec3(-X_ / 2 + 0.6, Y_ / 2 - 0.6, 0), Uniform(rng, -M_PI, M_PI));
      } else {
        const bool on_floor = o.category_name == "backpack" || o.category_name == "handbag";
        const int floor = static_cast<int>(desk_surfaces_.size()) - 1;
        bool found = false;
        for (int tries = 0; tries < 8 && !found; ++tries) {
          found = FreeSpot(rng, on_floor ? floor : UniformInt(rng, 0, floor - 1), changeable_[k].footprint_m, &T);
        }
        // No free spot: turned where it stands, which keeps it within its footprint.
        if (!found) T = o.placement[0].T_world_object * PoseXYZYaw(Vec3::Zero(), Uniform(rng, 1.0, 2.0));
      }
      o.placement[1].T_world_object = T;
    }
    for (int k : plan.removed) world_.objects[changeable_[k].object].placement[1].present = false;
    for (int k = 0, added = 0; added < s_.pass2.added && k < 20 * (s_.pass2.added + 1); ++k) {
      if (AddItem(rng, kCatalog[UniformInt(rng, 0, 12)], true)) ++added;
    }
  }

  // ---- People walking ------------------------------------------------------------------
  void MakeWalkers() {
    std::mt19937_64 rng = Rng("walkers");
    // The camera's base pose is 2 m in front of the desk (MakeCamera).
    const double front = desk_.x() - 2.0 + spec_.walker_front_distance_m;
    if (spec_.walker_route == "in_front") {
      MakeWalkersInFront(rng, front);
      return;
    }
    std::vector<int> placed;  // sitters and walkers so far, kept clear of
    for (std::size_t i = 0; i < world_.objects.size(); ++i) {
      if (world_.objects[i].articulation == Articulation::kSitter) placed.push_back(static_cast<int>(i));
    }
    // Loops around the main desk (both directions) and a ping-pong line behind it.
    const double back = desk_.x() + 1.45, side = 1.7;
    std::vector<PathMotion> paths;
    for (bool ccw : {true, false}) {
      PathMotion p;
      p.waypoints = {Vec3(front, -side, 0), Vec3(back, -side, 0), Vec3(back, side, 0), Vec3(front, side, 0)};
      if (!ccw) std::reverse(p.waypoints.begin(), p.waypoints.end());
      paths.push_back(p);
    }
    PathMotion line;
    line.closed = false;
    line.waypoints = {Vec3(back, -Y_ / 2 + 0.7, 0), Vec3(back, Y_ / 2 - 1.2, 0)};
    paths.push_back(line);
    PathMotion beside = line;  // from the door side, across in front of the desk and back
    beside.waypoints = {Vec3(front - 0.1, -Y_ / 2 + 0.6, 0), Vec3(front - 0.1, -side, 0), Vec3(back, -side, 0)};
    paths.push_back(beside);
    for (int k = 0; k < spec_.people_walking; ++k) {
      Object& o = MakePerson(rng);
      o.articulation = Articulation::kWalker;
      const double speed = spec_.walking_speed_mps * Uniform(rng, 0.85, 1.15);
      std::vector<PathMotion> mine;
      for (std::size_t c = 0; c < paths.size(); ++c) mine.push_back(paths[(c + k) % paths.size()]);
      for (PathMotion& p : mine) p.speed_mps = speed;
      PlaceOnPaths(&world_, rng, static_cast<int>(world_.objects.size()) - 1, mine, placed,
                   /*min_camera_m=*/0.6, /*min_other_m=*/0.7, /*step_s=*/0.1);
      placed.push_back(static_cast<int>(world_.objects.size()) - 1);
    }
  }

  // A narrow loop from the front leg to half a metre short of the desk, 2.2 m wide: the
  // leader starts near the middle of the front leg, so the pair is in the first frames
  // (and in the first map) as in TUM's sequences; the others follow spacing_m apart.
  // Known gap: with the walking scenarios' 0.6 m spacing, walkers come 0.40 m apart
  // (centre to centre) at the loop's corners, where arms may touch; wider spacing or a
  // deeper loop kept them apart but let plain track walking_static (a looser pair).
  void MakeWalkersInFront(std::mt19937_64& rng, double front) {
    const double far = std::max(front + 0.2, std::min(front + 0.5, desk_.x() - 0.65)), half_width = 1.1;
    PathMotion loop;
    loop.waypoints = {Vec3(front, half_width, 0), Vec3(front, -half_width, 0), Vec3(far, -half_width, 0),
                      Vec3(far, half_width, 0)};
    loop.speed_mps = spec_.walking_speed_mps * Uniform(rng, 0.85, 1.15);
    loop.start_offset_m = half_width + Uniform(rng, -0.3, 0.3);
    for (int k = 0; k < spec_.people_walking; ++k) {
      Object& o = MakePerson(rng);
      o.articulation = Articulation::kWalker;
      for (Placement& p : o.placement) {
        p.present = true;
        p.moving = true;
        p.path = loop;
        p.path.start_offset_m -= k * spec_.walker_spacing_m;
      }
    }
  }

  // ---- Camera ----------------------------------------------------------------------------
  // Hand-held motion around a base pose 2 m in front of the desk, looking at its centre.
  void MakeCamera() {
    std::mt19937_64 rng = Rng("camera");
    const Vec3 target(desk_.x(), 0.0, kDeskHeightM + 0.15);
    const Vec3 base(desk_.x() - 2.0, Uniform(rng, -0.1, 0.1), Uniform(rng, 1.3, 1.5));
    const Eigen::Matrix3d R0 = LookAt(base, target);
    SmoothNoise n[9];
    for (SmoothNoise& x : n) x = SmoothNoise::Make(rng, 0.08);
    SmoothNoise shake[6];
    for (SmoothNoise& x : shake) x = SmoothNoise::Make(rng, 0.6);
    const std::string& motion = spec_.camera_motion;
    CameraRoute route;
    for (int k = 0; k < spec_.frames; ++k) {
      const double t = k / s_.camera.fps;
      Vec3 p = base;
      Eigen::Matrix3d R = R0;
      if (motion == "xyz") {
        // Translation along the camera's three axes, small rotation.
        p += R0 * Vec3(0.28 * n[0].Eval(t), 0.2 * n[1].Eval(t), 0.25 * n[2].Eval(t));
        R = R0 * Eigen::AngleAxisd(3 * kDeg * n[3].Eval(t), Vec3::UnitX()).matrix() *
            Eigen::AngleAxisd(3 * kDeg * n[4].Eval(t), Vec3::UnitY()).matrix();
      } else if (motion == "static") {
        p += R0 * Vec3(0.008 * n[0].Eval(t), 0.008 * n[1].Eval(t), 0.008 * n[2].Eval(t));
        R = R0 * Eigen::AngleAxisd(0.6 * kDeg * n[3].Eval(t), Vec3::UnitY()).matrix();
      } else if (motion == "rpy") {
        // Rotation about the optical axes: pitch (x), yaw (y), roll (z).
        p += R0 * Vec3(0.02 * n[0].Eval(t), 0.02 * n[1].Eval(t), 0.02 * n[2].Eval(t));
        R = R0 * Eigen::AngleAxisd(15 * kDeg * n[3].Eval(t), Vec3::UnitX()).matrix() *
            Eigen::AngleAxisd(22 * kDeg * n[4].Eval(t), Vec3::UnitY()).matrix() *
            Eigen::AngleAxisd(18 * kDeg * n[5].Eval(t), Vec3::UnitZ()).matrix();
      } else {  // halfsphere: on a 1 m diameter half sphere, looking at the desk
        const Vec3 fwd = Vec3(target.x() - base.x(), target.y() - base.y(), 0).normalized();
        const Vec3 left = Vec3::UnitZ().cross(fwd);
        const double polar = 70 * kDeg * (0.5 - 0.5 * std::cos(2 * M_PI * t / 11.0));
        const double azimuth = 2 * M_PI * t / 7.3;
        const Vec3 dir = std::cos(polar) * fwd +
                         std::sin(polar) * (std::cos(azimuth) * left + std::sin(azimuth) * Vec3::UnitZ());
        p = base + 0.5 * (dir - fwd);  // starts at the base pose
        R = LookAt(p, target);
      }
      // Hand shake on top of every motion.
      p += Vec3(0.002 * shake[0].Eval(t), 0.002 * shake[1].Eval(t), 0.002 * shake[2].Eval(t));
      R = R * Eigen::AngleAxisd(0.3 * kDeg * shake[3].Eval(t), Vec3::UnitX()).matrix() *
          Eigen::AngleAxisd(0.3 * kDeg * shake[4].Eval(t), Vec3::UnitY()).matrix();
      CameraKey key;
      key.stamp_s = t;
      key.T_wc.linear() = R;
      key.T_wc.translation() = p;
      route.keys.push_back(key);
    }
    world_.camera_route[0] = route;
    world_.camera_route[1] = OffsetRoute(route, s_.pass2.camera_offset_m, s_.pass2.camera_yaw_offset_deg);
  }

  void MakeLights() {
    for (const Vec2& p : LightSpots()) {
      Light l;
      l.directional = false;
      l.position = At(p, Z_ - 0.1);
      l.direction = Vec3(0, 0, -1);
      l.diffuse = Eigen::Vector3f(0.42f, 0.42f, 0.4f);
      l.ambient = Eigen::Vector3f(0.12f, 0.12f, 0.12f);
      l.specular = Eigen::Vector3f(0.1f, 0.1f, 0.1f);
      world_.lights.push_back(l);
    }
  }

  const Scenario& s_;
  const OfficeSpec& spec_;
  World world_;
  WorldBuilder b_;
  double X_, Y_, Z_;
  Vec2 desk_;
  int wall_, carpet_, ceiling_, wood_, door_, whiteboard_, spines_, keyboard_, skin_t_;
  int black_, grey_, metal_, fabric_, light_, window_, plant_;
  std::vector<int> posters_, screens_, prints_, clothes_;
  std::vector<Surface> desk_surfaces_;
  std::map<int, std::vector<Spot>> taken_;
  std::vector<Item> fixed_items_;
  // What pass 2 may relocate or remove, with the radius of its footprint.
  struct Changeable {
    int object;
    double footprint_m;
  };
  std::vector<Changeable> changeable_;
  int candidates_ = 0;
};

}  // namespace

World BuildOffice(const Scenario& scenario) { return OfficeBuilder(scenario).Build(); }

}  // namespace segslam::scenes
