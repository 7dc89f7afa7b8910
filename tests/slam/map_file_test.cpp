// The long-term map file: exact round trips, and every kind of damaged file refused with
// a message that names the file and the damage. The layout facts checked here (magic,
// little-endian version and size, SHA-256 trailer) are the ones map_file.h documents,
// recomputed independently with OpenSSL.
#include "slam/map_file.h"

#include <gtest/gtest.h>
#include <openssl/sha.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <unistd.h>

#include "core/error.h"

namespace segslam::slam {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kHeaderBytes = 24;    // magic 12, version 4, payload size 8
constexpr std::size_t kChecksumBytes = 32;  // SHA-256

PinholeCamera Freiburg1Camera() {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = 517.3;
  camera.fy = 516.5;
  camera.cx = 318.6;
  camera.cy = 255.3;
  return camera;
}

// A map whose every field holds a value that differs between records, so a field read
// into the wrong place or in the wrong order shows up.
LongTermMapData MakeMap(int keyframe_count, int point_count) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  LongTermMapData map;
  map.camera = Freiburg1Camera();
  map.description = "sequence fr1/xyz\nmode mutual\ncode 1.2.3-dirty";
  for (int i = 0; i < keyframe_count; ++i) {
    StoredKeyframe keyframe;
    keyframe.id = 1000 + 3 * i;
    keyframe.stamp_s = 1305031102.160407 + 0.0331 * i;
    keyframe.T_wc = Eigen::Translation3d(uniform(random), uniform(random), uniform(random)) *
                    Eigen::AngleAxisd(uniform(random),
                                      Eigen::Vector3d(uniform(random), uniform(random), 1.0)
                                          .normalized());
    map.keyframes.push_back(keyframe);
  }
  for (int i = 0; i < point_count; ++i) {
    StoredMapPoint point;
    point.id = (std::uint64_t{1} << 40) + i;
    point.position_w = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
    point.viewing_direction =
        Eigen::Vector3f(uniform(random), uniform(random), uniform(random)).normalized();
    point.min_distance_m = 0.5f + 0.01f * i;
    point.max_distance_m = 7.25f + 0.1f * i;
    for (int b = 0; b < kOrbDescriptorBytes; ++b) {
      point.descriptor[b] = static_cast<std::uint8_t>(random());
    }
    point.num_observations = 2 + 5 * i;
    point.color_rgb = {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(255 - i),
                       static_cast<std::uint8_t>(37 * i)};
    map.points.push_back(point);
  }
  return map;
}

std::string ReadBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteBytes(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

std::uint64_t LittleEndian(const std::string& bytes, std::size_t offset, int size) {
  std::uint64_t v = 0;
  for (int i = 0; i < size; ++i) {
    v |= std::uint64_t{static_cast<unsigned char>(bytes[offset + i])} << (8 * i);
  }
  return v;
}

std::string Sha256(const std::string& bytes) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), digest);
  return std::string(reinterpret_cast<const char*>(digest), sizeof digest);
}

// Replaces a file's payload and gives it a matching header and checksum: a file that is
// well-formed on the outside, to reach the checks of the payload's contents.
std::string WithPayload(const std::string& file_bytes, const std::string& payload) {
  std::string result = file_bytes.substr(0, 16);
  for (int i = 0; i < 8; ++i) result += static_cast<char>(payload.size() >> (8 * i));
  return result + payload + Sha256(payload);
}

std::string PayloadOf(const std::string& file_bytes) {
  return file_bytes.substr(kHeaderBytes, file_bytes.size() - kHeaderBytes - kChecksumBytes);
}

class MapFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("segslam_map_file_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Expects loading `file` to fail with a message naming the file and containing `fragment`.
  void ExpectLoadFails(const fs::path& file, const std::string& fragment) {
    try {
      LoadLongTermMap(file);
      ADD_FAILURE() << "loading " << file << " did not fail; expected '" << fragment << "'";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(file.string()), std::string::npos) << message;
      EXPECT_NE(message.find(fragment), std::string::npos)
          << "missing '" << fragment << "' in: " << message;
    }
  }

  fs::path dir_;
};

