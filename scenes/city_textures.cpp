// Textures of one place each (scenes/city_textures.h). Amounts of detail are given per
// square metre or per metre and converted with the patch's scale, so a street looks the
// same at any px_per_m, only sharper.
#include "scenes/city_textures.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "scenes/texture_primitives.h"

namespace segslam::scenes {
namespace {

using namespace texture;
using cv::Point;
using cv::Point2f;
using cv::Rect;
using cv::Scalar;

// A count of things for an area of `area_m2` at `per_m2`, at least `at_least`.
int CountFor(double area_m2, double per_m2, int at_least = 0) {
  return std::max(at_least, static_cast<int>(std::lround(area_m2 * per_m2)));
}

int Px(double metres, double px_per_m, int at_least = 1) {
  return std::max(at_least, static_cast<int>(std::lround(metres * px_per_m)));
}

// Anti-aliased polygon fill with sub-pixel corners (OpenCV's 4 fractional bits).
void FillPolygon(cv::Mat& img, const std::vector<Point2f>& corners, const Scalar& colour) {
  constexpr int kShift = 4;
  std::vector<Point> pts;
  for (const Point2f& c : corners) pts.emplace_back(cvRound(c.x * (1 << kShift)), cvRound(c.y * (1 << kShift)));
  cv::fillConvexPoly(img, pts, colour, cv::LINE_AA, kShift);
}

// A map in [0, 1] of how much paint is worn off: smooth blotches and speckle.
cv::Mat WearMap(cv::RNG& rng, cv::Size size, double px_per_m) {
  cv::Mat wear(size, CV_32FC1, Scalar(0));
  AccumulateSmoothNoise(wear, rng, Px(1.5, px_per_m, 2), 0.35);
  AccumulateSmoothNoise(wear, rng, Px(0.25, px_per_m, 2), 0.25);
  cv::Mat speckle(size, CV_32FC1);
  rng.fill(speckle, cv::RNG::NORMAL, 0.0, 0.15);
  wear += speckle;
  cv::threshold(wear, wear, 0.1, 0, cv::THRESH_TOZERO);  // most paint is intact
  cv::min(wear * 1.6, 1.0, wear);
  return wear;
}

// Blends `paint` into `img` where `coverage` (CV_8UC1, 255 = painted) says, less the wear.
void ApplyPaint(cv::Mat& img, const cv::Mat& coverage, const cv::Mat& wear, const Scalar& paint) {
  for (int r = 0; r < img.rows; ++r) {
    cv::Vec3b* px = img.ptr<cv::Vec3b>(r);
    const uchar* c = coverage.ptr<uchar>(r);
    const float* w = wear.ptr<float>(r);
    for (int col = 0; col < img.cols; ++col) {
      const float a = c[col] / 255.0f * (1.0f - w[col]);
      if (a <= 0) continue;
      for (int k = 0; k < 3; ++k) px[col][k] = cv::saturate_cast<uchar>(px[col][k] * (1 - a) + paint[k] * a);
    }
  }
}

// A wandering line of `segments` steps of about `step_px`, from `start`.
void DrawCrack(cv::Mat& img, cv::RNG& rng, Point2f start, int segments, double step_px, const Scalar& colour, int thickness) {
  double heading = rng.uniform(0.0, 2 * M_PI);
  Point2f p = start;
  for (int s = 0; s < segments; ++s) {
    heading += rng.uniform(-0.7, 0.7);
    const double len = step_px * rng.uniform(0.5, 1.5);
    const Point2f q = p + Point2f(static_cast<float>(len * std::cos(heading)), static_cast<float>(len * std::sin(heading)));
    cv::line(img, Point(cvRound(p.x), cvRound(p.y)), Point(cvRound(q.x), cvRound(q.y)), colour, thickness, cv::LINE_AA);
    p = q;
  }
}

// Text fitted into `box` (one line, Hershey font), centred.
void DrawFittedText(cv::Mat& img, const std::string& text, Rect box, int font, const Scalar& ink) {
  if (box.width < 4 || box.height < 4 || text.empty()) return;
  int baseline = 0;
  const cv::Size unit = cv::getTextSize(text, font, 1.0, 1, &baseline);
  const double scale = std::min(box.width * 0.9 / unit.width, box.height * 0.75 / unit.height);
  if (scale <= 0.05) return;
  const int thickness = std::max(1, static_cast<int>(std::lround(scale * 1.6)));
  const cv::Size size = cv::getTextSize(text, font, scale, thickness, &baseline);
  const Point origin(box.x + (box.width - size.width) / 2, box.y + (box.height + size.height) / 2);
  cv::putText(img, text, origin, font, scale, ink, thickness, cv::LINE_AA);
}

int RandomFont(cv::RNG& rng) {
  static const std::array<int, 5> kFonts = {cv::FONT_HERSHEY_SIMPLEX, cv::FONT_HERSHEY_DUPLEX, cv::FONT_HERSHEY_COMPLEX,
                                             cv::FONT_HERSHEY_TRIPLEX, cv::FONT_HERSHEY_SCRIPT_SIMPLEX};
  return kFonts[rng.uniform(0, static_cast<int>(kFonts.size()))];
}

Scalar InkFor(const Scalar& background) {
  return (background[0] + background[1] + background[2]) / 3 > 120 ? Scalar(25, 25, 25) : Scalar(245, 245, 245);
}

}  // namespace

cv::Size GroundPatch::SizePx() const {
  return cv::Size(Px(hi_m.x() - lo_m.x(), px_per_m, 2), Px(hi_m.y() - lo_m.y(), px_per_m, 2));
}

cv::Point2f GroundPatch::ToPixel(const Eigen::Vector2d& p) const {
  return cv::Point2f(static_cast<float>((p.x() - lo_m.x()) * px_per_m), static_cast<float>((hi_m.y() - p.y()) * px_per_m));
}

std::string MakeWord(cv::RNG& rng, int min_letters, int max_letters) {
  static const char* kOnsets[] = {"b", "c", "d", "f", "g", "h", "k", "l", "m", "n", "p", "r", "s", "t", "v", "z",
                                  "br", "st", "tr", "gr", "ch", "sh", "pl", "kr", "fl", "w"};
  static const char* kVowels[] = {"a", "e", "i", "o", "u", "ai", "ou", "ee", "y", "ia"};
  const int target = rng.uniform(min_letters, max_letters + 1);
  std::string word;
  while (static_cast<int>(word.size()) < target) {
    word += kOnsets[rng.uniform(0, static_cast<int>(std::size(kOnsets)))];
    word += kVowels[rng.uniform(0, static_cast<int>(std::size(kVowels)))];
    if (rng.uniform(0, 3) == 0) word += kOnsets[rng.uniform(0, 16)];
  }
  word.resize(std::min<std::size_t>(word.size(), static_cast<std::size_t>(max_letters)));
  word[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(word[0])));
  return word;
}

