#include "harness/run_evaluation.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include <fmt/format.h>

#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/input_file.h"
#include "core/json_file.h"
#include "core/pose.h"
#include "core/strings.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"
#include "harness/dataset_run.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
// frames.jsonl stores stamps as doubles, rgb.txt with 6 decimals: a frame of the dataset
// agrees to well under this.
constexpr double kStampToleranceS = 1e-4;

struct LoggedInstance {
  int id = 0;
  bool judged = false;
  bool moving = false;
  int features = 0;  // the frame's features inside the instance's mask
};

struct LoggedFrame {
  int index = 0;
  double stamp_s = 0;
  std::string rgb_file;  // the dataset's file of this frame (rgb.txt), set by MatchToSequence
  bool tracked = false;    // a pose in trajectory.txt: status "tracking" or "relocalized"
  bool localized = false;
  int features = 0;  // extracted in the frame
  std::vector<LoggedInstance> instances;
};

// frames.jsonl as slam_runner.cpp's WriteFrameLog writes it: one line per frame the run
// read, frames 0, 1, 2 ... in order, each once, with a status WriteFrameLog writes. A
// localized frame is one whose status is not "lost", and on a loaded map one on that map
// (slam::FrameResult::localized_on_map()).
std::vector<LoggedFrame> ReadFrameLog(const fs::path& path) {
  if (!fs::exists(path)) throw FileError(path, "eval: missing frame log; is this an output folder of segslam run?");
  std::ifstream in = OpenInputFile(path);
  std::vector<LoggedFrame> frames;
  int line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    if (line.empty()) continue;
    const std::string where = "eval: " + path.string() + ":" + std::to_string(line_number) + ": ";
    try {
      const nlohmann::json json = nlohmann::json::parse(line);
      LoggedFrame frame;
      frame.index = json.at("frame").get<int>();
      // Each frame once, in the order the run read them: a line repeated or left out
      // would count twice or not at all.
      if (frame.index != static_cast<int>(frames.size())) {
        throw Error(where + fmt::format("frame {} where frame {} was expected (a run logs frames 0, 1, 2 ... each "
                                        "once, in order)",
                                        frame.index, frames.size()));
      }
      frame.stamp_s = json.at("stamp").get<double>();
      const std::string status = json.at("status").get<std::string>();
      if (status != "tracking" && status != "relocalized" && status != "lost") {
        throw Error(where + "unknown status '" + PrintableText(status) + "' (expected tracking, relocalized or lost)");
      }
      frame.tracked = status != "lost";
      frame.localized = frame.tracked && json.value("on_long_term_map", true);
      frame.features = json.value("features", 0);
      for (const nlohmann::json& instance : json.at("instances")) {
        frame.instances.push_back({instance.at("id").get<int>(), instance.at("judged").get<bool>(),
                                   instance.at("moving").get<bool>(), instance.value("features", 0)});
      }
      frames.push_back(std::move(frame));
    } catch (const nlohmann::json::exception& e) {
      throw Error(where + e.what());
    }
  }
  if (frames.empty()) throw FileError(path, "eval: frame log is empty");
  return frames;
}

// A value of trajectory.txt's header: "# segslam run, mode mutual, sequence ..." gives
// ("mode ", ",") -> "mutual"; "# instance masks: gt" gives ("instance masks: ", "") -> "gt".
std::string HeaderValue(const fs::path& trajectory_file, const std::string& marker, const std::string& end_marker) {
  std::ifstream in = OpenInputFile(trajectory_file);
  for (std::string line; std::getline(in, line) && line.rfind('#', 0) == 0;) {
    const auto start = line.find(marker);
    if (start == std::string::npos) continue;
    const auto value_start = start + marker.size();
    const auto end = end_marker.empty() ? std::string::npos : line.find(end_marker, value_start);
    return line.substr(value_start, end == std::string::npos ? std::string::npos : end - value_start);
  }
  return "";
}

double NumberOrNaN(const nlohmann::json& json, const char* key) {
  const auto found = json.find(key);
  if (found == json.end() || !found->is_number()) return kNaN;
  return found->get<double>();
}

MaskScores MaskScoresFromJson(const nlohmann::json& json) {
  return {NumberOrNaN(json, "mAP"), NumberOrNaN(json, "AP50"), NumberOrNaN(json, "mIoU")};
}

nlohmann::json StatisticsJson(const std::optional<ErrorStatistics>& s) {
  if (!s.has_value()) return nullptr;
  return {{"count", s->count}, {"rmse", s->rmse}, {"mean", s->mean}, {"median", s->median},
          {"std", s->std},     {"min", s->min},   {"max", s->max}};
}

nlohmann::json NumberJson(double value) { return std::isnan(value) ? nlohmann::json(nullptr) : nlohmann::json(value); }

