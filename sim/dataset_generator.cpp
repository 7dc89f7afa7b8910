#include "sim/dataset_generator.h"

#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/lens_distortion.h"
#include "core/manifest.h"
#include "core/output_folders.h"
#include "core/pose.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"
#include "sim/sensor_model.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <deque>
#include <future>
#include <map>
#include <optional>
#include <set>
#include <thread>

namespace segslam::sim {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// What one frame's mask says about each instance in it.
struct InstanceInFrame {
  std::uint16_t id = 0;
  int area_px = 0;
  int x_min = 0, y_min = 0, x_max = -1, y_max = -1;
  std::vector<int> rle_counts;  // COCO uncompressed RLE, column-major, starts with a 0-run
};

// One column-major sweep over the mask yields every instance's area, box and RLE.
std::vector<InstanceInFrame> AnalyseMask(const cv::Mat& ids) {
  const int rows = ids.rows, cols = ids.cols;
  std::map<std::uint16_t, InstanceInFrame> by_id;
  std::map<std::uint16_t, int> run_end;  // end (exclusive, column-major index) of the last 1-run
  std::uint16_t previous = 0;
  int run_start = 0;
  auto close_run = [&](std::uint16_t id, int start, int end) {
    if (id == 0) return;
    auto& instance = by_id[id];
    instance.id = id;
    int& last_end = run_end[id];  // 0 when new
    instance.rle_counts.push_back(start - last_end);
    instance.rle_counts.push_back(end - start);
    last_end = end;
  };
  for (int x = 0; x < cols; ++x) {
    for (int y = 0; y < rows; ++y) {
      const std::uint16_t id = ids.at<std::uint16_t>(y, x);
      const int position = x * rows + y;
      if (id != previous) {
        close_run(previous, run_start, position);
        previous = id;
        run_start = position;
      }
      if (id != 0) {
        auto& instance = by_id[id];
        if (instance.area_px == 0) {
          instance.x_min = instance.x_max = x;
          instance.y_min = instance.y_max = y;
        }
        ++instance.area_px;
        instance.x_min = std::min(instance.x_min, x);
        instance.x_max = std::max(instance.x_max, x);
        instance.y_min = std::min(instance.y_min, y);
        instance.y_max = std::max(instance.y_max, y);
      }
    }
  }
  close_run(previous, run_start, rows * cols);
  std::vector<InstanceInFrame> result;
  for (auto& [id, instance] : by_id) {
    instance.rle_counts.push_back(rows * cols - run_end[id]);
    result.push_back(std::move(instance));
  }
  return result;
}

struct FrameRecord {
  double stamp_s = 0.0;
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  std::vector<InstanceInFrame> instances;
};

InstanceTable InstancesOfPass(const scenes::World& world, scenes::Pass pass) {
  InstanceTable table;
  for (const auto& object : world.objects) {
    if (!object.placement[scenes::PassIndex(pass)].present) continue;
    table.Add({object.instance_id, object.coco_category_id, object.category_name, object.moveable});
  }
  return table;
}

// `first_frame_sha256`: of the first frame's colour file, so that an import onto another
// sequence with the same stamps is refused (seg::CocoDetections::Read).
nlohmann::json CocoAnnotations(const scenes::World& world, const InstanceTable& instances,
                               const std::vector<FrameRecord>& frames, const std::string& first_frame_sha256) {
  nlohmann::json images = nlohmann::json::array();
  nlohmann::json annotations = nlohmann::json::array();
  std::set<int> used_categories;
  for (const auto& info : instances.instances()) used_categories.insert(info.category_id);
  int annotation_id = 1;
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string name = TumSequenceWriter::StampName(frames[i].stamp_s);
    const int image_id = static_cast<int>(i) + 1;
    images.push_back({{"id", image_id},
                      {"file_name", "rgb/" + name + ".png"},
                      {"depth_file_name", "depth/" + name + ".png"},
                      {"mask_file_name", "masks/" + name + ".png"},
                      {"width", world.camera.width},
                      {"height", world.camera.height},
                      {"timestamp", frames[i].stamp_s}});
    for (const auto& instance : frames[i].instances) {
      const InstanceInfo* info = instances.Find(instance.id);
      const int box_width = instance.x_max - instance.x_min + 1;
      const int box_height = instance.y_max - instance.y_min + 1;
      annotations.push_back(
          {{"id", annotation_id++},
           {"image_id", image_id},
           {"category_id", info->category_id},
           {"segmentation",
            {{"size", {world.camera.height, world.camera.width}}, {"counts", instance.rle_counts}}},
           {"area", instance.area_px},
           {"bbox", {instance.x_min, instance.y_min, box_width, box_height}},
           {"iscrowd", 0},
           {"instance_id", instance.id}});
    }
  }
  nlohmann::json categories = nlohmann::json::array();
  for (int id : used_categories) {
    const CocoCategory* category = FindCocoCategory(id);
    categories.push_back({{"id", id},
                          {"name", std::string(category->name)},
                          {"supercategory", std::string(category->supercategory)}});
  }
  nlohmann::json info = {{"description", "segslam synthetic sequence " + world.name}, {"version", "1.0"}};
  if (!frames.empty()) {
    info["first_frame"] = "rgb/" + TumSequenceWriter::StampName(frames.front().stamp_s) + ".png";
    info["first_frame_sha256"] = first_frame_sha256;
  }
  return {{"info", info},
          {"images", images},
          {"annotations", annotations},
          {"categories", categories}};
}