// ---- Ground ---------------------------------------------------------------------------

cv::Mat StreetTexture(std::uint64_t seed, const GroundPatch& patch, const std::vector<RoadMarking>& markings) {
  cv::RNG rng = MakeRng(seed);
  const cv::Size size = patch.SizePx();
  const double ppm = patch.px_per_m;
  const double area_m2 = (patch.hi_m - patch.lo_m).prod();
  const auto random_point = [&] { return Point2f(rng.uniform(0.f, float(size.width)), rng.uniform(0.f, float(size.height))); };
  cv::Mat img(size, CV_8UC3, Scalar(72, 74, 76) + Scalar::all(rng.uniform(-8, 8)));
  AddFractalNoise(img, rng, 9);
  // Aggregate: light and dark stones of 1 to 2 cm.
  const int stone_px = std::max(0, Px(0.01, ppm, 0));
  for (int k = CountFor(size.area(), 0.02); k > 0; --k) {
    const int v = rng.uniform(0, 2) ? rng.uniform(95, 150) : rng.uniform(30, 55);
    cv::circle(img, random_point(), stone_px + rng.uniform(0, 2), Scalar::all(v), cv::FILLED);
  }
  // Repair patches: a rectangle of newer or older asphalt with a sealed edge.
  for (int k = CountFor(area_m2, 1.0 / 60); k > 0; --k) {
    const Point2f c = random_point();
    const cv::Size2f half(float(Px(rng.uniform(0.3, 1.4), ppm)), float(Px(rng.uniform(0.3, 1.0), ppm)));
    const cv::RotatedRect box(c, half * 2.f, rng.uniform(-8.f, 8.f) + (rng.uniform(0, 2) ? 90.f : 0.f));
    Point2f corners[4];
    box.points(corners);
    FillPolygon(img, {corners, corners + 4}, Scalar::all(rng.uniform(48, 100)));
    for (int i = 0; i < 4; ++i) cv::line(img, corners[i], corners[(i + 1) % 4], Scalar(28, 28, 30), std::max(1, Px(0.03, ppm)), cv::LINE_AA);
  }
  // Tar-sealed seams across the patch and cracks.
  for (int k = CountFor(area_m2, 1.0 / 400, 1); k > 0; --k) {
    DrawCrack(img, rng, random_point(), rng.uniform(20, 60), ppm * 0.8, Scalar(26, 27, 29), std::max(1, Px(0.03, ppm)));
  }
  for (int k = CountFor(area_m2, 1.0 / 20); k > 0; --k) {
    DrawCrack(img, rng, random_point(), rng.uniform(4, 14), ppm * 0.2, Scalar(32, 32, 34), std::max(1, Px(0.01, ppm)));
  }
  // Markings in worn paint.
  cv::Mat coverage(size, CV_8UC1, Scalar(0));
  for (const RoadMarking& m : markings) {
    const Eigen::Vector2d along(std::cos(m.yaw_rad), std::sin(m.yaw_rad)), across(-along.y(), along.x());
    std::vector<Point2f> corners;
    for (const auto& s : {Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, -1), Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1)}) {
      corners.push_back(patch.ToPixel(m.centre_m + along * (s.x() * m.half_m.x()) + across * (s.y() * m.half_m.y())));
    }
    FillPolygon(coverage, corners, Scalar(255));
  }
  if (!markings.empty()) ApplyPaint(img, coverage, WearMap(rng, size, ppm), Jitter(rng, Scalar(222, 226, 228), 6));
  // Oil stains and tyre grime, soft edged.
  cv::Mat stains(size, CV_32FC1, Scalar(0));
  for (int k = CountFor(area_m2, 1.0 / 40); k > 0; --k) {
    cv::ellipse(stains, random_point(), cv::Size(Px(rng.uniform(0.1, 0.5), ppm), Px(rng.uniform(0.08, 0.3), ppm)),
                rng.uniform(0, 180), 0, 360, Scalar(rng.uniform(-30, -12)), cv::FILLED);
  }
  cv::GaussianBlur(stains, stains, cv::Size(0, 0), std::max(0.5, 0.04 * ppm));
  AddMap(img, stains);
  // Manholes and drain grates.
  for (int k = CountFor(area_m2, 1.0 / 350); k > 0; --k) {
    const Point2f c = random_point();
    const int r = Px(rng.uniform(0.3, 0.36), ppm, 2);
    cv::circle(img, c, r + Px(0.05, ppm), Scalar(50, 52, 54), cv::FILLED, cv::LINE_AA);
    cv::circle(img, c, r, Scalar::all(rng.uniform(70, 100)), cv::FILLED, cv::LINE_AA);
    const int rings = rng.uniform(2, 5);
    for (int i = 1; i <= rings; ++i) cv::circle(img, c, r * i / (rings + 1), Scalar(40, 42, 44), 1, cv::LINE_AA);
    for (int i = 0; i < rng.uniform(0, 6); ++i) {
      const double a = rng.uniform(0.0, 2 * M_PI);
      cv::line(img, c, c + Point2f(float(r * std::cos(a)), float(r * std::sin(a))), Scalar(42, 44, 46), 1, cv::LINE_AA);
    }
  }
  for (int k = CountFor(area_m2, 1.0 / 500); k > 0; --k) {
    const Point2f c = random_point();
    const int w = Px(0.5, ppm, 3), h = Px(0.3, ppm, 2);
    const Rect grate(cvRound(c.x), cvRound(c.y), w, h);
    cv::rectangle(img, grate, Scalar(25, 25, 27), cv::FILLED);
    for (int x = grate.x + 1; x < grate.x + w; x += std::max(2, Px(0.05, ppm))) {
      cv::line(img, Point(x, grate.y), Point(x, grate.y + h), Scalar(80, 82, 84), 1);
    }
  }
  AddGrain(img, rng, 6.0);
  return img;
}