// Every frame the run logged must be the frame of the dataset's sequence at its index
// (a run reads the sequence's first N frames); each gets its rgb file (whose stem names
// its masks).
void MatchToSequence(const fs::path& frame_log, std::vector<LoggedFrame>& frames, const fs::path& sequence_dir) {
  // The frames' stamps and colour files as the run read them: associations.txt when the
  // sequence has one (then it needs no rgb.txt), else rgb.txt.
  std::vector<TumFrameEntry> sequence_frames;
  if (fs::exists(sequence_dir / "associations.txt")) {
    sequence_frames = ReadTumAssociations(sequence_dir / "associations.txt");
  } else {
    for (const auto& [stamp, file] : ReadTumFileList(sequence_dir / "rgb.txt")) {
      sequence_frames.push_back({stamp, file, stamp, ""});
    }
  }
  for (LoggedFrame& frame : frames) {
    const auto above = std::lower_bound(
        sequence_frames.begin(), sequence_frames.end(), frame.stamp_s - kStampToleranceS,
        [](const TumFrameEntry& entry, double stamp) { return entry.rgb_stamp_s < stamp; });
    if (above == sequence_frames.end() || std::abs(above->rgb_stamp_s - frame.stamp_s) > kStampToleranceS) {
      throw Error(fmt::format("eval: {}: frame {} (stamp {:.6f}) is not a frame of {}: the run is of another sequence",
                              frame_log.string(), frame.index, frame.stamp_s, sequence_dir.string()));
    }
    if (above - sequence_frames.begin() != frame.index) {
      throw Error(fmt::format("eval: {}: frame {} has the stamp {:.6f} of the sequence's frame {} in {}: the log is "
                              "out of step with the sequence",
                              frame_log.string(), frame.index, frame.stamp_s, above - sequence_frames.begin(),
                              sequence_dir.string()));
    }
    frame.rgb_file = above->rgb_file;
  }
}

// frames.jsonl against the trajectory written with it (and the count of frames the run
// read, where its header records it): every frame the log calls tracked has a pose, and
// every pose belongs to such a frame. A log cut short, lines left out, or a trajectory of
// another run fail here rather than be scored.
void CheckFrameLogAgainstTrajectory(const fs::path& frame_log, const std::vector<LoggedFrame>& frames,
                                    const fs::path& trajectory_file, const std::vector<StampedPose>& estimate) {
  const std::string frames_run = HeaderValue(trajectory_file, "frames run: ", "");
  if (!frames_run.empty() && frames_run != std::to_string(frames.size())) {
    throw Error(fmt::format("eval: {}: {} frame(s), but {} says the run read {}: the frame log is incomplete or "
                            "from another run",
                            frame_log.string(), frames.size(), trajectory_file.string(), PrintableText(frames_run)));
  }
  std::size_t pose = 0;
  for (const LoggedFrame& frame : frames) {
    const bool has_pose = pose < estimate.size() && std::abs(estimate[pose].stamp_s - frame.stamp_s) <= kStampToleranceS;
    if (pose < estimate.size() && estimate[pose].stamp_s < frame.stamp_s - kStampToleranceS) break;  // reported below
    if (frame.tracked && !has_pose) {
      throw Error(fmt::format("eval: {}: frame {} (stamp {:.6f}) is tracked, but {} has no pose for it: the two "
                              "files are not of one run",
                              frame_log.string(), frame.index, frame.stamp_s, trajectory_file.string()));
    }
    if (!frame.tracked && has_pose) {
      throw Error(fmt::format("eval: {}: frame {} (stamp {:.6f}) is lost, but {} has a pose for it: the two files "
                              "are not of one run",
                              frame_log.string(), frame.index, frame.stamp_s, trajectory_file.string()));
    }
    if (has_pose) ++pose;
  }
  if (pose < estimate.size()) {
    throw Error(fmt::format("eval: {}: the pose at stamp {:.6f} has no tracked frame in {} ({} frame(s)): the frame "
                            "log is cut short or not of this run",
                            trajectory_file.string(), estimate[pose].stamp_s, frame_log.string(), frames.size()));
  }
}

// The ground-truth instance that each instance of `run_ids` (CV_16U) covers most, by
// pixels of `gt_ids` (CV_16U, same size) inside its region; 0 = background.
std::map<int, int> DominantGroundTruthIds(const cv::Mat& run_ids, const cv::Mat& gt_ids) {
  std::map<int, std::map<int, int>> overlap;  // run id -> gt id -> pixels
  for (int y = 0; y < run_ids.rows; ++y) {
    const auto* run_row = run_ids.ptr<std::uint16_t>(y);
    const auto* gt_row = gt_ids.ptr<std::uint16_t>(y);
    for (int x = 0; x < run_ids.cols; ++x) {
      if (run_row[x] != 0) ++overlap[run_row[x]][gt_row[x]];
    }
  }
  std::map<int, int> dominant;
  for (const auto& [run_id, counts] : overlap) {
    dominant[run_id] = std::max_element(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
                         return a.second < b.second;
                       })->first;
  }
  return dominant;
}

// MovingDetectionScores (see the header for how instances relate to the ground truth).
// The band of MovingDistanceBands() that a distance in metres falls in.
const std::string& DistanceBand(double distance_m) {
  const std::vector<std::string>& bands = MovingDistanceBands();
  return distance_m < 10 ? bands[0] : distance_m < 20 ? bands[1] : distance_m < 40 ? bands[2] : bands[3];
}

// The class of MovingClasses() of a ground-truth instance: its category, or "other".
std::string MovingClass(const InstanceTable& table, int gt_id) {
  const InstanceInfo* info = table.Find(static_cast<std::uint16_t>(gt_id));
  if (info != nullptr && Contains(MovingClasses(), info->category_name)) return info->category_name;
  return "other";
}

