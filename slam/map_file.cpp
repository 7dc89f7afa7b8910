#include "slam/map_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include <fmt/format.h>
#include <openssl/evp.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/input_file.h"

namespace segslam::slam {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[12] = {'S', 'E', 'G', 'S', 'L', 'A', 'M', '-', 'M', 'A', 'P', '\0'};
constexpr std::size_t kMagicBytes = sizeof(kMagic);
constexpr std::size_t kHeaderBytes = kMagicBytes + 4 + 8;  // magic, version, payload size
constexpr std::size_t kChecksumBytes = 32;                 // SHA-256
// The largest payload a reader accepts: 64 GiB, some 600 million map points, far above any
// map a run builds (a few MB); a larger size field is a damaged header.
constexpr std::uint64_t kMaxPayloadBytes = std::uint64_t{64} << 30;

// Payload layout of version 1, in order:
//   camera:      i32 width, i32 height, f64 fx, fy, cx, cy
//   description: u64 byte length, UTF-8 bytes
//   keyframes:   u64 count, then per keyframe u64 id, f64 stamp, f64 x 12 (the 3x4 matrix
//                [R | t] of T_wc, row-major; stored as a matrix, not a quaternion, so that
//                a round trip is bit-exact)
//   points:      u64 count, then per point u64 id, f64 x 3 position, f32 x 3 viewing
//                direction, f32 min and max distance, 32 descriptor bytes,
//                u32 observations, u8 x 3 colour
constexpr std::size_t kKeyframeBytes = 8 + 8 + 12 * 8;
constexpr std::size_t kPointBytes = 8 + 3 * 8 + 3 * 4 + 2 * 4 + kOrbDescriptorBytes + 4 + 3;

// A keyframe rotation further than this from orthonormal is a corrupt or mis-built pose;
// stored doubles from a real rotation are orthonormal to ~1e-15.
constexpr double kRotationTolerance = 1e-6;
// A loaded point's observation count is added to in int arithmetic as the localizer
// observes it; no real map comes near this bound, far below INT_MAX.
constexpr std::uint32_t kMaxObservationsPerPoint = 1u << 24;

class PayloadWriter {
 public:
  void U8(std::uint8_t v) { bytes_.push_back(static_cast<char>(v)); }
  void U32(std::uint32_t v) {
    for (int shift = 0; shift < 32; shift += 8) U8(static_cast<std::uint8_t>(v >> shift));
  }
  void U64(std::uint64_t v) {
    for (int shift = 0; shift < 64; shift += 8) U8(static_cast<std::uint8_t>(v >> shift));
  }
  void I32(std::int32_t v) { U32(static_cast<std::uint32_t>(v)); }
  void F32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    U32(bits);
  }
  void F64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    U64(bits);
  }
  void Bytes(const void* data, std::size_t size) {
    bytes_.append(static_cast<const char*>(data), size);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

// Reads little-endian values from a byte range; running past its end throws, naming the
// file and what was being read.
class PayloadReader {
 public:
  PayloadReader(const fs::path& file, const unsigned char* data, std::size_t size)
      : file_(file), data_(data), size_(size) {}

  std::size_t remaining() const { return size_ - offset_; }

  std::uint8_t U8(const char* what) {
    Require(1, what);
    return data_[offset_++];
  }
  std::uint32_t U32(const char* what) {
    Require(4, what);
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(data_[offset_ + i]) << (8 * i);
    offset_ += 4;
    return v;
  }
  std::uint64_t U64(const char* what) {
    Require(8, what);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(data_[offset_ + i]) << (8 * i);
    offset_ += 8;
    return v;
  }
  std::int32_t I32(const char* what) { return static_cast<std::int32_t>(U32(what)); }
  float F32(const char* what) {
    const std::uint32_t bits = U32(what);
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  double F64(const char* what) {
    const std::uint64_t bits = U64(what);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  void Bytes(void* out, std::size_t size, const char* what) {
    Require(size, what);
    std::memcpy(out, data_ + offset_, size);
    offset_ += size;
  }

  // Checks that `count` records of `record_bytes` each fit in what is left, before
  // anything is allocated for them: a damaged count must not become a huge allocation.
  void RequireRecords(std::uint64_t count, std::size_t record_bytes, const char* what) const {
    if (count > remaining() / record_bytes) {
      throw FileError(file_, fmt::format("{} count {} needs {:.0f} bytes but only {} remain in "
                                         "the payload",
                                         what, count, static_cast<double>(count) * record_bytes,
                                         remaining()));
    }
  }

 private:
  void Require(std::size_t size, const char* what) const {
    if (size > remaining()) {
      throw FileError(file_, fmt::format("payload ends inside {} (at byte {} of {})", what,
                                         offset_, size_));
    }
  }

  const fs::path& file_;
  const unsigned char* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
};

std::array<unsigned char, kChecksumBytes> Sha256(const void* data, std::size_t size) {
  struct ContextDeleter {
    void operator()(EVP_MD_CTX* context) const { EVP_MD_CTX_free(context); }
  };
  std::unique_ptr<EVP_MD_CTX, ContextDeleter> context(EVP_MD_CTX_new());
  std::array<unsigned char, kChecksumBytes> digest{};
  unsigned int digest_size = 0;
  if (!context || EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr) != 1 ||
      EVP_DigestUpdate(context.get(), data, size) != 1 ||
      EVP_DigestFinal_ex(context.get(), digest.data(), &digest_size) != 1 ||
      digest_size != kChecksumBytes) {
    throw Error("OpenSSL could not compute a SHA-256 digest");
  }
  return digest;
}

bool AllFinite(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

// The reasons a map is not fit to be stored or used, shared by saving and loading so that
// everything written can be read back. Empty if the map is valid.
std::string FindInvalidValue(const LongTermMapData& map) {
  std::string camera_error;
  if (!map.camera.IsValid(&camera_error)) return "invalid camera: " + camera_error;
  for (const StoredKeyframe& keyframe : map.keyframes) {
    if (!std::isfinite(keyframe.stamp_s) || !AllFinite(keyframe.T_wc)) {
      return fmt::format("keyframe {} has a non-finite stamp or pose", keyframe.id);
    }
    const Eigen::Matrix3d R = keyframe.T_wc.linear();
    const double orthonormality_error =
        (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (orthonormality_error > kRotationTolerance || R.determinant() < 0) {
      return fmt::format("keyframe {} has a pose whose rotation is not a rotation matrix",
                         keyframe.id);
    }
  }
  for (const StoredMapPoint& point : map.points) {
    if (!point.position_w.allFinite() || !point.viewing_direction.allFinite() ||
        !std::isfinite(point.min_distance_m) || !std::isfinite(point.max_distance_m)) {
      return fmt::format("map point {} has a non-finite position, direction or distance",
                         point.id);
    }
    if (point.min_distance_m < 0 || point.min_distance_m > point.max_distance_m) {
      return fmt::format("map point {} has an invalid distance range [{}, {}] m", point.id,
                         point.min_distance_m, point.max_distance_m);
    }
    if (point.num_observations > kMaxObservationsPerPoint) {
      return fmt::format("map point {} claims {} observations (at most {})", point.id,
                         point.num_observations, kMaxObservationsPerPoint);
    }
  }
  return "";
}

std::string EncodePayload(const LongTermMapData& map) {
  PayloadWriter out;
  out.I32(map.camera.width);
  out.I32(map.camera.height);
  out.F64(map.camera.fx);
  out.F64(map.camera.fy);
  out.F64(map.camera.cx);
  out.F64(map.camera.cy);
  out.U64(map.description.size());
  out.Bytes(map.description.data(), map.description.size());

  out.U64(map.keyframes.size());
  for (const StoredKeyframe& keyframe : map.keyframes) {
    out.U64(keyframe.id);
    out.F64(keyframe.stamp_s);
    const Eigen::Matrix4d& T = keyframe.T_wc.matrix();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) out.F64(T(row, col));
    }
  }

  out.U64(map.points.size());
  for (const StoredMapPoint& point : map.points) {
    out.U64(point.id);
    for (int i = 0; i < 3; ++i) out.F64(point.position_w[i]);
    for (int i = 0; i < 3; ++i) out.F32(point.viewing_direction[i]);
    out.F32(point.min_distance_m);
    out.F32(point.max_distance_m);
    out.Bytes(point.descriptor.data(), point.descriptor.size());
    out.U32(point.num_observations);
    for (std::uint8_t channel : point.color_rgb) out.U8(channel);
  }
  return out.bytes();
}

LongTermMapData DecodePayload(const fs::path& file, const unsigned char* data,
                              std::size_t size) {
  PayloadReader in(file, data, size);
  LongTermMapData map;
  map.camera.width = in.I32("camera");
  map.camera.height = in.I32("camera");
  map.camera.fx = in.F64("camera");
  map.camera.fy = in.F64("camera");
  map.camera.cx = in.F64("camera");
  map.camera.cy = in.F64("camera");

  const std::uint64_t description_bytes = in.U64("description length");
  in.RequireRecords(description_bytes, 1, "description byte");
  map.description.resize(description_bytes);
  in.Bytes(map.description.data(), description_bytes, "description");

  const std::uint64_t keyframe_count = in.U64("keyframe count");
  in.RequireRecords(keyframe_count, kKeyframeBytes, "keyframe");
  map.keyframes.resize(keyframe_count);
  for (StoredKeyframe& keyframe : map.keyframes) {
    keyframe.id = in.U64("keyframe");
    keyframe.stamp_s = in.F64("keyframe");
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) T(row, col) = in.F64("keyframe");
    }
    keyframe.T_wc.matrix() = T;
  }

  const std::uint64_t point_count = in.U64("point count");
  in.RequireRecords(point_count, kPointBytes, "point");
  map.points.resize(point_count);
  for (StoredMapPoint& point : map.points) {
    point.id = in.U64("point");
    for (int i = 0; i < 3; ++i) point.position_w[i] = in.F64("point");
    for (int i = 0; i < 3; ++i) point.viewing_direction[i] = in.F32("point");
    point.min_distance_m = in.F32("point");
    point.max_distance_m = in.F32("point");
    in.Bytes(point.descriptor.data(), point.descriptor.size(), "point");
    point.num_observations = in.U32("point");
    for (std::uint8_t& channel : point.color_rgb) channel = in.U8("point");
  }

  if (in.remaining() != 0) {
    throw FileError(file, fmt::format("{} unexpected bytes after the last map point",
                                      in.remaining()));
  }
  return map;
}