std::vector<ObjectTrack> ObjectTracks(const scenes::World& world, scenes::Pass pass,
                                      const std::vector<FrameRecord>& frames) {
  const double frame_period_s = 1.0 / world.camera.fps;
  std::vector<ObjectTrack> tracks;
  for (const auto& object : world.objects) {
    const bool present = object.placement[scenes::PassIndex(pass)].present;
    ObjectTrack track;
    track.instance_id = object.instance_id;
    for (size_t i = 0; i < frames.size(); ++i) {
      TrackSample sample;
      sample.frame = static_cast<int>(i);
      sample.stamp_s = frames[i].stamp_s;
      sample.present = present;
      if (present) {
        sample.T_world_object = scenes::ObjectPoseAt(object, pass, sample.stamp_s);
        // Moved since the previous frame: what a tracker comparing this frame with the
        // ones before it can see (the first frame: over one frame period before it).
        sample.moving = scenes::ObjectMovesAt(object, pass, sample.stamp_s - frame_period_s, frame_period_s);
      }
      for (const auto& instance : frames[i].instances) {
        if (instance.id == object.instance_id) sample.visible_pixels = instance.area_px;
      }
      track.samples.push_back(sample);
    }
    tracks.push_back(std::move(track));
  }
  return tracks;
}

// Keeps at most `limit` frame jobs in flight; Wait() rethrows a worker's exception.
class FrameJobQueue {
 public:
  explicit FrameJobQueue(int limit) : limit_(std::max(1, limit)) {}
  void Push(std::function<void()> job) {
    while (static_cast<int>(in_flight_.size()) >= limit_) PopOldest();
    in_flight_.push_back(std::async(std::launch::async, std::move(job)));
  }
  void WaitAll() {
    while (!in_flight_.empty()) PopOldest();
  }

 private:
  void PopOldest() {
    auto oldest = std::move(in_flight_.front());
    in_flight_.pop_front();
    oldest.get();
  }
  int limit_;
  std::deque<std::future<void>> in_flight_;
};

int FramesOfPass(const scenes::World& world, scenes::Pass pass, int max_frames_per_pass) {
  const int frames = world.frames_per_pass[scenes::PassIndex(pass)];
  return max_frames_per_pass > 0 ? std::min(frames, max_frames_per_pass) : frames;
}

double KindDefaultMaxDepth(const scenes::World& world) {
  // Beyond these ranges a real RGB-D sensor (Kinect indoors, a stereo/ToF unit on a car
  // outdoors) returns nothing; the scenario's sensor.max_depth_m overrides.
  return world.kind == "office" ? 8.0 : 60.0;
}

// Files of one pass beside its frames: the instance table, COCO annotations, object
// tracks, the scenario and the manifest.
void WritePassMetadata(const fs::path& pass_dir, const scenes::World& world, const scenes::Scenario& scenario,
                       scenes::Pass pass, const InstanceTable& instances, const std::vector<FrameRecord>& records) {
  instances.Write(pass_dir / "instances.json");
  const std::string first_frame_sha256 =
      records.empty() ? std::string()
                      : Sha256OfFile(pass_dir / "rgb" / (TumSequenceWriter::StampName(records.front().stamp_s) + ".png"));
  WriteFileAtomically(pass_dir / "annotations_coco.json",
                      CocoAnnotations(world, instances, records, first_frame_sha256).dump() + "\n");
  WriteTracks(pass_dir / "tracks.json", ObjectTracks(world, pass, records));
  WriteFileAtomically(pass_dir / "scenario.yaml", scenario.text);
  WriteManifest(pass_dir, {{"scenario", scenario.name},
                           {"seed", scenario.seed},
                           {"pass", scenes::PassName(pass)},
                           {"frames", static_cast<int>(records.size())}});
}