void CountJudgement(bool judged_moving, bool truly_moving, MovingDetectionCounts* counts) {
  if (judged_moving) {
    ++(truly_moving ? counts->true_positives : counts->false_positives);
  } else {
    ++(truly_moving ? counts->false_negatives : counts->true_negatives);
  }
}

void ScoreMovingDetection(const std::vector<LoggedFrame>& frames, const fs::path& run_dir, const fs::path& sequence_dir,
                          const std::vector<StampedPose>& ground_truth, PassEvaluation* pass) {
  const fs::path tracks_file = sequence_dir / "tracks.json";
  if (!fs::exists(tracks_file)) {
    pass->moving_missing_reason = "no tracks.json in " + sequence_dir.string();
    return;
  }
  const fs::path refined_dir = run_dir / "refined_masks";
  const bool by_overlap = fs::is_directory(refined_dir);
  const bool same_ids = !by_overlap && (pass->masks == "gt" || pass->masks == "none" || pass->masks.empty());
  if (!by_overlap && !same_ids) {
    pass->moving_missing_reason = "instance ids of '" + pass->masks + "' carry no ground-truth identity and the run "
                                  "saved no masks to relate them";
    return;
  }
  struct TruthSample {
    bool moving = false;
    Eigen::Vector3d position_w = Eigen::Vector3d::Zero();
  };
  std::map<std::pair<int, int>, TruthSample> truth;  // (instance id, frame) -> sample
  for (const ObjectTrack& track : ReadTracks(tracks_file)) {
    for (const TrackSample& sample : track.samples) {
      truth[{track.instance_id, sample.frame}] = {sample.moving, sample.T_world_object.translation()};
    }
  }
  InstanceTable table;
  if (fs::exists(sequence_dir / "instances.json")) table = InstanceTable::Read(sequence_dir / "instances.json");
  std::map<double, Eigen::Vector3d> camera_at;  // ground-truth stamp -> camera position
  for (const StampedPose& pose : ground_truth) camera_at[pose.stamp_s] = pose.T_wc.translation();
  // The band of a ground-truth instance in a frame; empty without its pose or the camera's.
  const auto band_of = [&](int gt_id, const LoggedFrame& frame) -> std::string {
    const auto sample = truth.find({gt_id, frame.index});
    const auto camera = camera_at.lower_bound(frame.stamp_s - 1e-3);
    if (sample == truth.end() || camera == camera_at.end() || camera->first > frame.stamp_s + 1e-3) return "";
    return DistanceBand((sample->second.position_w - camera->second).norm());
  };
  MovingDetectionScores scores;
  for (const std::string& band : MovingDistanceBands()) scores.by_distance[band] = {};
  for (const std::string& name : MovingClasses()) scores.by_class[name] = {};
  // Adds to the whole, and to the band and class of a ground-truth instance (not background).
  const auto count = [&](int gt_id, const LoggedFrame& frame, const auto& add) {
    add(&scores);
    if (gt_id == 0) return;
    const std::string band = band_of(gt_id, frame);
    if (!band.empty()) add(&scores.by_distance[band]);
    add(&scores.by_class[MovingClass(table, gt_id)]);
  };
  // Only a run of a judging mode lists every instance it saw; the other modes list none.
  const bool lists_instances = pass->mode == "mutual" || pass->mode == "mutual-sparse" || pass->mode == "oracle";
  std::vector<double> moving_feature_shares;
  const auto add_share = [&](const LoggedFrame& frame, int moving_features) {
    if (lists_instances && frame.features > 0) {
      moving_feature_shares.push_back(std::min(1.0, double(moving_features) / frame.features));
    }
  };
  for (const LoggedFrame& frame : frames) {
    if (frame.instances.empty()) {
      add_share(frame, 0);
      continue;
    }
    std::map<int, int> gt_id_of;
    if (by_overlap) {
      const std::string stem = fs::path(frame.rgb_file).stem().string();
      const fs::path run_mask = refined_dir / (stem + ".png");
      const fs::path gt_mask = sequence_dir / "masks" / (stem + ".png");
      const cv::Mat run_ids = ReadInstanceMask(run_mask);
      const cv::Mat gt_ids = ReadInstanceMask(gt_mask);
      if (run_ids.size() != gt_ids.size()) throw FileError(run_mask, "eval: size differs from " + gt_mask.string());
      gt_id_of = DominantGroundTruthIds(run_ids, gt_ids);
    }
    std::map<int, bool> seen_moving;  // truly moving ground-truth id -> judged moving here
    int moving_features = 0;
    for (const LoggedInstance& instance : frame.instances) {
      int gt_id = instance.id;
      if (by_overlap) {
        const auto found = gt_id_of.find(instance.id);
        gt_id = found == gt_id_of.end() ? 0 : found->second;
      }
      const auto found = truth.find({gt_id, frame.index});
      const bool moving = found != truth.end() && found->second.moving;
      if (moving) {
        seen_moving[gt_id] = seen_moving[gt_id] || (instance.judged && instance.moving);
        moving_features += instance.features;
      }
      if (!instance.judged) continue;
      count(gt_id, frame, [&](MovingDetectionCounts* c) { CountJudgement(instance.moving, moving, c); });
    }
    for (const auto& [gt_id, detected] : seen_moving) {
      count(gt_id, frame, [&, detected = detected](MovingDetectionCounts* c) {
        ++c->moving_seen;
        c->moving_seen_detected += detected;
      });
    }
    add_share(frame, moving_features);
  }
  if (!moving_feature_shares.empty()) scores.moving_feature_share = ComputeErrorStatistics(moving_feature_shares);
  pass->moving = scores;
}

