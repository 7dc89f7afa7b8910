#include "harness/dataset_run.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/manifest.h"
#include "core/output_folders.h"
#include "seg/refiner_options.h"
#include "slam/tracker_options.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

// `fixed_alignment`: score the ATE in that frame (pass 2 in pass 1's map frame); without
// one, align (Horn), unless `in_map_frame` says there is no map frame to score in.
PassRun RunPass(const DatasetRunOptions& args, const std::string& name, const fs::path& sequence_dir,
                const fs::path& map_in, const fs::path& map_out, const fs::path& out_dir,
                const std::optional<Eigen::Isometry3d>& fixed_alignment, bool in_map_frame = false) {
  const TumSequence sequence = TumSequence::OpenWithCameraFile(sequence_dir, args.camera_file);
  SlamRunOptions options = SlamRunOptionsFor(args);
  if (args.run.RefinesMasks()) options.refined_masks_dir = out_dir / "refined_masks";
  options.map_in = map_in;
  options.on_frame = [&](int done, int total) {
    if (args.on_frame) args.on_frame(name, done, total);
  };
  PassRun outcome;
  outcome.name = name;
  outcome.sequence = {sequence_dir, sequence.entries().front().rgb_file, sequence.FirstFrameSha256()};
  outcome.aligned = !fixed_alignment.has_value() && !in_map_frame;
  outcome.run = RunSlamOnSequence(sequence, options);

  fs::create_directories(out_dir);
  // The header says which masks gave the instance ids of frames.jsonl, and how many frames
  // the run read, so that eval can tell a complete frames.jsonl (both eval needs).
  WriteTumTrajectory(out_dir / "trajectory.txt", outcome.run.trajectory,
                     fmt::format("segslam run, mode {}, sequence {}\ninstance masks: {}\nframes run: {}\n"
                                 "camera-to-world T_wc of localized frames",
                                 args.run.ModeName(), sequence_dir.string(), args.run.masks.Describe(),
                                 outcome.run.frames.size()));
  WriteFrameLog(out_dir / "frames.jsonl", outcome.run.frames);
  if (outcome.run.segmentation.has_value()) {
    const LoopSegmentationScores& scores = *outcome.run.segmentation;
    const nlohmann::json json = {
        {"sequence", sequence_dir.string()},
        {"segmenter", scores.segmenter},
        {"seed", args.run.masks.seed},
        {"poses", "slam"},
        {"frames", outcome.run.frames.size()},
        {"refined_from_previous_frames", scores.refined_from_previous},
        {"raw", scores.raw.ToJson()},
        {"refined", scores.refined.ToJson()},
        {"refine_ms_median", scores.refine_ms_median},
        {"decisions",
         {{"new", scores.decision_counts[0]},
          {"kept", scores.decision_counts[1]},
          {"replaced", scores.decision_counts[2]},
          {"added", scores.decision_counts[3]},
          {"dropped", scores.decision_counts[4]}}}};
    WriteFileAtomically(out_dir / "seg.json", json.dump(2) + "\n");
  }
  if (!map_out.empty()) {
    slam::SaveLongTermMap(map_out, outcome.run.long_term_map);
    fs::path ply = map_out;
    ply.replace_extension(".ply");
    slam::ExportPly(ply, outcome.run.long_term_map);
  }
  if (sequence.has_groundtruth() && outcome.run.trajectory.size() >= 3 && !(in_map_frame && !fixed_alignment)) {
    AteOptions ate_options;
    std::vector<StampedPose> estimate = outcome.run.trajectory;
    if (fixed_alignment.has_value()) {
      ate_options.align = false;
      for (StampedPose& pose : estimate) pose.T_wc = *fixed_alignment * pose.T_wc;
    }
    outcome.ate = ComputeAte(sequence.groundtruth(), estimate, ate_options);
  }
  return outcome;
}

}  // namespace

bool IsTwoPassDataset(const fs::path& dataset) {
  return fs::is_directory(dataset / "pass1") && fs::is_directory(dataset / "pass2");
}

SlamRunOptions SlamRunOptionsFor(const DatasetRunOptions& options) {
  SlamRunOptions slam_options;
  slam_options.run = options.run;
  slam_options.max_frames = options.frames;
  for (const std::string& assignment : options.tracker_options) {
    slam::SetTrackerOption(&slam_options.tracker, assignment);
  }
  if (options.run.RefinesMasks()) {
    for (const std::string& assignment : options.refiner_options) {
      seg::SetRefinerOption(&slam_options.refiner, assignment);
    }
  }
  return slam_options;
}

void CheckDatasetRunOptions(const DatasetRunOptions& options) {
  slam::TrackerOptions tracker;
  for (const std::string& assignment : options.tracker_options) slam::SetTrackerOption(&tracker, assignment);
  if (!options.refiner_options.empty()) {
    if (!options.run.RefinesMasks()) {
      throw Error("run: --refiner applies to the mutual loop: mode mutual with --segmenter or --masks");
    }
    seg::RefinerOptions refiner;
    for (const std::string& assignment : options.refiner_options) seg::SetRefinerOption(&refiner, assignment);
    if (std::string problem; !refiner.IsValid(&problem)) throw Error("run: --refiner: " + problem);
  }
}

