// The city's vehicles and parking: a car, truck or bus model, and the cars parked at the
// curbs with pass 2's changes (relocated along the curb or to another slot, removed, added).
#include "scenes/city_builder_internal.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace segslam::scenes::city_internal {

// A car, truck or bus as one rigid part; object frame on the ground at the centre,
// x forward.
Part CityBuilder::MakeVehicle(std::mt19937_64& rng, const std::string& kind) {
  static const Eigen::Vector4f kPalette[] = {
      {0.95f, 0.95f, 0.95f, 1}, {0.08f, 0.08f, 0.09f, 1}, {0.6f, 0.62f, 0.65f, 1}, {0.7f, 0.08f, 0.07f, 1},
      {0.1f, 0.2f, 0.55f, 1},   {0.35f, 0.36f, 0.38f, 1}, {0.1f, 0.3f, 0.15f, 1},  {0.95f, 0.75f, 0.1f, 1},
      {0.5f, 0.25f, 0.1f, 1},   {0.3f, 0.5f, 0.7f, 1}};
  // Its own shade of a common colour, and plates with its own registration.
  const std::uint64_t vehicle_seed = SubSeed(s_.seed, "vehicle", vehicle_count_++);
  std::mt19937_64 own(vehicle_seed);
  Eigen::Vector4f colour = kPalette[UniformInt(rng, 0, 9)];
  colour.head<3>() = (colour.head<3>() * static_cast<float>(Uniform(own, 0.85, 1.1))).cwiseMin(1.f);
  // Paint and glass of its own (panel gaps, scratches, dirt; what shows through the
  // windows), each picture as large as the largest face it covers.
  const auto paint_of = [&](const std::string& name, const Vec2& size_m, const Eigen::Vector4f& rgba, std::uint64_t index) {
    const std::uint64_t seed = SubSeed(vehicle_seed, name, index);
    const cv::Size px = PixelsFor(size_m, kVehiclePxPerM);
    return pictures_.Add(b_, name, px, size_m, [seed, px] { return VehiclePaintTexture(seed, px); }, rgba, 0.5f, 0.5f);
  };
  const auto glass_of = [&](const Vec2& size_m) {
    const std::uint64_t seed = SubSeed(vehicle_seed, "glass");
    const cv::Size px = PixelsFor(size_m, kVehiclePxPerM);
    return pictures_.Add(b_, "car_glass", px, size_m, [seed, px] { return VehicleGlassTexture(seed, px); },
                         Eigen::Vector4f::Ones(), 0.6f);
  };
  const int plate = AddPicture("plate", Vec2(0.52, 0.13), cv::Size(256, 64), [vehicle_seed] { return NumberPlateTexture(vehicle_seed); });
  Part part{"body", {}};
  auto& g = part.geoms;
  auto wheels = [&](double L, double W, double r) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).matrix();
    for (double x : {-0.33 * L, 0.33 * L}) {
      for (double y : {-1.0, 1.0}) {
        g.push_back(MakeShape(Shape::kCylinder, Vec3(x, y * (W / 2 - 0.14), r), Vec3(r, 0.12, 0), look_.rubber, R));
        g.push_back(MakeShape(Shape::kCylinder, Vec3(x, y * (W / 2 - 0.01), r), Vec3(r * 0.55, 0.005, 0), look_.chrome, R));
      }
    }
  };
  auto lights_and_plates = [&](double L, double W, double z) {
    for (double y : {-1.0, 1.0}) {
      g.push_back(MakeBox(Vec3(L / 2, y * (W / 2 - 0.22), z), Vec3(0.02, 0.16, 0.06), look_.headlight));
      g.push_back(MakeBox(Vec3(-L / 2, y * (W / 2 - 0.2), z), Vec3(0.02, 0.14, 0.07), look_.taillight));
    }
    g.push_back(MakeBox(Vec3(L / 2 + 0.01, 0, z - 0.2), Vec3(0.01, 0.26, 0.065), plate));
    g.push_back(MakeBox(Vec3(-L / 2 - 0.01, 0, z - 0.1), Vec3(0.01, 0.26, 0.065), plate));
  };
  if (kind == "truck") {
    const double L = Uniform(rng, 6.0, 7.0), W = 2.3;
    const int paint = paint_of(kind + "_paint", Vec2(W, 1.9), colour, 0);
    g.push_back(MakeBox(Vec3(L / 2 - 0.9, 0, 1.45), Vec3(0.9, W / 2, 0.95), paint));           // cab
    g.push_back(MakeBox(Vec3(L / 2 - 0.35, 0, 1.85), Vec3(0.36, W / 2 - 0.08, 0.4), glass_of(Vec2(W, 0.8))));  // windscreen
    const int cargo = paint_of("truck_cargo", Vec2(L - 1.9, 2.7), Eigen::Vector4f(0.92f, 0.92f, 0.9f, 1), 1);
    g.push_back(MakeBox(Vec3(-0.95, 0, 1.9), Vec3(L / 2 - 0.95, W / 2, 1.35), cargo));          // box
    const std::uint64_t logo_seed = SubSeed(vehicle_seed, "logo");
    const int logo = AddPicture("truck_logo", Vec2(3.2, 1.2), cv::Size(320, 120), [logo_seed] { return CompanyLogoTexture(logo_seed); });
    g.push_back(MakeBox(Vec3(-0.95, W / 2 + 0.005, 2.0), Vec3(1.6, 0.005, 0.6), logo));
    g.push_back(MakeBox(Vec3(0, 0, 0.55), Vec3(L / 2, W / 2 - 0.1, 0.12), look_.dark_metal));   // chassis
    wheels(L, W, 0.45);
    lights_and_plates(L, W, 0.75);
  } else if (kind == "bus") {
    const double L = 11.0, W = 2.5;
    g.push_back(MakeBox(Vec3(0, 0, 1.75), Vec3(L / 2, W / 2, 1.3), paint_of(kind + "_paint", Vec2(L, 2.6), colour, 0)));
    const int glass = glass_of(Vec2(L, 1.6));
    g.push_back(MakeBox(Vec3(0, 0, 2.15), Vec3(L / 2 - 0.4, W / 2 + 0.01, 0.5), glass));
    g.push_back(MakeBox(Vec3(L / 2 + 0.01, 0, 2.0), Vec3(0.01, W / 2 - 0.1, 0.8), glass));
    wheels(L * 0.85, W, 0.5);
    lights_and_plates(L, W, 0.8);
  } else {
    const double L = Uniform(rng, 4.1, 4.8), W = Uniform(rng, 1.75, 1.9), hb = Uniform(rng, 0.32, 0.4);
    const double cabin_l = L * Uniform(rng, 0.45, 0.6);
    const int paint = paint_of(kind + "_paint", Vec2(L, W), colour, 0);
    g.push_back(MakeBox(Vec3(0, 0, 0.28 + hb), Vec3(L / 2, W / 2, hb), paint));  // lower body
    g.push_back(MakeBox(Vec3(-0.08 * L, 0, 0.28 + 2 * hb + 0.24), Vec3(cabin_l / 2, W / 2 - 0.1, 0.24), glass_of(Vec2(cabin_l, W))));
    g.push_back(MakeBox(Vec3(-0.08 * L, 0, 0.28 + 2 * hb + 0.5), Vec3(cabin_l / 2 - 0.1, W / 2 - 0.12, 0.025), paint));  // roof
    g.push_back(MakeBox(Vec3(L / 2 - 0.05, 0, 0.4), Vec3(0.08, W / 2, 0.1), look_.rubber));    // bumpers
    g.push_back(MakeBox(Vec3(-L / 2 + 0.05, 0, 0.4), Vec3(0.08, W / 2, 0.1), look_.rubber));
    for (double y : {-1.0, 1.0}) {  // mirrors
      g.push_back(MakeBox(Vec3(0.18 * L, y * (W / 2 + 0.08), 0.28 + 2 * hb + 0.1), Vec3(0.06, 0.08, 0.06), paint));
    }
    wheels(L, W, 0.32);
    lights_and_plates(L, W, 0.28 + hb + 0.1);
  }
  return part;
}

