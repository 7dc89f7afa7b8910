// Pictures of single surfaces (a facade, a stretch of street, a number plate) packed into
// a few large textures, "pages". MuJoCo 2.2.2 renders at most 100 textures
// (sim/mjcf_builder.cpp), and a city has a picture of its own for every surface; each
// picture's material shows its window of a page (Material::texture_origin and
// texture_tile_m), on boxes only. Internal to scenes/.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <functional>
#include <string>
#include <vector>

#include "scenes/builder.h"

namespace segslam::scenes {

class PicturePages {
 public:
  // Pages of page_px x page_px pixels; pictures are kept gutter_px apart so that the
  // renderer's mipmaps do not blend neighbours at close range.
  explicit PicturePages(int page_px = 2048, int gutter_px = 4) : page_px_(page_px), gutter_px_(gutter_px) {}
  PicturePages(const PicturePages&) = delete;
  PicturePages& operator=(const PicturePages&) = delete;

  // A new material showing a picture of `size_px` that `draw` makes (it must return a
  // CV_8UC3 image of exactly that size), stretched over `size_m` of a box face. The
  // material's texture is set by Pack(). Throws std::invalid_argument for a picture larger
  // than a page.
  int Add(WorldBuilder& builder, const std::string& name, cv::Size size_px, const Eigen::Vector2d& size_m,
          std::function<cv::Mat()> draw, const Eigen::Vector4f& rgba = Eigen::Vector4f::Ones(), float specular = 0.1f,
          float shininess = 0.2f);

  // Places every picture added on pages (new textures of `world`, tallest pictures
  // first, in rows), gives each material its window, and draws the pictures in
  // parallel; the same pictures give the same pages byte for byte. Then starts afresh.
  void Pack(World* world);

  std::size_t size() const { return pictures_.size(); }

 private:
  struct Picture {
    int material = -1;
    cv::Size size_px;
    Eigen::Vector2d size_m;
    std::function<cv::Mat()> draw;
  };
  int page_px_, gutter_px_;
  std::vector<Picture> pictures_;
};

}  // namespace segslam::scenes
