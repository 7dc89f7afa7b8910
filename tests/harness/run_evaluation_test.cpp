// EvaluateRun on small synthetic datasets and runs written here: pass 2 is scored with
// pass 1's alignment (not re-aligned), and moving-object detection counts judged
// instances only, against tracks.json.
#include "harness/run_evaluation.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/pose.h"
#include "core/tracks.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 31;          // 3 s at 10 Hz: RPE over 1 s has pairs
constexpr double kFrameIntervalS = 0.1;

std::vector<StampedPose> GroundTruth(double lateral_offset_m) {
  std::vector<StampedPose> poses;
  for (int i = 0; i < kFrames; ++i) {
    StampedPose pose;
    pose.stamp_s = 100 + i * kFrameIntervalS;
    pose.T_wc = Eigen::Isometry3d::Identity();
    pose.T_wc.linear() = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.T_wc.translation() = Eigen::Vector3d(0.3 * i, lateral_offset_m + 0.02 * i * i, 1.5);
    poses.push_back(pose);
  }
  return poses;
}

std::vector<StampedPose> Moved(const Eigen::Isometry3d& T, std::vector<StampedPose> poses) {
  for (StampedPose& pose : poses) pose.T_wc = T * pose.T_wc;
  return poses;
}

void WriteSequence(const fs::path& dir, const std::vector<StampedPose>& ground_truth) {
  fs::create_directories(dir);
  std::ofstream rgb(dir / "rgb.txt");
  for (const StampedPose& pose : ground_truth) rgb << std::fixed << pose.stamp_s << " rgb/x.png\n";
  WriteTumTrajectory(dir / "groundtruth.txt", ground_truth, "");
}

void WriteRun(const fs::path& dir, const std::vector<StampedPose>& estimate, const std::string& instances_of_frame_0,
              const std::string& masks = "gt") {
  fs::create_directories(dir);
  WriteTumTrajectory(dir / "trajectory.txt", estimate, "segslam run, mode mutual, sequence test\ninstance masks: " + masks);
  std::ofstream frames(dir / "frames.jsonl");
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    frames << "{\"frame\": " << i << ", \"stamp\": " << std::fixed << estimate[i].stamp_s
           << ", \"status\": \"tracking\", \"instances\": [" << (i == 0 ? instances_of_frame_0 : "") << "]}\n";
  }
}

class RunEvaluationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("segslam_run_evaluation_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(RunEvaluationTest, PassTwoIsScoredWithPassOnesAlignment) {
  Eigen::Isometry3d T_est_gt = Eigen::Isometry3d::Identity();  // the run's own frame
  T_est_gt.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_est_gt.translation() = Eigen::Vector3d(2, -1, 0.5);
  WriteSequence(dir_ / "data" / "pass1", GroundTruth(0));
  WriteSequence(dir_ / "data" / "pass2", GroundTruth(0.5));
  WriteRun(dir_ / "run" / "pass1", Moved(T_est_gt, GroundTruth(0)), "");
  // Pass 2 localized in the map, but 0.1 m off along x everywhere: a re-alignment would
  // hide that; pass 1's alignment keeps it.
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = Eigen::Vector3d(0.1, 0, 0);
  WriteRun(dir_ / "run" / "pass2", Moved(T_est_gt * shift, GroundTruth(0.5)), "");

  const RunEvaluation evaluation = EvaluateRun(dir_ / "run", dir_ / "data");
  ASSERT_EQ(evaluation.passes.size(), 2u);
  const PassEvaluation& pass1 = evaluation.passes[0];
  const PassEvaluation& pass2 = evaluation.passes[1];
  ASSERT_TRUE(pass1.ate_m.has_value());
  ASSERT_TRUE(pass2.ate_m.has_value());
  EXPECT_TRUE(pass1.ate_aligned);
  EXPECT_FALSE(pass2.ate_aligned);
  EXPECT_LT(pass1.ate_m->rmse, 1e-6);
  EXPECT_NEAR(pass2.ate_m->rmse, 0.1, 1e-6);
  EXPECT_EQ(pass1.mode, "mutual");
  EXPECT_DOUBLE_EQ(pass2.LocalizedShare(), 1.0);
  // RPE is relative: the constant shift does not change it.
  ASSERT_TRUE(pass2.rpe_translation_m.has_value());
  EXPECT_LT(pass2.rpe_translation_m->rmse, 1e-6);
  EXPECT_FALSE(pass1.seg_raw.has_value());
  EXPECT_FALSE(pass1.moving.has_value());  // no tracks.json
  const std::map<std::string, double> metrics = PassMetrics(pass2);
  EXPECT_NEAR(metrics.at("ate_rmse_m"), 0.1, 1e-6);
  EXPECT_TRUE(std::isnan(metrics.at("seg_refined_map")));
}

