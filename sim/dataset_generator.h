// Dataset generation: renders both passes of a scenario and writes them as TUM-layout
// sequences with instance masks, instance tables, COCO annotations, object tracks,
// camera files, a copy of the scenario and checksummed manifests.
//
// Layout of the output directory:
//   scenario.yaml, manifest.json
//   pass1/, pass2/: rgb/ depth/ masks/ rgb.txt depth.txt associations.txt
//                   groundtruth.txt camera.yaml instances.json annotations_coco.json
//                   tracks.json scenario.yaml manifest.json
// The directory is built under a temporary name beside the target and renamed into
// place only when complete, so a failure or Ctrl-C never leaves one that looks complete.
#pragma once

#include "scenes/scenario.h"
#include "sim/gl_context.h"
#include "sim/world_renderer.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <filesystem>
#include <functional>
#include <string>

namespace segslam::sim {

struct GenerateOptions {
  GlBackend backend = GlBackend::kOsmesa;  // off-screen GL back-end
  RenderOptions render;                    // renderer switches (shadows...)
  int max_frames_per_pass = 0;             // 0 = all frames the scenario defines
  int encode_threads = 0;                  // threads for noise + PNG encoding; 0 = cores
  // Replace an existing output directory: only a dataset segslam generated (its manifest
  // lists every file; core/output_folders.h), or an empty folder; any other is refused.
  bool overwrite = false;
  // With overwrite: keep a complete dataset (one with manifest.json) that appeared there
  // while this one was generated, and drop this one. Two processes filling one cache
  // entry make the same bytes; replacing would pull the first's dataset from under it.
  bool keep_complete_dataset = false;
  bool write_files = true;                 // false: render + noise + encode, write nothing
                                           // (benchmarks of the pipeline without disk)
  const std::atomic<bool>* cancel = nullptr;  // set to true to stop (Ctrl-C); checked per frame
  // Called once both passes are written, with the staging folder, before the top
  // manifest.json is written and the folder renamed into place; the keys of the object it
  // returns are added to the manifest's "extra". For figures measured on the finished
  // passes by code sim/ may not use (the harness's aliasing measure needs slam/). It
  // sees the folder as it will be, so no file is changed after its checksum is taken.
  // Not called without write_files. What it throws ends the generation as any error does.
  std::function<nlohmann::json(const std::filesystem::path& staged_dir)> staged_extra;

  bool IsValid(std::string* error) const;
};

struct GenerationProgress {
  int pass_index = 0;   // 0 or 1
  int frames_done = 0;  // in this pass
  int frames_total = 0;
  double frames_per_second = 0.0;  // over the whole run so far
};
using ProgressCallback = std::function<void(const GenerationProgress&)>;

struct GenerateSummary {
  int frames = 0;              // both passes
  double seconds = 0.0;        // wall time of the whole generation
  double render_seconds = 0.0;  // of which spent in the renderer (scene update + GL)
  std::string gl_renderer;     // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  bool kept_existing = false;  // keep_complete_dataset found one there and kept it
  int movers_left_out = 0;     // scenes::World::movers_left_out
  int red_lights_left_out = 0;  // scenes::World::red_lights_left_out
  double FramesPerSecond() const { return seconds > 0 ? frames / seconds : 0.0; }
};

// Generates the dataset of `scenario` into `out_dir`. Throws segslam::Error on bad
// input, unwritable output, an unavailable GL back-end, cancellation, or an `out_dir`
// that is a file or (with overwrite) a folder that is no dataset; in every such case
// nothing is left at `out_dir` (an existing directory there is kept unless the run
// completes with overwrite=true). Staging folders of killed generations to the same
// `out_dir` on this host are removed (core/atomic_file.h).
GenerateSummary GenerateDataset(const scenes::Scenario& scenario,
                                const std::filesystem::path& out_dir,
                                const GenerateOptions& options,
                                const ProgressCallback& progress = {});

// Renders both passes without noise or files: the renderer's own speed.
struct RenderOnlySummary {
  int frames = 0;
  double seconds = 0.0;
  std::string gl_renderer;
  double FramesPerSecond() const { return seconds > 0 ? frames / seconds : 0.0; }
};
RenderOnlySummary RenderOnly(const scenes::Scenario& scenario, GlBackend backend,
                             const RenderOptions& render, int max_frames_per_pass);

}  // namespace segslam::sim
