#include "core/image_io.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <png.h>
#include <zlib.h>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/input_file.h"

namespace segslam {
namespace {

// What a reader takes: checked from a PNG's header before decoding, and on the decoded
// image (other formats, and what a header cannot say).
struct ImageRequirements {
  const char* noun;                 // "image" or "mask", for "<noun> is WxH"
  const char* expected_size_owner;  // "camera expects": "<noun> is WxH, camera expects wxh"
  bool sixteen_bit_grey = false;    // depth and masks; colour is 8-bit
  const char* type_text = "";       // "depth image must be 16-bit single-channel (CV_16UC1)"
  std::optional<cv::Size> expected_size;
};

void CheckImageSize(const std::filesystem::path& path, long long width, long long height,
                    const ImageRequirements& requirements) {
  if (requirements.expected_size.has_value()) {
    const cv::Size& expected = *requirements.expected_size;
    if (width != expected.width || height != expected.height) {
      throw FileError(path, fmt::format("{} is {}x{}, {} {}x{}", requirements.noun, width, height,
                                        requirements.expected_size_owner, expected.width, expected.height));
    }
  }
  if (width * height > kMaxImagePixels) {
    throw FileError(path, fmt::format("{} is {}x{}, larger than any camera image segslam reads ({} pixels at most)",
                                      requirements.noun, width, height, kMaxImagePixels));
  }
}

// Refuses, from a PNG's header alone, what the decoder would spend time and memory on
// only for the image to be refused afterwards.
void CheckPngHeader(const std::filesystem::path& path, const ImageRequirements& requirements) {
  const std::optional<PngHeader> header = ReadPngHeader(path);
  if (!header.has_value()) return;
  CheckImageSize(path, header->width, header->height, requirements);
  const bool sixteen_bit_grey = header->bit_depth == 16 && header->channels == 1;
  if (requirements.sixteen_bit_grey ? !sixteen_bit_grey : header->bit_depth > 8) {
    // Named as the decoder would give it (a palette's one channel aside).
    const int type = CV_MAKETYPE(header->bit_depth == 16 ? CV_16U : CV_8U, header->channels);
    throw FileError(path, fmt::format("{}, found {} (a {}-bit PNG)", requirements.type_text, CvTypeName(type),
                                      header->bit_depth));
  }
}

// Reads any image unchanged (keeping 16-bit depth and channel count) once its PNG header
// passed `requirements`; throws if missing or not decodable, or of another size.
cv::Mat ReadUnchanged(const std::filesystem::path& path, const ImageRequirements& requirements) {
  CheckInputFile(path);
  CheckPngHeader(path, requirements);
  cv::Mat image;
  try {
    image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw FileError(path, std::string("cannot decode image: ") + e.what());
  }
  if (image.empty()) throw FileError(path, "cannot decode image (corrupt or unsupported)");
  CheckImageSize(path, image.cols, image.rows, requirements);
  return image;
}

void ClosePngFile(std::FILE* file) { std::fclose(file); }

// Row filters per kind of image, measured on rendered city frames (see image_io.h).
constexpr int kDepthPngFilter = PNG_FILTER_SUB;
constexpr int kColorPngFilter = PNG_FILTER_SUB;

void AppendPngBytes(png_structp png, png_bytep data, png_size_t size) {
  auto* bytes = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  try {
    bytes->insert(bytes->end(), data, data + size);
  } catch (const std::bad_alloc&) {
    png_error(png, "out of memory");  // a C++ exception must not cross libpng's C frames
  }
}

[[noreturn]] void OnPngError(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}

void IgnorePngWarning(png_structp, png_const_charp) {}

// PNG bytes of a CV_8UC1, CV_8UC3 (BGR) or CV_16UC1 image at zlib level 1, every row with
// the same `filter` (a PNG_FILTER_* flag) and zlib `strategy` (Z_DEFAULT_STRATEGY, ...).
// OpenCV 4.6's imencode cannot choose the filter, and libpng then tries all five on every
// row, which costs more than it saves on our images (image_io.h gives the measurements).
// libpng reports errors by longjmp, so this frame holds nothing that needs destroying
// beyond what it destroys itself. Returns false with libpng's message in *error.
bool EncodePngRows(const cv::Mat& image, int filter, int strategy,
                   std::vector<unsigned char>* bytes, std::string* error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, error, OnPngError,
                                            IgnorePngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, bytes, AppendPngBytes, nullptr);
  png_set_compression_level(png, 1);
  png_set_compression_strategy(png, strategy);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, filter);
  const bool sixteen_bit = image.depth() == CV_16U;
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols),
               static_cast<png_uint_32>(image.rows), sixteen_bit ? 16 : 8,
               image.channels() == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
  if (image.channels() == 3) png_set_bgr(png);
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  if (sixteen_bit) png_set_swap(png);  // PNG stores 16-bit samples big-endian
#endif
  for (int row = 0; row < image.rows; ++row) {
    png_write_row(png, const_cast<png_bytep>(image.ptr<unsigned char>(row)));
  }
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