std::uint64_t LittleEndianAt(const std::string& bytes, std::size_t offset, int size) {
  std::uint64_t v = 0;
  for (int i = 0; i < size; ++i) {
    v |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[offset + i])) << (8 * i);
  }
  return v;
}

std::string DescribeCamera(const PinholeCamera& c) {
  return fmt::format("{}x{} fx {} fy {} cx {} cy {}", c.width, c.height, c.fx, c.fy, c.cx, c.cy);
}

bool NearlyEqual(double a, double b, double relative_tolerance) {
  return std::abs(a - b) <= relative_tolerance * std::max(std::abs(a), std::abs(b));
}

}  // namespace

void SaveLongTermMap(const fs::path& path, const LongTermMapData& map) {
  if (const std::string problem = FindInvalidValue(map); !problem.empty()) {
    throw FileError(path, "refusing to write a map that could not be read back: " + problem);
  }
  const std::string payload = EncodePayload(map);
  const auto checksum = Sha256(payload.data(), payload.size());

  PayloadWriter header;
  header.Bytes(kMagic, kMagicBytes);
  header.U32(kMapFormatVersion);
  header.U64(payload.size());

  std::string file_bytes;
  file_bytes.reserve(kHeaderBytes + payload.size() + kChecksumBytes);
  file_bytes += header.bytes();
  file_bytes += payload;
  file_bytes.append(reinterpret_cast<const char*>(checksum.data()), checksum.size());
  WriteFileAtomically(path, file_bytes);
}