// ATE: Horn-aligned, or in pass 1's aligned frame (see the header).
// `fixed_alignment`: score in that frame (pass 2 in pass 1's map frame); without one,
// align (Horn), unless `in_map_frame` says there is no map frame to score in.
void ScoreAte(const std::vector<StampedPose>& ground_truth, const std::vector<StampedPose>& estimate,
              const std::optional<Eigen::Isometry3d>& fixed_alignment, bool in_map_frame, PassEvaluation* pass) {
  pass->ate_aligned = !fixed_alignment.has_value() && !in_map_frame;
  if (in_map_frame && !fixed_alignment.has_value()) {
    // Aligning pass 2 on its own would flatter it.
    pass->ate_missing_reason = "pass 1 has no ATE, so no map frame to score pass 2 in";
    return;
  }
  const std::size_t needed = pass->ate_aligned ? 3 : 1;
  if (estimate.size() < needed) {
    pass->ate_missing_reason = fmt::format("{} pose(s) estimated, ATE needs {}", estimate.size(), needed);
    return;
  }
  AteOptions ate_options;
  std::vector<StampedPose> moved = estimate;
  if (fixed_alignment.has_value()) {
    ate_options.align = false;
    for (StampedPose& pose : moved) pose.T_wc = *fixed_alignment * pose.T_wc;
  }
  try {
    const AteResult ate = ComputeAte(ground_truth, moved, ate_options);
    pass->ate_m = ate.translation_m;
    pass->T_gt_est = fixed_alignment.has_value() ? *fixed_alignment : ate.T_gt_est;
  } catch (const Error& e) {
    pass->ate_missing_reason = e.what();
  }
}

// RPE over 1 s, as evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s.
void ScoreRpe(const std::vector<StampedPose>& ground_truth, const std::vector<StampedPose>& estimate,
              PassEvaluation* pass) {
  if (estimate.size() < 2) {
    pass->rpe_missing_reason = fmt::format("{} pose(s) estimated", estimate.size());
    return;
  }
  try {
    const RpeResult rpe = ComputeRpe(ground_truth, estimate, RpeOptions{});
    pass->rpe_translation_m = rpe.translation_m;
    pass->rpe_rotation_deg = Scaled(rpe.rotation_rad, kDegreesPerRadian);
  } catch (const Error& e) {
    pass->rpe_missing_reason = e.what();
  }
}

// Raw vs refined masks, where the mutual loop scored them (seg.json of a run).
void ReadLoopSegmentationScores(const fs::path& seg_file, PassEvaluation* pass) {
  if (!fs::exists(seg_file)) return;
  const nlohmann::json seg = ReadJsonFile(seg_file);
  try {
    pass->seg_raw = MaskScoresFromJson(seg.at("raw"));
    pass->seg_refined = MaskScoresFromJson(seg.at("refined"));
    pass->segmenter = seg.value("segmenter", "");
  } catch (const nlohmann::json::exception& e) {
    throw FileError(seg_file, std::string("eval: malformed: ") + e.what());
  }
}

// Pass 1's ground truth and estimate: the map that pass 2 is scored against map-relatively.
struct MapPass {
  std::vector<StampedPose> ground_truth;
  std::vector<StampedPose> estimate;  // T_wc in the map's frame
};

// The map-relative relocalization error of pass 2 over the frames the run processed.
void ScoreMapRelative(const MapPass& map_pass, const std::vector<LoggedFrame>& frames,
                      const std::vector<StampedPose>& ground_truth, const std::vector<StampedPose>& estimate,
                      PassEvaluation* pass) {
  std::vector<double> frame_stamps_s;
  frame_stamps_s.reserve(frames.size());
  for (const LoggedFrame& frame : frames) frame_stamps_s.push_back(frame.stamp_s);
  pass->map_relative =
      ComputeMapRelativeError(map_pass.ground_truth, map_pass.estimate, frame_stamps_s, ground_truth, estimate);
}