cv::Mat PavedStripTexture(std::uint64_t seed, const GroundPatch& patch, double paver_m) {
  cv::RNG rng = MakeRng(seed);
  const cv::Size size = patch.SizePx();
  const double ppm = patch.px_per_m;
  const double area_m2 = (patch.hi_m - patch.lo_m).prod();
  // Concrete greys, a little warm or cool from one block to the next.
  const Scalar joint = Scalar(95, 100, 105) + Scalar::all(rng.uniform(-12, 12));
  const Scalar base = Jitter(rng, Scalar(160, 166, 172) + Scalar::all(rng.uniform(-25, 25)), 6);
  cv::Mat img(size, CV_8UC3, joint);
  // Pavers in a running bond along x, aligned with the world grid so neighbouring strips
  // meet; each with its own shade, some cracked, a few replaced by another stone.
  const double cell_px = paver_m * ppm;
  const double gap_px = std::max(1.0, 0.008 * ppm);
  const double x0 = std::fmod(patch.lo_m.x(), paver_m) * ppm, y0 = std::fmod(patch.hi_m.y(), paver_m) * ppm;
  for (int row = 0; row * cell_px - y0 < size.height + cell_px; ++row) {
    const double y = row * cell_px - y0;
    const double shift = (row % 2) * 0.5 * cell_px - x0;
    for (double x = -cell_px + shift; x < size.width + cell_px; x += cell_px) {
      const Scalar shade = rng.uniform(0, 40) == 0 ? Jitter(rng, base * 0.7, 20) : Jitter(rng, base, 14);
      const Rect r(cvRound(x + gap_px / 2), cvRound(y + gap_px / 2), cvRound(cell_px - gap_px), cvRound(cell_px - gap_px));
      cv::rectangle(img, r, shade, cv::FILLED);
      if (rng.uniform(0, 12) == 0) {
        cv::line(img, Point(r.x, r.y + rng.uniform(0, std::max(1, r.height))),
                 Point(r.x + r.width, r.y + rng.uniform(0, std::max(1, r.height))), joint, 1, cv::LINE_AA);
      }
    }
  }
  AddFractalNoise(img, rng, 7);
  const auto random_point = [&] { return Point(rng.uniform(0, size.width), rng.uniform(0, size.height)); };
  cv::Mat stains(size, CV_32FC1, Scalar(0));
  for (int k = CountFor(area_m2, 1.0 / 15); k > 0; --k) {
    cv::circle(stains, random_point(), Px(rng.uniform(0.1, 0.6), ppm), Scalar(rng.uniform(-25, -8)), cv::FILLED);
  }
  cv::GaussianBlur(stains, stains, cv::Size(0, 0), std::max(0.5, 0.06 * ppm));
  AddMap(img, stains);
  for (int k = CountFor(area_m2, 0.6); k > 0; --k) {  // gum spots and leaves
    const bool leaf = rng.uniform(0, 3) == 0;
    const Scalar c = leaf ? Jitter(rng, Scalar(40, 90, 120), 25) : Scalar::all(rng.uniform(60, 120));
    cv::ellipse(img, random_point(), cv::Size(Px(leaf ? 0.04 : 0.012, ppm), Px(leaf ? 0.02 : 0.012, ppm)),
                rng.uniform(0, 180), 0, 360, c, cv::FILLED, cv::LINE_AA);
  }
  AddGrain(img, rng, 6.0);
  return img;
}

