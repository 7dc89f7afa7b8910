#include "core/tracks.h"

#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "core/error.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using TracksTest = testing::TempDirTest;

std::vector<ObjectTrack> MakeTracks() {
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0, 1);
  std::vector<ObjectTrack> tracks;
  for (std::uint16_t id : {3, 8}) {
    ObjectTrack track;
    track.instance_id = id;
    for (int f = 0; f < 20; ++f) {
      TrackSample s;
      s.frame = f;
      s.stamp_s = f / 30.0;
      s.present = f != 5;
      s.moving = f > 10;
      Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
      s.T_world_object.linear() = q.normalized().toRotationMatrix();
      s.T_world_object.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng));
      s.visible_pixels = f * 100;
      track.samples.push_back(s);
    }
    tracks.push_back(track);
  }
  return tracks;
}

std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::ostringstream s;
  s << file.rdbuf();
  return s.str();
}

TEST_F(TracksTest, RoundTripAndDeterministicBytes) {
  const auto tracks = MakeTracks();
  const auto path = dir() / "tracks.json";
  WriteTracks(path, tracks);
  const auto back = ReadTracks(path);
  ASSERT_EQ(back.size(), tracks.size());
  // Shortest round-trip doubles: poses come back to rounding of the rotation matrix.
  constexpr double kMaxMatrixError = 1e-14;
  for (size_t i = 0; i < tracks.size(); ++i) {
    EXPECT_EQ(back[i].instance_id, tracks[i].instance_id);
    ASSERT_EQ(back[i].samples.size(), tracks[i].samples.size());
    for (size_t j = 0; j < tracks[i].samples.size(); ++j) {
      const TrackSample& a = tracks[i].samples[j];
      const TrackSample& b = back[i].samples[j];
      EXPECT_EQ(a.frame, b.frame);
      EXPECT_EQ(a.stamp_s, b.stamp_s);
      EXPECT_EQ(a.present, b.present);
      EXPECT_EQ(a.moving, b.moving);
      EXPECT_EQ(a.visible_pixels, b.visible_pixels);
      EXPECT_LT((a.T_world_object.matrix() - b.T_world_object.matrix()).norm(), kMaxMatrixError);
    }
  }
  // The same tracks, built again from the same seed, give the same bytes. (Re-writing what
  // was read may differ in the last digit: quaternion -> matrix -> quaternion is not exact.)
  const auto path2 = dir() / "tracks2.json";
  WriteTracks(path2, MakeTracks());
  EXPECT_TRUE(ReadAll(path) == ReadAll(path2));
  EXPECT_NE(ReadAll(path).find("\"q\": ["), std::string::npos);
}

TEST(TracksFromJson, Errors) {
  auto from = [](const char* text) {
    return ErrorMessage([&] { TracksFromJson(nlohmann::json::parse(text), "k.json"); });
  };
  const char* sample_ok =
      R"({"frame": 0, "stamp_s": 0, "present": true, "moving": false, "t": [0,0,0],
          "q": [0,0,0,1], "visible_pixels": 0})";
  EXPECT_NO_THROW(TracksFromJson(
      nlohmann::json::parse(std::string(R"({"tracks": [{"instance_id": 1, "samples": [)") +
                            sample_ok + "]}]}"),
      "k.json"));
  EXPECT_NE(from(R"({"tracks": [{"instance_id": 0, "samples": []}]})").find("1..65535"),
            std::string::npos);
  EXPECT_NE(from(R"({"tracks": [{"instance_id": 1}]})").find("samples"), std::string::npos);
  EXPECT_NE(from(R"({"tracks": [{"instance_id": 1, "samples": []},
                                 {"instance_id": 1, "samples": []}]})")
                .find("duplicate"),
            std::string::npos);
  EXPECT_NE(from(R"({"tracks": [{"instance_id": 1, "samples": [
      {"frame": 0, "stamp_s": 0, "present": true, "moving": false, "t": [0,0,0],
       "q": [0,0,0,2], "visible_pixels": 0}]}]})")
                .find("quaternion"),
            std::string::npos);
  EXPECT_NE(from(R"({"tracks": [{"instance_id": 1, "samples": [
      {"frame": 0, "stamp_s": 0, "present": true, "moving": false, "t": [0,0],
       "q": [0,0,0,1], "visible_pixels": 0}]}]})")
                .find("\"t\""),
            std::string::npos);
  const std::string message = from(R"({"tracks": [{"instance_id": 1, "samples": [
      {"frame": 2, "stamp_s": 0, "present": true, "moving": false, "t": [0,0,0],
       "q": [0,0,0,1], "visible_pixels": 0},
      {"frame": 2, "stamp_s": 0, "present": true, "moving": false, "t": [0,0,0],
       "q": [0,0,0,1], "visible_pixels": 0}]}]})");
  EXPECT_NE(message.find("k.json: tracks[0].samples[1]"), std::string::npos) << message;
  EXPECT_NE(message.find("does not increase"), std::string::npos) << message;
}

}  // namespace
}  // namespace segslam