namespace {

// run.json: what the run read, per pass (SequenceIdentity), and that the folder is a run's.
void WriteRunRecord(const fs::path& dir, const fs::path& dataset, const DatasetRunOptions& options,
                    const std::vector<std::pair<std::string, PassRun>>& passes) {
  nlohmann::json records = nlohmann::json::array();
  for (const auto& [folder, pass] : passes) {
    records.push_back({{"name", pass.name},
                       {"folder", folder},
                       {"sequence", pass.sequence.sequence_dir.string()},
                       {"first_frame", pass.sequence.first_frame},
                       {"first_frame_sha256", pass.sequence.first_frame_sha256}});
  }
  // Every tunable as the run used it; the refiner's only where the loop refined masks.
  const SlamRunOptions used = SlamRunOptionsFor(options);
  nlohmann::json effective = {{"tracker", slam::TrackerOptionRegistry().ToJson(used.tracker)}};
  if (options.run.RefinesMasks()) effective["refiner"] = seg::RefinerOptionRegistry().ToJson(used.refiner);
  const nlohmann::json record = {{"format", "segslam-run-1"},
                                 {"mode", options.run.ModeName()},
                                 {"masks", options.run.masks.Describe()},
                                 {"dataset", dataset.string()},
                                 {"frames_per_sequence_limit", options.frames},
                                 {"options", effective},
                                 {"passes", records}};
  WriteFileAtomically(dir / kRunRecordFile, record.dump(2) + "\n");
}

fs::path WithPlyExtension(fs::path path) { return path.replace_extension(".ply"); }

// A map outside the run's folder (--map-out elsewhere) and its .ply: written into a hidden
// folder beside the map and moved to their places just before the run's folder is, so that
// a run that fails leaves neither; the folder goes in any case. It is named as a staging
// folder, ".<name>.partial-<pid>@<host>", so that what a killed run left there is cleared
// by the next run to the same map (core/atomic_file.h's ClearAbandonedStaging).
class PendingMap {
 public:
  explicit PendingMap(fs::path target)
      : target_(std::move(target)),
        folder_(target_.parent_path() / ("." + target_.filename().string() + ".partial-" +
                                         std::to_string(static_cast<long>(::getpid())) + "@" + StagingHostName())) {
    ClearAbandonedStaging(target_);
    std::error_code error;
    fs::remove_all(folder_, error);
    if (!fs::create_directory(folder_, error) || error) {
      throw FileError(target_, "cannot write beside it: " + (error ? error.message() : std::string("unknown reason")));
    }
  }
  PendingMap(const PendingMap&) = delete;
  PendingMap& operator=(const PendingMap&) = delete;
  ~PendingMap() {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }
  // Where the run writes the map; its .ply goes beside it.
  fs::path path() const { return folder_ / target_.filename(); }
  void MoveIntoPlace() {
    for (const auto& [from, to] : {std::make_pair(path(), target_),
                                   std::make_pair(WithPlyExtension(path()), WithPlyExtension(target_))}) {
      std::error_code error;
      fs::rename(from, to, error);
      if (error) throw FileError(to, "cannot move the finished file here: " + error.message());
    }
  }

 private:
  fs::path target_, folder_;
};

// Where the long-term map goes while the run is staged: inside the staging folder when it
// belongs to the run's folder (the default, or --map-out inside --out), else a pending
// folder beside --map-out (with its .ply).
struct StagedMap {
  fs::path path;  // empty: no map is written
  std::optional<PendingMap> pending;
};

void StageMap(const fs::path& map_out, const fs::path& out_dir, const fs::path& staging_dir, StagedMap* staged) {
  if (map_out.empty()) return;
  std::error_code error;
  if (fs::is_directory(map_out, error)) {
    throw FileError(map_out, "is a folder; --map-out takes the path of the map file to write, e.g. " +
                                 (map_out / "map.segslam").string());
  }
  const fs::path relative = fs::weakly_canonical(map_out).lexically_relative(fs::weakly_canonical(out_dir));
  if (!relative.empty() && *relative.begin() != "..") {
    staged->path = staging_dir / relative;
    fs::create_directories(staged->path.parent_path());
    return;
  }
  const fs::path parent = map_out.parent_path().empty() ? fs::path(".") : map_out.parent_path();
  fs::create_directories(parent, error);
  if (error) throw FileError(parent, "cannot create the folder of --map-out: " + error.message());
  staged->path = staged->pending.emplace(parent / map_out.filename()).path();
}

}  // namespace

