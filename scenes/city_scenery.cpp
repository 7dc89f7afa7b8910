// The city's static scenery: textures and materials, the ground, the streets' surfaces and
// markings, blocks, sidewalks, buildings with their facades, street furniture and the
// fixed COCO objects (traffic lights, stop signs, hydrants, benches).
#include "scenes/city_builder_internal.h"
#include "scenes/textures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace segslam::scenes::city_internal {

// The size in pixels of a picture of `size_m` at `px_per_m` (at least 2 x 2).
cv::Size CityBuilder::PixelsFor(const Vec2& size_m, double px_per_m) {
  return cv::Size(std::max(2, static_cast<int>(std::lround(size_m.x() * px_per_m))),
                  std::max(2, static_cast<int>(std::lround(size_m.y() * px_per_m))));
}

// A picture of one place (a street, a facade, a plate) drawn at `px_per_m` over a
// box face of `size_m`; returns its material. The pictures are packed into a few
// textures and drawn, in parallel, at the end of Build() (scenes/picture_pages.h).
int CityBuilder::AddPicture(const std::string& name, const Vec2& size_m, double px_per_m, std::function<cv::Mat()> draw) {
  return pictures_.Add(b_, name, PixelsFor(size_m, px_per_m), size_m, std::move(draw));
}

// A picture drawn at a fixed size in pixels (plates, signs).
int CityBuilder::AddPicture(const std::string& name, const Vec2& size_m, cv::Size size_px, std::function<cv::Mat()> draw) {
  return pictures_.Add(b_, name, size_px, size_m, std::move(draw));
}

// Pixels per metre for a surface spanning [lo, hi] (horizontal extent): full detail
// near the route, coarse beyond, and never more than kMaxTexturePx on a side.
double CityBuilder::DetailPxPerM(const Vec2& lo, const Vec2& hi, double far_px_per_m, double longest_side_m) const {
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < camera_lane_.p.size(); k += 4) {  // every metre
    const Vec2 q = camera_lane_.p[k].cwiseMax(lo).cwiseMin(hi);
    nearest = std::min(nearest, (camera_lane_.p[k] - q).norm());
  }
  const double px_per_m = nearest <= kNearRouteM ? kNearPxPerM : far_px_per_m;
  return std::min(px_per_m, kMaxTexturePx / std::max(longest_side_m, 1e-3));
}

void CityBuilder::MakeLook() {
  const std::uint64_t seed = s_.seed;
  auto tex = [&](const std::string& name, cv::Mat img, double u, double v) {
    return b_.AddTexture(name, std::move(img), Vec2(u, v));
  };
  auto mat = [&](const std::string& name, int t, Eigen::Vector4f rgba, float spec = 0.1f) {
    return b_.AddMaterial(name, t, rgba, spec);
  };
  const Eigen::Vector4f white(1, 1, 1, 1);
  // Untextured asphalt beyond the streets' surfaces, which have pictures of their own.
  look_.ground = mat("ground", -1, Eigen::Vector4f(0.29f, 0.29f, 0.3f, 1), 0.05f);
  look_.railing = mat("railing", -1, Eigen::Vector4f(0.16f, 0.17f, 0.17f, 1), 0.3f);
  look_.bark = mat("bark", tex("bark", BarkTexture(SubSeed(seed, "bark")), 1, 1), white);
  const int metal_t = tex("metal", MetalTexture(SubSeed(seed, "metal")), 0.5, 0.5);
  look_.metal = mat("metal", metal_t, Eigen::Vector4f(0.75f, 0.78f, 0.78f, 1), 0.4f);
  look_.dark_metal = mat("dark_metal", metal_t, Eigen::Vector4f(0.3f, 0.32f, 0.3f, 1), 0.4f);
  for (int i = 0; i < 6; ++i) {
    look_.clothes_textures[i] = tex("cloth_" + std::to_string(i), ClothTexture(SubSeed(seed, "cloth", i), i), 0.5, 0.5);
  }
  look_.skin_texture = tex("skin", SkinTexture(SubSeed(seed, "skin")), 0.2, 0.2);
  look_.rubber = mat("rubber", -1, Eigen::Vector4f(0.08f, 0.08f, 0.08f, 1));
  look_.chrome = mat("chrome", -1, Eigen::Vector4f(0.7f, 0.7f, 0.72f, 1), 0.8f);
  look_.headlight = mat("headlight", -1, Eigen::Vector4f(0.95f, 0.95f, 0.85f, 1), 0.8f);
  look_.taillight = mat("taillight", -1, Eigen::Vector4f(0.7f, 0.05f, 0.05f, 1), 0.6f);
  look_.stop_sign = mat("stop_sign", tex("stop_sign", StopSignTexture(SubSeed(seed, "stop")), 0.75, 0.75), white);
  look_.traffic_lamps = mat("traffic_lamps", tex("traffic_lamps", TrafficLightTexture(SubSeed(seed, "tl")), 0.35, 0.9), white);
  look_.wood = mat("bench_wood", tex("bench_wood", WoodTexture(SubSeed(seed, "bench")), 1, 1), white);
  look_.red_paint = mat("hydrant_red", -1, Eigen::Vector4f(0.75f, 0.1f, 0.08f, 1), 0.3f);
  const int foliage_t = tex("foliage", FoliageTexture(SubSeed(seed, "foliage")), 2.5, 2.5);
  for (int i = 0; i < 3; ++i) {
    look_.foliage.push_back(mat("foliage_" + std::to_string(i), foliage_t,
                                Eigen::Vector4f(0.8f + 0.1f * i, 1.0f, 0.8f + 0.08f * i, 1)));
  }
}