// A pass on a loaded map counts as localized only the frames matched to that map: a
// frame tracked on the points the run made itself ("on_long_term_map": false) is in the
// trajectory and in the ATE, but not in the localized share.
TEST_F(RunEvaluationTest, PassTwoCountsOnlyFramesOnTheLongTermMapAsLocalized) {
  WriteSequence(dir_ / "data" / "pass1", GroundTruth(0));
  WriteSequence(dir_ / "data" / "pass2", GroundTruth(0.5));
  WriteRun(dir_ / "run" / "pass1", GroundTruth(0), "");
  const std::vector<StampedPose> pass2 = GroundTruth(0.5);
  WriteRun(dir_ / "run" / "pass2", pass2, "");
  std::ofstream frames(dir_ / "run" / "pass2" / "frames.jsonl");
  int off_map = 0;
  for (std::size_t i = 0; i < pass2.size(); ++i) {
    const bool on_map = i % 4 != 0;
    off_map += !on_map;
    frames << "{\"frame\": " << i << ", \"stamp\": " << std::fixed << pass2[i].stamp_s
           << ", \"status\": \"tracking\", \"long_term_inliers\": " << (on_map ? 80 : 3)
           << ", \"on_long_term_map\": " << (on_map ? "true" : "false") << ", \"instances\": []}\n";
  }
  frames.close();
  ASSERT_GT(off_map, 0);
  const RunEvaluation evaluation = EvaluateRun(dir_ / "run", dir_ / "data");
  ASSERT_EQ(evaluation.passes.size(), 2u);
  EXPECT_DOUBLE_EQ(evaluation.passes[0].LocalizedShare(), 1.0);
  EXPECT_EQ(evaluation.passes[1].localized_frames, static_cast<int>(pass2.size()) - off_map);
  ASSERT_TRUE(evaluation.passes[1].ate_m.has_value());
  EXPECT_LT(evaluation.passes[1].ate_m->rmse, 1e-6);
}

// Pass 1 lost its map (two poses: no ATE, no alignment): pass 2 has no map frame to be
// scored in, and is not aligned on its own instead.
TEST_F(RunEvaluationTest, PassTwoHasNoAteWithoutPassOnesAlignment) {
  WriteSequence(dir_ / "data" / "pass1", GroundTruth(0));
  WriteSequence(dir_ / "data" / "pass2", GroundTruth(0.5));
  std::vector<StampedPose> two_poses = GroundTruth(0);
  two_poses.resize(2);
  WriteRun(dir_ / "run" / "pass1", two_poses, "");
  WriteRun(dir_ / "run" / "pass2", GroundTruth(0.5), "");
  const RunEvaluation evaluation = EvaluateRun(dir_ / "run", dir_ / "data");
  ASSERT_EQ(evaluation.passes.size(), 2u);
  EXPECT_FALSE(evaluation.passes[0].ate_m.has_value());
  EXPECT_FALSE(evaluation.passes[1].ate_m.has_value());
  EXPECT_NE(evaluation.passes[1].ate_missing_reason.find("no map frame"), std::string::npos)
      << evaluation.passes[1].ate_missing_reason;
  EXPECT_TRUE(std::isnan(PassMetrics(evaluation.passes[1]).at("ate_rmse_m")));
}

