// Reading and writing the per-frame images of a sequence. In memory:
// - colour: CV_8UC3, BGR order (OpenCV's);
// - depth: CV_32F, metres along the optical axis, 0 = no depth;
// - instance masks: CV_16U, 0 = background, else a sequence-wide instance id.
// On disk depth and masks are 16-bit single-channel PNGs; depth stores
// round(depth_m * depth_factor). Every reader throws segslam::Error naming the file and
// what is wrong; every writer writes atomically (see atomic_file.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace segslam {

// CV_8UC3 BGR. 8-bit grayscale is converted to BGR, 8-bit BGRA drops alpha. Throws if
// the file is missing or not decodable, or if it is not 8-bit with 1, 3 or 4 channels.
cv::Mat ReadColorImage(const std::filesystem::path& path);

// CV_32F metres: stored value / depth_factor, stored 0 stays 0 (no depth). Requires a
// 16-bit single-channel image (else throws, naming the type found) and depth_factor > 0.
cv::Mat ReadDepthImage(const std::filesystem::path& path, double depth_factor);

// Writes CV_32F (or CV_64F) single-channel metres as a 16-bit PNG with
// round(depth_m * depth_factor). Non-finite or <= 0 depths, and depths whose stored value
// would exceed 65535, become 0 (no depth). PNG compression level 1 (fast).
// Throws on a wrong type, empty image or non-positive depth_factor.
void WriteDepthImage(const std::filesystem::path& path, const cv::Mat& depth_m,
                     double depth_factor);

// CV_16U instance ids. Throws unless the file is a 16-bit single-channel image.
cv::Mat ReadInstanceMask(const std::filesystem::path& path);

// Writes a CV_16U id image losslessly (EncodeInstanceMaskPng). Throws on other types.
void WriteInstanceMask(const std::filesystem::path& path, const cv::Mat& ids);

// PNG bytes of a CV_16U id image: zlib level 1 and no row filter. Label images are long
// runs of one value, which zlib finds unfiltered; OpenCV 4.6 cannot turn the filters off
// and libpng then tries all five on every row (measured on a 640x480 refined mask: 11 ms
// through cv::imencode, 2.6 ms here, 1 % more bytes). Throws segslam::Error on other types.
std::vector<unsigned char> EncodeInstanceMaskPng(const cv::Mat& ids);

// Writes a CV_8UC3 BGR image (PNG compression 1 for .png; any imencode format by
// extension). Throws on other types.
void WriteColorImage(const std::filesystem::path& path, const cv::Mat& bgr);

// PNG bytes of `image` at zlib `compression` level 0..9. Throws on encoder failure.
std::vector<unsigned char> EncodePng(const cv::Mat& image, int compression);

// "CV_16UC1"-style name of an OpenCV type, for error messages.
std::string CvTypeName(int type);

}  // namespace segslam
