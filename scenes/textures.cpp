// Procedural textures from a few primitives: smooth multi-scale noise, per-pixel grain,
// glyph-like strokes (text without a font) and jittered grids.
#include "scenes/textures.h"
#include "scenes/texture_primitives.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace segslam::scenes {
using namespace texture;
using cv::Point;
using cv::Rect;
using cv::Scalar;

cv::Mat FacadeTexture(std::uint64_t seed, FacadeStyle style, int floors, int bays) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(768, 1024, CV_8UC3);
  const int fh = img.rows / floors, bw = img.cols / bays;

  // Wall material.
  Scalar wall;
  switch (style) {
    case FacadeStyle::kBrick:
      wall = Jitter(rng, Scalar(60, 80, 150), 25);
      Brickwork(img, rng, wall);
      break;
    case FacadeStyle::kConcrete:
      wall = Jitter(rng, Scalar(165, 170, 170), 25);
      img.setTo(wall);
      for (int x = 0; x < img.cols; x += bw / 2) cv::line(img, Point(x, 0), Point(x, img.rows), wall * 0.7, 2);
      break;
    case FacadeStyle::kGlass:
      wall = Jitter(rng, Scalar(120, 110, 95), 20);
      img.setTo(wall);
      break;
    case FacadeStyle::kPlaster:
      wall = Jitter(rng, Scalar(170, 200, 220), 35);
      img.setTo(wall);
      break;
  }
  AddFractalNoise(img, rng, style == FacadeStyle::kBrick ? 6 : 10);

  // Floor bands (slabs / cornices).
  const Scalar band = Jitter(rng, wall * 0.8, 20);
  for (int f = 0; f < floors; ++f) {
    cv::rectangle(img, Rect(0, f * fh + fh - 10, img.cols, 10), band, cv::FILLED);
    cv::line(img, Point(0, f * fh + fh - 10), Point(img.cols, f * fh + fh - 10), band * 0.6, 2);
  }

  // Windows: one or two per bay, per-window variation in interior and curtains.
  const Scalar frame = rng.uniform(0, 2) ? Scalar(235, 235, 235) : Jitter(rng, Scalar(60, 60, 60), 30);
  const bool wide = style == FacadeStyle::kGlass;
  const int per_bay = wide ? 1 : rng.uniform(1, 3);
  for (int f = 0; f < floors; ++f) {
    for (int b = 0; b < bays; ++b) {
      for (int k = 0; k < per_bay; ++k) {
        const int cell = bw / per_bay;
        const int ww = wide ? cell - 12 : cell * rng.uniform(45, 62) / 100;
        const int wh = wide ? fh - 22 : fh * rng.uniform(50, 62) / 100;
        const int x = b * bw + k * cell + (cell - ww) / 2;
        const int y = f * fh + (fh - 10 - wh) / 2;
        DrawWindow(img, rng, Rect(x, y, ww, wh), frame, wide ? 3 : 4);
        if (!wide) {
          // Sill and lintel.
          cv::rectangle(img, Rect(x - 5, y + wh, ww + 10, 6), Jitter(rng, Scalar(200, 200, 200), 20), cv::FILLED);
          cv::rectangle(img, Rect(x - 3, y - 5, ww + 6, 5), band, cv::FILLED);
          // Occasional balcony railing or air conditioner.
          if (rng.uniform(0, 7) == 0) {
            for (int xx = x - 6; xx < x + ww + 6; xx += 6) cv::line(img, Point(xx, y + wh - 24), Point(xx, y + wh), Scalar(40, 40, 40), 2);
            cv::line(img, Point(x - 6, y + wh - 24), Point(x + ww + 6, y + wh - 24), Scalar(40, 40, 40), 3);
          } else if (rng.uniform(0, 8) == 0) {
            cv::rectangle(img, Rect(x + ww / 4, y + wh - 22, ww / 2, 20), Scalar(200, 205, 205), cv::FILLED);
            cv::circle(img, Point(x + ww / 2, y + wh - 12), 7, Scalar(90, 90, 90), 1, cv::LINE_AA);
          }
        }
      }
    }
  }

  // Stains, rain streaks and a little grain.
  for (int k = rng.uniform(6, 14); k > 0; --k) {
    const int x = rng.uniform(0, img.cols);
    const int y = rng.uniform(0, img.rows);
    cv::line(img, Point(x, y), Point(x + rng.uniform(-4, 5), y + rng.uniform(20, 120)), wall * 0.75, rng.uniform(1, 4), cv::LINE_AA);
  }
  AddGrain(img, rng, 5.0);
  return img;
}

