// Procedural textures: CV_8UC3 BGR images, fully determined by their seed. They are
// made for feature detection as much as for looks: irregular detail at the scale the
// camera sees (5-30 m in a city, 1-3 m in an office), never perfectly periodic, so ORB
// finds many distinct corners and matches do not alias.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>

namespace segslam::scenes {

enum class FacadeStyle { kBrick, kConcrete, kGlass, kPlaster };

// City (the pictures of single places, facades and streets, are in city_textures.h).
// Sizes in pixels are noted; the builders choose the tile size in metres.
cv::Mat BarkTexture(std::uint64_t seed);        // 256 x 256
cv::Mat FoliageTexture(std::uint64_t seed);     // 512 x 512
cv::Mat MetalTexture(std::uint64_t seed);       // 128 x 128
cv::Mat StopSignTexture(std::uint64_t seed);    // 256 x 256
cv::Mat TrafficLightTexture(std::uint64_t seed);  // 128 x 256, three lamps
cv::Mat ClothTexture(std::uint64_t seed, int pattern);  // 256 x 256; pattern 0..4
cv::Mat SkinTexture(std::uint64_t seed);        // 64 x 64

// Office.
// A facade of `floors` by `bays` windows, 1024 x 768: the view out of an office window.
cv::Mat FacadeTexture(std::uint64_t seed, FacadeStyle style, int floors, int bays);
cv::Mat WallTexture(std::uint64_t seed);        // 512 x 512, painted plaster
cv::Mat PosterTexture(std::uint64_t seed);      // 384 x 512 (portrait)
cv::Mat WhiteboardTexture(std::uint64_t seed);  // 1024 x 512
cv::Mat CarpetTexture(std::uint64_t seed);      // 512 x 512
cv::Mat CeilingTexture(std::uint64_t seed);     // 512 x 512, 4 x 4 ceiling tiles
cv::Mat WoodTexture(std::uint64_t seed);        // 512 x 512, grain along u
cv::Mat SpinesTexture(std::uint64_t seed);      // 512 x 256, book / binder spines
cv::Mat ScreenTexture(std::uint64_t seed);      // 512 x 320, desktop with windows
cv::Mat KeyboardTexture(std::uint64_t seed);    // 512 x 160
cv::Mat PrintTexture(std::uint64_t seed);       // 256 x 256, printed label / mug print

}  // namespace segslam::scenes
