// Drawing primitives shared by the procedural textures (scenes/textures.cpp and
// scenes/city_textures.cpp): smooth multi-scale noise, per-pixel grain, glyph-like
// strokes and windows. Internal to scenes/. Images are CV_8UC3 BGR; maps CV_32FC1.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>

namespace segslam::scenes::texture {

// The generator of one texture, fully determined by `seed`.
cv::RNG MakeRng(std::uint64_t seed);

// `c` with each channel moved by up to +-amount, clamped to [0, 255].
cv::Scalar Jitter(cv::RNG& rng, cv::Scalar c, double amount);
cv::Scalar RandomColor(cv::RNG& rng, int lo = 20, int hi = 235);

// Adds a single-channel float map to every channel of a BGR image, saturating.
void AddMap(cv::Mat& img, const cv::Mat& map);
// Smooth noise with features about `cell_px` wide and `amplitude` grey levels, added to
// `map` (CV_32FC1 of the image size).
void AccumulateSmoothNoise(cv::Mat& map, cv::RNG& rng, int cell_px, double amplitude);
void AddSmoothNoise(cv::Mat& img, cv::RNG& rng, int cell_px, double amplitude, bool colored = false);
// Per-pixel grain of standard deviation `sigma` grey levels.
void AddGrain(cv::Mat& img, cv::RNG& rng, double sigma);
// Multi-octave smooth noise, from 128-pixel stains to 4-pixel mottling.
void AddFractalNoise(cv::Mat& img, cv::RNG& rng, double amplitude);

// One row of glyph-like strokes filling `box`, like text seen from afar.
void DrawGlyphs(cv::Mat& img, cv::RNG& rng, cv::Rect box, cv::Scalar color, int thickness = 1);
// Lines of glyphs filling `box`, `line_px` high.
void DrawParagraph(cv::Mat& img, cv::RNG& rng, cv::Rect box, cv::Scalar color, int line_px);
// A window `r`: a dark room with furniture silhouettes, curtains or blinds, a sky
// reflection, and its frame and mullions `frame_px` wide.
void DrawWindow(cv::Mat& img, cv::RNG& rng, cv::Rect r, cv::Scalar frame, int frame_px);
// Running-bond brickwork over the whole image, bricks of 30 cm by 7.5 cm at `px_per_m`.
void Brickwork(cv::Mat& img, cv::RNG& rng, cv::Scalar base, double px_per_m = 80);

}  // namespace segslam::scenes::texture
