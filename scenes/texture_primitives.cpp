// The drawing primitives of the procedural textures (scenes/texture_primitives.h).
#include "scenes/texture_primitives.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace segslam::scenes::texture {

using cv::Point;
using cv::Rect;
using cv::Scalar;


cv::RNG MakeRng(std::uint64_t seed) { return cv::RNG(seed ^ 0x5deece66dull); }

Scalar Jitter(cv::RNG& rng, Scalar c, double amount) {
  return Scalar(std::clamp(c[0] + rng.uniform(-amount, amount), 0.0, 255.0),
                std::clamp(c[1] + rng.uniform(-amount, amount), 0.0, 255.0),
                std::clamp(c[2] + rng.uniform(-amount, amount), 0.0, 255.0));
}

Scalar RandomColor(cv::RNG& rng, int lo, int hi) {
  return Scalar(rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi));
}

// Adds a single-channel float map to every channel of a BGR image, saturating.
void AddMap(cv::Mat& img, const cv::Mat& map) {
  for (int r = 0; r < img.rows; ++r) {
    cv::Vec3b* px = img.ptr<cv::Vec3b>(r);
    const float* m = map.ptr<float>(r);
    for (int c = 0; c < img.cols; ++c) {
      for (int k = 0; k < 3; ++k) px[c][k] = cv::saturate_cast<uchar>(px[c][k] + m[c]);
    }
  }
}

// Smooth noise with features about `cell_px` wide and `amplitude` grey levels, added
// to `map` (CV_32FC1 of the image size).
void AccumulateSmoothNoise(cv::Mat& map, cv::RNG& rng, int cell_px, double amplitude) {
  const int w = std::max(2, map.cols / cell_px + 2), h = std::max(2, map.rows / cell_px + 2);
  cv::Mat small(h, w, CV_32FC1);
  rng.fill(small, cv::RNG::NORMAL, 0.0, amplitude);
  cv::Mat big;
  cv::resize(small, big, map.size(), 0, 0, cv::INTER_CUBIC);
  map += big;
}

void AddSmoothNoise(cv::Mat& img, cv::RNG& rng, int cell_px, double amplitude, bool colored) {
  if (colored) {  // independent noise per channel
    const int w = std::max(2, img.cols / cell_px + 2), h = std::max(2, img.rows / cell_px + 2);
    cv::Mat small(h, w, CV_32FC3), big, f;
    rng.fill(small, cv::RNG::NORMAL, 0.0, amplitude);
    cv::resize(small, big, img.size(), 0, 0, cv::INTER_CUBIC);
    img.convertTo(f, CV_32FC3);
    f += big;
    f.convertTo(img, CV_8UC3);
    return;
  }
  cv::Mat map(img.size(), CV_32FC1, cv::Scalar(0));
  AccumulateSmoothNoise(map, rng, cell_px, amplitude);
  AddMap(img, map);
}

// Per-pixel grain.
void AddGrain(cv::Mat& img, cv::RNG& rng, double sigma) {
  cv::Mat map(img.size(), CV_32FC1);
  rng.fill(map, cv::RNG::NORMAL, 0.0, sigma);
  AddMap(img, map);
}

// Multi-octave smooth noise: large stains to fine mottling.
void AddFractalNoise(cv::Mat& img, cv::RNG& rng, double amplitude) {
  cv::Mat map(img.size(), CV_32FC1, cv::Scalar(0));
  for (int cell = 128, i = 0; cell >= 4; cell /= 2, ++i) {
    AccumulateSmoothNoise(map, rng, cell, amplitude / (1.0 + 0.4 * i));
  }
  AddMap(img, map);
}

// One row of glyph-like strokes filling `box`, like text seen from afar.
void DrawGlyphs(cv::Mat& img, cv::RNG& rng, Rect box, Scalar color, int thickness) {
  const int h = box.height;
  int x = box.x;
  while (x + h / 2 < box.x + box.width) {
    const int w = std::max(2, static_cast<int>(h * rng.uniform(0.35, 0.8)));
    const int strokes = rng.uniform(2, 5);
    for (int s = 0; s < strokes; ++s) {
      const Point a(x + rng.uniform(0, w + 1), box.y + rng.uniform(0, h + 1));
      const Point b(x + rng.uniform(0, w + 1), box.y + rng.uniform(0, h + 1));
      if (rng.uniform(0, 4) == 0) {
        cv::ellipse(img, (a + b) / 2, cv::Size(std::max(1, w / 2), std::max(1, h / 3)), 0,
                    rng.uniform(0, 180), rng.uniform(180, 360), color, thickness, cv::LINE_AA);
      } else {
        cv::line(img, a, b, color, thickness, cv::LINE_AA);
      }
    }
    x += w + std::max(1, h / 5);
    if (rng.uniform(0, 6) == 0) x += h / 2;  // a word gap
  }
}