void CityBuilder::MakeGround() {
  // An untextured plane under everything; the streets' surfaces lie on it
  // (MakeStreetSurfaces) and the sidewalks and buildings stand on it.
  const double margin = 2.5 * block_;
  const Vec2 lo = Vec2((imin_ - 1) * block_ - margin, (jmin_ - 1) * block_ - margin);
  const Vec2 hi = Vec2((imax_ + 1) * block_ + margin, (jmax_ + 1) * block_ + margin);
  Geom g;
  g.shape = Shape::kPlane;
  g.size = Vec3(0.5 * (hi.x() - lo.x()), 0.5 * (hi.y() - lo.y()), 0);
  g.T_parent_geom.translation() = At(0.5 * (lo + hi), 0);
  g.material = look_.ground;
  world_.static_geoms.push_back(g);
}

// Every street between two intersections and every intersection of the blocks' grid a
// slab of its own asphalt, with the markings that lie on it painted in.
void CityBuilder::MakeStreetSurfaces() {
  const auto add = [&](const Vec2& lo, const Vec2& hi, const std::string& tag, std::uint64_t index) {
    GroundPatch patch;
    patch.lo_m = lo;
    patch.hi_m = hi;
    patch.px_per_m = DetailPxPerM(lo, hi, kFarGroundPxPerM, (hi - lo).maxCoeff());
    std::vector<RoadMarking> on_patch;
    for (const RoadMarking& m : markings_) {
      const double reach = m.half_m.norm();
      if ((m.centre_m.array() + reach > lo.array()).all() && (m.centre_m.array() - reach < hi.array()).all()) {
        on_patch.push_back(m);
      }
    }
    const std::uint64_t seed = SubSeed(s_.seed, tag, index);
    const int m = AddPicture(tag, hi - lo, patch.SizePx(), [seed, patch, on_patch] { return StreetTexture(seed, patch, on_patch); });
    world_.static_geoms.push_back(MakeBox(At(0.5 * (lo + hi), kRoadTopM / 2), At(0.5 * (hi - lo), kRoadTopM / 2), m));
  };
  const Vec2 half_road = Vec2::Constant(road_ / 2);
  for (int i = imin_ - 1; i <= imax_ + 1; ++i) {
    for (int j = jmin_ - 1; j <= jmax_ + 1; ++j) {
      const std::uint64_t index = static_cast<std::uint64_t>((i + 1000) * 4096 + (j + 1000));
      const Vec2 c = NodePos({i, j});
      add(c - half_road, c + half_road, "intersection", index);
      if (i <= imax_) add(c + Vec2(road_ / 2, -road_ / 2), NodePos({i + 1, j}) + Vec2(-road_ / 2, road_ / 2), "street_x", index);
      if (j <= jmax_) add(c + Vec2(-road_ / 2, road_ / 2), NodePos({i, j + 1}) + Vec2(road_ / 2, -road_ / 2), "street_y", index);
    }
  }
}