// `map_pass`: pass 1 where this is pass 2, scored map-relatively against it; else null.
PassEvaluation EvaluatePass(const std::string& name, const fs::path& run_dir, const fs::path& sequence_dir,
                            const std::optional<Eigen::Isometry3d>& fixed_alignment, bool in_map_frame = false,
                            const MapPass* map_pass = nullptr) {
  PassEvaluation pass;
  pass.name = name;
  pass.run_dir = run_dir;
  pass.sequence_dir = sequence_dir;

  const fs::path ground_truth_file = sequence_dir / "groundtruth.txt";
  if (!fs::exists(ground_truth_file)) {
    throw Error("eval: " + ground_truth_file.string() +
                ": no ground truth (groundtruth.txt missing); eval needs a dataset with ground-truth poses");
  }
  const fs::path trajectory_file = run_dir / "trajectory.txt";
  if (!fs::exists(trajectory_file)) {
    throw Error("eval: " + trajectory_file.string() + ": no trajectory; is " + run_dir.string() +
                " an output folder of segslam run?");
  }
  // Stamps alone do not tell two generated worlds of one frame rate apart.
  CheckRunReadSequence(run_dir, sequence_dir);
  const fs::path frame_log = run_dir / "frames.jsonl";
  std::vector<LoggedFrame> frames = ReadFrameLog(frame_log);
  MatchToSequence(frame_log, frames, sequence_dir);
  pass.mode = HeaderValue(trajectory_file, ", mode ", ",");
  pass.masks = HeaderValue(trajectory_file, "instance masks: ", "");
  pass.frames = static_cast<int>(frames.size());
  pass.localized_frames =
      static_cast<int>(std::count_if(frames.begin(), frames.end(), [](const LoggedFrame& f) { return f.localized; }));

  const std::vector<StampedPose> ground_truth = ReadTumTrajectory(ground_truth_file);
  const std::vector<StampedPose> estimate = ReadTumTrajectory(trajectory_file);
  CheckFrameLogAgainstTrajectory(frame_log, frames, trajectory_file, estimate);

  ScoreAte(ground_truth, estimate, fixed_alignment, in_map_frame, &pass);
  ScoreRpe(ground_truth, estimate, &pass);
  if (map_pass != nullptr) ScoreMapRelative(*map_pass, frames, ground_truth, estimate, &pass);
  ReadLoopSegmentationScores(run_dir / "seg.json", &pass);

  // Moving-object detection over judged instances (MovingDetectionScores).
  ScoreMovingDetection(frames, run_dir, sequence_dir, ground_truth, &pass);
  return pass;
}

// The map-relative error's summary (not its frames); null where there is none (pass 1).
nlohmann::json MapRelativeJson(const std::optional<MapRelativeResult>& r) {
  if (!r.has_value()) return nullptr;
  return {{"place", "the pass-1 frame with an estimate whose ground-truth camera position is nearest"},
          {"max_place_distance_m", r->options.max_place_distance_m},
          {"within_translation_m", r->options.within_translation_m},
          {"within_rotation_deg", r->options.within_rotation_deg},
          {"frames_without_ground_truth", r->frames_without_ground_truth},
          {"frames_without_place", r->frames_without_place},
          {"frames_with_place", r->frames_with_place},
          {"frames_unestimated", r->frames_unestimated},
          {"frames_within", r->frames_within},
          {"within_share", NumberJson(r->WithinShare())},
          {"translation_m", StatisticsJson(r->translation_m)},
          {"rotation_deg", StatisticsJson(r->rotation_deg)}};
}

std::string Fixed(const std::optional<ErrorStatistics>& s, double ErrorStatistics::*field, int decimals) {
  if (!s.has_value()) return "n/a";
  return fmt::format("{:.{}f}", (*s).*field, decimals);
}

std::string Percent(double value) { return std::isnan(value) ? "n/a" : fmt::format("{:.1f}", 100 * value); }

// The map-relative relocalization error of the passes that have one (pass 2), as a
// section of its own under the ATE table; "" when none has.
std::string MapRelativeTable(const std::vector<PassEvaluation>& passes, size_t name_width) {
  const auto has = [](const PassEvaluation& p) { return p.map_relative.has_value(); };
  const auto first = std::find_if(passes.begin(), passes.end(), has);
  if (first == passes.end()) return "";
  const MapRelativeOptions& options = first->map_relative->options;
  std::string text = fmt::format(
      "\nMap-relative relocalization error: each frame's pose against pass 1's estimate at the nearest pass-1 place "
      "(pass 1's own error drops out); places within {:g} m; within: <= {:g} m and <= {:g} deg, a frame without "
      "a pose is not within\n"
      "{:<{}} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} | {:>8} {:>8} | {:>8}\n"
      "{:<{}} {:>8} {:>8} {:>8} | {:^26} | {:^17} | {:>8}\n",
      options.max_place_distance_m, options.within_translation_m, options.within_rotation_deg, "sequence", name_width,
      "placed", "no pose", "no place", "rmse", "median", "max", "rmse", "max", "within", "", name_width, "", "", "",
      "translation [m]", "rotation [deg]", "%");
  for (const PassEvaluation& p : passes) {
    if (!p.map_relative.has_value()) continue;
    const MapRelativeResult& r = *p.map_relative;
    text += fmt::format("{:<{}} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} | {:>8} {:>8} | {:>8}\n", p.name, name_width,
                        r.frames_with_place, r.frames_unestimated, r.frames_without_place + r.frames_without_ground_truth,
                        Fixed(r.translation_m, &ErrorStatistics::rmse, 4), Fixed(r.translation_m, &ErrorStatistics::median, 4),
                        Fixed(r.translation_m, &ErrorStatistics::max, 4), Fixed(r.rotation_deg, &ErrorStatistics::rmse, 3),
                        Fixed(r.rotation_deg, &ErrorStatistics::max, 3), Percent(r.WithinShare()));
  }
  return text;
}

}  // namespace

