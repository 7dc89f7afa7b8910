#include "core/coco_rle.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"

namespace segslam {

namespace {

// pycocotools' decoder shifts 5 bits per character into a 64-bit long; more than 12
// characters for one count would shift past it.
constexpr int kMaxGroupsPerCount = 12;

}  // namespace

std::vector<std::uint32_t> DecodeCocoRleString(std::string_view text, const std::string& origin) {
  std::vector<std::uint32_t> counts;
  size_t position = 0;
  while (position < text.size()) {
    std::int64_t value = 0;
    int groups = 0;
    bool more = true;
    while (more) {
      if (position >= text.size()) {
        throw Error(origin + ": compressed RLE counts end inside a count (the string is cut short)");
      }
      const int group = static_cast<unsigned char>(text[position]) - 48;
      if (group < 0 || group > 63) {
        throw Error(fmt::format("{}: compressed RLE counts hold '{}' at position {}, outside '0'..'o'", origin,
                                PrintableText(text.substr(position, 1)), position));
      }
      if (groups == kMaxGroupsPerCount) {
        throw Error(fmt::format("{}: compressed RLE count at position {} is longer than {} characters", origin,
                                position, kMaxGroupsPerCount));
      }
      value |= static_cast<std::int64_t>(group & 0x1f) << (5 * groups);
      more = (group & 0x20) != 0;
      ++position;
      ++groups;
      // Bit 4 of the last group is the sign: extend it over the bits above.
      if (!more && (group & 0x10) != 0) value |= static_cast<std::int64_t>(~std::uint64_t{0} << (5 * groups));
    }
    if (counts.size() > 2) value += counts[counts.size() - 2];
    if (value < 0 || value > std::numeric_limits<std::uint32_t>::max()) {
      throw Error(fmt::format("{}: compressed RLE count {} decodes to {}, outside 0..2^32-1", origin,
                              counts.size(), value));
    }
    counts.push_back(static_cast<std::uint32_t>(value));
  }
  return counts;
}

std::string EncodeCocoRleString(const std::vector<std::uint32_t>& counts) {
  std::string text;
  for (size_t i = 0; i < counts.size(); ++i) {
    std::int64_t value = counts[i];
    if (i > 2) value -= counts[i - 2];
    bool more = true;
    while (more) {
      int group = static_cast<int>(value & 0x1f);
      value >>= 5;  // arithmetic: a negative value ends at -1
      more = (group & 0x10) != 0 ? value != -1 : value != 0;
      if (more) group |= 0x20;
      text.push_back(static_cast<char>(group + 48));
    }
  }
  return text;
}

std::vector<std::uint32_t> CocoRleCounts(const cv::Mat& mask) {
  CV_Assert(mask.type() == CV_8UC1);
  std::vector<std::uint32_t> counts;
  std::uint32_t run = 0;
  bool inside = false;
  for (int x = 0; x < mask.cols; ++x) {
    for (int y = 0; y < mask.rows; ++y) {
      const bool pixel_inside = mask.at<std::uint8_t>(y, x) != 0;
      if (pixel_inside != inside) {
        counts.push_back(run);
        run = 0;
        inside = pixel_inside;
      }
      ++run;
    }
  }
  counts.push_back(run);
  return counts;
}

cv::Mat CocoRleToMask(const std::vector<std::uint32_t>& counts, cv::Size size, const std::string& origin) {
  std::uint64_t total = 0;
  for (std::uint32_t count : counts) total += count;
  const auto area = static_cast<std::uint64_t>(size.area());
  if (total != area) {
    throw Error(fmt::format("{}: RLE counts cover {} pixels, a {}x{} mask has {}", origin, total, size.width,
                            size.height, area));
  }
  cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
  const auto rows = static_cast<std::uint64_t>(size.height);
  std::uint64_t position = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    const std::uint64_t end = position + counts[i];
    if (i % 2 == 1) {
      for (std::uint64_t p = position; p < end; ++p) {
        mask.at<std::uint8_t>(static_cast<int>(p % rows), static_cast<int>(p / rows)) = 1;
      }
    }
    position = end;
  }
  return mask;
}

