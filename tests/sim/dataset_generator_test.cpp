// Checks of generated datasets against independent facts: re-projection with the
// ground-truth poses, an independent RGB-D odometry (OpenCV contrib), ORB texture
// richness, mask geometry, object tracks, pass-2 changes and byte determinism.
// The datasets are generated once by CTest fixtures (tests/sim/CMakeLists.txt).
#include "core/camera.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/lens_distortion.h"
#include "core/manifest.h"
#include "core/pose.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"
#include "scenes/scenario.h"
#include "sim/dataset_generator.h"

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sys/stat.h>
#include <unistd.h>

namespace segslam {
namespace {

namespace fs = std::filesystem;

fs::path TestDataset(const std::string& name) { return fs::path(SEGSLAM_TEST_DATA_DIR) / name; }

double Median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  const size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + middle, values.end());
  return values[middle];
}

struct Pass {
  TumSequence sequence;
  std::vector<cv::Mat> masks;
};

Pass OpenPass(const fs::path& dir) {
  Pass pass{TumSequence::Open(dir), {}};
  for (const auto& entry : pass.sequence.entries()) {
    const std::string stem = fs::path(entry.rgb_file).stem().string();
    pass.masks.push_back(ReadInstanceMask(dir / "masks" / (stem + ".png")));
  }
  return pass;
}

// Median relative depth error of static background pixels of frame `a` re-projected
// into frame `b` with the ground-truth poses.
double ReprojectionDepthError(const Pass& pass, size_t a, size_t b) {
  const PinholeCamera& camera = pass.sequence.camera().intrinsics;
  const RgbdFrame frame_a = pass.sequence.LoadFrame(a);
  const RgbdFrame frame_b = pass.sequence.LoadFrame(b);
  const Eigen::Isometry3d T_b_a =
      pass.sequence.groundtruth()[b].T_wc.inverse() * pass.sequence.groundtruth()[a].T_wc;
  std::vector<double> relative_errors;
  constexpr int kStep = 3;  // every third pixel is plenty for a median
  for (int v = 0; v < camera.height; v += kStep) {
    for (int u = 0; u < camera.width; u += kStep) {
      const float depth_a = frame_a.depth_m.at<float>(v, u);
      if (depth_a <= 0.f || pass.masks[a].at<std::uint16_t>(v, u) != 0) continue;
      const Eigen::Vector3d p_b = T_b_a * camera.BackProject(Eigen::Vector2d(u, v), depth_a);
      if (p_b.z() <= 0) continue;
      const Eigen::Vector2d pixel_b = camera.Project(p_b);
      const int ub = static_cast<int>(std::lround(pixel_b.x()));
      const int vb = static_cast<int>(std::lround(pixel_b.y()));
      if (ub < 0 || vb < 0 || ub >= camera.width || vb >= camera.height) continue;
      if (pass.masks[b].at<std::uint16_t>(vb, ub) != 0) continue;
      const float depth_b = frame_b.depth_m.at<float>(vb, ub);
      if (depth_b <= 0.f) continue;
      relative_errors.push_back(std::abs(depth_b - p_b.z()) / p_b.z());
    }
  }
  EXPECT_GT(relative_errors.size(), 1000u) << "too few re-projected pixels";
  return Median(relative_errors);
}

class GroundTruthConsistency : public ::testing::TestWithParam<std::string> {};