// A block between street lines i..i+1 and j..j+1: a raised sidewalk slab and
// buildings on lots around its edge.
void CityBuilder::MakeBlocks() {
  for (int i = imin_ - 1; i <= imax_; ++i) {
    for (int j = jmin_ - 1; j <= jmax_; ++j) {
      std::mt19937_64 rng = Rng("block", static_cast<std::uint64_t>((i + 1000) * 4096 + (j + 1000)));
      const Vec2 lo = NodePos({i, j}) + Vec2::Constant(road_ / 2);
      const Vec2 hi = NodePos({i + 1, j + 1}) - Vec2::Constant(road_ / 2);
      const std::uint64_t block_index = static_cast<std::uint64_t>((i + 1000) * 4096 + (j + 1000));
      MakeSidewalks(lo, hi, block_index, Uniform(rng, 0.3, 0.6));
      // Lots: 2-3 columns by 2 rows, all touching a street.
      const Vec2 in_lo = lo + Vec2::Constant(walk_), in_hi = hi - Vec2::Constant(walk_);
      const int nx = UniformInt(rng, 2, 3);
      std::vector<double> xs = {in_lo.x()}, ys = {in_lo.y(), 0.5 * (in_lo.y() + in_hi.y()) + Uniform(rng, -2, 2), in_hi.y()};
      for (int k = 1; k < nx; ++k) {
        xs.push_back(in_lo.x() + (in_hi.x() - in_lo.x()) * (k + Uniform(rng, -0.15, 0.15)) / nx);
      }
      xs.push_back(in_hi.x());
      for (int a = 0; a + 1 < static_cast<int>(xs.size()); ++a) {
        for (int c = 0; c < 2; ++c) {
          // The sides of the lot on the block's edge face a street.
          const std::array<bool, 4> street_sides = {a == 0, a + 2 == static_cast<int>(xs.size()), c == 0, c == 1};
          MakeBuilding(rng, Vec2(xs[a], ys[c]), Vec2(xs[a + 1], ys[c + 1]), street_sides);
        }
      }
    }
  }
}

// The sidewalks of the block [lo, hi]: four paved strips along its edges, each with a
// picture of its own, around an untextured slab under the lots.
void CityBuilder::MakeSidewalks(const Vec2& lo, const Vec2& hi, std::uint64_t block_index, double paver_m) {
  const Vec2 w = Vec2::Constant(walk_);
  // Four strips, none overlapping: along x the whole block, along y between them.
  const std::array<std::pair<Vec2, Vec2>, 4> strips = {{
      {lo, Vec2(hi.x(), lo.y() + walk_)},                             // along x, low y
      {Vec2(lo.x(), hi.y() - walk_), hi},                             // along x, high y
      {Vec2(lo.x(), lo.y() + walk_), Vec2(lo.x() + walk_, hi.y() - walk_)},  // along y, low x
      {Vec2(hi.x() - walk_, lo.y() + walk_), Vec2(hi.x(), hi.y() - walk_)},  // along y, high x
  }};
  for (std::size_t k = 0; k < strips.size(); ++k) {
    const auto& [a, b] = strips[k];
    GroundPatch patch;
    patch.lo_m = a;
    patch.hi_m = b;
    patch.px_per_m = DetailPxPerM(a, b, kFarGroundPxPerM, (b - a).maxCoeff());
    const std::uint64_t seed = SubSeed(s_.seed, "sidewalk", block_index * 4 + k);
    const int m = AddPicture("sidewalk", b - a, patch.SizePx(), [seed, patch, paver_m] { return PavedStripTexture(seed, patch, paver_m); });
    world_.static_geoms.push_back(MakeBox(At(0.5 * (a + b), kCurbHeightM / 2), At(0.5 * (b - a), kCurbHeightM / 2), m));
  }
  const int inner = b_.AddMaterial("lot_ground", -1, Eigen::Vector4f(0.55f, 0.55f, 0.53f, 1));
  world_.static_geoms.push_back(MakeBox(At(0.5 * (lo + hi), kCurbHeightM / 2), At(0.5 * (hi - lo) - w, kCurbHeightM / 2), inner));
}

