// What segslam wrote: its output folders recognised by what each kind holds, so that
// --force and re-runs replace only those (the OwnOutputCheck of core/atomic_file.h's
// StagingDirectory). Each check returns "" for a folder of its kind, else what in it
// segslam did not write, e.g. "notes/t.tex is in no manifest.json".
#pragma once

#include <filesystem>
#include <string>

namespace segslam {

// The files that say what a folder is.
inline constexpr char kManifestFile[] = "manifest.json";  // a dataset or a sequence (core/manifest.h)
inline constexpr char kRunRecordFile[] = "run.json";      // an output of `segslam run` (harness/dataset_run.h)
// A folder of external masks (seg/external_masks.h: WriteMaskFolderRecord).
inline constexpr char kMaskFolderRecordFile[] = "segslam_sequence.json";

// True when `dir` holds a manifest.json that segslam wrote (format "segslam-manifest-*").
bool HoldsSegslamManifest(const std::filesystem::path& dir);

// A dataset `segslam generate` wrote: a segslam manifest.json that lists every file in it,
// apart from run outputs and mask folders (below) that segslam wrote inside it.
std::string ForeignContentOfDataset(const std::filesystem::path& dir);

// An output folder of `segslam run`: run.json (or, from builds before it, a trajectory.txt
// whose header names segslam run) and nothing but what a run writes: trajectory.txt,
// frames.jsonl, seg.json, maps (*.segslam, *.ply), refined_masks/ (*.png, *.json) and
// pass1/, pass2/ holding the same.
std::string ForeignContentOfRunOutput(const std::filesystem::path& dir);

// A folder `segslam masks import` wrote: segslam_sequence.json and *.png, *.json files.
std::string ForeignContentOfMaskFolder(const std::filesystem::path& dir);

}  // namespace segslam