double MovingDetectionCounts::Precision() const {
  const int predicted = true_positives + false_positives;
  return predicted > 0 ? double(true_positives) / predicted : kNaN;
}

double MovingDetectionCounts::Recall() const {
  const int actual = true_positives + false_negatives;
  return actual > 0 ? double(true_positives) / actual : kNaN;
}

double MovingDetectionCounts::Coverage() const {
  return moving_seen > 0 ? double(moving_seen_detected) / moving_seen : kNaN;
}

nlohmann::json PassEvaluation::ToJson() const {
  nlohmann::json T_gt_est_json = nlohmann::json::array();
  for (int row = 0; row < 4; ++row) {
    nlohmann::json values = nlohmann::json::array();
    for (int col = 0; col < 4; ++col) values.push_back(T_gt_est.matrix()(row, col));
    T_gt_est_json.push_back(values);
  }
  nlohmann::json json = {
      {"name", name},
      {"run_dir", run_dir.string()},
      {"sequence", sequence_dir.string()},
      {"mode", mode},
      {"masks", masks},
      {"frames", frames},
      {"localized_frames", localized_frames},
      {"localized_share", LocalizedShare()},
      {"ate", {{"aligned", ate_aligned}, {"T_gt_est", T_gt_est_json}, {"translation_m", StatisticsJson(ate_m)}}},
      {"rpe",
       {{"delta", 1}, {"delta_unit", "s"}, {"translation_m", StatisticsJson(rpe_translation_m)},
        {"rotation_deg", StatisticsJson(rpe_rotation_deg)}}},
      {"map_relative", MapRelativeJson(map_relative)},
      {"segmentation", nullptr},
      {"moving_detection", nullptr},
      {"metrics", nlohmann::json::object()}};
  if (!ate_m.has_value()) json["ate"]["missing"] = ate_missing_reason;
  if (!rpe_translation_m.has_value()) json["rpe"]["missing"] = rpe_missing_reason;
  if (seg_raw.has_value() && seg_refined.has_value()) {
    json["segmentation"] = {
        {"segmenter", segmenter},
        {"raw", {{"mAP", NumberJson(seg_raw->mAP)}, {"AP50", NumberJson(seg_raw->AP50)}, {"mIoU", NumberJson(seg_raw->mIoU)}}},
        {"refined",
         {{"mAP", NumberJson(seg_refined->mAP)}, {"AP50", NumberJson(seg_refined->AP50)},
          {"mIoU", NumberJson(seg_refined->mIoU)}}}};
  }
  if (!moving.has_value()) json["moving_detection"] = {{"missing", moving_missing_reason}};
  if (moving.has_value()) {
    json["moving_detection"] = {{"judged", moving->Judged()},
                                {"true_positives", moving->true_positives},
                                {"false_positives", moving->false_positives},
                                {"false_negatives", moving->false_negatives},
                                {"true_negatives", moving->true_negatives},
                                {"precision", NumberJson(moving->Precision())},
                                {"recall", NumberJson(moving->Recall())},
                                {"moving_seen", moving->moving_seen},
                                {"moving_seen_detected", moving->moving_seen_detected},
                                {"coverage", NumberJson(moving->Coverage())},
                                {"moving_feature_share", StatisticsJson(moving->moving_feature_share)}};
    const auto counts_json = [](const MovingDetectionCounts& c) {
      return nlohmann::json{{"judged", c.Judged()},
                            {"true_positives", c.true_positives},
                            {"false_positives", c.false_positives},
                            {"false_negatives", c.false_negatives},
                            {"true_negatives", c.true_negatives},
                            {"precision", NumberJson(c.Precision())},
                            {"moving_seen", c.moving_seen},
                            {"moving_seen_detected", c.moving_seen_detected},
                            {"coverage", NumberJson(c.Coverage())}};
    };
    for (const auto& [band, counts] : moving->by_distance) json["moving_detection"]["by_distance"][band] = counts_json(counts);
    for (const auto& [name, counts] : moving->by_class) json["moving_detection"]["by_class"][name] = counts_json(counts);
  }
  for (const auto& [metric, value] : PassMetrics(*this)) json["metrics"][metric] = NumberJson(value);
  return json;
}

nlohmann::json RunEvaluation::ToJson() const {
  nlohmann::json json = {{"run_dir", run_dir.string()}, {"dataset", dataset.string()}, {"passes", nlohmann::json::array()}};
  for (const PassEvaluation& pass : passes) json["passes"].push_back(pass.ToJson());
  return json;
}