std::string CityBuilder::VehicleKind(std::mt19937_64& rng, bool allow_bus) {
  const double r = Uniform(rng, 0, 1);
  if (r < 0.12) return "truck";
  if (allow_bus && r < 0.2) return "bus";
  return "car";
}

VehicleDims CityBuilder::Dims(const std::string& kind) {
  return kind == "bus" ? kBusDims : kind == "truck" ? kTruckDims : kCarDims;
}

namespace {

// A vehicle parked in a slot in one pass: its shift toward the row's next slot and its
// half length.
struct ParkedVehicle {
  double shift_m = 0, half_length = 0;
};

// Which slot holds which vehicle in each pass, so that no two parked vehicles touch:
// stalls are 6.5 m long, a truck 7.2 m, and pass 2 moves vehicles along the curb.
class ParkingLot {
 public:
  explicit ParkingLot(const std::vector<Slot>& slots) : slots_(slots), parked_(slots.size()), used_(slots.size()) {}

  // Whether a vehicle of `half_length` shifted by `shift_m` fits slot i in `pass`: apart
  // from its neighbours, and within its slot at the ends of a row.
  bool Fits(std::size_t i, int pass, double half_length, double shift_m) const {
    for (int dir : {-1, 1}) {
      const std::optional<std::size_t> j = Neighbour(i, dir);
      if (!j && dir * shift_m + half_length > kSlotLengthM / 2 + 1e-9) return false;
      if (!j || !parked_[*j][pass]) continue;
      const double gap = dir * (dir * kSlotLengthM + parked_[*j][pass]->shift_m - shift_m);
      if (gap < half_length + parked_[*j][pass]->half_length + kParkedGapM) return false;
    }
    return true;
  }