// A building on the lot [lo, hi]: an untextured body in its own colour; each side that
// faces a street (street_sides: low x, high x, low y, high y) carries a facade of its
// own (floors, bays, windows, shops with their own names), with balconies and awnings
// where that facade has them; a cornice and now and then a rooftop structure.
void CityBuilder::MakeBuilding(std::mt19937_64& rng, Vec2 lo, Vec2 hi, const std::array<bool, 4>& street_sides) {
  // Occasional setback from the street and narrow gaps between neighbours.
  const double setback = Chance(rng, 0.25) ? Uniform(rng, 0.3, 1.5) : 0.0;
  lo += Vec2::Constant(setback * 0.5 + 0.1);
  hi -= Vec2::Constant(setback * 0.5 + 0.1);
  const double height = Chance(rng, 0.3) ? Uniform(rng, 22, 40) : Uniform(rng, 8, 22);
  const Vec2 c = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const FacadeStyle styles[4] = {FacadeStyle::kBrick, FacadeStyle::kConcrete, FacadeStyle::kGlass, FacadeStyle::kPlaster};
  const FacadeStyle style = styles[UniformInt(rng, 0, 3)];
  const bool shops = Chance(rng, 0.7);
  const std::uint64_t building_seed = SubSeed(s_.seed, "building", building_count_++);
  const double z0 = kCurbHeightM;
  // The facades' layouts first: the body takes the colour of their walls.
  const Vec2 normals[4] = {Vec2(-1, 0), Vec2(1, 0), Vec2(0, -1), Vec2(0, 1)};
  std::vector<std::pair<int, FacadeLayout>> faces;
  for (int side = 0; side < 4; ++side) {
    if (!street_sides[side]) continue;
    const double width = side < 2 ? 2 * half.y() : 2 * half.x();
    faces.emplace_back(side, PlanFacade(building_seed, side, width, height, style, shops));
  }
  const cv::Scalar wall = faces.empty() ? cv::Scalar(150, 150, 150) : faces.front().second.wall_bgr;
  const Eigen::Vector4f body_rgba(float(wall[2] / 255), float(wall[1] / 255), float(wall[0] / 255), 1);
  const int body = b_.AddMaterial("building_body", -1, body_rgba);
  world_.static_geoms.push_back(MakeBox(At(c, z0 + height / 2), At(half, height / 2), body));
  for (const auto& [side, layout] : faces) {
    const Vec2 n = normals[side];
    const Vec2 mid = c + n * std::abs(n.dot(half));
    const double px_per_m = DetailPxPerM(mid - half.cwiseProduct(n.cwiseAbs().reverse()), mid + half.cwiseProduct(n.cwiseAbs().reverse()),
                                         kFarFacadePxPerM, std::max(layout.width_m, height));
    const std::uint64_t seed = SubSeed(building_seed, "facade", static_cast<std::uint64_t>(side));
    const int skin = AddPicture("facade", Vec2(layout.width_m, height), px_per_m,
                                [seed, layout = layout, px_per_m] { return FacadeTexture(seed, layout, px_per_m); });
    MakeFacade(layout, skin, c, half, n, z0);
  }
  // A cornice that breaks the silhouette, and a plant room or stair housing on some roofs.
  Eigen::Vector4f trim_rgba = body_rgba * static_cast<float>(Uniform(rng, 0.7, 0.9));
  trim_rgba.w() = 1;
  const int trim = b_.AddMaterial("building_trim", -1, trim_rgba);
  world_.static_geoms.push_back(MakeBox(At(c, z0 + height + 0.4), At(half + Vec2::Constant(0.15), 0.4), trim));
  if (Chance(rng, 0.5)) {
    const Vec2 size(Uniform(rng, 0.2, 0.45) * half.x(), Uniform(rng, 0.2, 0.45) * half.y());
    const Vec2 at = c + Vec2(Uniform(rng, -0.4, 0.4) * half.x(), Uniform(rng, -0.4, 0.4) * half.y());
    const double h = Uniform(rng, 1.5, 3.5);
    world_.static_geoms.push_back(MakeBox(At(at, z0 + height + 0.8 + h / 2), At(size, h / 2), trim));
  }
}