std::string RunEvaluation::Table() const {
  // Real sequences have long names ("rgbd_dataset_freiburg3_walking_xyz"); the column fits them.
  size_t name_width = 8;
  for (const PassEvaluation& p : passes) name_width = std::max(name_width, p.name.size());
  std::string text;
  text += fmt::format("{:<{}} {:>6} {:>9} | {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:<9} | {:>9} {:>9}\n", "sequence",
                      name_width, "frames", "localized", "rmse", "mean", "median", "std", "min", "max", "", "trans m",
                      "rot deg");
  text += fmt::format("{:<{}} {:>6} {:>9} | {:^63} | {:^19}\n", "", name_width, "", "%", "ATE [m]", "RPE rmse per s");
  for (const PassEvaluation& p : passes) {
    text += fmt::format("{:<{}} {:>6} {:>9} | {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:<9} | {:>9} {:>9}\n", p.name,
                        name_width, p.frames, Percent(p.LocalizedShare()), Fixed(p.ate_m, &ErrorStatistics::rmse, 4),
                        Fixed(p.ate_m, &ErrorStatistics::mean, 4), Fixed(p.ate_m, &ErrorStatistics::median, 4),
                        Fixed(p.ate_m, &ErrorStatistics::std, 4), Fixed(p.ate_m, &ErrorStatistics::min, 4),
                        Fixed(p.ate_m, &ErrorStatistics::max, 4), p.ate_m ? (p.ate_aligned ? "aligned" : "map frame") : "",
                        Fixed(p.rpe_translation_m, &ErrorStatistics::rmse, 4),
                        Fixed(p.rpe_rotation_deg, &ErrorStatistics::rmse, 3));
  }
  for (const PassEvaluation& p : passes) {
    if (!p.ate_m.has_value()) text += fmt::format("{}: no ATE: {}\n", p.name, p.ate_missing_reason);
    if (!p.rpe_translation_m.has_value()) text += fmt::format("{}: no RPE: {}\n", p.name, p.rpe_missing_reason);
  }

  text += MapRelativeTable(passes, name_width);

  const bool any_seg = std::any_of(passes.begin(), passes.end(), [](const auto& p) { return p.seg_raw.has_value(); });
  if (any_seg) {
    text += fmt::format("\nSegmentation in the loop (percent)\n{:<{}} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6}\n",
                        "sequence", name_width, "mAP", "AP50", "mIoU", "mAP", "AP50", "mIoU");
    text += fmt::format("{:<{}} | {:^20} | {:^20}\n", "", name_width, "raw", "refined");
    for (const PassEvaluation& p : passes) {
      if (!p.seg_raw.has_value()) continue;
      text += fmt::format("{:<{}} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6}\n", p.name, name_width,
                          Percent(p.seg_raw->mAP),
                          Percent(p.seg_raw->AP50), Percent(p.seg_raw->mIoU), Percent(p.seg_refined->mAP),
                          Percent(p.seg_refined->AP50), Percent(p.seg_refined->mIoU));
    }
  }

  for (const PassEvaluation& p : passes) {
    if (!p.moving.has_value()) text += fmt::format("{}: no moving-object scores: {}\n", p.name, p.moving_missing_reason);
  }
  const bool any_moving = std::any_of(passes.begin(), passes.end(), [](const auto& p) { return p.moving.has_value(); });
  if (any_moving) {
    text += fmt::format("\nMoving-object detection over judged instances vs tracks.json; coverage: the share of moving "
                        "instances seen (a feature on them, judged or not) that were judged moving; moving features: "
                        "the share of a frame's features on truly moving instances, mean and max over frames\n"
                        "{:<{}} {:>7} {:>9} {:>7} {:>5} {:>5} {:>5} {:>5} {:>8} {:>15}\n",
                        "sequence", name_width, "judged", "precision", "recall", "tp", "fp", "fn", "tn", "coverage",
                        "moving features");
    for (const PassEvaluation& p : passes) {
      if (!p.moving.has_value()) continue;
      const MovingDetectionScores& m = *p.moving;
      const std::string share = m.moving_feature_share.has_value()
                                    ? Percent(m.moving_feature_share->mean) + " / " + Percent(m.moving_feature_share->max)
                                    : "n/a";
      text += fmt::format("{:<{}} {:>7} {:>9} {:>7} {:>5} {:>5} {:>5} {:>5} {:>8} {:>15}\n", p.name, name_width,
                          m.Judged(),
                          Percent(m.Precision()), Percent(m.Recall()), m.true_positives, m.false_positives,
                          m.false_negatives, m.true_negatives, Percent(m.Coverage()), share);
    }
    text += "\nWhere it misses: coverage (of movers seen) / precision (of instances judged moving), percent\n";
    for (const PassEvaluation& p : passes) {
      if (!p.moving.has_value()) continue;
      for (const auto* groups : {&p.moving->by_distance, &p.moving->by_class}) {
        std::vector<std::string> cells;
        for (const auto& [group, c] : *groups) {
          cells.push_back(fmt::format("{} {} of {} / {}", group, Percent(c.Coverage()), c.moving_seen,
                                      Percent(c.Precision())));
        }
        text += fmt::format("{:<{}} {}\n", p.name, name_width, Join(cells, ";  "));
      }
    }
  }
  return text;
}