  // How far a vehicle in slot i may move along the curb in direction dir (+1 ahead) in
  // `pass`: up to the next vehicle; into an empty neighbouring slot only as far as still
  // leaves room for a car there; at the end of a row, not beyond its own slot.
  double Room(std::size_t i, int pass, double half_length, int dir) const {
    const std::optional<std::size_t> j = Neighbour(i, dir);
    if (!j) return kSlotLengthM / 2 - half_length;
    const std::optional<ParkedVehicle>& other = parked_[*j][pass];
    if (!other) return kSlotLengthM - half_length - kCarDims.half_length - kParkedGapM;
    return kSlotLengthM + dir * other->shift_m - half_length - other->half_length - kParkedGapM;
  }

  // The first slot of `order` not taken before that fits the vehicle in the passes
  // where it is present, or null when none does; marks it taken.
  std::optional<std::size_t> Take(const std::vector<std::size_t>& order, const std::array<bool, 2>& passes,
                                  double half_length) {
    for (std::size_t i : order) {
      if (used_[i]) continue;
      if ((passes[0] && !Fits(i, 0, half_length, 0)) || (passes[1] && !Fits(i, 1, half_length, 0))) continue;
      used_[i] = true;
      for (int pass : {0, 1}) {
        if (passes[pass]) parked_[i][pass] = ParkedVehicle{0, half_length};
      }
      return i;
    }
    return std::nullopt;
  }

  void Leave(std::size_t i, int pass) { parked_[i][pass].reset(); }
  void Park(std::size_t i, int pass, const ParkedVehicle& v) { parked_[i][pass] = v; }

 private:
  std::optional<std::size_t> Neighbour(std::size_t i, int dir) const {
    const std::size_t j = i + dir;
    if (j >= slots_.size() || slots_[j].row != slots_[i].row) return std::nullopt;
    return j;
  }

  const std::vector<Slot>& slots_;
  std::vector<std::array<std::optional<ParkedVehicle>, 2>> parked_;
  std::vector<bool> used_;  // taken in either pass: a slot left in pass 2 stays empty
};

}  // namespace