// ---- Facades ---------------------------------------------------------------------------

FacadeLayout PlanFacade(std::uint64_t building_seed, int face, double width_m, double height_m, FacadeStyle style,
                        bool shops) {
  // What the faces of one building share (materials, storey heights, window shapes) comes
  // from the building's seed, where the windows and shops are from the face's.
  cv::RNG rng = MakeRng(building_seed);
  cv::RNG face_rng = MakeRng(building_seed * 0x9e3779b97f4a7c15ull + static_cast<std::uint64_t>(face) + 1);
  FacadeLayout f;
  f.width_m = width_m;
  f.height_m = height_m;
  f.style = style;
  switch (style) {
    case FacadeStyle::kBrick: f.wall_bgr = Jitter(rng, Scalar(60, 80, 150), 30); break;
    case FacadeStyle::kConcrete: f.wall_bgr = Jitter(rng, Scalar(160, 166, 168), 30); break;
    case FacadeStyle::kGlass: f.wall_bgr = Jitter(rng, Scalar(120, 110, 95), 25); break;
    case FacadeStyle::kPlaster: {
      // Colours of real rendered walls: creams, ochres, greys, muted pastels.
      static const Scalar kPlasters[] = {Scalar(190, 215, 230), Scalar(120, 175, 215), Scalar(170, 180, 185),
                                         Scalar(150, 190, 200), Scalar(200, 200, 190), Scalar(110, 140, 190),
                                         Scalar(175, 200, 170), Scalar(200, 185, 200), Scalar(215, 225, 232)};
      f.wall_bgr = Jitter(rng, kPlasters[rng.uniform(0, static_cast<int>(std::size(kPlasters)))], 14);
      break;
    }
  }
  f.trim_bgr = Jitter(rng, rng.uniform(0, 2) ? Scalar(215, 215, 210) : f.wall_bgr * 0.75, 20);
  f.frame_bgr = rng.uniform(0, 2) ? Jitter(rng, Scalar(235, 235, 235), 15) : Jitter(rng, Scalar(55, 55, 55), 30);
  f.floor_m = rng.uniform(2.9, 3.7);
  f.ground_floor_m = std::min(height_m, shops ? rng.uniform(3.8, 4.9) : rng.uniform(3.0, 3.9));
  f.upper_floors = std::max(0, static_cast<int>(std::floor((height_m - f.ground_floor_m - 0.5) / f.floor_m)));
  const bool glass = style == FacadeStyle::kGlass;
  const int per_bay = glass ? 1 : rng.uniform(1, 3);
  const double bay_m = rng.uniform(2.4, 4.2);
  const double width_share = glass ? rng.uniform(0.82, 0.92) : rng.uniform(0.4, 0.68) * (per_bay == 2 ? 0.9 : 1.0);
  const double height_share = glass ? rng.uniform(0.75, 0.85) : rng.uniform(0.45, 0.65);
  const bool balconies = !glass && f.upper_floors > 0 && rng.uniform(0, 10) < 3;
  const bool attic = rng.uniform(0, 4) == 0;
  rng = face_rng;

  // Bays: columns of windows, each a little wider or narrower than the next.
  const double margin = rng.uniform(0.3, 1.2);
  const double usable = std::max(1.0, width_m - 2 * margin);
  const int bays = std::max(1, static_cast<int>(std::lround(usable / bay_m)));
  std::vector<double> edges = {margin};
  {
    std::vector<double> w(bays);
    double total = 0;
    for (double& b : w) total += (b = rng.uniform(0.93, 1.07));
    for (double b : w) edges.push_back(edges.back() + usable * b / total);
  }
  std::vector<bool> blank(bays, false), balcony_bay(bays, false);
  for (int b = 0; b < bays; ++b) blank[b] = bays > 2 && rng.uniform(0, 12) == 0;
  for (int b = 0; b < bays; ++b) balcony_bay[b] = balconies && rng.uniform(0, 2) == 0;
  for (int fl = 0; fl < f.upper_floors; ++fl) {
    const double z_floor = f.ground_floor_m + fl * f.floor_m;
    // The top floor's windows are sometimes smaller (an attic storey).
    const double hs = (fl + 1 == f.upper_floors && attic) ? height_share * 0.7 : height_share;
    for (int b = 0; b < bays; ++b) {
      if (blank[b]) continue;
      const double cell = (edges[b + 1] - edges[b]) / per_bay;
      for (int k = 0; k < per_bay; ++k) {
        const double ww = cell * width_share * rng.uniform(0.98, 1.02);
        const double wh = f.floor_m * hs * rng.uniform(0.98, 1.02);
        const double cx = edges[b] + (k + 0.5) * cell + rng.uniform(-0.03, 0.03);
        const double z0 = z_floor + (f.floor_m - wh) * 0.55 + rng.uniform(-0.03, 0.03);
        f.windows.push_back({cx - ww / 2, cx + ww / 2, z0, z0 + wh});
        if (balcony_bay[b] && k == 0) {
          const double bx0 = edges[b] + 0.15, bx1 = edges[b + 1] - 0.15;
          f.balconies.push_back({bx0, bx1, z_floor, z_floor});
        }
      }
    }
  }
  // The ground floor: shops side by side with their own names, or a lobby with windows.
  const double gf = f.ground_floor_m;
  if (shops) {
    double x = 0;
    while (x < width_m - 0.5) {
      double w = rng.uniform(4.5, 11.0);
      if (width_m - x - w < 3.5) w = width_m - x;  // the last shop takes the rest
      FacadeLayout::Shop s;
      s.x0_m = x;
      s.x1_m = x + w;
      s.sign = MakeWord(rng, 4, 9);
      if (rng.uniform(0, 3) == 0) s.sign += " " + MakeWord(rng, 3, 6);
      s.sign_bgr = RandomColor(rng, 25, 230);
      s.awning = rng.uniform(0, 2) == 0;
      s.awning_bgr = RandomColor(rng, 30, 220);
      const double door_w = rng.uniform(0.9, 1.4);
      const double door_x = rng.uniform(0, 2) ? x + w - door_w - 0.4 : x + 0.4;
      f.doors.push_back({door_x, door_x + door_w, 0.0, std::min(gf - 0.9, 2.3)});
      f.shops.push_back(s);
      x += w;
    }
  } else {
    const double door_w = rng.uniform(1.2, 2.0);
    const double door_x = rng.uniform(margin, std::max(margin, width_m - margin - door_w));
    f.doors.push_back({door_x, door_x + door_w, 0.0, std::min(gf - 0.5, 2.6)});
    for (int b = 0; b < bays; ++b) {
      const double cx = 0.5 * (edges[b] + edges[b + 1]) + rng.uniform(-0.05, 0.05);
      const double ww = (edges[b + 1] - edges[b]) * width_share;
      if (cx + ww / 2 > door_x - 0.3 && cx - ww / 2 < door_x + door_w + 0.3) continue;  // not over the door
      f.ground_windows.push_back({cx - ww / 2, cx + ww / 2, 0.9, std::min(gf - 0.4, 0.9 + gf * 0.5)});
    }
  }
  return f;
}