// One generation: the world, its renderer and sensor, shared by both passes.
class DatasetGeneration {
 public:
  DatasetGeneration(const scenes::Scenario& scenario, const fs::path& out_dir, const GenerateOptions& options,
                    const ProgressCallback& progress)
      : scenario_(scenario),
        options_(options),
        progress_(progress),
        world_(scenes::BuildWorld(scenario)),
        target_(out_dir),
        staging_(options.write_files ? std::optional<StagingDirectory>(std::in_place, out_dir, options.overwrite,
                                                                           ForeignContentOfDataset, "dataset")
                                     : std::nullopt),
        renderer_(world_, options.backend, options.render),
        sensor_(scenario.sensor, renderer_.intrinsics(), KindDefaultMaxDepth(world_), world_.camera.fps),
        sequence_camera_{renderer_.intrinsics(), world_.camera.depth_factor, world_.camera.distortion},
        threads_(options.encode_threads > 0 ? options.encode_threads
                                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))) {
    summary_.gl_renderer = renderer_.gl_renderer();
    summary_.movers_left_out = world_.movers_left_out;
    summary_.red_lights_left_out = world_.red_lights_left_out;
    if (!world_.camera.distortion.IsZero()) lens_.emplace(renderer_.intrinsics(), world_.camera.distortion);
  }

  GenerateSummary Run() {
    for (scenes::Pass pass : scenes::kBothPasses) GeneratePass(pass);
    if (staging_) {
      WriteFileAtomically(staging_->path() / "scenario.yaml", scenario_.text);
      nlohmann::json extra = {{"scenario", scenario_.name},
                              {"seed", scenario_.seed},
                              {"kind", world_.kind},
                              {"generator", "segslam generate"},
                              {"movers_left_out", world_.movers_left_out},
                              {"red_lights_left_out", world_.red_lights_left_out}};
      if (options_.staged_extra) {
        const nlohmann::json added = options_.staged_extra(staging_->path());
        if (!added.is_object()) throw Error("generate: staged_extra must return a JSON object");
        for (const auto& [key, value] : added.items()) extra[key] = value;
        if (options_.cancel && options_.cancel->load()) throw Error("generate: cancelled");
      }
      WriteManifest(staging_->path(), extra);
      if (options_.keep_complete_dataset && fs::exists(target_ / "manifest.json")) {
        summary_.kept_existing = true;  // the staging folder goes with staging_
      } else {
        staging_->Commit();
      }
    }
    summary_.seconds = SecondsSince(start_);
    return summary_;
  }

 private:
  // Renders the pass frame by frame; noise, mask analysis and PNG encoding of each
  // frame run beside the renderer (FinishFrame).
  void GeneratePass(scenes::Pass pass) {
    const int pass_index = scenes::PassIndex(pass);
    const int frame_count = FramesOfPass(world_, pass, options_.max_frames_per_pass);
    const fs::path pass_dir = staging_ ? staging_->path() / scenes::PassName(pass) : fs::path();
    std::optional<TumSequenceWriter> writer;
    if (staging_) {
      writer.emplace(pass_dir, sequence_camera_);
      fs::create_directories(pass_dir / "masks");
    }
    const InstanceTable instances = InstancesOfPass(world_, pass);

    std::vector<FrameRecord> records(static_cast<size_t>(frame_count));
    FrameJobQueue jobs(2 * threads_);
    Eigen::Isometry3d T_wc_previous = scenes::CameraPoseAt(world_, pass, 0.0);
    for (int i = 0; i < frame_count; ++i) {
      if (options_.cancel && options_.cancel->load()) throw Error("generate: cancelled");
      const double stamp_s = scenes::FrameStamp(world_, i);
      const Eigen::Isometry3d T_wc = scenes::CameraPoseAt(world_, pass, stamp_s);
      const auto render_start = Clock::now();
      renderer_.SetScene(pass, stamp_s);
      auto frame = std::make_shared<RenderedFrame>(renderer_.RenderFrom(T_wc));
      summary_.render_seconds += SecondsSince(render_start);
      records[i].stamp_s = stamp_s;
      records[i].T_wc = T_wc;
      if (writer) writer->AddEntry(stamp_s, T_wc);
      FrameRecord* record = &records[i];
      const TumSequenceWriter* frame_writer = writer ? &*writer : nullptr;
      jobs.Push([=, &instances]() {
        FinishFrame(pass_index, i, T_wc_previous, T_wc, frame_writer, pass_dir, instances, frame.get(), record);
      });
      T_wc_previous = T_wc;
      ++summary_.frames;
      if (progress_) progress_({pass_index, i + 1, frame_count, summary_.frames / SecondsSince(start_)});
    }
    jobs.WaitAll();
    if (writer) {
      writer->Finish();
      WritePassMetadata(pass_dir, world_, scenario_, pass, instances, records);
    }
  }

  // A rendered frame bent through the lens (when the camera has one), then sensor noise on
  // it, its mask analysed and checked against the pass's instances, then its images written
  // (or, with no writer, only encoded, to measure).
  void FinishFrame(int pass_index, int i, const Eigen::Isometry3d& T_wc_previous, const Eigen::Isometry3d& T_wc,
                   const TumSequenceWriter* writer, const fs::path& pass_dir, const InstanceTable& instances,
                   RenderedFrame* frame, FrameRecord* record) const {
    const double stamp_s = record->stamp_s;
    if (lens_) {
      // Optics before the sensor: the noise lies on the stored pixels, as a real camera's.
      if (!frame->color_bgr.empty()) frame->color_bgr = lens_->DistortColour(frame->color_bgr);
      if (!frame->depth_m.empty()) frame->depth_m = lens_->DistortDepth(frame->depth_m);
      if (!frame->instance_ids.empty()) frame->instance_ids = lens_->DistortIds(frame->instance_ids);
    }
    sensor_.Apply(scenario_.seed, pass_index, i, T_wc_previous, T_wc, frame);
    record->instances = AnalyseMask(frame->instance_ids);
    const std::string name = TumSequenceWriter::StampName(stamp_s);
    CheckMaskIds(frame->instance_ids, instances, name);
    if (writer != nullptr) {
      WriteColorImage(writer->RgbPath(stamp_s), frame->color_bgr);
      WriteDepthImage(writer->DepthPath(stamp_s), frame->depth_m, sequence_camera_.depth_factor);
      WriteInstanceMask(pass_dir / "masks" / (name + ".png"), frame->instance_ids);
    } else {
      EncodeColorPng(frame->color_bgr);
      EncodeDepthPng(frame->depth_m, sequence_camera_.depth_factor);
      EncodeInstanceMaskPng(frame->instance_ids);
    }
  }

  const scenes::Scenario& scenario_;
  const GenerateOptions& options_;
  const ProgressCallback& progress_;
  const Clock::time_point start_ = Clock::now();
  const scenes::World world_;
  fs::path target_;
  std::optional<StagingDirectory> staging_;
  WorldRenderer renderer_;
  const SensorModel sensor_;
  const SequenceCamera sequence_camera_;
  std::optional<ImageUndistorter> lens_;  // Only for a camera with distortion.
  const int threads_;
  GenerateSummary summary_;
};

}  // namespace