void ExpectSameMap(const LongTermMapData& a, const LongTermMapData& b) {
  EXPECT_EQ(a.camera.width, b.camera.width);
  EXPECT_EQ(a.camera.height, b.camera.height);
  EXPECT_EQ(a.camera.fx, b.camera.fx);
  EXPECT_EQ(a.camera.fy, b.camera.fy);
  EXPECT_EQ(a.camera.cx, b.camera.cx);
  EXPECT_EQ(a.camera.cy, b.camera.cy);
  EXPECT_EQ(a.description, b.description);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t i = 0; i < a.keyframes.size(); ++i) {
    EXPECT_EQ(a.keyframes[i].id, b.keyframes[i].id);
    EXPECT_EQ(a.keyframes[i].stamp_s, b.keyframes[i].stamp_s);
    // Bit-exact, not approximately equal: the file stores the matrix itself.
    EXPECT_TRUE(a.keyframes[i].T_wc.matrix() == b.keyframes[i].T_wc.matrix()) << i;
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    const StoredMapPoint& p = a.points[i];
    const StoredMapPoint& q = b.points[i];
    EXPECT_EQ(p.id, q.id);
    EXPECT_TRUE(p.position_w == q.position_w) << i;
    EXPECT_TRUE(p.viewing_direction == q.viewing_direction) << i;
    EXPECT_EQ(p.min_distance_m, q.min_distance_m);
    EXPECT_EQ(p.max_distance_m, q.max_distance_m);
    EXPECT_EQ(p.descriptor, q.descriptor);
    EXPECT_EQ(p.num_observations, q.num_observations);
    EXPECT_EQ(p.color_rgb, q.color_rgb);
  }
}

TEST_F(MapFileTest, RoundTripIsExact) {
  const LongTermMapData map = MakeMap(5, 40);
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, map);
  ExpectSameMap(map, LoadLongTermMap(file));
}

TEST_F(MapFileTest, EmptyMapRoundTrips) {
  LongTermMapData map;
  map.camera = Freiburg1Camera();
  const fs::path file = dir_ / "empty.segmap";
  SaveLongTermMap(file, map);
  const LongTermMapData loaded = LoadLongTermMap(file);
  ExpectSameMap(map, loaded);
  EXPECT_TRUE(loaded.keyframes.empty());
  EXPECT_TRUE(loaded.points.empty());
}

TEST_F(MapFileTest, LayoutIsMagicVersionSizePayloadSha256) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(2, 3));
  const std::string bytes = ReadBytes(file);
  ASSERT_GT(bytes.size(), kHeaderBytes + kChecksumBytes);
  EXPECT_EQ(bytes.substr(0, 12), std::string("SEGSLAM-MAP\0", 12));
  EXPECT_EQ(LittleEndian(bytes, 12, 4), kMapFormatVersion);
  EXPECT_EQ(LittleEndian(bytes, 16, 8), bytes.size() - kHeaderBytes - kChecksumBytes);
  EXPECT_EQ(bytes.substr(bytes.size() - kChecksumBytes), Sha256(PayloadOf(bytes)));
  // No temporary file is left beside the map.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(MapFileTest, TruncatedFileIsRefusedAtEveryCut) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(3, 10));
  const std::string bytes = ReadBytes(file);
  const fs::path cut = dir_ / "cut.segmap";
  // Inside the magic, inside the header, at the payload's start, in its middle, and one
  // byte short of the end (inside the checksum).
  for (std::size_t size : {std::size_t{5}, std::size_t{12}, std::size_t{20}, kHeaderBytes,
                           bytes.size() / 2, bytes.size() - kChecksumBytes, bytes.size() - 1}) {
    SCOPED_TRACE("cut at " + std::to_string(size));
    WriteBytes(cut, bytes.substr(0, size));
    ExpectLoadFails(cut, "truncated");
  }
  // Past the header, the message gives both sizes.
  WriteBytes(cut, bytes.substr(0, bytes.size() / 2));
  ExpectLoadFails(cut, "expected " + std::to_string(bytes.size()) + " bytes, the file has " +
                           std::to_string(bytes.size() / 2));
}