// Parked cars at the curbs, most along the route; pass 2 relocates, removes, adds.
void CityBuilder::MakeParkedCars() {
  std::mt19937_64 rng = Rng("parked");
  // Slot order: route slots first, each group shuffled.
  std::vector<std::size_t> route_slots, other_slots;
  for (std::size_t i = 0; i < slots_.size(); ++i) (slots_[i].on_route ? route_slots : other_slots).push_back(i);
  Shuffle(route_slots, rng);
  Shuffle(other_slots, rng);
  std::vector<std::size_t> order = route_slots;
  order.insert(order.end(), other_slots.begin(), other_slots.end());
  ParkingLot lot(slots_);
  auto pose_of = [&](const Slot& slot, const VehicleDims& dims, double shift_m) {
    const Vec2 centre = slot.curb + slot.to_road * (kCurbGapM + dims.half_width) + shift_m * slot.along_row;
    return PoseXYZYaw(At(centre, 0.0), slot.yaw + Uniform(rng, -0.03, 0.03));
  };
  // A vehicle of a random kind (never a bus) in the first slot of `order` that fits it,
  // parked there in the passes it is present in and absent from the other; none when no
  // slot fits.
  auto park_new = [&](const std::array<bool, 2>& passes) -> std::optional<std::size_t> {
    const std::string kind = VehicleKind(rng, false);
    const VehicleDims dims = Dims(kind);
    const std::optional<std::size_t> slot = lot.Take(order, passes, dims.half_length);
    if (!slot) return std::nullopt;
    Object& o = b_.AddObject(kind);
    o.parts.push_back(MakeVehicle(rng, o.category_name));
    const Eigen::Isometry3d pose = pose_of(slots_[*slot], dims, 0);
    for (int pass : {0, 1}) {
      o.placement[pass].present = passes[pass];
      if (passes[pass]) o.placement[pass].T_world_object = pose;
    }
    return slot;
  };

  // Pass 1 cars.
  std::vector<int> ids;
  std::vector<std::size_t> own_slots;
  for (int k = 0; k < spec_.parked_cars; ++k) {
    const std::optional<std::size_t> slot = park_new({true, true});
    if (!slot) break;
    ids.push_back(static_cast<int>(world_.objects.size()) - 1);
    own_slots.push_back(*slot);
  }
  // Pass 2: relocate (within the car's own slot, along the curb, or to a free slot),
  // remove, add.
  const ChangePlan plan = PlanSecondPass(static_cast<int>(ids.size()), s_.pass2, rng);
  for (int k : plan.removed) {
    world_.objects[ids[k]].placement[1].present = false;
    lot.Leave(own_slots[k], 1);
  }
  const double shift_m = s_.pass2.relocated_shift_m;
  for (int k : plan.relocated) {
    Object& car = world_.objects[ids[k]];
    const VehicleDims dims = Dims(car.category_name);
    const std::size_t i = own_slots[k];
    lot.Leave(i, 1);
    if (shift_m > 0) {
      // Moved by at least half the option, the preferred way if there is room for that.
      const double want = Uniform(rng, 0.5, 1.0) * shift_m;
      const int preferred = Chance(rng, 0.5) ? 1 : -1;
      std::optional<double> shift;
      for (int dir : {preferred, -preferred}) {
        const double room = lot.Room(i, 1, dims.half_length, dir);
        if (!shift && room >= 0.5 * shift_m) shift = dir * std::min(want, room);
      }
      if (shift) {
        lot.Park(i, 1, {*shift, dims.half_length});
        car.placement[1].T_world_object = pose_of(slots_[i], dims, *shift);
        continue;
      }
      // No room along the curb (a truck between two vehicles): parked elsewhere.
    }
    const std::optional<std::size_t> slot = lot.Take(order, {false, true}, dims.half_length);
    if (!slot) {
      lot.Park(i, 1, {0, dims.half_length});
      continue;
    }
    car.placement[1].T_world_object = pose_of(slots_[*slot], dims, 0);
  }
  for (int k = 0; k < s_.pass2.added; ++k) {
    if (!park_new({false, true})) break;
  }
  parked_candidates_ = static_cast<int>(ids.size());
}

}  // namespace segslam::scenes::city_internal