RunEvaluation EvaluateRun(const fs::path& run_dir, const fs::path& dataset) {
  if (!fs::is_directory(run_dir)) throw Error("eval: " + run_dir.string() + ": no such run folder");
  if (!fs::is_directory(dataset)) throw Error("eval: " + dataset.string() + ": no such dataset folder");
  RunEvaluation evaluation;
  evaluation.run_dir = run_dir;
  evaluation.dataset = dataset;
  const bool run_two_pass = fs::is_directory(run_dir / "pass1") || fs::is_directory(run_dir / "pass2");
  const bool dataset_two_pass = IsTwoPassDataset(dataset);
  if (run_two_pass != dataset_two_pass) {
    throw Error("eval: " + run_dir.string() + (run_two_pass ? " holds pass1/pass2 outputs but " : " is a single-sequence run but ") +
                dataset.string() + (dataset_two_pass ? " has two passes" : " is a single sequence") +
                ": run and dataset do not match");
  }
  if (dataset_two_pass) {
    evaluation.passes.push_back(EvaluatePass("pass1", run_dir / "pass1", dataset / "pass1", std::nullopt));
    std::optional<Eigen::Isometry3d> alignment;
    if (evaluation.passes[0].ate_m.has_value()) alignment = evaluation.passes[0].T_gt_est;
    // Pass 1's files were read and checked by its evaluation above.
    const MapPass map_pass{ReadTumTrajectory(dataset / "pass1" / "groundtruth.txt"),
                           ReadTumTrajectory(run_dir / "pass1" / "trajectory.txt")};
    evaluation.passes.push_back(
        EvaluatePass("pass2", run_dir / "pass2", dataset / "pass2", alignment, /*in_map_frame=*/true, &map_pass));
  } else {
    evaluation.passes.push_back(EvaluatePass(dataset.filename().string(), run_dir, dataset, std::nullopt));
  }
  return evaluation;
}

const std::vector<std::string>& PassMetricNames() {
  static const std::vector<std::string> names = {
      "ate_rmse_m",         "ate_mean_m",         "ate_median_m",       "ate_std_m",
      "ate_min_m",          "ate_max_m",          "rpe_trans_rmse_m",   "rpe_rot_rmse_deg",
      "localized_share",    "reloc_trans_rmse_m", "reloc_rot_rmse_deg", "reloc_within_share",
      "seg_raw_map",        "seg_raw_ap50",       "seg_raw_miou",       "seg_refined_map",
      "seg_refined_ap50",   "seg_refined_miou",   "moving_precision",   "moving_recall",
      "moving_coverage",    "moving_feature_share_mean",                "moving_feature_share_max"};
  static const std::vector<std::string> with_breakdown = [] {
    std::vector<std::string> all = names;
    for (const auto* groups : {&MovingDistanceBands(), &MovingClasses()}) {
      for (const std::string& group : *groups) {
        all.push_back("moving_precision_" + group);
        all.push_back("moving_coverage_" + group);
      }
    }
    return all;
  }();
  return with_breakdown;
}

std::map<std::string, double> PassMetrics(const PassEvaluation& pass) {
  std::map<std::string, double> metrics;
  for (const std::string& name : PassMetricNames()) metrics[name] = kNaN;
  if (pass.ate_m.has_value()) {
    metrics["ate_rmse_m"] = pass.ate_m->rmse;
    metrics["ate_mean_m"] = pass.ate_m->mean;
    metrics["ate_median_m"] = pass.ate_m->median;
    metrics["ate_std_m"] = pass.ate_m->std;
    metrics["ate_min_m"] = pass.ate_m->min;
    metrics["ate_max_m"] = pass.ate_m->max;
  }
  if (pass.rpe_translation_m.has_value()) metrics["rpe_trans_rmse_m"] = pass.rpe_translation_m->rmse;
  if (pass.rpe_rotation_deg.has_value()) metrics["rpe_rot_rmse_deg"] = pass.rpe_rotation_deg->rmse;
  metrics["localized_share"] = pass.LocalizedShare();
  if (pass.map_relative.has_value()) {
    if (pass.map_relative->translation_m.has_value()) metrics["reloc_trans_rmse_m"] = pass.map_relative->translation_m->rmse;
    if (pass.map_relative->rotation_deg.has_value()) metrics["reloc_rot_rmse_deg"] = pass.map_relative->rotation_deg->rmse;
    metrics["reloc_within_share"] = pass.map_relative->WithinShare();
  }
  if (pass.seg_raw.has_value()) {
    metrics["seg_raw_map"] = pass.seg_raw->mAP;
    metrics["seg_raw_ap50"] = pass.seg_raw->AP50;
    metrics["seg_raw_miou"] = pass.seg_raw->mIoU;
  }
  if (pass.seg_refined.has_value()) {
    metrics["seg_refined_map"] = pass.seg_refined->mAP;
    metrics["seg_refined_ap50"] = pass.seg_refined->AP50;
    metrics["seg_refined_miou"] = pass.seg_refined->mIoU;
  }
  if (pass.moving.has_value()) {
    metrics["moving_precision"] = pass.moving->Precision();
    metrics["moving_recall"] = pass.moving->Recall();
    metrics["moving_coverage"] = pass.moving->Coverage();
    for (const auto* groups : {&pass.moving->by_distance, &pass.moving->by_class}) {
      for (const auto& [group, counts] : *groups) {
        metrics["moving_precision_" + group] = counts.Precision();
        metrics["moving_coverage_" + group] = counts.Coverage();
      }
    }
    if (pass.moving->moving_feature_share.has_value()) {
      metrics["moving_feature_share_mean"] = pass.moving->moving_feature_share->mean;
      metrics["moving_feature_share_max"] = pass.moving->moving_feature_share->max;
    }
  }
  return metrics;
}

}  // namespace segslam::harness