cv::Mat BarkTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(256, 256, CV_8UC3, Scalar(45, 65, 85));
  for (int k = 0; k < 70; ++k) {
    const int x = rng.uniform(0, 256);
    cv::line(img, Point(x, 0), Point(x + rng.uniform(-20, 21), 256), Scalar(25, 40, 55), rng.uniform(1, 5), cv::LINE_AA);
  }
  AddFractalNoise(img, rng, 14);
  AddGrain(img, rng, 8.0);
  return img;
}

cv::Mat FoliageTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 512, CV_8UC3, Scalar(30, 70, 35));
  // Thousands of leaves: small ellipses in greens, light on top.
  for (int k = 0; k < 6000; ++k) {
    const Point p(rng.uniform(0, 512), rng.uniform(0, 512));
    const double light = 1.3 - 0.6 * p.y / 512.0;
    const Scalar c(rng.uniform(15, 60) * light, rng.uniform(70, 150) * light, rng.uniform(30, 90) * light);
    cv::ellipse(img, p, cv::Size(rng.uniform(3, 9), rng.uniform(2, 5)), rng.uniform(0, 180), 0, 360, c, cv::FILLED, cv::LINE_AA);
  }
  for (int k = 0; k < 400; ++k) {  // gaps with sky and shadow
    cv::circle(img, Point(rng.uniform(0, 512), rng.uniform(0, 512)), rng.uniform(1, 4),
               rng.uniform(0, 3) ? Scalar(15, 30, 15) : Scalar(220, 200, 170), cv::FILLED);
  }
  AddGrain(img, rng, 6.0);
  return img;
}

cv::Mat MetalTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(128, 128, CV_8UC3, Scalar(105, 110, 110));
  AddFractalNoise(img, rng, 10);
  for (int k = 0; k < 6; ++k) {  // stickers and rust
    cv::rectangle(img, Rect(rng.uniform(0, 110), rng.uniform(0, 110), rng.uniform(4, 18), rng.uniform(4, 18)),
                  rng.uniform(0, 2) ? RandomColor(rng, 150, 250) : Scalar(30, 60, 110), cv::FILLED);
  }
  AddGrain(img, rng, 5.0);
  return img;
}

cv::Mat StopSignTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(256, 256, CV_8UC3, Scalar(35, 30, 190));
  cv::rectangle(img, Rect(0, 0, 256, 256), Scalar(240, 240, 240), 14);
  cv::putText(img, "STOP", Point(22, 155), cv::FONT_HERSHEY_DUPLEX, 2.6, Scalar(245, 245, 245), 9, cv::LINE_AA);
  AddGrain(img, rng, 4.0);
  return img;
}

cv::Mat TrafficLightTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(256, 128, CV_8UC3, Scalar(30, 32, 30));
  const Scalar lamps[3] = {Scalar(40, 40, 90), Scalar(40, 90, 100), Scalar(60, 110, 40)};
  const int lit = rng.uniform(0, 3);
  for (int i = 0; i < 3; ++i) {
    const Scalar c = i == lit ? Scalar(std::min(255.0, lamps[i][0] * 2.5), std::min(255.0, lamps[i][1] * 2.5), std::min(255.0, lamps[i][2] * 2.5)) : lamps[i];
    cv::circle(img, Point(64, 45 + 83 * i), 32, c, cv::FILLED, cv::LINE_AA);
    cv::circle(img, Point(64, 45 + 83 * i), 36, Scalar(10, 10, 10), 4, cv::LINE_AA);
  }
  AddGrain(img, rng, 4.0);
  return img;
}

