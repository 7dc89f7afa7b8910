// Reading and writing the per-frame images of a sequence. In memory:
// - colour: CV_8UC3, BGR order (OpenCV's);
// - depth: CV_32F, metres along the optical axis, 0 = no depth;
// - instance masks: CV_16U, 0 = background, else a sequence-wide instance id.
// On disk depth and masks are 16-bit single-channel PNGs; depth stores
// round(depth_m * depth_factor). Every reader throws segslam::Error naming the file and
// what is wrong; every writer writes atomically (see atomic_file.h).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace segslam {

// What a PNG file's header (its IHDR chunk) says, read without decoding a pixel.
struct PngHeader {
  int width = 0, height = 0;
  int bit_depth = 0;  // bits per sample: 1, 2, 4, 8 or 16
  int channels = 0;   // 1 grey, 2 grey + alpha, 3 RGB or a palette, 4 RGBA
};

// The header of a PNG file; nullopt when the file does not start with PNG's signature
// (another format, which OpenCV decodes unchecked). Throws segslam::Error naming the file
// when it cannot be opened or its header is damaged.
std::optional<PngHeader> ReadPngHeader(const std::filesystem::path& path);

// The largest image any reader below decodes, in pixels (8192 x 8192): the readers check
// a PNG's header first, so a small file that claims a huge image (a 20000 x 20000 16-bit
// PNG compresses to under 1 MB and decodes to 800 MB) is refused before it is decoded.
constexpr long long kMaxImagePixels = 1LL << 26;

// Each reader below refuses, from a PNG's header and before decoding it, an image over
// kMaxImagePixels, one of another size than `expected_size` where that is given (naming
// both sizes), and one whose bit depth or channels its kind cannot take; files of other
// formats are checked the same way once decoded.

// CV_8UC3 BGR. 8-bit grayscale is converted to BGR, 8-bit BGRA drops alpha. Throws if
// the file is missing or not decodable, or if it is not 8-bit with 1, 3 or 4 channels.
cv::Mat ReadColorImage(const std::filesystem::path& path,
                       const std::optional<cv::Size>& expected_size = std::nullopt);

// CV_32F metres: stored value / depth_factor, stored 0 stays 0 (no depth). Requires a
// 16-bit single-channel image (else throws, naming the type found) and depth_factor > 0.
cv::Mat ReadDepthImage(const std::filesystem::path& path, double depth_factor,
                       const std::optional<cv::Size>& expected_size = std::nullopt);

// The PNG writers below encode with libpng directly: zlib level 1 and one row filter
// chosen per kind of image. OpenCV 4.6's imencode cannot choose the filter, and libpng
// then tries all five on every row, which on our images costs more than it saves.
// Measured on 640x480 frames of the default city, against cv::imencode at level 1, per
// frame:
// - instance mask, no filter: 11 -> 2.6 ms, 1 % larger;
// - depth, the Sub filter: 24.8 -> 13.5 ms, 0.6 % larger. Huffman coding alone or RLE
//   would encode the city's noisy depth faster but grow the office's smooth depth by 28
//   to 36 %.
// - colour, with Huffman coding alone: the Paeth filter took 28.9 -> 20.5 ms and was 1.5 %
//   larger. Colour now uses the Sub filter, which is larger again but decodes much faster,
//   and every run over a dataset decodes every colour frame. Paeth -> Sub, medians of
//   `taskset -c 0 build/core_benchmarks --sequence DIR --benchmark_filter=Color
//   --benchmark_repetitions=5`, the two builds alternated twice (ranges over the two):
//   | frames                 | decode [ms]          | encode [ms]            | size   |
//   | default city, pass 1   | 10.3-12.4 -> 6.1-7.5 | 17.3-21.2 -> 17.9-19.4 | +7.1 % |
//   | office_walking_xyz     | 10.6-12.4 -> 6.0-7.5 | 19.4-23.1 -> 13.9-18.9 | +4.6 % |
//   | 7-Scenes (real Kinect) | 9.3 -> 6.0-6.2       | 16.3-19.8 -> 13.1      | +9.9 % |
// Each writer writes atomically and throws segslam::Error naming the file on a wrong type
// or an empty image; the Encode* functions return the bytes and throw the same errors
// without a file name.

// Writes CV_32F (or CV_64F) single-channel metres as a 16-bit PNG with
// round(depth_m * depth_factor). Non-finite or <= 0 depths, and depths whose stored value
// would exceed 65535, become 0 (no depth). Also throws on a non-positive depth_factor.
void WriteDepthImage(const std::filesystem::path& path, const cv::Mat& depth_m,
                     double depth_factor);
std::vector<unsigned char> EncodeDepthPng(const cv::Mat& depth_m, double depth_factor);

// CV_16U instance ids. Throws unless the file is a 16-bit single-channel image.
cv::Mat ReadInstanceMask(const std::filesystem::path& path,
                         const std::optional<cv::Size>& expected_size = std::nullopt);

// Writes a CV_16U id image losslessly. Label images are long runs of one value, which
// zlib finds without a row filter.
void WriteInstanceMask(const std::filesystem::path& path, const cv::Mat& ids);
std::vector<unsigned char> EncodeInstanceMaskPng(const cv::Mat& ids);

// Writes a CV_8UC3 BGR image: PNG for .png, any other imencode format by extension.
// Camera images carry sensor noise, which defeats LZ77 matching, so PNGs use Huffman
// coding alone (faster, and 10 % smaller than zlib level 1 on rendered city frames).
void WriteColorImage(const std::filesystem::path& path, const cv::Mat& bgr);
std::vector<unsigned char> EncodeColorPng(const cv::Mat& bgr);

// "CV_16UC1"-style name of an OpenCV type, for error messages.
std::string CvTypeName(int type);

}  // namespace segslam