cv::Mat FacadeTexture(std::uint64_t seed, const FacadeLayout& f, double ppm) {
  cv::RNG rng = MakeRng(seed ^ 0x9e3779b97f4a7c15ull);
  const int W = Px(f.width_m, ppm, 2), H = Px(f.height_m, ppm, 2);
  cv::Mat img(H, W, CV_8UC3, f.wall_bgr);
  const auto rect = [&](const FacadeLayout::Opening& o) {
    const int x0 = cvRound(o.x0_m * ppm), x1 = cvRound(o.x1_m * ppm);
    const int y0 = cvRound((f.height_m - o.z1_m) * ppm), y1 = cvRound((f.height_m - o.z0_m) * ppm);
    return Rect(x0, y0, std::max(1, x1 - x0), std::max(1, y1 - y0)) & Rect(0, 0, W, H);
  };
  const auto row_of = [&](double z_m) { return cvRound((f.height_m - z_m) * ppm); };
  // The wall.
  switch (f.style) {
    case FacadeStyle::kBrick: Brickwork(img, rng, f.wall_bgr, ppm); break;
    case FacadeStyle::kConcrete:
      for (double x = rng.uniform(0.5, 2.0); x < f.width_m; x += rng.uniform(1.2, 3.0)) {  // panel joints
        cv::line(img, Point(cvRound(x * ppm), 0), Point(cvRound(x * ppm), H), f.wall_bgr * 0.72, std::max(1, Px(0.02, ppm)));
      }
      break;
    case FacadeStyle::kGlass:
    case FacadeStyle::kPlaster: break;
  }
  AddFractalNoise(img, rng, f.style == FacadeStyle::kBrick ? 6 : 10);
  // Floor bands (slabs and cornices), one per floor.
  const int band_px = std::max(1, Px(0.14, ppm));
  for (int fl = 0; fl <= f.upper_floors; ++fl) {
    const int y = row_of(f.ground_floor_m + fl * f.floor_m);
    cv::rectangle(img, Rect(0, y - band_px / 2, W, band_px), Jitter(rng, f.trim_bgr, 8), cv::FILLED);
  }
  // Upper windows with sills and lintels.
  const int frame_px = std::max(1, Px(0.05, ppm));
  for (const FacadeLayout::Opening& o : f.windows) {
    const Rect r = rect(o);
    if (r.width < 2 || r.height < 2) continue;
    DrawWindow(img, rng, r, Jitter(rng, f.frame_bgr, 10), frame_px);
    if (f.style != FacadeStyle::kGlass) {
      const int sill = std::max(1, Px(0.07, ppm));
      cv::rectangle(img, Rect(r.x - sill, r.y + r.height, r.width + 2 * sill, sill), Jitter(rng, f.trim_bgr, 15), cv::FILLED);
      if (rng.uniform(0, 3) == 0) {  // a rain streak under the sill
        const int x = r.x + rng.uniform(0, std::max(1, r.width));
        cv::line(img, Point(x, r.y + r.height + sill), Point(x + rng.uniform(-2, 3), r.y + r.height + sill + Px(rng.uniform(0.3, 1.5), ppm)),
                 f.wall_bgr * 0.78, std::max(1, Px(0.04, ppm)), cv::LINE_AA);
      }
      if (rng.uniform(0, 14) == 0) {  // an air conditioner
        const Rect ac(r.x + r.width / 4, r.y + r.height - Px(0.45, ppm), r.width / 2, Px(0.4, ppm));
        cv::rectangle(img, ac & Rect(0, 0, W, H), Scalar(200, 205, 205), cv::FILLED);
        cv::circle(img, Point(ac.x + ac.width / 2, ac.y + ac.height / 2), std::max(1, ac.height / 3), Scalar(90, 90, 90), 1, cv::LINE_AA);
      }
    }
  }
  // Balcony railings drawn on the wall behind the slabs (the slabs are geometry).
  for (const FacadeLayout::Opening& b : f.balconies) {
    const int y = row_of(b.z0_m);
    const int x0 = cvRound(b.x0_m * ppm), x1 = cvRound(b.x1_m * ppm), top = y - Px(1.0, ppm);
    for (int x = x0; x <= x1; x += std::max(2, Px(0.12, ppm))) cv::line(img, Point(x, top), Point(x, y), Scalar(45, 45, 45), std::max(1, Px(0.02, ppm)));
    cv::line(img, Point(x0, top), Point(x1, top), Scalar(45, 45, 45), std::max(1, Px(0.04, ppm)));
  }
  // The ground floor.
  const int gf_top = row_of(f.ground_floor_m);
  for (const FacadeLayout::Shop& s : f.shops) {
    const int x0 = cvRound(s.x0_m * ppm), x1 = cvRound(s.x1_m * ppm);
    const int sign_h = std::max(2, Px(0.7, ppm));
    const Rect sign(x0 + Px(0.15, ppm), gf_top + Px(0.15, ppm), std::max(2, x1 - x0 - Px(0.3, ppm)), sign_h);
    cv::rectangle(img, sign & Rect(0, 0, W, H), s.sign_bgr, cv::FILLED);
    DrawFittedText(img, s.sign, sign, RandomFont(rng), InkFor(s.sign_bgr));
    const Rect window(x0 + Px(0.3, ppm), sign.y + sign.height + Px(0.25, ppm), std::max(2, x1 - x0 - Px(0.6, ppm)),
                      std::max(2, row_of(0.5) - (sign.y + sign.height + Px(0.25, ppm))));
    if ((window & Rect(0, 0, W, H)) == window && window.height > 2) {
      DrawWindow(img, rng, window, Scalar(40, 40, 40), frame_px);
      for (int k = CountFor((s.x1_m - s.x0_m), 2.5); k > 0; --k) {  // goods on display
        const Point p(window.x + rng.uniform(0, std::max(1, window.width - 4)), window.y + rng.uniform(window.height / 3, std::max(window.height / 3 + 1, window.height - 4)));
        cv::rectangle(img, Rect(p.x, p.y, Px(rng.uniform(0.05, 0.2), ppm), Px(rng.uniform(0.08, 0.3), ppm)) & window, RandomColor(rng), cv::FILLED);
      }
      DrawParagraph(img, rng, Rect(window.x + Px(0.2, ppm), window.y + Px(0.2, ppm), window.width / 3, Px(0.4, ppm)),
                    Scalar(240, 240, 240), std::max(2, Px(0.08, ppm)));
    }
  }
  for (const FacadeLayout::Opening& o : f.ground_windows) DrawWindow(img, rng, rect(o), Jitter(rng, f.frame_bgr, 10), frame_px);
  for (const FacadeLayout::Opening& d : f.doors) {
    const Rect r = rect(d);
    cv::rectangle(img, r, Jitter(rng, Scalar(50, 45, 40), 25), cv::FILLED);
    cv::rectangle(img, Rect(r.x + r.width / 6, r.y + r.height / 10, r.width * 2 / 3, r.height / 2) & Rect(0, 0, W, H), Scalar(70, 62, 55), cv::FILLED);
    cv::line(img, Point(r.x + r.width * 5 / 6, r.y + r.height / 2), Point(r.x + r.width * 5 / 6, r.y + r.height * 3 / 5), Scalar(190, 190, 190), std::max(1, Px(0.03, ppm)));
    // A house number or a plaque beside the door.
    const Rect plaque(r.x + r.width + Px(0.15, ppm), r.y + r.height / 4, Px(0.35, ppm, 2), Px(0.25, ppm, 2));
    if ((plaque & Rect(0, 0, W, H)) == plaque) {
      cv::rectangle(img, plaque, Scalar(200, 120, 40), cv::FILLED);
      DrawFittedText(img, std::to_string(rng.uniform(1, 300)), plaque, cv::FONT_HERSHEY_SIMPLEX, Scalar(245, 245, 245));
    }
  }
  // Grime rising from the pavement, posters and tags near the ground, a drainpipe.
  cv::Mat grime(H, W, CV_32FC1, Scalar(0));
  const int grime_px = Px(rng.uniform(0.4, 1.2), ppm);
  for (int y = std::max(0, H - grime_px); y < H; ++y) grime.row(y).setTo(Scalar(-18.0 * (y - (H - grime_px)) / grime_px));
  AccumulateSmoothNoise(grime, rng, Px(0.8, ppm, 2), 6);
  AddMap(img, grime);
  for (int k = CountFor(f.width_m, 0.12); k > 0; --k) {
    const Point p(rng.uniform(0, W), row_of(rng.uniform(0.6, 2.0)));
    if (rng.uniform(0, 2)) {
      const Rect poster(p.x, p.y, Px(0.42, ppm, 2), Px(0.6, ppm, 2));
      cv::rectangle(img, poster & Rect(0, 0, W, H), RandomColor(rng, 120, 250), cv::FILLED);
      DrawParagraph(img, rng, Rect(poster.x + 2, poster.y + 2, poster.width - 4, poster.height - 4) & Rect(0, 0, W, H),
                    Scalar(30, 30, 30), std::max(2, Px(0.05, ppm)));
    } else {
      DrawGlyphs(img, rng, Rect(p.x, p.y, Px(rng.uniform(0.6, 2.0), ppm, 2), Px(0.4, ppm, 2)), RandomColor(rng, 20, 250),
                 std::max(1, Px(0.04, ppm)));
    }
  }
  if (rng.uniform(0, 2)) {
    const int x = rng.uniform(0, W);
    cv::line(img, Point(x, 0), Point(x, H), Scalar(70, 75, 78), std::max(1, Px(0.1, ppm)));
  }
  AddGrain(img, rng, 5.0);
  return img;
}