std::vector<PassRun> RunDataset(const fs::path& dataset, const fs::path& out_dir, const DatasetRunOptions& options) {
  CheckDatasetRunOptions(options);
  const bool two_pass = IsTwoPassDataset(dataset);
  if (two_pass && !options.map_in.empty()) {
    throw Error("run: --map-in applies to a single sequence; " + dataset.string() + " has two passes");
  }
  // The outputs are one unit: written into a staging folder and moved into place only when
  // every pass and the map are written. An existing --out is replaced only when it is a
  // run's output; a file there, or a folder of other files, is refused before any frame.
  StagingDirectory staging(out_dir, /*overwrite=*/true, ForeignContentOfRunOutput, "run output");
  StagedMap map;
  StageMap(two_pass && options.map_out.empty() ? out_dir / "pass1" / "map.segslam" : options.map_out, out_dir,
           staging.path(), &map);
  std::vector<std::pair<std::string, PassRun>> passes;  // (folder in the run's, pass)
  if (two_pass) {
    passes.emplace_back("pass1",
                        RunPass(options, "pass1", dataset / "pass1", {}, map.path, staging.path() / "pass1", std::nullopt));
    // Pass 2 is scored in the map's frame: pass 1's alignment to the ground truth, not
    // a new one (the paper's Table III); without it, not at all.
    std::optional<Eigen::Isometry3d> alignment;
    if (passes[0].second.ate.has_value()) alignment = passes[0].second.ate->T_gt_est;
    passes.emplace_back("pass2", RunPass(options, "pass2", dataset / "pass2", map.path, {}, staging.path() / "pass2",
                                         alignment, /*in_map_frame=*/true));
  } else {
    passes.emplace_back(".", RunPass(options, dataset.filename().string(), dataset, options.map_in, map.path,
                                     staging.path(), std::nullopt));
  }
  WriteRunRecord(staging.path(), dataset, options, passes);
  if (map.pending) map.pending->MoveIntoPlace();
  staging.Commit();
  std::vector<PassRun> result;
  for (auto& [folder, pass] : passes) result.push_back(std::move(pass));
  return result;
}

namespace {

// The run.json that describes the pass folder `pass_dir` and the pass's folder in it:
// its own (".") or, for pass1/ or pass2/, that of the run it is a pass of; none for a
// run of a build before run.json.
std::optional<std::pair<fs::path, std::string>> FindRunRecord(const fs::path& pass_dir) {
  if (fs::exists(pass_dir / kRunRecordFile)) return std::make_pair(pass_dir / kRunRecordFile, std::string("."));
  const fs::path dir = pass_dir.filename().empty() ? pass_dir.parent_path() : pass_dir;
  const fs::path parent_record = (dir.has_parent_path() ? dir.parent_path() : fs::path(".")) / kRunRecordFile;
  if (fs::exists(parent_record)) return std::make_pair(parent_record, dir.filename().string());
  return std::nullopt;
}

std::string StringField(const nlohmann::json& json, const char* key) {
  return json.is_object() && json.contains(key) && json.at(key).is_string() ? json.at(key).get<std::string>()
                                                                             : std::string();
}

}  // namespace

void CheckRunReadSequence(const fs::path& pass_dir, const fs::path& sequence_dir) {
  const auto found = FindRunRecord(pass_dir);
  if (!found) return;
  const auto& [record_file, folder] = *found;
  const nlohmann::json record = ReadJsonFile(record_file);
  const nlohmann::json* pass = nullptr;
  if (record.is_object() && record.contains("passes") && record.at("passes").is_array()) {
    for (const nlohmann::json& entry : record.at("passes")) {
      if (StringField(entry, "folder") == folder) pass = &entry;
    }
  }
  const std::string first_frame = pass ? StringField(*pass, "first_frame") : "";
  const std::string first_frame_sha256 = pass ? StringField(*pass, "first_frame_sha256") : "";
  if (first_frame.empty() || first_frame_sha256.empty()) {
    throw FileError(record_file, "eval: no record of the sequence that " + pass_dir.string() +
                                     " read (expected \"passes\": [{\"folder\": \"" + folder +
                                     "\", \"first_frame\", \"first_frame_sha256\"}])");
  }
  const std::string read = StringField(*pass, "sequence").empty() ? "another sequence" : StringField(*pass, "sequence");
  const fs::path here = sequence_dir / first_frame;
  const std::string mismatch = "eval: " + pass_dir.string() + " is a run of " + read + ", not of " +
                               sequence_dir.string() + ": ";
  std::error_code error;
  if (!fs::is_regular_file(here, error)) {
    throw Error(mismatch + "the first colour frame it read, " + first_frame + " (" + record_file.string() +
                "), is not there; score a run against the dataset it read");
  }
  if (Sha256OfFile(here) != first_frame_sha256) {
    throw Error(mismatch + "the first colour frame it read, " + first_frame + ", differs from " + here.string() +
                " (SHA-256 recorded in " + record_file.string() + "); score a run against the dataset it read");
  }
}

}  // namespace segslam::harness