// Lines of text: a paragraph of glyph rows inside `box`.
void DrawParagraph(cv::Mat& img, cv::RNG& rng, Rect box, Scalar color, int line_px) {
  for (int y = box.y; y + line_px <= box.y + box.height; y += line_px * 3 / 2) {
    const int len = static_cast<int>(box.width * rng.uniform(0.4, 1.0));
    DrawGlyphs(img, rng, Rect(box.x, y, len, line_px), color, std::max(1, line_px / 8));
  }
}

// Window interior: a dark room with random furniture silhouettes, curtains or blinds,
// and a sky reflection gradient.
void DrawWindow(cv::Mat& img, cv::RNG& rng, Rect r, Scalar frame, int frame_px) {
  cv::Mat roi = img(r);
  // Interior: dark gradient plus blobs.
  const Scalar room = Scalar(rng.uniform(25, 70), rng.uniform(25, 70), rng.uniform(25, 75));
  roi.setTo(room);
  for (int k = rng.uniform(2, 6); k > 0; --k) {
    const Point a(rng.uniform(0, r.width), rng.uniform(r.height / 3, r.height));
    cv::rectangle(roi, a, a + Point(rng.uniform(4, r.width / 2 + 5), rng.uniform(4, r.height / 2 + 5)),
                  Jitter(rng, room, 40), cv::FILLED);
  }
  if (rng.uniform(0, 3) == 0) {  // a lit lamp
    cv::circle(roi, Point(rng.uniform(0, r.width), rng.uniform(0, r.height / 2)),
               rng.uniform(2, 6), Scalar(150, 220, 250), cv::FILLED, cv::LINE_AA);
  }
  // Curtains (one or two sides) or blinds.
  const int kind = rng.uniform(0, 4);
  const Scalar cloth = Jitter(rng, Scalar(200, 210, 215), 50);
  if (kind == 0) {
    cv::rectangle(roi, Rect(0, 0, r.width * rng.uniform(20, 45) / 100, r.height), cloth, cv::FILLED);
    cv::rectangle(roi, Rect(r.width - r.width * rng.uniform(15, 40) / 100, 0, r.width, r.height),
                  cloth, cv::FILLED);
  } else if (kind == 1) {
    const int down = r.height * rng.uniform(20, 80) / 100;
    for (int y = 0; y < down; y += 4) cv::line(roi, Point(0, y), Point(r.width, y), cloth, 2);
  }
  // Reflection: a diagonal bright band.
  cv::Mat refl(roi.size(), roi.type(), Scalar::all(0));
  const int off = rng.uniform(-r.width, r.width);
  std::vector<Point> band = {Point(off, r.height), Point(off + r.width / 2, 0),
                             Point(off + r.width, 0), Point(off + r.width / 2, r.height)};
  cv::fillConvexPoly(refl, band, Scalar(60, 55, 45), cv::LINE_AA);
  cv::add(roi, refl, roi);
  // Frame and mullions.
  cv::rectangle(roi, Rect(0, 0, r.width, r.height), frame, frame_px);
  if (rng.uniform(0, 2) == 0) cv::line(roi, Point(r.width / 2, 0), Point(r.width / 2, r.height), frame, frame_px);
  if (rng.uniform(0, 2) == 0) {
    const int y = r.height * rng.uniform(25, 40) / 100;
    cv::line(roi, Point(0, y), Point(r.width, y), frame, frame_px);
  }
}

void Brickwork(cv::Mat& img, cv::RNG& rng, Scalar base, double px_per_m) {
  const Scalar mortar = Jitter(rng, Scalar(170, 180, 185), 15);
  img.setTo(mortar);
  // A brick with its mortar joint: 7.5 cm by 30 cm.
  const int bh = std::max(3, static_cast<int>(std::lround(0.1125 * px_per_m)));
  const int bw = std::max(6, static_cast<int>(std::lround(0.3 * px_per_m)));
  for (int y = 0, row = 0; y < img.rows; y += bh, ++row) {
    for (int x = (row % 2) * -bw / 2; x < img.cols; x += bw) {
      cv::rectangle(img, Rect(x + 1, y + 1, bw - 2, bh - 2), Jitter(rng, base, 28), cv::FILLED);
    }
  }
}

}  // namespace segslam::scenes::texture