LongTermMapData LoadLongTermMap(const fs::path& path) {
  const std::string bytes = ReadFileText(path);

  // A file shorter than the magic that matches as far as it goes is a cut-off map; one that
  // does not match is something else.
  if (bytes.empty()) throw FileError(path, "empty file, not a segslam map");
  const std::size_t magic_bytes_present = std::min(bytes.size(), kMagicBytes);
  if (std::memcmp(bytes.data(), kMagic, magic_bytes_present) != 0) {
    throw FileError(path, "not a segslam map (wrong magic bytes)");
  }
  if (bytes.size() < kHeaderBytes) {
    throw FileError(path, fmt::format("truncated: the header alone needs {} bytes, the file has {}",
                                      kHeaderBytes, bytes.size()));
  }
  const auto version = static_cast<std::uint32_t>(LittleEndianAt(bytes, kMagicBytes, 4));
  if (version != kMapFormatVersion) {
    throw FileError(path, fmt::format("unsupported map format version {} (this build reads "
                                      "version {})",
                                      version, kMapFormatVersion));
  }
  const std::uint64_t payload_size = LittleEndianAt(bytes, kMagicBytes + 4, 8);
  // A size no map comes near is a damaged header, not a file cut short (which keeps its
  // header's true size); compared before adding to payload_size, which may be near 2^64.
  if (payload_size > kMaxPayloadBytes) {
    throw FileError(path, fmt::format("corrupt: the header gives {} bytes of map data, more than any map holds "
                                      "({} at most); the file has {} bytes",
                                      payload_size, kMaxPayloadBytes, bytes.size()));
  }
  const std::size_t available = bytes.size() - kHeaderBytes;
  if (available < kChecksumBytes || payload_size > available - kChecksumBytes) {
    throw FileError(path, fmt::format("truncated: expected {} bytes, the file has {}",
                                      kHeaderBytes + payload_size + kChecksumBytes, bytes.size()));
  }
  const std::size_t expected_size = kHeaderBytes + payload_size + kChecksumBytes;
  if (bytes.size() != expected_size) {
    throw FileError(path, fmt::format("{} unexpected bytes after the checksum (expected {} "
                                      "bytes, the file has {})",
                                      bytes.size() - expected_size, expected_size, bytes.size()));
  }

  const auto* payload = reinterpret_cast<const unsigned char*>(bytes.data()) + kHeaderBytes;
  const auto checksum = Sha256(payload, payload_size);
  if (std::memcmp(checksum.data(), payload + payload_size, kChecksumBytes) != 0) {
    throw FileError(path, "corrupt: the SHA-256 checksum of the payload does not match");
  }

  LongTermMapData map = DecodePayload(path, payload, payload_size);
  if (const std::string problem = FindInvalidValue(map); !problem.empty()) {
    throw FileError(path, problem);
  }
  return map;
}