bool GenerateOptions::IsValid(std::string* error) const {
  if (max_frames_per_pass < 0) {
    *error = "max_frames_per_pass must be >= 0";
    return false;
  }
  if (encode_threads < 0) {
    *error = "encode_threads must be >= 0";
    return false;
  }
  return true;
}

GenerateSummary GenerateDataset(const scenes::Scenario& scenario, const fs::path& out_dir,
                                const GenerateOptions& options, const ProgressCallback& progress) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("generate: " + error);
  return DatasetGeneration(scenario, out_dir, options, progress).Run();
}

RenderOnlySummary RenderOnly(const scenes::Scenario& scenario, GlBackend backend,
                             const RenderOptions& render, int max_frames_per_pass) {
  const scenes::World world = scenes::BuildWorld(scenario);
  WorldRenderer renderer(world, backend, render);
  RenderOnlySummary summary;
  summary.gl_renderer = renderer.gl_renderer();
  const auto start = Clock::now();
  for (scenes::Pass pass : scenes::kBothPasses) {
    const int frame_count = FramesOfPass(world, pass, max_frames_per_pass);
    for (int i = 0; i < frame_count; ++i) {
      renderer.Render(pass, scenes::FrameStamp(world, i));
      ++summary.frames;
    }
  }
  summary.seconds = SecondsSince(start);
  return summary;
}

}  // namespace segslam::sim