std::vector<unsigned char> EncodePngOrThrow(const cv::Mat& image, int filter, int strategy,
                                            const char* what) {
  std::vector<unsigned char> png;
  std::string error = "libpng could not start";
  if (!EncodePngRows(image, filter, strategy, &png, &error)) {
    throw Error(std::string("cannot encode ") + what + " as PNG: " + error);
  }
  return png;
}

// round(depth * depth_factor) into `raw` (CV_16UC1 of depth_m's size). Out-of-range depth
// is stored as 0, "no depth", rather than clipped, so a reader never sees a wrong distance.
template <typename Depth>
void StoreDepthRows(const cv::Mat& depth_m, double depth_factor, cv::Mat* raw) {
  for (int r = 0; r < depth_m.rows; ++r) {
    const Depth* in = depth_m.ptr<Depth>(r);
    auto* out = raw->ptr<std::uint16_t>(r);
    for (int c = 0; c < depth_m.cols; ++c) {
      const double stored = std::round(static_cast<double>(in[c]) * depth_factor);
      out[c] = (std::isfinite(stored) && stored > 0 && stored <= 65535)
                   ? static_cast<std::uint16_t>(stored)
                   : 0;
    }
  }
}

// Runs `work` (encoding for `path`) and rethrows its error as one that names the file.
template <typename Work>
decltype(auto) NamingFile(const std::filesystem::path& path, Work work) {
  try {
    return work();
  } catch (const Error& e) {
    throw FileError(path, e.what());
  }
}

void RequireImageType(const cv::Mat& image, int type, const char* what) {
  if (image.empty() || image.type() != type) {
    throw Error(std::string(what) + " to write must be a non-empty " + CvTypeName(type) +
                " image, got " + CvTypeName(image.type()));
  }
}

bool IsPng(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png";
}

}  // namespace

std::string CvTypeName(int type) {
  static const char* const kDepths[] = {"8U", "8S", "16U", "16S", "32S", "32F", "64F", "16F"};
  return std::string("CV_") + kDepths[CV_MAT_DEPTH(type)] + "C" +
         std::to_string(CV_MAT_CN(type));
}

std::optional<PngHeader> ReadPngHeader(const std::filesystem::path& path) {
  CheckInputFile(path);
  const std::unique_ptr<std::FILE, decltype(&ClosePngFile)> file(std::fopen(path.c_str(), "rb"), ClosePngFile);
  if (file == nullptr) throw FileError(path, std::string("cannot open file: ") + std::strerror(errno));
  constexpr std::size_t kSignatureBytes = 8;
  png_byte signature[kSignatureBytes] = {};
  if (std::fread(signature, 1, kSignatureBytes, file.get()) != kSignatureBytes ||
      png_sig_cmp(signature, 0, kSignatureBytes) != 0) {
    return std::nullopt;
  }
  // libpng reads the chunks before the first IDAT (the header and a few small ones) and
  // reports errors by longjmp: nothing in this frame needs destroying beyond libpng's own.
  std::string error = "libpng could not start";
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, OnPngError, IgnorePngWarning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw FileError(path, "damaged PNG header: " + error);
  }
  png_init_io(png, file.get());
  png_set_sig_bytes(png, kSignatureBytes);
  png_read_info(png, info);
  PngHeader header;
  header.width = static_cast<int>(png_get_image_width(png, info));
  header.height = static_cast<int>(png_get_image_height(png, info));
  header.bit_depth = png_get_bit_depth(png, info);
  header.channels = png_get_channels(png, info);
  png_destroy_read_struct(&png, &info, nullptr);
  return header;
}

cv::Mat ReadColorImage(const std::filesystem::path& path, const std::optional<cv::Size>& expected_size) {
  cv::Mat image = ReadUnchanged(path, {"image", "camera expects", false,
                                       "colour image must be 8-bit", expected_size});
  if (image.depth() != CV_8U) {
    throw FileError(path, "colour image must be 8-bit, found " + CvTypeName(image.type()));
  }
  switch (image.channels()) {
    case 3:
      return image;
    case 1: {
      cv::Mat bgr;
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
      return bgr;
    }
    case 4: {
      cv::Mat bgr;
      cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
      return bgr;
    }
    default:
      throw FileError(path, "colour image must have 1, 3 or 4 channels, found " +
                                CvTypeName(image.type()));
  }
}