cv::Mat ClothTexture(std::uint64_t seed, int pattern) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(256, 256, CV_8UC3, Scalar(200, 200, 200));
  const Scalar a = Scalar::all(rng.uniform(170, 240)), b = Scalar::all(rng.uniform(60, 140));
  switch (pattern % 5) {
    case 0:  // plaid
      for (int x = 0; x < 256; x += rng.uniform(20, 40)) cv::rectangle(img, Rect(x, 0, rng.uniform(4, 12), 256), b, cv::FILLED);
      for (int y = 0; y < 256; y += rng.uniform(20, 40)) cv::rectangle(img, Rect(0, y, 256, rng.uniform(4, 12)), b * 0.8, cv::FILLED);
      break;
    case 1:  // stripes
      for (int y = 0; y < 256; y += rng.uniform(12, 30)) cv::rectangle(img, Rect(0, y, 256, rng.uniform(4, 10)), b, cv::FILLED);
      break;
    case 2:  // print / logo on plain cloth
      img.setTo(a);
      cv::circle(img, Point(128, 100), 40, b, cv::FILLED, cv::LINE_AA);
      DrawGlyphs(img, rng, Rect(60, 150, 140, 30), b * 0.5, 3);
      break;
    case 3:  // denim
      img.setTo(a);
      for (int k = -256; k < 256; k += 3) cv::line(img, Point(k, 0), Point(k + 256, 256), b, 1);
      break;
    default:  // knit texture
      img.setTo(a);
      AddSmoothNoise(img, rng, 4, 25);
  }
  AddSmoothNoise(img, rng, 24, 10);  // folds
  AddGrain(img, rng, 5.0);
  return img;
}

cv::Mat SkinTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(64, 64, CV_8UC3, Scalar(225, 225, 225));
  AddSmoothNoise(img, rng, 8, 8);
  return img;
}

cv::Mat WallTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 512, CV_8UC3, Jitter(rng, Scalar(205, 215, 220), 15));
  AddFractalNoise(img, rng, 6);
  // Scuffs, pin holes, tape remains.
  for (int k = 0; k < 60; ++k) {
    const Point p(rng.uniform(0, 512), rng.uniform(0, 512));
    if (rng.uniform(0, 3) == 0) {
      cv::rectangle(img, Rect(p.x, p.y, rng.uniform(6, 20), rng.uniform(3, 8)), Scalar(170, 200, 210), cv::FILLED);
    } else {
      cv::circle(img, p, rng.uniform(1, 3), Scalar::all(rng.uniform(100, 170)), cv::FILLED, cv::LINE_AA);
    }
  }
  for (int k = 0; k < 6; ++k) {
    const Point p(rng.uniform(0, 512), rng.uniform(0, 512));
    cv::line(img, p, p + Point(rng.uniform(-60, 60), rng.uniform(-8, 8)), Scalar::all(rng.uniform(140, 180)), rng.uniform(1, 3), cv::LINE_AA);
  }
  AddGrain(img, rng, 3.0);
  return img;
}

cv::Mat PosterTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 384, CV_8UC3, RandomColor(rng, 140, 250));
  // A big picture area with shapes, a title and body text.
  const Rect pic(24, 90, 336, 220);
  cv::rectangle(img, pic, RandomColor(rng, 30, 200), cv::FILLED);
  for (int k = rng.uniform(5, 14); k > 0; --k) {
    const Point p(pic.x + rng.uniform(0, pic.width), pic.y + rng.uniform(0, pic.height));
    if (rng.uniform(0, 2)) {
      cv::circle(img(pic), p - pic.tl(), rng.uniform(8, 50), RandomColor(rng), cv::FILLED, cv::LINE_AA);
    } else {
      std::vector<Point> tri = {p - pic.tl(), p - pic.tl() + Point(rng.uniform(-80, 80), rng.uniform(-80, 80)),
                                p - pic.tl() + Point(rng.uniform(-80, 80), rng.uniform(-80, 80))};
      cv::fillConvexPoly(img(pic), tri, RandomColor(rng), cv::LINE_AA);
    }
  }
  DrawGlyphs(img, rng, Rect(24, 24, 336, 46), Scalar(20, 20, 20), 4);
  DrawParagraph(img, rng, Rect(24, 330, 336, 160), Scalar(30, 30, 30), 12);
  AddGrain(img, rng, 3.0);
  return img;
}

