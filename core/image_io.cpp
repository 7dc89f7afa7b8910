#include "core/image_io.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <new>
#include <string>
#include <vector>

#include <png.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace segslam {
namespace {

// Reads any image unchanged (keeping 16-bit depth and channel count); throws if missing
// or not decodable.
cv::Mat ReadUnchanged(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw FileError(path, std::filesystem::exists(path, ec) ? "not a regular file"
                                                            : "image file does not exist");
  }
  cv::Mat image;
  try {
    image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw FileError(path, std::string("cannot decode image: ") + e.what());
  }
  if (image.empty()) throw FileError(path, "cannot decode image (corrupt or unsupported)");
  return image;
}

std::vector<int> PngParams(int compression) {
  return {cv::IMWRITE_PNG_COMPRESSION, compression};
}

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

// libpng reports errors by longjmp, so this frame holds nothing that needs destroying
// beyond what it destroys itself. Returns false with libpng's message in *error.
bool EncodeUnfilteredGray16Png(const cv::Mat& image, std::vector<unsigned char>* bytes,
                               std::string* error) {
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
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols),
               static_cast<png_uint_32>(image.rows), 16, PNG_COLOR_TYPE_GRAY,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  png_set_swap(png);  // PNG stores 16-bit samples big-endian
#endif
  for (int row = 0; row < image.rows; ++row) {
    png_write_row(png, const_cast<png_bytep>(image.ptr<unsigned char>(row)));
  }
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
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

cv::Mat ReadColorImage(const std::filesystem::path& path) {
  cv::Mat image = ReadUnchanged(path);
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

cv::Mat ReadDepthImage(const std::filesystem::path& path, double depth_factor) {
  if (!(depth_factor > 0) || !std::isfinite(depth_factor)) {
    throw FileError(path, "depth factor must be positive, got " + std::to_string(depth_factor));
  }
  const cv::Mat raw = ReadUnchanged(path);
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
  if (!(depth_factor > 0) || !std::isfinite(depth_factor)) {
    throw FileError(path, "depth factor must be positive, got " + std::to_string(depth_factor));
  }
  if (depth_m.empty() || depth_m.channels() != 1 ||
      (depth_m.depth() != CV_32F && depth_m.depth() != CV_64F)) {
    throw FileError(path, "depth to write must be a non-empty CV_32FC1 or CV_64FC1 image, got " +
                              CvTypeName(depth_m.type()));
  }
  if (!IsPng(path)) throw FileError(path, "depth images must be written as .png (lossless)");
  cv::Mat raw(depth_m.size(), CV_16UC1);
  for (int r = 0; r < depth_m.rows; ++r) {
    auto* out = raw.ptr<std::uint16_t>(r);
    for (int c = 0; c < depth_m.cols; ++c) {
      const double d = depth_m.depth() == CV_32F ? depth_m.at<float>(r, c)
                                                 : depth_m.at<double>(r, c);
      const double stored = std::round(d * depth_factor);
      // Out-of-range depth is written as "no depth" rather than clipped, so a reader
      // never sees a wrong distance.
      out[c] = (std::isfinite(stored) && stored > 0 && stored <= 65535)
                   ? static_cast<std::uint16_t>(stored)
                   : 0;
    }
  }
  WriteImageAtomically(path, raw, PngParams(1));
}

cv::Mat ReadInstanceMask(const std::filesystem::path& path) {
  cv::Mat mask = ReadUnchanged(path);
  if (mask.type() != CV_16UC1) {
    throw FileError(path, "instance mask must be 16-bit single-channel (CV_16UC1), found " +
                              CvTypeName(mask.type()));
  }
  return mask;
}

void WriteInstanceMask(const std::filesystem::path& path, const cv::Mat& ids) {
  if (ids.empty() || ids.type() != CV_16UC1) {
    throw FileError(path, "instance mask to write must be a non-empty CV_16UC1 image, got " +
                              CvTypeName(ids.type()));
  }
  if (!IsPng(path)) throw FileError(path, "instance masks must be written as .png (lossless)");
  std::vector<unsigned char> png;
  try {
    png = EncodeInstanceMaskPng(ids);
  } catch (const Error& e) {
    throw FileError(path, e.what());
  }
  WriteBytesAtomically(path, png.data(), png.size());
}

std::vector<unsigned char> EncodeInstanceMaskPng(const cv::Mat& ids) {
  if (ids.empty() || ids.type() != CV_16UC1) {
    throw Error("instance mask to encode must be a non-empty CV_16UC1 image, got " +
                CvTypeName(ids.type()));
  }
  std::vector<unsigned char> png;
  std::string error = "libpng could not start";
  if (!EncodeUnfilteredGray16Png(ids, &png, &error)) {
    throw Error("cannot encode instance mask as PNG: " + error);
  }
  return png;
}

void WriteColorImage(const std::filesystem::path& path, const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    throw FileError(path, "colour image to write must be a non-empty CV_8UC3 image, got " +
                              CvTypeName(bgr.type()));
  }
  // Camera images carry sensor noise, which defeats LZ77 matching: Huffman coding alone
  // is faster and, measured on rendered city frames, 10% smaller than zlib level 1.
  std::vector<int> params;
  if (IsPng(path)) {
    params = {cv::IMWRITE_PNG_COMPRESSION, 1, cv::IMWRITE_PNG_STRATEGY,
              cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY};
  }
  WriteImageAtomically(path, bgr, params);
}

std::vector<unsigned char> EncodePng(const cv::Mat& image, int compression) {
  std::vector<unsigned char> buffer;
  if (image.empty() || !cv::imencode(".png", image, buffer, PngParams(compression))) {
    throw Error("cannot encode a " + CvTypeName(image.type()) + " image as PNG");
  }
  return buffer;
}

}  // namespace segslam