cv::Mat CocoPolygonsToMask(const std::vector<std::vector<double>>& polygons, cv::Size size,
                           const std::string& origin) {
  cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
  std::vector<double> crossings;
  for (size_t k = 0; k < polygons.size(); ++k) {
    const std::vector<double>& xy = polygons[k];
    if (xy.size() % 2 != 0 || xy.size() < 6) {
      throw Error(fmt::format("{}: polygon {} has {} coordinates; it needs x, y pairs, at least three", origin, k,
                              xy.size()));
    }
    // A scan line through each row of pixel centres, filled between pairs of edge
    // crossings (even-odd). cv::fillPoly also fills every pixel its outline touches, half
    // a pixel beyond the edges all round. Each polygon on its own: several polygons of one
    // mask are a union.
    const size_t corners = xy.size() / 2;
    for (int row = 0; row < size.height; ++row) {
      const double y = row + 0.5;
      crossings.clear();
      for (size_t a = 0; a < corners; ++a) {
        const size_t b = (a + 1) % corners;
        const double ya = xy[2 * a + 1], yb = xy[2 * b + 1];
        // Half-open in y, so a corner on the scan line is crossed once, not twice.
        if ((ya <= y && y < yb) || (yb <= y && y < ya)) {
          const double x = xy[2 * a] + (y - ya) / (yb - ya) * (xy[2 * b] - xy[2 * a]);
          // Clamped so that the int conversions below cannot overflow (JSON allows 3e9 or
          // 1e300); -1 and width + 1 lie beyond every column, which is all that matters.
          // max(-1, x) first: it also turns a NaN (0 * inf, from corners near 1e308) into -1.
          crossings.push_back(std::min(std::max(-1.0, x), size.width + 1.0));
        }
      }
      std::sort(crossings.begin(), crossings.end());
      for (size_t c = 0; c + 1 < crossings.size(); c += 2) {
        // Columns whose centre x + 0.5 lies in [left, right).
        const int first = std::max(0, static_cast<int>(std::ceil(crossings[c] - 0.5)));
        const int last = std::min(size.width - 1, static_cast<int>(std::ceil(crossings[c + 1] - 0.5)) - 1);
        for (int column = first; column <= last; ++column) mask.at<std::uint8_t>(row, column) = 1;
      }
    }
  }
  return mask;
}

cv::Mat DecodeCocoSegmentation(const nlohmann::json& segmentation, cv::Size size, const std::string& origin) {
  if (segmentation.is_array()) {
    std::vector<std::vector<double>> polygons;
    for (size_t k = 0; k < segmentation.size(); ++k) {
      const nlohmann::json& polygon = segmentation[k];
      if (!polygon.is_array()) throw Error(fmt::format("{}: polygon {} is not a list of numbers", origin, k));
      std::vector<double> coordinates;
      for (const nlohmann::json& value : polygon) {
        if (!value.is_number()) throw Error(fmt::format("{}: polygon {} holds a non-number", origin, k));
        coordinates.push_back(value.get<double>());
      }
      polygons.push_back(std::move(coordinates));
    }
    return CocoPolygonsToMask(polygons, size, origin);
  }
  if (!segmentation.is_object() || !segmentation.contains("size") || !segmentation.contains("counts")) {
    throw Error(origin + ": segmentation is neither a list of polygons nor an RLE with \"size\" and \"counts\"");
  }
  const nlohmann::json& rle_size = segmentation.at("size");
  if (!rle_size.is_array() || rle_size.size() != 2 || !rle_size[0].is_number_integer() ||
      !rle_size[1].is_number_integer()) {
    throw Error(origin + ": RLE \"size\" is not [height, width]");
  }
  const int height = rle_size[0].get<int>();
  const int width = rle_size[1].get<int>();
  if (height != size.height || width != size.width) {
    throw Error(fmt::format("{}: RLE size [{}, {}] (height, width) is not the image's [{}, {}]", origin, height, width,
                            size.height, size.width));
  }
  const nlohmann::json& counts = segmentation.at("counts");
  if (counts.is_string()) return CocoRleToMask(DecodeCocoRleString(counts.get<std::string>(), origin), size, origin);
  if (!counts.is_array()) throw Error(origin + ": RLE \"counts\" is neither a string nor a list of integers");
  std::vector<std::uint32_t> runs;
  for (const nlohmann::json& count : counts) {
    if (!count.is_number_integer() || count.get<std::int64_t>() < 0 ||
        count.get<std::int64_t>() > std::numeric_limits<std::uint32_t>::max()) {
      throw Error(origin + ": RLE \"counts\" holds something other than a count of pixels");
    }
    runs.push_back(count.get<std::uint32_t>());
  }
  return CocoRleToMask(runs, size, origin);
}

}  // namespace segslam