// ---- Vehicles ---------------------------------------------------------------------------

cv::Mat VehiclePaintTexture(std::uint64_t seed, cv::Size size) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(size, CV_8UC3, Scalar::all(235));
  AddSmoothNoise(img, rng, std::max(4, size.width / 8), 9);
  const int seam = std::max(1, size.width / 150);
  // Door seams across the side, a handle behind each.
  for (int k = rng.uniform(1, 4); k > 0; --k) {
    const int x = rng.uniform(size.width / 5, std::max(size.width / 5 + 1, size.width * 4 / 5));
    cv::line(img, Point(x, 0), Point(x + rng.uniform(-3, 4), size.height), Scalar::all(95), seam, cv::LINE_AA);
    const Rect handle(x + size.width / 30, size.height / 4, std::max(2, size.width / 18), std::max(1, size.height / 20));
    cv::rectangle(img, handle & Rect(0, 0, size.width, size.height), Scalar::all(rng.uniform(120, 170)), cv::FILLED);
  }
  for (int k = rng.uniform(2, 12); k > 0; --k) {  // scratches
    const Point p(rng.uniform(0, size.width), rng.uniform(0, size.height));
    cv::line(img, p, p + Point(rng.uniform(-size.width / 8, size.width / 8 + 1), rng.uniform(-4, 5)),
             Scalar::all(rng.uniform(150, 255)), 1, cv::LINE_AA);
  }
  if (rng.uniform(0, 3) == 0) {  // a sticker or a dent's shadow
    const Point p(rng.uniform(0, size.width), rng.uniform(0, size.height));
    cv::ellipse(img, p, cv::Size(rng.uniform(3, 12), rng.uniform(3, 9)), rng.uniform(0, 180), 0, 360,
                rng.uniform(0, 2) ? RandomColor(rng, 40, 250) : Scalar::all(150), cv::FILLED, cv::LINE_AA);
  }
  cv::Mat dirt = img(Rect(0, size.height * 3 / 4, size.width, size.height - size.height * 3 / 4));
  AddSmoothNoise(dirt, rng, 4, rng.uniform(10, 30));
  AddGrain(img, rng, 3.0);
  return img;
}