// The facade `layout` on the side of the body (centre c, half extents `half`) whose
// outward normal is `n`: a thin textured skin on the wall, and the layout's balconies
// and awnings as geometry.
void CityBuilder::MakeFacade(const FacadeLayout& layout, int skin, const Vec2& c, const Vec2& half, const Vec2& n, double z0) {
  const double w = layout.width_m, h = layout.height_m;
  const double yaw = YawOf(n);
  // Seen from the street, the facade's x runs to the viewer's right: n rotated by -90 deg.
  const Vec2 right = Right(n) * -1.0;
  const Vec2 wall = c + n * std::abs(n.dot(half));
  const Vec2 left_edge = wall - right * (w / 2);
  world_.static_geoms.push_back(MakeBox(At(wall + n * kFacadeSkinM, z0 + h / 2), Vec3(kFacadeSkinM, w / 2, h / 2), skin, yaw));
  const auto on_facade = [&](double x_m, double out_m) { return left_edge + right * x_m + n * (2 * kFacadeSkinM + out_m); };
  if (!layout.balconies.empty()) {
    const cv::Scalar bgr = layout.trim_bgr;
    const int slab = b_.AddMaterial("balcony", -1, Eigen::Vector4f(float(bgr[2] / 255), float(bgr[1] / 255), float(bgr[0] / 255), 1));
    for (const FacadeLayout::Opening& b : layout.balconies) {
      const double depth = 1.0, bw = b.x1_m - b.x0_m, mid = 0.5 * (b.x0_m + b.x1_m);
      world_.static_geoms.push_back(MakeBox(At(on_facade(mid, depth / 2), z0 + b.z0_m - 0.08), Vec3(depth / 2, bw / 2, 0.08), slab, yaw));
      world_.static_geoms.push_back(MakeBox(At(on_facade(mid, depth - 0.02), z0 + b.z0_m + 0.5), Vec3(0.02, bw / 2, 0.5), look_.railing, yaw));
    }
  }
  for (const FacadeLayout::Shop& shop : layout.shops) {
    if (!shop.awning) continue;
    // A fabric awning under the sign, sloping 15 degrees down toward the street.
    const cv::Scalar bgr = shop.awning_bgr;
    const int fabric = b_.AddMaterial("awning", -1, Eigen::Vector4f(float(bgr[2] / 255), float(bgr[1] / 255), float(bgr[0] / 255), 1));
    const double depth = 1.3, tilt = 15.0 * M_PI / 180;
    Geom g = MakeBox(At(on_facade(0.5 * (shop.x0_m + shop.x1_m), 0.5 * depth * std::cos(tilt)),
                        z0 + layout.ground_floor_m - 1.0 - 0.5 * depth * std::sin(tilt)),
                     Vec3(depth / 2, (shop.x1_m - shop.x0_m) / 2 - 0.2, 0.03), fabric, yaw);
    g.T_parent_geom.linear() = g.T_parent_geom.linear() * Eigen::AngleAxisd(tilt, Vec3::UnitY()).matrix();
    world_.static_geoms.push_back(g);
  }
}