// Pass 1 drifts (its map bends away from the ground truth along the route) and pass 2
// relocalizes on that map perfectly: the ATE in the map's frame counts the map's error,
// the map-relative error does not. Three pass-2 frames are lost: not within.
TEST_F(RunEvaluationTest, PassTwoIsScoredMapRelativelyToPassOnesEstimate) {
  // A straight route, pass 2 0.1 m beside it: pass-2 frame i's nearest pass-1 frame is i.
  const auto route = [](double lateral_m) {
    std::vector<StampedPose> poses;
    for (int i = 0; i < kFrames; ++i) {
      Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
      T_wc.linear() = Eigen::AngleAxisd(0.01 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      T_wc.translation() = Eigen::Vector3d(0.3 * i, lateral_m, 1.5);
      poses.push_back({100 + i * kFrameIntervalS, T_wc});
    }
    return poses;
  };
  // The map's error at frame i, in the world: a yaw and a sideways shift that grow.
  const auto drift = [](int i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(0.005 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(0, 0.01 * i, 0);
    return T;
  };
  const std::vector<StampedPose> truth1 = route(0), truth2 = route(0.1);
  std::vector<StampedPose> estimate1 = truth1, estimate2;
  for (int i = 0; i < kFrames; ++i) {
    estimate1[i].T_wc = drift(i) * truth1[i].T_wc;
    if (i < 10 || i > 12) estimate2.push_back({truth2[i].stamp_s, drift(i) * truth2[i].T_wc});
  }
  WriteSequence(dir_ / "data" / "pass1", truth1);
  WriteSequence(dir_ / "data" / "pass2", truth2);
  WriteRun(dir_ / "run" / "pass1", estimate1, "");
  WriteRun(dir_ / "run" / "pass2", estimate2, "");
  std::ofstream frames(dir_ / "run" / "pass2" / "frames.jsonl");  // every frame, 10 to 12 lost
  for (int i = 0; i < kFrames; ++i) {
    frames << "{\"frame\": " << i << ", \"stamp\": " << std::fixed << truth2[i].stamp_s << ", \"status\": \""
           << (i >= 10 && i <= 12 ? "lost" : "tracking") << "\", \"instances\": []}\n";
  }
  frames.close();

  const RunEvaluation evaluation = EvaluateRun(dir_ / "run", dir_ / "data");
  ASSERT_EQ(evaluation.passes.size(), 2u);
  const PassEvaluation& pass2 = evaluation.passes[1];
  EXPECT_FALSE(evaluation.passes[0].map_relative.has_value());
  ASSERT_TRUE(pass2.map_relative.has_value());
  ASSERT_TRUE(pass2.ate_m.has_value());
  EXPECT_GT(pass2.ate_m->rmse, 0.05);  // the map's error, which Horn's alignment of pass 1 cannot remove
  const std::map<std::string, double> metrics = PassMetrics(pass2);
  EXPECT_LT(metrics.at("reloc_trans_rmse_m"), 1e-6);
  EXPECT_LT(metrics.at("reloc_rot_rmse_deg"), 1e-4);
  EXPECT_DOUBLE_EQ(metrics.at("reloc_within_share"), (kFrames - 3.0) / kFrames);
  EXPECT_TRUE(std::isnan(PassMetrics(evaluation.passes[0]).at("reloc_within_share")));

  const nlohmann::json json = evaluation.ToJson();
  EXPECT_TRUE(json["passes"][0]["map_relative"].is_null());
  EXPECT_EQ(json["passes"][1]["map_relative"]["frames_with_place"], kFrames);
  EXPECT_EQ(json["passes"][1]["map_relative"]["frames_unestimated"], 3);
  EXPECT_EQ(json["passes"][1]["map_relative"]["frames_without_place"], 0);
  EXPECT_TRUE(json["passes"][1]["metrics"].contains("reloc_trans_rmse_m"));
  const std::string table = evaluation.Table();
  EXPECT_NE(table.find("Map-relative relocalization error"), std::string::npos) << table;
  EXPECT_NE(table.find("90.3"), std::string::npos) << table;  // 28 of 31 within
  // The section's header lines and its row line up.
  std::istringstream lines(table.substr(table.find("Map-relative relocalization error")));
  std::vector<std::string> section;
  for (std::string line; std::getline(lines, line) && section.size() < 4;) section.push_back(line);
  ASSERT_EQ(section.size(), 4u);
  EXPECT_EQ(section[3].rfind("pass2 ", 0), 0u) << table;
  for (int i : {2, 3}) {
    EXPECT_EQ(section[i].find('|'), section[1].find('|')) << table;
    EXPECT_EQ(section[i].rfind('|'), section[1].rfind('|')) << table;
  }
}

// A real sequence's folder name is longer than "pass1"; the columns still line up.
TEST(RunEvaluationTableTest, ColumnsLineUpUnderALongSequenceName) {
  RunEvaluation evaluation;
  PassEvaluation pass;
  pass.name = "rgbd_dataset_freiburg3_walking_xyz";
  pass.frames = 859;
  pass.localized_frames = 859;
  pass.ate_m = ErrorStatistics{};
  pass.rpe_translation_m = ErrorStatistics{};
  pass.rpe_rotation_deg = ErrorStatistics{};
  evaluation.passes.push_back(pass);
  pass.name = "short";
  evaluation.passes.push_back(pass);

  std::istringstream table(evaluation.Table());
  std::vector<std::string> lines;
  for (std::string line; std::getline(table, line) && lines.size() < 4;) lines.push_back(line);
  ASSERT_EQ(lines.size(), 4u);  // two header lines, two passes
  EXPECT_EQ(lines[2].rfind("rgbd_dataset_freiburg3_walking_xyz ", 0), 0u) << lines[2];
  const size_t first_bar = lines[0].find('|');
  ASSERT_NE(first_bar, std::string::npos);
  EXPECT_GT(first_bar, pass.name.size() + std::string(" frames localized ").size());
  for (const std::string& line : lines) {
    EXPECT_EQ(line.find('|'), first_bar) << line;
    EXPECT_EQ(line.rfind('|'), lines[0].rfind('|')) << line;
  }
  // The frame count ends where its header does.
  EXPECT_EQ(lines[2].find(" 859 ") + 4, lines[0].find("frames") + 6);
}

TEST_F(RunEvaluationTest, MovingDetectionCountsJudgedInstancesAgainstTracks) {
  const fs::path sequence = dir_ / "sequence";
  WriteSequence(sequence, GroundTruth(0));
  // Instances 3 and 5 move at frame 0, 4 stands still, 6 moves; 7 has no track.
  std::vector<ObjectTrack> tracks;
  for (const auto& [id, moving] : std::vector<std::pair<int, bool>>{{3, true}, {4, false}, {5, true}, {6, true}}) {
    ObjectTrack track;
    track.instance_id = static_cast<std::uint16_t>(id);
    TrackSample sample;
    sample.frame = 0;
    sample.stamp_s = 100;
    sample.moving = moving;
    track.samples.push_back(sample);
    tracks.push_back(track);
  }
  WriteTracks(sequence / "tracks.json", tracks);
  const std::string judgements =
      "{\"id\": 3, \"judged\": true, \"moving\": true},"    // true positive
      "{\"id\": 4, \"judged\": true, \"moving\": true},"    // false positive
      "{\"id\": 5, \"judged\": true, \"moving\": false},"   // false negative
      "{\"id\": 6, \"judged\": false, \"moving\": false},"  // not judged: not counted
      "{\"id\": 7, \"judged\": true, \"moving\": false}";   // no track: truly static, true negative
  WriteRun(dir_ / "run", GroundTruth(0), judgements);

  const RunEvaluation evaluation = EvaluateRun(dir_ / "run", sequence);
  ASSERT_EQ(evaluation.passes.size(), 1u);
  ASSERT_TRUE(evaluation.passes[0].moving.has_value());
  const MovingDetectionScores& scores = *evaluation.passes[0].moving;
  EXPECT_EQ(scores.true_positives, 1);
  EXPECT_EQ(scores.false_positives, 1);
  EXPECT_EQ(scores.false_negatives, 1);
  EXPECT_EQ(scores.true_negatives, 1);
  EXPECT_EQ(scores.Judged(), 4);
  EXPECT_DOUBLE_EQ(scores.Precision(), 0.5);
  EXPECT_DOUBLE_EQ(scores.Recall(), 0.5);
  EXPECT_TRUE(std::isnan(MovingDetectionScores{}.Precision()));
  // Coverage counts the unjudged mover 6 too: of movers 3, 5 and 6, only 3 was found.
  EXPECT_EQ(scores.moving_seen, 3);
  EXPECT_EQ(scores.moving_seen_detected, 1);
  EXPECT_DOUBLE_EQ(scores.Coverage(), 1.0 / 3.0);
  EXPECT_TRUE(std::isnan(MovingDetectionScores{}.Coverage()));
}

// Where the judgement misses: the same counts by distance from the camera (the object's
// tracks.json position against the frame's ground-truth camera) and by class.
TEST_F(RunEvaluationTest, MovingDetectionBreaksDownByDistanceAndClass) {
  const fs::path sequence = dir_ / "sequence";
  WriteSequence(sequence, GroundTruth(0));  // frame 0's camera at (0, 0, 1.5)
  InstanceTable table;
  std::vector<ObjectTrack> tracks;
  // id, category, distance ahead of frame 0's camera, truly moving.
  for (const auto& [id, category, distance_m, moving] :
       std::vector<std::tuple<int, int, double, bool>>{{3, 1, 5, true}, {4, 3, 15, false}, {5, 8, 30, true}, {6, 6, 50, true}}) {
    table.Add({static_cast<std::uint16_t>(id), category, "", false});
    ObjectTrack track;
    track.instance_id = static_cast<std::uint16_t>(id);
    TrackSample sample;
    sample.stamp_s = 100;
    sample.moving = moving;
    sample.T_world_object.translation() = Eigen::Vector3d(distance_m, 0, 1.5);
    track.samples.push_back(sample);
    tracks.push_back(track);
  }
  WriteTracks(sequence / "tracks.json", tracks);
  std::ofstream(sequence / "instances.json") << table.ToJson().dump();
  const std::string judgements =
      "{\"id\": 3, \"judged\": true, \"moving\": true},"    // person at 5 m: true positive
      "{\"id\": 4, \"judged\": true, \"moving\": true},"    // car at 15 m: false positive
      "{\"id\": 5, \"judged\": true, \"moving\": false},"   // truck at 30 m: false negative
      "{\"id\": 6, \"judged\": false, \"moving\": false},"  // bus at 50 m: seen, missed
      "{\"id\": 7, \"judged\": true, \"moving\": false}";   // no track: other, no distance
  WriteRun(dir_ / "run", GroundTruth(0), judgements);

  const RunEvaluation evaluation = EvaluateRun(dir_ / "run", sequence);
  ASSERT_TRUE(evaluation.passes[0].moving.has_value());
  const MovingDetectionScores& scores = *evaluation.passes[0].moving;
  const auto& near = scores.by_distance.at("0_10m");
  EXPECT_EQ(near.true_positives, 1);
  EXPECT_DOUBLE_EQ(near.Coverage(), 1.0);
  EXPECT_EQ(scores.by_distance.at("10_20m").false_positives, 1);
  EXPECT_DOUBLE_EQ(scores.by_distance.at("10_20m").Precision(), 0.0);
  EXPECT_EQ(scores.by_distance.at("20_40m").false_negatives, 1);
  EXPECT_DOUBLE_EQ(scores.by_distance.at("20_40m").Coverage(), 0.0);
  EXPECT_EQ(scores.by_distance.at("40m_plus").Judged(), 0);
  EXPECT_EQ(scores.by_distance.at("40m_plus").moving_seen, 1);
  EXPECT_EQ(scores.by_class.at("person").true_positives, 1);
  EXPECT_EQ(scores.by_class.at("car").false_positives, 1);
  EXPECT_EQ(scores.by_class.at("truck").false_negatives, 1);
  EXPECT_EQ(scores.by_class.at("bus").moving_seen, 1);
  EXPECT_EQ(scores.by_class.at("other").true_negatives, 1);
  int banded = 0;
  for (const auto& [band, counts] : scores.by_distance) banded += counts.Judged();
  EXPECT_EQ(banded, 3) << "the instance without a track has no distance";
  const std::map<std::string, double> metrics = PassMetrics(evaluation.passes[0]);
  EXPECT_DOUBLE_EQ(metrics.at("moving_coverage_0_10m"), 1.0);
  EXPECT_DOUBLE_EQ(metrics.at("moving_precision_car"), 0.0);
  EXPECT_TRUE(std::isnan(metrics.at("moving_coverage_car")));
  const nlohmann::json json = evaluation.passes[0].ToJson();
  EXPECT_EQ(json["moving_detection"]["by_class"]["truck"]["false_negatives"], 1);
}

// The share of a frame's features on truly moving instances, per frame: instances count
// whether judged or not, static ones and those without a track do not, a frame without
// instances counts as 0 and one without features is left out.
TEST_F(RunEvaluationTest, MovingFeatureShareCountsFeaturesOnTrulyMovingInstances) {
  const fs::path sequence = dir_ / "sequence";
  WriteSequence(sequence, GroundTruth(0));
  std::vector<ObjectTrack> tracks;
  for (const auto& [id, moving_in_frame_3] : std::vector<std::pair<int, bool>>{{3, true}, {4, false}, {5, false}}) {
    ObjectTrack track;
    track.instance_id = static_cast<std::uint16_t>(id);
    for (int frame : {0, 3}) {
      TrackSample sample;
      sample.frame = frame;
      sample.stamp_s = 100 + frame * kFrameIntervalS;
      sample.moving = frame == 0 ? id != 4 : moving_in_frame_3;  // 5 stops after frame 0
      track.samples.push_back(sample);
    }
    tracks.push_back(track);
  }
  WriteTracks(sequence / "tracks.json", tracks);
  const std::vector<StampedPose> ground_truth = GroundTruth(0);
  const std::vector<StampedPose> estimate(ground_truth.begin(), ground_truth.begin() + 4);
  auto write_run = [&](const std::string& mode) {
    fs::create_directories(dir_ / mode);
    WriteTumTrajectory(dir_ / mode / "trajectory.txt", estimate,
                       "segslam run, mode " + mode + ", sequence test\ninstance masks: gt");
    std::ofstream frames(dir_ / mode / "frames.jsonl");
    const std::string instances[4] = {
        // 3 and 5 move (30 + 20 of 200 features), 4 stands still, 7 has no track.
        "{\"id\": 3, \"judged\": true, \"moving\": true, \"features\": 30},"
        "{\"id\": 4, \"judged\": true, \"moving\": false, \"features\": 50},"
        "{\"id\": 5, \"judged\": false, \"moving\": false, \"features\": 20},"
        "{\"id\": 7, \"judged\": false, \"moving\": false, \"features\": 40}",
        "",  // no instance in view: 0
        "",  // no features at all (a blank wall): left out
        // 3 moves (60 of 100), 5 stands still now.
        "{\"id\": 3, \"judged\": false, \"moving\": false, \"features\": 60},"
        "{\"id\": 5, \"judged\": true, \"moving\": false, \"features\": 30}"};
    const int features[4] = {200, 100, 0, 100};
    for (int i = 0; i < 4; ++i) {
      frames << "{\"frame\": " << i << ", \"stamp\": " << std::fixed << estimate[i].stamp_s
             << ", \"status\": \"tracking\", \"features\": " << features[i] << ", \"instances\": ["
             << (mode == "mutual" ? instances[i] : "") << "]}\n";
    }
  };
  write_run("mutual");
  write_run("mask-moveable");

  const RunEvaluation mutual = EvaluateRun(dir_ / "mutual", sequence);
  ASSERT_TRUE(mutual.passes[0].moving.has_value());
  const std::optional<ErrorStatistics>& share = mutual.passes[0].moving->moving_feature_share;
  ASSERT_TRUE(share.has_value());
  EXPECT_EQ(share->count, 3u);
  EXPECT_DOUBLE_EQ(share->max, 0.6);
  EXPECT_DOUBLE_EQ(share->median, 0.25);
  EXPECT_NEAR(share->mean, (0.25 + 0.0 + 0.6) / 3, 1e-12);
  EXPECT_NEAR(PassMetrics(mutual.passes[0]).at("moving_feature_share_mean"), (0.25 + 0.6) / 3, 1e-12);

  // Other modes list no instances: the share is unknown there, not 0.
  const RunEvaluation mask_moveable = EvaluateRun(dir_ / "mask-moveable", sequence);
  ASSERT_TRUE(mask_moveable.passes[0].moving.has_value());
  EXPECT_FALSE(mask_moveable.passes[0].moving->moving_feature_share.has_value());
  EXPECT_TRUE(std::isnan(PassMetrics(mask_moveable.passes[0]).at("moving_feature_share_max")));
}

// A segmenter's ids carry no ground-truth identity: each judged instance stands for the
// ground-truth instance its refined mask covers most.
TEST_F(RunEvaluationTest, SegmenterInstancesAreRelatedToGroundTruthByTheirMasks) {
  const fs::path sequence = dir_ / "sequence";
  WriteSequence(sequence, GroundTruth(0));
  std::vector<ObjectTrack> tracks;
  for (const auto& [id, moving] : std::vector<std::pair<int, bool>>{{3, true}, {4, false}}) {
    ObjectTrack track;
    track.instance_id = static_cast<std::uint16_t>(id);
    TrackSample sample;
    sample.stamp_s = 100;
    sample.moving = moving;
    track.samples.push_back(sample);
    tracks.push_back(track);
  }
  WriteTracks(sequence / "tracks.json", tracks);
  // Ground truth: instance 3 on the left half, 4 on the right half (40 x 20 pixels).
  cv::Mat gt_ids(20, 40, CV_16U, cv::Scalar(0));
  gt_ids(cv::Rect(0, 0, 20, 20)).setTo(3);
  gt_ids(cv::Rect(20, 0, 20, 20)).setTo(4);
  fs::create_directories(sequence / "masks");
  WriteInstanceMask(sequence / "masks" / "x.png", gt_ids);
  // The refined mask: segmenter id 1 mostly over 3, id 2 mostly over 4, id 5 on nothing.
  cv::Mat run_ids(20, 40, CV_16U, cv::Scalar(0));
  run_ids(cv::Rect(2, 0, 22, 10)).setTo(1);
  run_ids(cv::Rect(18, 10, 20, 10)).setTo(2);
  run_ids(cv::Rect(0, 12, 4, 4)).setTo(6);
  const std::string judgements =
      "{\"id\": 1, \"judged\": true, \"moving\": true},"    // over moving 3: true positive
      "{\"id\": 2, \"judged\": true, \"moving\": true},"    // over static 4: false positive
      "{\"id\": 5, \"judged\": true, \"moving\": false},"   // no pixels: background, true negative
      "{\"id\": 6, \"judged\": false, \"moving\": false}";  // a second piece over 3, not judged
  WriteRun(dir_ / "run", GroundTruth(0), judgements, "simulated fcis-like seed 1");
  fs::create_directories(dir_ / "run" / "refined_masks");
  WriteInstanceMask(dir_ / "run" / "refined_masks" / "x.png", run_ids);

  RunEvaluation evaluation = EvaluateRun(dir_ / "run", sequence);
  ASSERT_TRUE(evaluation.passes[0].moving.has_value()) << evaluation.passes[0].moving_missing_reason;
  const MovingDetectionScores& scores = *evaluation.passes[0].moving;
  EXPECT_EQ(scores.true_positives, 1);
  EXPECT_EQ(scores.false_positives, 1);
  EXPECT_EQ(scores.false_negatives, 0);
  EXPECT_EQ(scores.true_negatives, 1);
  // Ground-truth instance 3 is seen through two pieces, and counted once: found.
  EXPECT_EQ(scores.moving_seen, 1);
  EXPECT_EQ(scores.moving_seen_detected, 1);

  // Without the masks the ids mean nothing: not scored, and the reason says so.
  fs::remove_all(dir_ / "run" / "refined_masks");
  evaluation = EvaluateRun(dir_ / "run", sequence);
  EXPECT_FALSE(evaluation.passes[0].moving.has_value());
  EXPECT_NE(evaluation.passes[0].moving_missing_reason.find("no ground-truth identity"), std::string::npos);
}

// frames.jsonl is checked against the trajectory and the sequence before it is counted: a
// log cut short reported "5 frames, 100 % localized", a repeated line counted twice, an
// unknown status counted as localized.
class FrameLogTest : public RunEvaluationTest {
 protected:
  void SetUp() override {
    RunEvaluationTest::SetUp();
    WriteSequence(dir_ / "sequence", GroundTruth(0));
    WriteRun(dir_ / "run", GroundTruth(0), "");
    std::ifstream in(dir_ / "run" / "frames.jsonl");
    for (std::string line; std::getline(in, line);) lines_.push_back(line);
  }
  // The error of EvaluateRun with frames.jsonl made of `lines`, or "" if none.
  std::string EvaluationErrorWith(const std::vector<std::string>& lines) {
    std::ofstream out(dir_ / "run" / "frames.jsonl");
    for (const std::string& line : lines) out << line << "\n";
    out.close();
    try {
      EvaluateRun(dir_ / "run", dir_ / "sequence");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  std::vector<std::string> lines_;
};

TEST_F(FrameLogTest, CompleteLogIsScored) { EXPECT_EQ(EvaluationErrorWith(lines_), ""); }

TEST_F(FrameLogTest, LogCutShortIsRefused) {
  const std::string error = EvaluationErrorWith({lines_.begin(), lines_.begin() + 5});
  EXPECT_NE(error.find((dir_ / "run" / "trajectory.txt").string() + ": the pose at stamp 100.500000 has no tracked "
                       "frame in " + (dir_ / "run" / "frames.jsonl").string() + " (5 frame(s))"),
            std::string::npos)
      << error;
}

TEST_F(FrameLogTest, RepeatedOrMissingLineIsRefused) {
  std::vector<std::string> repeated = lines_;
  repeated.insert(repeated.begin() + 3, lines_[2]);
  const std::string where = (dir_ / "run" / "frames.jsonl").string() + ":4: ";
  EXPECT_NE(EvaluationErrorWith(repeated).find(where + "frame 2 where frame 3 was expected"), std::string::npos)
      << EvaluationErrorWith(repeated);
  std::vector<std::string> missing = lines_;
  missing.erase(missing.begin() + 3);
  EXPECT_NE(EvaluationErrorWith(missing).find(where + "frame 4 where frame 3 was expected"), std::string::npos)
      << EvaluationErrorWith(missing);
}

TEST_F(FrameLogTest, UnknownStatusIsRefused) {
  std::vector<std::string> lines = lines_;
  lines[6].replace(lines[6].find("\"tracking\""), 10, "\"flying\"");
  const std::string error = EvaluationErrorWith(lines);
  EXPECT_NE(error.find((dir_ / "run" / "frames.jsonl").string() +
                       ":7: unknown status 'flying' (expected tracking, relocalized or lost)"),
            std::string::npos)
      << error;
}

// A lost frame must have no pose, a tracked one must have one: else the log and the
// trajectory are not of one run.
TEST_F(FrameLogTest, StatusDisagreeingWithTheTrajectoryIsRefused) {
  std::vector<std::string> lines = lines_;
  lines[6].replace(lines[6].find("\"tracking\""), 10, "\"lost\"");
  EXPECT_NE(EvaluationErrorWith(lines).find("frame 6 (stamp 100.600000) is lost, but"), std::string::npos)
      << EvaluationErrorWith(lines);
}

// With its frames' stamps shifted by one, the log is out of step with the sequence.
TEST_F(FrameLogTest, FrameOfAnotherIndexIsRefused) {
  std::vector<std::string> lines(lines_.begin(), lines_.begin() + 3);
  const std::string stamp_of_frame_1 = "100.100000";
  lines[0].replace(lines[0].find("100.000000"), 10, stamp_of_frame_1);
  EXPECT_NE(EvaluationErrorWith(lines).find("frame 0 has the stamp 100.100000 of the sequence's frame 1"),
            std::string::npos)
      << EvaluationErrorWith(lines);
}

// `segslam run` records the frames it read in the trajectory's header: a log whose last
// lines (lost frames, without poses) are gone disagrees with it.
TEST_F(FrameLogTest, CountDisagreeingWithTheTrajectoryHeaderIsRefused) {
  std::vector<StampedPose> first_ten = GroundTruth(0);
  first_ten.resize(10);
  WriteTumTrajectory(dir_ / "run" / "trajectory.txt", first_ten,
                     "segslam run, mode mutual, sequence test\ninstance masks: gt\nframes run: 12");
  std::vector<std::string> lines(lines_.begin(), lines_.begin() + 12);
  for (int i = 10; i < 12; ++i) lines[i].replace(lines[i].find("\"tracking\""), 10, "\"lost\"");
  EXPECT_EQ(EvaluationErrorWith(lines), "");
  lines.resize(10);
  EXPECT_NE(EvaluationErrorWith(lines).find((dir_ / "run" / "frames.jsonl").string() +
                                            ": 10 frame(s), but " + (dir_ / "run" / "trajectory.txt").string() +
                                            " says the run read 12"),
            std::string::npos)
      << EvaluationErrorWith(lines);
}

TEST_F(RunEvaluationTest, RunWithoutFrameLogNamesTheFile) {
  WriteSequence(dir_ / "sequence", GroundTruth(0));
  fs::create_directories(dir_ / "run");
  WriteTumTrajectory(dir_ / "run" / "trajectory.txt", GroundTruth(0), "");
  try {
    EvaluateRun(dir_ / "run", dir_ / "sequence");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "run" / "frames.jsonl").string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace segslam::harness
