// Textures made for one place of a city: a stretch of street with its markings, a
// sidewalk strip, one face of one building, a number plate, a street sign. Each is drawn
// at the real size of the surface it covers and mapped onto it once, so no picture
// repeats within a surface and no two surfaces share one: a loop detector finds no
// look-alike place that a real street would not give it (DESIGN.md, conventions).
// Internal to scenes/; images are CV_8UC3 BGR, row 0 at the top.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "scenes/textures.h"

namespace segslam::scenes {

// A horizontal rectangle of ground, axis-aligned in the world, drawn at px_per_m: image
// columns run along +x from lo_m.x(), rows along -y from hi_m.y(), as sim/ maps a texture
// onto the top face of a box (scenes/world.h, Geom).
struct GroundPatch {
  Eigen::Vector2d lo_m{0, 0}, hi_m{1, 1};
  double px_per_m = 32;
  cv::Size SizePx() const;
  cv::Point2f ToPixel(const Eigen::Vector2d& p_world) const;
};

// A painted road marking (a dash, a line, a zebra stripe) as a rectangle on the ground:
// its centre, half extents along and across its own axis, and that axis' yaw; world frame.
struct RoadMarking {
  Eigen::Vector2d centre_m{0, 0};
  Eigen::Vector2d half_m{0.5, 0.1};
  double yaw_rad = 0;
};

// Asphalt of this patch alone: aggregate, tonal variation, cracks, tar-sealed seams,
// repair patches, oil stains, a manhole or drain now and then, and `markings` (those
// that touch the patch) in paint worn by tyres.
cv::Mat StreetTexture(std::uint64_t seed, const GroundPatch& patch, const std::vector<RoadMarking>& markings);

// Pavers `paver_m` square in a running bond along x, each with its own shade, some
// cracked or replaced, with stains, gum spots and leaves.
cv::Mat PavedStripTexture(std::uint64_t seed, const GroundPatch& patch, double paver_m);

// The drawing of one face of one building: where its floors, windows, shops, doors and
// balconies are, in metres from the face's left edge (x) and its foot (z). The city
// builder places balcony and awning geometry from the same layout, so geometry and
// picture agree.
struct FacadeLayout {
  struct Opening {
    double x0_m = 0, x1_m = 0, z0_m = 0, z1_m = 0;
  };
  struct Shop {
    double x0_m = 0, x1_m = 0;
    std::string sign;  // the shop's name, its own text
    bool awning = false;
    cv::Scalar sign_bgr, awning_bgr;
  };
  double width_m = 10, height_m = 10;
  FacadeStyle style = FacadeStyle::kPlaster;
  cv::Scalar wall_bgr, trim_bgr, frame_bgr;
  double ground_floor_m = 4;  // the ground floor's height
  double floor_m = 3.2;       // each upper floor's height
  int upper_floors = 0;
  std::vector<Opening> windows;    // every window above the ground floor
  std::vector<Opening> balconies;  // slabs under some windows: x range, floor level z0 = z1
  std::vector<Shop> shops;         // ground floor, left to right; none: a lobby
  std::vector<Opening> doors;      // ground floor
  std::vector<Opening> ground_windows;  // ground floor windows of a building without shops
};

// Draws a layout for face `face` (0..3) of a building, `width_m` wide and `height_m`
// high. The building's seed sets what its faces share (wall, storey heights, window
// shapes); the face's own draws set its bays, windows and shops, every window a little
// off the grid (as built, never exactly periodic).
FacadeLayout PlanFacade(std::uint64_t building_seed, int face, double width_m, double height_m, FacadeStyle style,
                        bool shops);

// The face's picture at `px_per_m` (its size: width_m x height_m at that scale), weathered
// as a whole: grime near the ground, rain streaks under sills, posters, tags.
cv::Mat FacadeTexture(std::uint64_t seed, const FacadeLayout& layout, double px_per_m);

// A vehicle's paint, near white (its material's colour tints it): panel seams, handles,
// scratches, a dent or sticker, dirt toward the sills; `size_px` covers its largest face.
cv::Mat VehiclePaintTexture(std::uint64_t seed, cv::Size size_px);
// A vehicle's windows: sky reflected at the top, what shows through below (headrests,
// a passenger, a parking ticket), a glare streak.
cv::Mat VehicleGlassTexture(std::uint64_t seed, cv::Size size_px);

// A number plate with its own registration (letters and digits), 256 x 64.
cv::Mat NumberPlateTexture(std::uint64_t seed);

// A small street sign with its own text (a street name, a parking rule), 128 x 160.
cv::Mat StreetSignTexture(std::uint64_t seed);

// A company's name and colours, as painted on a truck's box, 320 x 120.
cv::Mat CompanyLogoTexture(std::uint64_t seed);

// A pronounceable made-up word of `min_letters` to `max_letters` letters, capitalised:
// shop names and street names that no two places share.
std::string MakeWord(cv::RNG& rng, int min_letters, int max_letters);

}  // namespace segslam::scenes