// A size field larger than any map is a damaged header, not a file cut short: a cut file
// keeps its header's true size.
TEST_F(MapFileTest, ImpossibleSizeFieldIsCorruptNotTruncated) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(3, 10));
  std::string bytes = ReadBytes(file);
  bytes[16 + 5] = static_cast<char>(0xff);  // the payload size's sixth byte: about 2^45 bytes
  WriteBytes(file, bytes);
  ExpectLoadFails(file, "corrupt: the header gives " + std::to_string(LittleEndian(bytes, 16, 8)) +
                            " bytes of map data, more than any map holds");
  try {
    LoadLongTermMap(file);
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST_F(MapFileTest, FlippedPayloadByteIsCorrupt) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(3, 10));
  std::string bytes = ReadBytes(file);
  for (std::size_t offset : {kHeaderBytes, kHeaderBytes + 100, bytes.size() - kChecksumBytes - 1}) {
    SCOPED_TRACE("flipped byte " + std::to_string(offset));
    std::string damaged = bytes;
    damaged[offset] = static_cast<char>(damaged[offset] ^ 0x10);
    WriteBytes(file, damaged);
    ExpectLoadFails(file, "corrupt");
  }
}

TEST_F(MapFileTest, WrongMagicIsNotAMap) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(1, 1));
  std::string bytes = ReadBytes(file);
  bytes[0] = 'X';
  WriteBytes(file, bytes);
  ExpectLoadFails(file, "not a segslam map");

  const fs::path ply = dir_ / "cloud.ply";
  ExportPly(ply, MakeMap(1, 1));
  ExpectLoadFails(ply, "not a segslam map");
}

TEST_F(MapFileTest, FutureVersionIsNamed) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(1, 1));
  std::string bytes = ReadBytes(file);
  bytes[12] = static_cast<char>(kMapFormatVersion + 1);
  WriteBytes(file, bytes);
  ExpectLoadFails(file, "unsupported map format version " +
                            std::to_string(kMapFormatVersion + 1) + " (this build reads version " +
                            std::to_string(kMapFormatVersion) + ")");
}

TEST_F(MapFileTest, MissingAndEmptyFilesAreNamed) {
  ExpectLoadFails(dir_ / "nowhere.segmap", "file does not exist");
  WriteBytes(dir_ / "empty.segmap", "");
  ExpectLoadFails(dir_ / "empty.segmap", "empty file");
}

TEST_F(MapFileTest, TrailingBytesAreRefused) {
  const fs::path file = dir_ / "map.segmap";
  SaveLongTermMap(file, MakeMap(1, 1));
  WriteBytes(file, ReadBytes(file) + "xyz");
  ExpectLoadFails(file, "3 unexpected bytes after the checksum");
}

// Payload offsets of version 1 (map_file.cpp): camera 40 bytes, then the description
// length and bytes, then the keyframe count.
TEST_F(MapFileTest, CountBeyondThePayloadIsRefusedBeforeAllocating) {
  const fs::path file = dir_ / "map.segmap";
  LongTermMapData map = MakeMap(2, 2);
  map.description = "d";
  SaveLongTermMap(file, map);
  const std::string bytes = ReadBytes(file);
  std::string payload = PayloadOf(bytes);
  const std::size_t keyframe_count_offset = 40 + 8 + 1;
  ASSERT_EQ(LittleEndian(payload, keyframe_count_offset, 8), 2u);
  for (int i = 0; i < 8; ++i) payload[keyframe_count_offset + i] = static_cast<char>(0xff);
  WriteBytes(file, WithPayload(bytes, payload));
  ExpectLoadFails(file, "keyframe count 18446744073709551615 needs");

  std::string long_description = PayloadOf(bytes);
  long_description[41] = 0x10;  // description length 1 -> 1 + 16 * 256, beyond the payload
  WriteBytes(file, WithPayload(bytes, long_description));
  ExpectLoadFails(file, "description byte count 4097");
}