void CheckMapCamera(const LongTermMapData& map, const PinholeCamera& camera,
                    const std::string& map_origin) {
  constexpr double kRelativeTolerance = 1e-6;
  const PinholeCamera& built = map.camera;
  const bool same = built.width == camera.width && built.height == camera.height &&
                    NearlyEqual(built.fx, camera.fx, kRelativeTolerance) &&
                    NearlyEqual(built.fy, camera.fy, kRelativeTolerance) &&
                    NearlyEqual(built.cx, camera.cx, kRelativeTolerance) &&
                    NearlyEqual(built.cy, camera.cy, kRelativeTolerance);
  if (!same) {
    throw Error(map_origin + ": the map was built with camera " + DescribeCamera(built) +
                " but this sequence's camera is " + DescribeCamera(camera) +
                "; a map from another camera cannot be used for relocalization");
  }
}

void ExportPly(const fs::path& path, const LongTermMapData& map) {
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  header += fmt::format("comment segslam long-term map: {} points, {} keyframes\n",
                        map.points.size(), map.keyframes.size());
  // PLY ends a comment at the line break, so each description line gets its own comment.
  std::istringstream description(map.description);
  for (std::string line; std::getline(description, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    header += "comment " + line + "\n";
  }
  header += fmt::format("element vertex {}\n", map.points.size());
  header +=
      "property float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      "end_header\n";

  PayloadWriter body;
  body.Bytes(header.data(), header.size());
  for (const StoredMapPoint& point : map.points) {
    for (int i = 0; i < 3; ++i) body.F32(static_cast<float>(point.position_w[i]));
    for (std::uint8_t channel : point.color_rgb) body.U8(channel);
  }
  WriteFileAtomically(path, body.bytes());
}

}  // namespace segslam::slam