TEST_P(GroundTruthConsistency, StaticPixelsReprojectWithMatchingDepth) {
  const fs::path dataset = TestDataset(GetParam());
  for (const char* pass_name : {"pass1", "pass2"}) {
    const Pass pass = OpenPass(dataset / pass_name);
    ASSERT_GE(pass.sequence.size(), 12u);
    for (size_t k : {1u, 5u}) {
      for (size_t a : {size_t{0}, pass.sequence.size() / 2, pass.sequence.size() - 1 - k}) {
        const double error = ReprojectionDepthError(pass, a, a + k);
        std::printf("%s %s frames %zu -> %zu: median relative depth error %.5f\n",
                    GetParam().c_str(), pass_name, a, a + k, error);
        EXPECT_LT(error, /*max_median_relative_depth_error=*/0.01)
            << pass_name << " frames " << a << " -> " << a + k;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(CityAndOffice, GroundTruthConsistency,
                         ::testing::Values("city_clean", "office_clean"));

// Chains OpenCV contrib's dense RGB-D odometry over pass 1 of a city route without moving
// objects; the end-point drift must stay under 2% of the distance travelled.
TEST(IndependentOdometry, RgbdOdometryAgreesWithGroundTruthOnStaticCity) {
  const TumSequence sequence = TumSequence::Open(TestDataset("city_static") / "pass1");
  const PinholeCamera& camera = sequence.camera().intrinsics;
  cv::Mat K = (cv::Mat_<float>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const std::vector<int> iterations = {7, 7, 7, 10};
  const std::vector<float> min_gradients = {10, 10, 10, 10};
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry = cv::rgbd::RgbdOdometry::create(
      K, /*minDepth=*/0.5f, /*maxDepth=*/30.f, /*maxDepthDiff=*/0.5f, iterations, min_gradients,
      /*maxPointsPart=*/0.1f, cv::rgbd::Odometry::RIGID_BODY_MOTION);
  // A car at 6 m/s moves 0.4 m per frame at 15 fps; OpenCV refuses steps over 0.15 m
  // by default.
  odometry->setMaxTranslation(1.0);
  odometry->setMaxRotation(30.0);

  auto gray_and_depth = [&](size_t i, cv::Mat* gray, cv::Mat* depth) {
    const RgbdFrame frame = sequence.LoadFrame(i);
    cv::cvtColor(frame.color_bgr, *gray, cv::COLOR_BGR2GRAY);
    *depth = frame.depth_m.clone();
    depth->setTo(std::numeric_limits<float>::quiet_NaN(), frame.depth_m == 0.f);
  };
  Eigen::Isometry3d T_wc = sequence.groundtruth().front().T_wc;
  double distance_m = 0;
  cv::Mat previous_gray, previous_depth, previous_Rt;
  gray_and_depth(0, &previous_gray, &previous_depth);
  for (size_t i = 1; i < sequence.size(); ++i) {
    cv::Mat gray, depth, Rt;
    gray_and_depth(i, &gray, &depth);
    // Constant-velocity prior: the previous step of the odometry itself (never the
    // ground truth) starts the search, as a real tracker would.
    ASSERT_TRUE(odometry->compute(previous_gray, previous_depth, cv::Mat(), gray, depth, cv::Mat(),
                                  Rt, previous_Rt))
        << "odometry failed at frame " << i;
    previous_Rt = Rt.clone();
    // Rt maps points of the previous camera frame into the current one: T_cur_prev.
    Eigen::Matrix4d T_cur_prev;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) T_cur_prev(r, c) = Rt.at<double>(r, c);
    T_wc = T_wc * Eigen::Isometry3d(T_cur_prev).inverse();
    distance_m += (sequence.groundtruth()[i].T_wc.translation() -
                   sequence.groundtruth()[i - 1].T_wc.translation()).norm();
    previous_gray = gray;
    previous_depth = depth;
  }
  const double drift_m = (T_wc.translation() - sequence.groundtruth().back().T_wc.translation()).norm();
  ASSERT_GT(distance_m, 20.0);
  EXPECT_LT(drift_m / distance_m, /*max_relative_drift=*/0.02)
      << "drift " << drift_m << " m over " << distance_m << " m";
  std::printf("RgbdOdometry end-point drift: %.3f m over %.1f m (%.2f%%)\n", drift_m, distance_m,
              100 * drift_m / distance_m);
}

class TextureRichness : public ::testing::TestWithParam<std::string> {};

TEST_P(TextureRichness, MedianOrbKeypointsWithDepth) {
  const TumSequence sequence = TumSequence::Open(TestDataset(GetParam()) / "pass1");
  cv::Ptr<cv::ORB> orb = cv::ORB::create(/*nfeatures=*/1000);
  std::vector<double> counts;
  for (size_t i = 0; i < sequence.size(); i += 3) {
    const RgbdFrame frame = sequence.LoadFrame(i);
    cv::Mat gray;
    cv::cvtColor(frame.color_bgr, gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> keypoints;
    orb->detect(gray, keypoints);
    int with_depth = 0;
    for (const auto& keypoint : keypoints) {
      const int u = std::clamp(static_cast<int>(std::lround(keypoint.pt.x)), 0, gray.cols - 1);
      const int v = std::clamp(static_cast<int>(std::lround(keypoint.pt.y)), 0, gray.rows - 1);
      with_depth += frame.depth_m.at<float>(v, u) > 0.f;
    }
    counts.push_back(with_depth);
  }
  EXPECT_GE(Median(counts), /*min_median_keypoints_with_depth=*/600.0) << GetParam();
  std::printf("%s: median ORB keypoints with depth %.0f of 1000 over %zu frames\n",
              GetParam().c_str(), Median(counts), counts.size());
}

INSTANTIATE_TEST_SUITE_P(CityAndOffice, TextureRichness,
                         ::testing::Values("city_static", "office_noisy"));

}  // namespace
}  // namespace segslam

namespace segslam {
namespace {

// Whether world point `p_world` lies on or inside `geom` of a part posed at
// T_world_part, with `tolerance_m` of slack (depth quantisation, rasterisation).
bool PointOnGeom(const scenes::Geom& geom, const Eigen::Isometry3d& T_world_part,
                 const Eigen::Vector3d& p_world, double tolerance_m) {
  const Eigen::Vector3d p = (T_world_part * geom.T_parent_geom).inverse() * p_world;
  const Eigen::Vector3d& s = geom.size;
  switch (geom.shape) {
    case scenes::Shape::kBox:
      return (p.cwiseAbs() - s).maxCoeff() <= tolerance_m;
    case scenes::Shape::kSphere:
      return p.norm() <= s.x() + tolerance_m;
    case scenes::Shape::kCylinder:
      return p.head<2>().norm() <= s.x() + tolerance_m && std::abs(p.z()) <= s.y() + tolerance_m;
    case scenes::Shape::kCapsule: {
      const double z = std::clamp(p.z(), -s.y(), s.y());
      return (p - Eigen::Vector3d(0, 0, z)).norm() <= s.x() + tolerance_m;
    }
    case scenes::Shape::kEllipsoid:
      return (p.array() / (s.array() + tolerance_m)).matrix().squaredNorm() <= 1.0;
    case scenes::Shape::kPlane:
      return std::abs(p.z()) <= tolerance_m && std::abs(p.x()) <= s.x() + tolerance_m &&
             std::abs(p.y()) <= s.y() + tolerance_m;
  }
  return false;
}

struct DatasetWithWorld {
  fs::path dir;
  scenes::Scenario scenario;
  scenes::World world;
};

DatasetWithWorld LoadDatasetWorld(const std::string& name) {
  DatasetWithWorld d;
  d.dir = TestDataset(name);
  d.scenario = scenes::LoadScenario(d.dir / "scenario.yaml");
  d.world = scenes::BuildWorld(d.scenario);
  return d;
}

class MaskGeometry : public ::testing::TestWithParam<std::string> {};

// Every pixel labelled with an instance, back-projected with its depth and the true
// camera pose, lies on that instance's geometry; every id is in instances.json.
TEST_P(MaskGeometry, InstancePixelsLieOnTheirGeoms) {
  const DatasetWithWorld d = LoadDatasetWorld(GetParam());
  std::map<std::uint16_t, const scenes::Object*> objects;
  for (const auto& object : d.world.objects) objects[object.instance_id] = &object;
  for (scenes::Pass pass_id : scenes::kBothPasses) {
    const fs::path pass_dir = d.dir / scenes::PassName(pass_id);
    const Pass pass = OpenPass(pass_dir);
    const InstanceTable instances = InstanceTable::Read(pass_dir / "instances.json");
    const PinholeCamera& camera = pass.sequence.camera().intrinsics;
    int checked = 0, on_geom = 0;
    std::set<std::uint16_t> seen;
    for (size_t i = 0; i < pass.sequence.size(); ++i) {
      CheckMaskIds(pass.masks[i], instances, "frame " + std::to_string(i));
      if (i % 4 != 0) continue;
      const RgbdFrame frame = pass.sequence.LoadFrame(i);
      const Eigen::Isometry3d& T_wc = pass.sequence.groundtruth()[i].T_wc;
      std::map<std::uint16_t, std::vector<Eigen::Isometry3d>> part_poses;
      for (int v = 0; v < camera.height; v += 2) {
        for (int u = 0; u < camera.width; u += 2) {
          const std::uint16_t id = pass.masks[i].at<std::uint16_t>(v, u);
          const float depth = frame.depth_m.at<float>(v, u);
          if (id == 0 || depth <= 0.f) continue;
          seen.insert(id);
          const scenes::Object& object = *objects.at(id);
          auto poses = part_poses.find(id);
          if (poses == part_poses.end()) {
            poses = part_poses.emplace(id, scenes::PartPosesAt(object, pass_id, frame.stamp_s)).first;
          }
          const Eigen::Vector3d p_world = T_wc * camera.BackProject(Eigen::Vector2d(u, v), depth);
          bool found = false;
          for (size_t part = 0; part < object.parts.size() && !found; ++part) {
            for (const auto& geom : object.parts[part].geoms) {
              if (PointOnGeom(geom, poses->second[part], p_world, /*tolerance_m=*/0.02)) {
                found = true;
                break;
              }
            }
          }
          ++checked;
          on_geom += found;
        }
      }
    }
    ASSERT_GT(checked, 1000) << "too few instance pixels in " << pass_dir;
    EXPECT_GE(static_cast<double>(on_geom) / checked, /*min_share_on_geometry=*/0.995)
        << pass_dir << ": " << checked - on_geom << " of " << checked << " pixels off their geom";
    EXPECT_GE(seen.size(), 3u) << "too few instances visible in " << pass_dir;
  }
}

INSTANTIATE_TEST_SUITE_P(CityAndOffice, MaskGeometry, ::testing::Values("city_clean", "office_clean"));

// tracks.json: an object flagged moving really moved (root or limbs) since the previous frame,
// one not flagged keeps its pose; moving instances exist in the dynamic scenario.
TEST(ObjectTracks, MovingFlagsMatchTheWorldsMotion) {
  const DatasetWithWorld d = LoadDatasetWorld("city_clean");
  std::map<std::uint16_t, const scenes::Object*> objects;
  for (const auto& object : d.world.objects) objects[object.instance_id] = &object;
  for (scenes::Pass pass : scenes::kBothPasses) {
    const auto tracks = ReadTracks(d.dir / scenes::PassName(pass) / "tracks.json");
    ASSERT_EQ(tracks.size(), d.world.objects.size());
    int moving_samples = 0, visible_moving_samples = 0;
    for (const auto& track : tracks) {
      const scenes::Object& object = *objects.at(track.instance_id);
      for (size_t i = 1; i < track.samples.size(); ++i) {
        const TrackSample& before = track.samples[i - 1];
        const TrackSample& now = track.samples[i];
        if (!now.present) continue;
        const auto parts_before = scenes::PartPosesAt(object, pass, before.stamp_s);
        const auto parts_now = scenes::PartPosesAt(object, pass, now.stamp_s);
        double largest_part_motion_m = 0;
        for (size_t p = 0; p < parts_now.size(); ++p) {
          largest_part_motion_m = std::max(
              largest_part_motion_m,
              (parts_before[p].translation() - parts_now[p].translation()).norm());
        }
        const double root_motion_m =
            (before.T_world_object.translation() - now.T_world_object.translation()).norm();
        if (now.moving) {
          ++moving_samples;
          visible_moving_samples += now.visible_pixels > 0;
          EXPECT_GT(largest_part_motion_m, 1e-4) << "instance " << track.instance_id << " frame " << i;
        } else {
          EXPECT_LT(root_motion_m, 1e-9) << "instance " << track.instance_id << " frame " << i;
          EXPECT_LT(largest_part_motion_m, 1e-9) << "instance " << track.instance_id << " frame " << i;
        }
      }
    }
    EXPECT_GT(moving_samples, 0);
    EXPECT_GT(visible_moving_samples, 0) << "no moving object is ever seen";
  }
}

// Pass 2 differs from pass 1 exactly as the scenario says: the counts of relocated,
// removed and added objects, every other object unchanged, traffic of its own (no mover
// is in both passes), and the camera route offset.
TEST(SecondPass, DiffersFromFirstExactlyAsTheScenarioSays) {
  const DatasetWithWorld d = LoadDatasetWorld("city_clean");
  const scenes::SecondPassChanges& changes = d.world.pass2_changes;
  const auto& spec = d.scenario.pass2;
  EXPECT_EQ(static_cast<int>(changes.relocated.size()),
            static_cast<int>(std::lround(spec.relocated_share * changes.candidates)));
  EXPECT_EQ(static_cast<int>(changes.removed.size()),
            static_cast<int>(std::lround(spec.removed_share * changes.candidates)));
  EXPECT_EQ(static_cast<int>(changes.added.size()), spec.added);

  const auto tracks1 = ReadTracks(d.dir / "pass1" / "tracks.json");
  const auto tracks2 = ReadTracks(d.dir / "pass2" / "tracks.json");
  ASSERT_EQ(tracks1.size(), tracks2.size());
  const std::set<std::uint16_t> relocated(changes.relocated.begin(), changes.relocated.end());
  const std::set<std::uint16_t> removed(changes.removed.begin(), changes.removed.end());
  const std::set<std::uint16_t> added(changes.added.begin(), changes.added.end());
  int seen_relocated = 0, seen_removed = 0, seen_added = 0, movers1 = 0, movers2 = 0;
  for (size_t k = 0; k < tracks1.size(); ++k) {
    ASSERT_EQ(tracks1[k].instance_id, tracks2[k].instance_id);
    const std::uint16_t id = tracks1[k].instance_id;
    const TrackSample& a = tracks1[k].samples.front();
    const TrackSample& b = tracks2[k].samples.front();
    const scenes::Object& object = d.world.objects[id - 1];
    ASSERT_EQ(object.instance_id, id);
    if (object.placement[0].moving || object.placement[1].moving) {
      EXPECT_NE(a.present, b.present) << "mover " << id << " is in both passes";
      movers1 += a.present;
      movers2 += b.present;
      continue;
    }
    if (a.present && !b.present) {
      ++seen_removed;
      EXPECT_TRUE(removed.count(id)) << id;
    } else if (!a.present && b.present) {
      ++seen_added;
      EXPECT_TRUE(added.count(id)) << id;
    } else if (a.present && b.present && !a.moving && !b.moving) {
      const double shift_m = (a.T_world_object.translation() - b.T_world_object.translation()).norm();
      if (relocated.count(id)) {
        ++seen_relocated;
        EXPECT_GT(shift_m, 1.0) << "relocated instance " << id << " barely moved";
      } else {
        EXPECT_LT(shift_m, 1e-9) << "instance " << id << " moved although not relocated";
      }
    }
  }
  EXPECT_EQ(seen_relocated, static_cast<int>(relocated.size()));
  EXPECT_EQ(seen_removed, static_cast<int>(removed.size()));
  EXPECT_EQ(seen_added, static_cast<int>(added.size()));
  const int movers = d.scenario.city.moving_cars + d.scenario.city.pedestrians;
  EXPECT_EQ(movers1, movers);
  EXPECT_EQ(movers2, movers);

  // The camera route of pass 2 is pass 1's, offset in the route frame (x forward, y left,
  // z up), at the same times; the city camera is level, so the route frame follows from
  // the optical axes: forward = z, left = -x, up = -y.
  const TumSequence pass1 = TumSequence::Open(d.dir / "pass1");
  const TumSequence pass2 = TumSequence::Open(d.dir / "pass2");
  ASSERT_EQ(pass1.size(), pass2.size());
  for (size_t i = 0; i < pass1.size(); i += 5) {
    const Eigen::Isometry3d& T1 = pass1.groundtruth()[i].T_wc;
    const Eigen::Vector3d delta = pass2.groundtruth()[i].T_wc.translation() - T1.translation();
    const Eigen::Matrix3d R = T1.rotation();
    const Eigen::Vector3d offset_route(delta.dot(R.col(2)), -delta.dot(R.col(0)), -delta.dot(R.col(1)));
    EXPECT_LT((offset_route - spec.camera_offset_m).norm(), /*max_offset_error_m=*/0.05)
        << "frame " << i << ": offset " << offset_route.transpose();
  }
}

// The same scenario generated twice gives byte-identical files.
TEST(Determinism, SameScenarioGivesIdenticalBytes) {
  const scenes::Scenario scenario =
      scenes::LoadScenario(fs::path(SEGSLAM_SOURCE_DIR) / "scenarios/test/office_small.yaml");
  const fs::path root = fs::temp_directory_path() / ("segslam_determinism_" + std::to_string(::getpid()));
  fs::remove_all(root);
  sim::GenerateOptions options;
  options.max_frames_per_pass = 6;
  sim::GenerateDataset(scenario, root / "a", options);
  options.encode_threads = 1;  // a different schedule must not change a byte
  sim::GenerateDataset(scenario, root / "b", options);
  const auto a = ListDirectoryWithChecksums(root / "a", {});
  const auto b = ListDirectoryWithChecksums(root / "b", {});
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(a.size(), 30u);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].path, b[i].path);
    EXPECT_EQ(a[i].sha256, b[i].sha256) << a[i].path;
  }
  EXPECT_TRUE(VerifyManifest(root / "a").empty());
  EXPECT_TRUE(VerifyManifest(root / "a" / "pass1").empty());
  fs::remove_all(root);
}

// overwrite replaces what is there; keep_complete_dataset keeps a complete dataset that
// appeared meanwhile (another shard filling the same cache entry) and drops its own.
TEST(Overwrite, KeepsACompleteDatasetOnlyWhenAsked) {
  const scenes::Scenario scenario =
      scenes::LoadScenario(fs::path(SEGSLAM_SOURCE_DIR) / "scenarios/test/office_small.yaml");
  const fs::path root = fs::temp_directory_path() / ("segslam_overwrite_" + std::to_string(::getpid()));
  fs::remove_all(root);
  sim::GenerateOptions options;
  options.max_frames_per_pass = 2;
  sim::GenerateDataset(scenario, root / "d", options);
  // A folder keeps its inode while it stays; a replacement is another folder renamed in.
  const auto inode = [](const fs::path& dir) {
    struct stat info {};
    EXPECT_EQ(::stat(dir.c_str(), &info), 0) << dir;
    return info.st_ino;
  };
  const auto first = inode(root / "d");

  options.overwrite = true;
  options.keep_complete_dataset = true;
  EXPECT_TRUE(sim::GenerateDataset(scenario, root / "d", options).kept_existing);
  EXPECT_EQ(inode(root / "d"), first);
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(root)) ++entries;
  EXPECT_EQ(entries, 1);  // no staging folder left

  options.keep_complete_dataset = false;
  EXPECT_FALSE(sim::GenerateDataset(scenario, root / "d", options).kept_existing);
  EXPECT_NE(inode(root / "d"), first);
  EXPECT_TRUE(VerifyManifest(root / "d").empty());
  fs::remove_all(root);
}

// camera.distortion: every stored image is the ideal render bent through the lens, and
// camera.yaml names the lens, so a run undistorts the frames again (core/lens_distortion.h).
TEST(LensDistortion, StoredImagesAreTheRendersBentThroughTheLens) {
  scenes::Scenario scenario =
      scenes::LoadScenario(fs::path(SEGSLAM_SOURCE_DIR) / "scenarios/test/office_small.yaml");
  scenes::ApplyOverride(scenario, "sensor.enabled", "false");  // No noise: images compare exactly.
  const fs::path root = fs::temp_directory_path() / ("segslam_lens_" + std::to_string(::getpid()));
  fs::remove_all(root);
  sim::GenerateOptions options;
  options.max_frames_per_pass = 3;
  sim::GenerateDataset(scenario, root / "ideal", options);
  scenes::ApplyOverride(scenario, "camera.distortion", "[0.2624, -0.9531, -0.0054, 0.0026, 1.1633]");
  sim::GenerateDataset(scenario, root / "lens", options);

  const TumSequence ideal = TumSequence::Open(root / "ideal" / "pass1");
  const TumSequence bent = TumSequence::Open(root / "lens" / "pass1");
  EXPECT_TRUE(ideal.camera().distortion.IsZero());
  EXPECT_EQ(bent.camera().distortion.k1, 0.2624);
  EXPECT_EQ(bent.camera().distortion.k3, 1.1633);
  const ImageUndistorter lens(bent.camera().intrinsics, bent.camera().distortion);
  ASSERT_EQ(ideal.size(), bent.size());
  for (size_t i = 0; i < ideal.size(); ++i) {
    const fs::path ideal_dir = ideal.dir(), bent_dir = bent.dir();
    const TumFrameEntry& entry = ideal.entries()[i];
    const std::string mask = "masks/" + fs::path(entry.rgb_file).filename().string();
    const cv::Mat ideal_ids = ReadInstanceMask(ideal_dir / mask);
    const cv::Mat bent_ids = ReadInstanceMask(bent_dir / mask);
    EXPECT_EQ(cv::norm(ReadColorImage(bent_dir / entry.rgb_file),
                       lens.DistortColour(ReadColorImage(ideal_dir / entry.rgb_file)), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(ReadDepthImage(bent_dir / entry.depth_file, 5000),
                       lens.DistortDepth(ReadDepthImage(ideal_dir / entry.depth_file, 5000)), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(bent_ids, lens.DistortIds(ideal_ids), cv::NORM_INF), 0.0);
    EXPECT_GT(cv::countNonZero(bent_ids != ideal_ids), 100) << "the lens bends the masks";
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace segslam

namespace segslam {
namespace {

// annotations_coco.json decodes back to exactly the masks: RLE, area and box.
TEST(CocoAnnotations, RleDecodesToTheMasks) {
  const fs::path pass_dir = TestDataset("city_clean") / "pass1";
  std::ifstream in(pass_dir / "annotations_coco.json");
  const nlohmann::json coco = nlohmann::json::parse(in);
  std::map<int, std::string> mask_files;
  for (const auto& image : coco.at("images")) {
    mask_files[image.at("id").get<int>()] = image.at("mask_file_name").get<std::string>();
  }
  ASSERT_FALSE(coco.at("annotations").empty());
  std::map<int, cv::Mat> masks;
  int checked = 0;
  for (const auto& annotation : coco.at("annotations")) {
    const int image_id = annotation.at("image_id").get<int>();
    if (!masks.count(image_id)) masks[image_id] = ReadInstanceMask(pass_dir / mask_files.at(image_id));
    const cv::Mat& mask = masks[image_id];
    const auto id = annotation.at("instance_id").get<std::uint16_t>();
    const auto& size = annotation.at("segmentation").at("size");
    ASSERT_EQ(size[0].get<int>(), mask.rows);
    ASSERT_EQ(size[1].get<int>(), mask.cols);
    // Uncompressed RLE: alternating runs of 0 and 1 over the column-major pixel order.
    cv::Mat decoded(mask.rows, mask.cols, CV_8U, cv::Scalar(0));
    long position = 0;
    bool ones = false;
    for (const auto& run : annotation.at("segmentation").at("counts")) {
      const long length = run.get<long>();
      for (long k = 0; k < length; ++k, ++position) {
        if (ones) decoded.at<std::uint8_t>(position % mask.rows, position / mask.rows) = 1;
      }
      ones = !ones;
    }
    ASSERT_EQ(position, static_cast<long>(mask.total()));
    const cv::Mat expected = mask == id;
    EXPECT_EQ(cv::countNonZero((decoded != 0) != expected), 0) << "instance " << id;
    EXPECT_EQ(annotation.at("area").get<int>(), cv::countNonZero(expected));
    const cv::Rect box = cv::boundingRect(expected);
    const auto& bbox = annotation.at("bbox");
    EXPECT_EQ(bbox[0].get<int>(), box.x);
    EXPECT_EQ(bbox[1].get<int>(), box.y);
    EXPECT_EQ(bbox[2].get<int>(), box.width);
    EXPECT_EQ(bbox[3].get<int>(), box.height);
    if (++checked >= 200) break;
  }
}

}  // namespace
}  // namespace segslam
