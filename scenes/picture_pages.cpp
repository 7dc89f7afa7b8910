#include "scenes/picture_pages.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace segslam::scenes {

int PicturePages::Add(WorldBuilder& builder, const std::string& name, cv::Size size_px, const Eigen::Vector2d& size_m,
                      std::function<cv::Mat()> draw, const Eigen::Vector4f& rgba, float specular, float shininess) {
  if (size_px.width <= 0 || size_px.height <= 0 || size_px.width + 2 * gutter_px_ > page_px_ ||
      size_px.height + 2 * gutter_px_ > page_px_) {
    throw std::invalid_argument("picture '" + name + "' of " + std::to_string(size_px.width) + "x" +
                                std::to_string(size_px.height) + " px does not fit a page of " + std::to_string(page_px_) + " px");
  }
  const int material = builder.AddMaterial(name, -1, rgba, specular, shininess);
  pictures_.push_back({material, size_px, size_m, std::move(draw)});
  return material;
}

void PicturePages::Pack(World* world) {
  // Rows ("shelves") of pictures, tallest first: a picture goes right of the last one in
  // the row while it fits, else it opens a row below, else a page.
  std::vector<std::size_t> order(pictures_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return pictures_[a].size_px.height > pictures_[b].size_px.height; });
  struct Placement {
    int page = 0;
    cv::Point origin;
  };
  std::vector<Placement> placed(pictures_.size());
  int pages = 0, x = page_px_, y = 0, row_height = 0;
  for (std::size_t i : order) {
    const cv::Size s = pictures_[i].size_px;
    if (x + s.width + gutter_px_ > page_px_) {  // a new row
      x = gutter_px_;
      y += row_height;
      row_height = s.height + gutter_px_;
      if (pages == 0 || y + s.height + gutter_px_ > page_px_) {  // a new page
        ++pages;
        y = gutter_px_;
      }
    }
    placed[i] = {pages - 1, cv::Point(x, y)};
    x += s.width + gutter_px_;
  }
  // One texture per page, then each picture's material shows its window.
  const int first_texture = static_cast<int>(world->textures.size());
  for (int p = 0; p < pages; ++p) {
    Texture t;
    t.name = "pictures_" + std::to_string(p);
    t.image_bgr = cv::Mat(page_px_, page_px_, CV_8UC3, cv::Scalar::all(128));
    t.tile_size_m = Eigen::Vector2d(1, 1);  // unused: every material gives its own
    world->textures.push_back(std::move(t));
  }
  for (std::size_t i = 0; i < pictures_.size(); ++i) {
    const Picture& pic = pictures_[i];
    Material& m = world->materials[pic.material];
    m.texture = first_texture + placed[i].page;
    m.texture_origin = Eigen::Vector2d(double(placed[i].origin.x) / page_px_, double(placed[i].origin.y) / page_px_);
    // One copy of the page covers page_px pixels at the picture's own scale.
    m.texture_tile_m = Eigen::Vector2d(page_px_ * pic.size_m.x() / pic.size_px.width, page_px_ * pic.size_m.y() / pic.size_px.height);
  }
  // Pictures land in disjoint windows, so they are drawn in parallel.
  cv::parallel_for_(cv::Range(0, static_cast<int>(pictures_.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const Picture& pic = pictures_[i];
      const cv::Mat img = pic.draw();
      if (img.type() != CV_8UC3 || img.size() != pic.size_px) {
        throw std::logic_error("picture of material " + std::to_string(pic.material) + " drawn at the wrong size or type");
      }
      img.copyTo(world->textures[first_texture + placed[i].page].image_bgr(cv::Rect(placed[i].origin, pic.size_px)));
    }
  });
  pictures_.clear();
}

}  // namespace segslam::scenes