cv::Mat ReadDepthImage(const std::filesystem::path& path, double depth_factor,
                       const std::optional<cv::Size>& expected_size) {
  if (!(depth_factor > 0) || !std::isfinite(depth_factor)) {
    throw FileError(path, "depth factor must be positive, got " + std::to_string(depth_factor));
  }
  const cv::Mat raw = ReadUnchanged(path, {"image", "camera expects", true,
                                           "depth image must be 16-bit single-channel (CV_16UC1)", expected_size});
  if (raw.type() != CV_16UC1) {
    throw FileError(path, "depth image must be 16-bit single-channel (CV_16UC1), found " +
                              CvTypeName(raw.type()));
  }
  cv::Mat depth_m;
  // Stored 0 maps to 0.0, which keeps "no depth" as 0.
  raw.convertTo(depth_m, CV_32F, 1.0 / depth_factor);
  return depth_m;
}

void WriteDepthImage(const std::filesystem::path& path, const cv::Mat& depth_m,
                     double depth_factor) {
  if (!IsPng(path)) throw FileError(path, "depth images must be written as .png (lossless)");
  const std::vector<unsigned char> png =
      NamingFile(path, [&] { return EncodeDepthPng(depth_m, depth_factor); });
  WriteBytesAtomically(path, png.data(), png.size());
}

std::vector<unsigned char> EncodeDepthPng(const cv::Mat& depth_m, double depth_factor) {
  if (!(depth_factor > 0) || !std::isfinite(depth_factor)) {
    throw Error("depth factor must be positive, got " + std::to_string(depth_factor));
  }
  if (depth_m.empty() || depth_m.channels() != 1 ||
      (depth_m.depth() != CV_32F && depth_m.depth() != CV_64F)) {
    throw Error("depth to write must be a non-empty CV_32FC1 or CV_64FC1 image, got " +
                CvTypeName(depth_m.type()));
  }
  cv::Mat raw(depth_m.size(), CV_16UC1);
  if (depth_m.depth() == CV_32F) {
    StoreDepthRows<float>(depth_m, depth_factor, &raw);
  } else {
    StoreDepthRows<double>(depth_m, depth_factor, &raw);
  }
  return EncodePngOrThrow(raw, kDepthPngFilter, Z_DEFAULT_STRATEGY, "depth");
}

cv::Mat ReadInstanceMask(const std::filesystem::path& path, const std::optional<cv::Size>& expected_size) {
  cv::Mat mask = ReadUnchanged(path, {"mask", "the sequence's images are", true,
                                      "instance mask must be 16-bit single-channel (CV_16UC1)", expected_size});
  if (mask.type() != CV_16UC1) {
    throw FileError(path, "instance mask must be 16-bit single-channel (CV_16UC1), found " +
                              CvTypeName(mask.type()));
  }
  return mask;
}

void WriteInstanceMask(const std::filesystem::path& path, const cv::Mat& ids) {
  if (!IsPng(path)) throw FileError(path, "instance masks must be written as .png (lossless)");
  const std::vector<unsigned char> png =
      NamingFile(path, [&] { return EncodeInstanceMaskPng(ids); });
  WriteBytesAtomically(path, png.data(), png.size());
}

std::vector<unsigned char> EncodeInstanceMaskPng(const cv::Mat& ids) {
  RequireImageType(ids, CV_16UC1, "instance mask");
  return EncodePngOrThrow(ids, PNG_FILTER_NONE, Z_DEFAULT_STRATEGY, "instance mask");
}

void WriteColorImage(const std::filesystem::path& path, const cv::Mat& bgr) {
  if (!IsPng(path)) {
    NamingFile(path, [&] { RequireImageType(bgr, CV_8UC3, "colour image"); });
    WriteImageAtomically(path, bgr);
    return;
  }
  const std::vector<unsigned char> png = NamingFile(path, [&] { return EncodeColorPng(bgr); });
  WriteBytesAtomically(path, png.data(), png.size());
}

std::vector<unsigned char> EncodeColorPng(const cv::Mat& bgr) {
  RequireImageType(bgr, CV_8UC3, "colour image");
  return EncodePngOrThrow(bgr, kColorPngFilter, Z_HUFFMAN_ONLY, "colour image");
}

}  // namespace segslam