cv::Mat WhiteboardTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 1024, CV_8UC3, Scalar(238, 240, 240));
  AddSmoothNoise(img, rng, 40, 4);
  const Scalar markers[3] = {Scalar(160, 60, 20), Scalar(30, 30, 30), Scalar(40, 40, 170)};
  // Handwritten lines, boxes with arrows, a plot.
  for (int k = 0; k < 9; ++k) {
    const Scalar m = markers[rng.uniform(0, 3)];
    const Point p(rng.uniform(30, 700), rng.uniform(30, 440));
    switch (rng.uniform(0, 3)) {
      case 0:
        DrawParagraph(img, rng, Rect(p.x, p.y, rng.uniform(120, 300), rng.uniform(30, 90)), m, 16);
        break;
      case 1: {
        const Rect box(p.x, p.y, rng.uniform(80, 180), rng.uniform(50, 90));
        cv::rectangle(img, box, m, 3, cv::LINE_AA);
        DrawGlyphs(img, rng, Rect(box.x + 10, box.y + box.height / 2 - 10, box.width - 20, 20), m, 2);
        cv::arrowedLine(img, Point(box.x + box.width, box.y + box.height / 2),
                        Point(box.x + box.width + rng.uniform(40, 120), box.y + rng.uniform(-40, 80)), m, 3, cv::LINE_AA);
        break;
      }
      default: {
        cv::line(img, p, p + Point(0, 120), m, 2);
        cv::line(img, p + Point(0, 120), p + Point(200, 120), m, 2);
        Point q = p + Point(0, 100);
        for (int i = 1; i < 12; ++i) {
          const Point r = p + Point(i * 16, 110 - i * 8 + rng.uniform(-20, 20));
          cv::line(img, q, r, markers[2], 2, cv::LINE_AA);
          q = r;
        }
      }
    }
  }
  cv::rectangle(img, Rect(0, 0, 1024, 512), Scalar(170, 170, 165), 12);
  AddGrain(img, rng, 2.0);
  return img;
}

cv::Mat CarpetTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 512, CV_8UC3, Jitter(rng, Scalar(95, 85, 75), 20));
  AddFractalNoise(img, rng, 10);
  // Fibre speckle and a faint irregular fleck pattern.
  for (int k = 0; k < 3000; ++k) {
    cv::circle(img, Point(rng.uniform(0, 512), rng.uniform(0, 512)), rng.uniform(0, 3),
               Scalar::all(rng.uniform(40, 160)), cv::FILLED);
  }
  AddGrain(img, rng, 10.0);
  return img;
}

cv::Mat CeilingTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 512, CV_8UC3, Scalar(235, 238, 238));
  for (int k = 0; k < 4000; ++k) {
    cv::circle(img, Point(rng.uniform(0, 512), rng.uniform(0, 512)), rng.uniform(0, 2), Scalar::all(rng.uniform(170, 215)), cv::FILLED);
  }
  for (int i = 0; i <= 4; ++i) {
    cv::line(img, Point(i * 128, 0), Point(i * 128, 512), Scalar(200, 200, 200), 4);
    cv::line(img, Point(0, i * 128), Point(512, i * 128), Scalar(200, 200, 200), 4);
  }
  AddSmoothNoise(img, rng, 64, 4);
  return img;
}

cv::Mat WoodTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(512, 512, CV_8UC3, Jitter(rng, Scalar(90, 140, 190), 20));
  // Grain: wavy lines along u, knots.
  for (int k = 0; k < 90; ++k) {
    const int y0 = rng.uniform(0, 512);
    const double amp = rng.uniform(2.0, 10.0), f = rng.uniform(0.005, 0.02), ph = rng.uniform(0.0, 6.28);
    std::vector<Point> line;
    for (int x = 0; x < 512; x += 8) line.push_back(Point(x, y0 + static_cast<int>(amp * std::sin(f * x + ph))));
    cv::polylines(img, line, false, Scalar(60, 100, 150) * rng.uniform(0.7, 1.1), static_cast<int>(rng.uniform(1, 3)), cv::LINE_AA);
  }
  for (int k = rng.uniform(1, 4); k > 0; --k) {
    const Point p(rng.uniform(0, 512), rng.uniform(0, 512));
    cv::ellipse(img, p, cv::Size(rng.uniform(10, 25), rng.uniform(5, 10)), 0, 0, 360, Scalar(40, 70, 110), 2, cv::LINE_AA);
  }
  // Cup rings and scratches on desks.
  for (int k = 0; k < 5; ++k) {
    cv::circle(img, Point(rng.uniform(0, 512), rng.uniform(0, 512)), rng.uniform(18, 30), Scalar(70, 110, 150), 1, cv::LINE_AA);
  }
  AddSmoothNoise(img, rng, 20, 8);
  AddGrain(img, rng, 4.0);
  return img;
}

