// COCO's encodings of an instance mask (the "segmentation" of an annotation, or of a
// detection in a results file), decoded to binary masks and encoded from them.
//
//   Run-length (RLE): {"size": [height, width], "counts": ...}. The counts alternate runs
//     of 0 and 1 over the pixels in column-major order (down the first column, then the
//     next), starting with a run of 0 that may be empty, and sum to height * width.
//     "counts" is a list of integers (uncompressed RLE) or a string (compressed RLE, as
//     pycocotools' maskApi writes it: each count, from the fourth on less the count two
//     before it, in groups of 5 bits, least significant first; each group is the
//     character 48 + group, plus 32 when another group follows; bit 4 of the last group
//     is the sign).
//   Polygons: [[x1, y1, x2, y2, ...], ...] in pixel coordinates whose origin is the
//     top-left corner of the top-left pixel (that pixel's centre is at (0.5, 0.5)); a
//     pixel is inside when its centre is (pycocotools rasterises with its own scan
//     conversion; the two can differ by a pixel along a boundary).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace segslam {

// Compressed RLE string -> counts. Throws segslam::Error starting with `origin` on a
// character outside '0'..'o', a string that ends inside a count, or a count that comes
// out negative or above 2^32 - 1.
std::vector<std::uint32_t> DecodeCocoRleString(std::string_view counts, const std::string& origin);
// Counts -> compressed RLE string (pycocotools' rleToString).
std::string EncodeCocoRleString(const std::vector<std::uint32_t>& counts);

// The RLE counts of a CV_8UC1 mask (nonzero = inside).
std::vector<std::uint32_t> CocoRleCounts(const cv::Mat& mask);
// Counts -> CV_8UC1 mask of `size` (1 inside, 0 outside). Throws segslam::Error starting
// with `origin` unless the counts sum to size.area().
cv::Mat CocoRleToMask(const std::vector<std::uint32_t>& counts, cv::Size size, const std::string& origin);
// Polygons -> CV_8UC1 mask of `size`. Throws segslam::Error starting with `origin` on a
// polygon with an odd number of coordinates or fewer than three points.
cv::Mat CocoPolygonsToMask(const std::vector<std::vector<double>>& polygons, cv::Size size,
                           const std::string& origin);

// Any of the encodings above, as JSON, -> CV_8UC1 mask of `size`. Throws segslam::Error
// starting with `origin` on malformed JSON values, or an RLE whose "size" is not `size`
// (the mask was made for another image).
cv::Mat DecodeCocoSegmentation(const nlohmann::json& segmentation, cv::Size size, const std::string& origin);

}  // namespace segslam