// ---- Streets, furniture and fixed COCO objects --------------------------------------
// Markings, furniture and fixed COCO objects along every street of the inner grid.
void CityBuilder::MakeStreets() {
  std::mt19937_64 rng = Rng("streets");
  for (int i = imin_; i <= imax_; ++i) {
    for (int j = jmin_; j <= jmax_; ++j) {
      const Node n{i, j};
      // Streets leaving this node in +x and +y.
      for (int axis = 0; axis < 2; ++axis) {
        const Node m = axis == 0 ? Node{i + 1, j} : Node{i, j + 1};
        if (m.first > imax_ || m.second > jmax_) continue;
        MakeStreetSegment(rng, n, m);
      }
      MakeIntersection(rng, n);
    }
  }
}

bool CityBuilder::OnRoute(const Node& a, const Node& b) const {
  return route_edges_.count({a, b}) || route_edges_.count({b, a});
}

void CityBuilder::MakeStreetSegment(std::mt19937_64& rng, const Node& a, const Node& b) {
  const Vec2 pa = NodePos(a), pb = NodePos(b);
  const Vec2 d = (pb - pa).normalized(), r = Right(d);
  const double yaw = YawOf(d);
  const double clear = road_ / 2 + 4.0;  // past the crosswalks
  const double len = block_ - 2 * clear;
  // Centre line: dashes 3 m long every 9 m (painted into the street's surface), from
  // where the last repainting happened to start.
  // (Its own generator: the markings change nothing else of the street.)
  std::mt19937_64 paint = Rng("centre_line", static_cast<std::uint64_t>((a.first + 1000) * 4096 + (a.second + 1000)) * 2 +
                                                 (b.first != a.first ? 0 : 1));
  for (double s = clear + Uniform(paint, 0, 6); s + 3.0 <= block_ - clear + 1e-9; s += 9.0) {
    markings_.push_back({pa + d * (s + 1.5), Vec2(1.5, 0.075), yaw});
  }
  // The parking lanes' lines along both curbs.
  for (double side : {-1.0, 1.0}) {
    markings_.push_back({pa + d * (block_ / 2) + r * side * (road_ / 2 - kParkingLaneM), Vec2(len / 2 + 2.5, 0.06), yaw});
  }
  // Sidewalk furniture on both sides: trees, lamps, benches, hydrants, parking slots.
  for (double side : {-1.0, 1.0}) {
    const Vec2 curb = r * side * (road_ / 2);
    const Vec2 out = r * side;  // from the road toward the buildings
    double s = clear + Uniform(rng, 0, 4);
    int k = 0;
    while (s < block_ - clear) {
      const Vec2 p = pa + d * s + curb + out * kFurnitureLineM;
      if (k % 3 == 1) {
        MakeLamp(p, -out);
      } else {
        MakeTree(rng, p);
      }
      s += Uniform(rng, 8, 13);
      ++k;
    }
    // Parking slots along the curb, heading with the traffic on that side.
    const Vec2 heading = side > 0 ? d : Vec2(-d);
    const bool on_route = OnRoute(a, b);
    // The row starts 0.25 m past the stop lines' centres (0.05 m past their edges) at
    // both ends, and vehicles in its end slots stay within them (ParkingLot::Fits), so
    // none stands on a stop line or a crosswalk.
    const int row = slots_.empty() ? 0 : slots_.back().row + 1;
    const int row_slots = static_cast<int>(std::floor((len - 0.5) / kSlotLengthM + 1e-9));
    const double row_start = clear + (len - row_slots * kSlotLengthM) / 2;
    for (int k = 0; k < row_slots; ++k) {
      Slot slot;
      slot.curb = pa + d * (row_start + (k + 0.5) * kSlotLengthM) + curb;
      slot.to_road = -out;
      slot.along_row = d;
      slot.yaw = YawOf(heading);
      slot.on_route = on_route;
      slot.row = row;
      slots_.push_back(slot);
    }
    // A few fixed COCO objects near the route: benches and hydrants.
    if (on_route && Chance(rng, 0.5)) {
      MakeBench(pa + d * Uniform(rng, clear + 2, block_ - clear - 2) + curb + out * (walk_ - kBenchFromFarEdgeM), YawOf(-out));
    }
    if (on_route && Chance(rng, 0.5)) {
      MakeHydrant(pa + d * Uniform(rng, clear, block_ - clear) + curb + out * 0.45);
    }
  }
}