cv::Mat SpinesTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(256, 512, CV_8UC3, Scalar(30, 30, 30));
  int x = 0;
  while (x < 512) {
    const int w = rng.uniform(10, 36), h = rng.uniform(150, 250);
    const Scalar c = RandomColor(rng);
    cv::rectangle(img, Rect(x, 256 - h, w - 1, h), c, cv::FILLED);
    const Scalar ink = (c[0] + c[1] + c[2]) / 3 > 120 ? Scalar(20, 20, 20) : Scalar(235, 235, 235);
    cv::rectangle(img, Rect(x + 2, 256 - h + 10, w - 5, 6), ink, cv::FILLED);
    for (int y = 256 - h + 30; y < 230; y += rng.uniform(12, 20)) {
      cv::line(img, Point(x + w / 2 + rng.uniform(-3, 3), y), Point(x + w / 2 + rng.uniform(-3, 3), y + rng.uniform(4, 10)), ink, 2);
    }
    x += w;
  }
  AddGrain(img, rng, 4.0);
  return img;
}

cv::Mat ScreenTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(320, 512, CV_8UC3, RandomColor(rng, 60, 200));
  AddSmoothNoise(img, rng, 64, 25, true);  // wallpaper
  // Task bar and overlapping windows with text, code and charts.
  cv::rectangle(img, Rect(0, 296, 512, 24), Scalar(40, 40, 40), cv::FILLED);
  for (int i = 0; i < 8; ++i) cv::rectangle(img, Rect(8 + 28 * i, 300, 20, 16), RandomColor(rng), cv::FILLED);
  for (int k = rng.uniform(2, 5); k > 0; --k) {
    const Rect w(rng.uniform(0, 250), rng.uniform(0, 120), rng.uniform(180, 300), rng.uniform(120, 170));
    const Rect r = w & Rect(0, 0, 512, 296);
    const bool dark = rng.uniform(0, 2);
    cv::rectangle(img, r, dark ? Scalar(35, 30, 30) : Scalar(245, 245, 245), cv::FILLED);
    cv::rectangle(img, Rect(r.x, r.y, r.width, 14), Scalar(120, 80, 40), cv::FILLED);
    if (rng.uniform(0, 3) == 0) {
      for (int b = 0; b < 8; ++b) {
        const int h = rng.uniform(10, r.height - 30);
        cv::rectangle(img, Rect(r.x + 10 + b * (r.width - 20) / 8, r.y + r.height - 5 - h, (r.width - 20) / 10, h), RandomColor(rng), cv::FILLED);
      }
    } else {
      DrawParagraph(img, rng, Rect(r.x + 8, r.y + 20, r.width - 16, r.height - 24),
                    dark ? Scalar(120, 230, 120) : Scalar(40, 40, 40), 6);
    }
    cv::rectangle(img, r, Scalar(80, 80, 80), 1);
  }
  return img;
}

cv::Mat KeyboardTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(160, 512, CV_8UC3, Scalar(30, 30, 32));
  const Scalar key = rng.uniform(0, 2) ? Scalar(225, 225, 225) : Scalar(55, 55, 58);
  const Scalar ink = key[0] > 128 ? Scalar(40, 40, 40) : Scalar(210, 210, 210);
  for (int row = 0; row < 5; ++row) {
    for (int x = 6 + row * 6; x < 500;) {
      const int w = (row == 4 && x > 120 && x < 150) ? 200 : 28;
      cv::rectangle(img, Rect(x, 8 + row * 30, w, 26), key, cv::FILLED);
      if (w < 100) DrawGlyphs(img, rng, Rect(x + 8, 14 + row * 30, 10, 10), ink, 1);
      x += w + 4;
    }
  }
  AddGrain(img, rng, 3.0);
  return img;
}

cv::Mat PrintTexture(std::uint64_t seed) {
  cv::RNG rng = MakeRng(seed);
  cv::Mat img(256, 256, CV_8UC3, RandomColor(rng, 150, 250));
  cv::rectangle(img, Rect(0, 60, 256, 120), RandomColor(rng, 20, 200), cv::FILLED);
  DrawGlyphs(img, rng, Rect(20, 90, 216, 50), RandomColor(rng, 200, 255), 4);
  DrawParagraph(img, rng, Rect(20, 190, 216, 50), Scalar(40, 40, 40), 8);
  AddGrain(img, rng, 3.0);
  return img;
}

}  // namespace segslam::scenes