cv::Mat VehicleGlassTexture(std::uint64_t seed, cv::Size size) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(size, CV_8UC3, Jitter(rng, Scalar(40, 35, 30), 8));
  const int sky = size.height * rng.uniform(30, 50) / 100;
  for (int y = 0; y < sky; ++y) {
    const double f = 1.0 - double(y) / std::max(1, sky);
    cv::line(img, Point(0, y), Point(size.width, y), Scalar(40 + 100 * f, 35 + 85 * f, 30 + 70 * f));
  }
  for (int k = rng.uniform(0, 4); k > 0; --k) {  // headrests and passengers
    const Point c(rng.uniform(0, size.width), size.height * rng.uniform(55, 80) / 100);
    cv::ellipse(img, c, cv::Size(std::max(2, size.height / 6), std::max(2, size.height / 4)), 0, 0, 360,
                Jitter(rng, Scalar(22, 22, 24), 10), cv::FILLED, cv::LINE_AA);
  }
  if (rng.uniform(0, 5) == 0) {  // a parking ticket or a sun shade
    cv::rectangle(img, Rect(rng.uniform(0, size.width), size.height * 2 / 3, size.width / 12 + 2, size.height / 6 + 2),
                  RandomColor(rng, 150, 250), cv::FILLED);
  }
  const int a = rng.uniform(0, size.height), b = rng.uniform(0, size.height);
  cv::line(img, Point(0, a), Point(size.width, b), Scalar(170, 165, 160), std::max(1, size.height / 30), cv::LINE_AA);
  AddSmoothNoise(img, rng, std::max(4, size.width / 10), 8);
  AddGrain(img, rng, 3.0);
  return img;
}