TEST_F(MapFileTest, InvalidValuesInsideAValidFileAreRefused) {
  const fs::path file = dir_ / "map.segmap";
  LongTermMapData map = MakeMap(0, 1);
  map.description.clear();
  SaveLongTermMap(file, map);
  const std::string bytes = ReadBytes(file);

  // The only point's x coordinate: camera 40, description length 8, keyframe count 8,
  // point count 8, point id 8.
  std::string nan_position = PayloadOf(bytes);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(&nan_position[40 + 8 + 8 + 8 + 8], &nan, sizeof nan);
  WriteBytes(file, WithPayload(bytes, nan_position));
  ExpectLoadFails(file, "non-finite");

  std::string zero_width = PayloadOf(bytes);
  std::memset(&zero_width[0], 0, 4);
  WriteBytes(file, WithPayload(bytes, zero_width));
  ExpectLoadFails(file, "invalid camera");

  // The point's observation count (after id 8, position 24, direction 12, distances 8,
  // descriptor 32): 2^31 would overflow the localizer's int count.
  std::string huge_count = PayloadOf(bytes);
  const std::uint32_t count = 0x80000000u;
  std::memcpy(&huge_count[40 + 8 + 8 + 8 + 84], &count, sizeof count);
  WriteBytes(file, WithPayload(bytes, huge_count));
  ExpectLoadFails(file, "claims 2147483648 observations");
}

TEST_F(MapFileTest, SaveRefusesWhatLoadWouldRefuse) {
  const fs::path file = dir_ / "map.segmap";
  LongTermMapData map = MakeMap(1, 2);
  map.points[1].position_w.y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(SaveLongTermMap(file, map), Error);
  map = MakeMap(1, 2);
  map.keyframes[0].T_wc.linear() *= 2.0;  // a scaled matrix is no rotation
  EXPECT_THROW(SaveLongTermMap(file, map), Error);
  map = MakeMap(1, 2);
  map.points[0].num_observations = 0x80000000u;
  EXPECT_THROW(SaveLongTermMap(file, map), Error);
  EXPECT_FALSE(fs::exists(file));
}

TEST(MapCameraTest, SameCameraPassesOtherCamerasAreNamed) {
  const LongTermMapData map = MakeMap(1, 1);
  PinholeCamera camera = Freiburg1Camera();
  EXPECT_NO_THROW(CheckMapCamera(map, camera, "old.segmap"));
  camera.fx *= 1 + 1e-8;  // below the 1e-6 relative tolerance: the same calibration
  EXPECT_NO_THROW(CheckMapCamera(map, camera, "old.segmap"));

  camera = Freiburg1Camera();
  camera.fx = 525.0;
  try {
    CheckMapCamera(map, camera, "old.segmap");
    ADD_FAILURE() << "a different fx was accepted";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("old.segmap: ", 0), 0u) << message;
    EXPECT_NE(message.find("517.3"), std::string::npos) << message;
    EXPECT_NE(message.find("525"), std::string::npos) << message;
  }

  camera = Freiburg1Camera();
  camera.width = 320;
  camera.height = 240;
  EXPECT_THROW(CheckMapCamera(map, camera, "old.segmap"), Error);
}

TEST_F(MapFileTest, PlyHeaderAndFirstVertex) {
  const LongTermMapData map = MakeMap(2, 17);
  const fs::path file = dir_ / "cloud.ply";
  ExportPly(file, map);
  const std::string bytes = ReadBytes(file);

  const std::string end_header = "end_header\n";
  const std::size_t body = bytes.find(end_header) + end_header.size();
  ASSERT_NE(body, std::string::npos + end_header.size());
  const std::string expected_header =
      "ply\n"
      "format binary_little_endian 1.0\n"
      "comment segslam long-term map: 17 points, 2 keyframes\n"
      "comment sequence fr1/xyz\n"
      "comment mode mutual\n"
      "comment code 1.2.3-dirty\n"
      "element vertex 17\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "property uchar red\n"
      "property uchar green\n"
      "property uchar blue\n"
      "end_header\n";
  EXPECT_EQ(bytes.substr(0, body), expected_header);

  constexpr std::size_t kVertexBytes = 3 * 4 + 3;
  ASSERT_EQ(bytes.size() - body, map.points.size() * kVertexBytes);
  for (int axis = 0; axis < 3; ++axis) {
    const auto bits = static_cast<std::uint32_t>(LittleEndian(bytes, body + 4 * axis, 4));
    float value;
    std::memcpy(&value, &bits, sizeof value);
    EXPECT_EQ(value, static_cast<float>(map.points[0].position_w[axis])) << axis;
  }
  for (int channel = 0; channel < 3; ++channel) {
    EXPECT_EQ(static_cast<unsigned char>(bytes[body + 12 + channel]),
              map.points[0].color_rgb[channel]);
  }
}

}  // namespace
}  // namespace segslam::slam