void CityBuilder::MakeIntersection(std::mt19937_64& rng, const Node& n) {
  const Vec2 c = NodePos(n);
  // Crosswalks on the arms, each painted to its own measure as crossings are (some
  // arms have none, some a ladder's side bars), so that no two intersections show the
  // same pattern of stripe corners; a stop line before each on the incoming lane.
  std::mt19937_64 paint = Rng("crosswalks", static_cast<std::uint64_t>((n.first + 1000) * 4096 + (n.second + 1000)));
  for (const Vec2& d : kStreetDirs) {
    const double stop_half = Uniform(paint, 0.15, 0.25);
    markings_.push_back({c + d * (road_ / 2 + kStopLineM) + Right(-d) * (road_ / 4), Vec2(stop_half, road_ / 4 - 0.3), YawOf(d)});
    if (Chance(paint, 0.15)) continue;
    const double length = Uniform(paint, 2.4, 3.2);
    const double from_edge = Uniform(paint, 0.3, kStopLineM - stop_half - 0.2 - length);
    const Vec2 p = c + d * (road_ / 2 + from_edge + length / 2);
    const double half_width = road_ / 2 - Uniform(paint, 0.4, 1.0);
    const double stripe = Uniform(paint, 0.4, 0.6), pitch = stripe + Uniform(paint, 0.35, 0.7);
    for (double across = -half_width + Uniform(paint, 0, pitch - stripe) + stripe / 2; across + stripe / 2 <= half_width;
         across += pitch) {
      markings_.push_back({p + Right(d) * across, Vec2(length / 2, stripe / 2), YawOf(d)});
    }
    if (Chance(paint, 0.3)) {  // a ladder: bars along both ends of the stripes
      for (double end : {-1.0, 1.0}) {
        markings_.push_back({p + d * (end * (length / 2 + 0.1)), Vec2(0.08, half_width), YawOf(d)});
      }
    }
  }
  // Near the route: traffic lights at two corners, or a stop sign.
  bool near_route = false;
  for (const Node& m : nodes_) near_route |= std::abs(m.first - n.first) + std::abs(m.second - n.second) <= 1;
  if (!near_route) return;
  const double q = road_ / 2 + 0.5;
  if (Chance(rng, 0.6)) {
    MakeTrafficLight(c + Vec2(q, -q), Vec2(-1, 0));
    MakeTrafficLight(c + Vec2(-q, q), Vec2(1, 0));
  } else {
    MakeStopSign(c + Vec2(-q, -q), Vec2(0, -1));
  }
}

void CityBuilder::MakeTree(std::mt19937_64& rng, const Vec2& p) {
  const double h = Uniform(rng, 3.0, 4.5), crown = Uniform(rng, 1.6, 2.4);
  world_.static_geoms.push_back(MakeRod(At(p, kCurbHeightM), At(p, kCurbHeightM + h + 0.5), Uniform(rng, 0.12, 0.2), look_.bark));
  const int foliage = look_.foliage[UniformInt(rng, 0, 2)];
  world_.static_geoms.push_back(MakeShape(Shape::kEllipsoid, At(p, kCurbHeightM + h + crown * 0.8),
                                          Vec3(crown, crown * Uniform(rng, 0.85, 1.1), crown * 1.1), foliage,
                                          Eigen::AngleAxisd(Uniform(rng, 0, M_PI), Vec3::UnitZ()).matrix()));
  // A second, smaller crown for an irregular outline.
  world_.static_geoms.push_back(MakeShape(Shape::kEllipsoid, At(p + Vec2(Uniform(rng, -0.8, 0.8), Uniform(rng, -0.8, 0.8)), kCurbHeightM + h + crown * 1.5),
                                          Vec3::Constant(crown * 0.65), foliage));
  // A tree grate around the trunk.
  world_.static_geoms.push_back(MakeBox(At(p, kCurbHeightM + 0.005), Vec3(0.6, 0.6, 0.005), look_.dark_metal));
}