// ---- Small signs ------------------------------------------------------------------------

cv::Mat NumberPlateTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(64, 256, CV_8UC3, Jitter(rng, Scalar(232, 235, 235), 8));
  cv::rectangle(img, Rect(0, 0, 22, 64), Scalar(140, 50, 20), cv::FILLED);
  std::string number;
  for (int i = 0; i < 2; ++i) number += static_cast<char>('A' + rng.uniform(0, 26));
  number += ' ';
  for (int i = 0; i < 3; ++i) number += static_cast<char>('0' + rng.uniform(0, 10));
  number += ' ';
  for (int i = 0; i < 2; ++i) number += static_cast<char>('A' + rng.uniform(0, 26));
  DrawFittedText(img, number, Rect(26, 4, 226, 56), cv::FONT_HERSHEY_DUPLEX, Scalar(20, 20, 20));
  cv::rectangle(img, Rect(0, 0, 256, 64), Scalar(20, 20, 20), 3);
  AddSmoothNoise(img, rng, 16, 8);  // dirt
  return img;
}

cv::Mat StreetSignTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  const bool blue = rng.uniform(0, 2);
  const Scalar background = blue ? Jitter(rng, Scalar(150, 70, 20), 20) : Jitter(rng, Scalar(235, 235, 235), 10);
  const Scalar ink = InkFor(background);
  cv::Mat img(160, 128, CV_8UC3, background);
  cv::rectangle(img, Rect(3, 3, 122, 154), ink, 3);
  DrawFittedText(img, MakeWord(rng, 4, 8), Rect(8, 12, 112, 44), RandomFont(rng), ink);
  DrawFittedText(img, rng.uniform(0, 2) ? std::to_string(rng.uniform(1, 24)) + "h" : MakeWord(rng, 2, 4), Rect(8, 60, 112, 40),
                 cv::FONT_HERSHEY_SIMPLEX, ink);
  DrawFittedText(img, std::to_string(rng.uniform(1, 999)), Rect(8, 106, 112, 40), cv::FONT_HERSHEY_DUPLEX, ink);
  AddSmoothNoise(img, rng, 20, 6);
  AddGrain(img, rng, 3.0);
  return img;
}

cv::Mat CompanyLogoTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  const Scalar background = Jitter(rng, Scalar(235, 235, 232), 10), brand = RandomColor(rng, 20, 200);
  cv::Mat img(120, 320, CV_8UC3, background);
  cv::rectangle(img, Rect(0, 84 + rng.uniform(0, 10), 320, rng.uniform(8, 22)), brand, cv::FILLED);
  if (rng.uniform(0, 2)) cv::circle(img, Point(40, 45), 30, brand, cv::FILLED, cv::LINE_AA);
  DrawFittedText(img, MakeWord(rng, 4, 9), Rect(76, 8, 236, 70), RandomFont(rng), brand);
  AddSmoothNoise(img, rng, 24, 6);
  AddGrain(img, rng, 3.0);
  return img;
}

}  // namespace segslam::scenes