void CityBuilder::MakeLamp(const Vec2& p, const Vec2& toward_road) {
  const double h = 6.0;
  world_.static_geoms.push_back(MakeRod(At(p, kCurbHeightM), At(p, kCurbHeightM + h), 0.08, look_.dark_metal));
  const Vec2 tip = p + toward_road * 1.4;
  world_.static_geoms.push_back(MakeRod(At(p, kCurbHeightM + h - 0.1), At(tip, kCurbHeightM + h + 0.15), 0.05, look_.dark_metal));
  world_.static_geoms.push_back(MakeBox(At(tip, kCurbHeightM + h + 0.05), Vec3(0.35, 0.16, 0.08), look_.metal, YawOf(toward_road)));
  // A sign board with its own text.
  const std::uint64_t seed = SubSeed(s_.seed, "street_sign", sign_count_++);
  const int board = AddPicture("street_sign", Vec2(0.6, 0.8), cv::Size(128, 160), [seed] { return StreetSignTexture(seed); });
  world_.static_geoms.push_back(MakeBox(At(p + toward_road * 0.12, kCurbHeightM + 2.6), Vec3(0.02, 0.3, 0.4), board, YawOf(toward_road)));
}

Object& CityBuilder::Fixed(const std::string& category, const Vec2& p, double yaw) {
  Object& o = b_.AddObject(category);
  o.parts.push_back(Part{category, {}});
  for (Placement& pl : o.placement) pl.T_world_object = PoseXYZYaw(At(p, kCurbHeightM), yaw);
  return o;
}

void CityBuilder::MakeTrafficLight(const Vec2& p, const Vec2& facing) {
  Object& o = Fixed("traffic light", p, YawOf(facing));
  auto& g = o.parts[0].geoms;
  g.push_back(MakeRod(Vec3(0, 0, 0), Vec3(0, 0, 3.2), 0.07, look_.dark_metal));
  g.push_back(MakeBox(Vec3(0.05, 0, 3.65), Vec3(0.12, 0.17, 0.45), look_.traffic_lamps));
  g.push_back(MakeBox(Vec3(-0.06, 0, 3.65), Vec3(0.02, 0.25, 0.55), look_.dark_metal));
}

void CityBuilder::MakeStopSign(const Vec2& p, const Vec2& facing) {
  Object& o = Fixed("stop sign", p, YawOf(facing));
  auto& g = o.parts[0].geoms;
  g.push_back(MakeRod(Vec3(0, 0, 0), Vec3(0, 0, 2.2), 0.035, look_.metal));
  g.push_back(MakeBox(Vec3(0.04, 0, 2.35), Vec3(0.015, 0.375, 0.375), look_.stop_sign));
}

void CityBuilder::MakeHydrant(const Vec2& p) {
  Object& o = Fixed("fire hydrant", p, 0.0);
  auto& g = o.parts[0].geoms;
  g.push_back(MakeShape(Shape::kCylinder, Vec3(0, 0, 0.35), Vec3(0.13, 0.35, 0), look_.red_paint));
  g.push_back(MakeShape(Shape::kSphere, Vec3(0, 0, 0.72), Vec3(0.14, 0, 0), look_.red_paint));
  g.push_back(MakeRod(Vec3(0, -0.22, 0.48), Vec3(0, 0.22, 0.48), 0.05, look_.chrome));
  g.push_back(MakeRod(Vec3(0, 0, 0.48), Vec3(0.2, 0, 0.48), 0.06, look_.red_paint));
}

void CityBuilder::MakeBench(const Vec2& p, double yaw) {
  Object& o = Fixed("bench", p, yaw);
  auto& g = o.parts[0].geoms;
  g.push_back(MakeBox(Vec3(0, 0, 0.45), Vec3(0.22, 0.9, 0.03), look_.wood));
  g.push_back(MakeBox(Vec3(-0.22, 0, 0.75), Vec3(0.03, 0.9, 0.2), look_.wood));
  for (double y : {-0.8, 0.8}) g.push_back(MakeBox(Vec3(0, y, 0.21), Vec3(0.2, 0.03, 0.21), look_.dark_metal));
}

}  // namespace segslam::scenes::city_internal
