// Atomic file writes: a reader (or a crashed run) never sees a half-written file under
// the final name. The data is written to "<path>.tmp-<pid>" in the same directory and
// then renamed over `path` (rename is atomic within one file system). No fsync: this
// protects against crashes of the process, not against power loss.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace segslam {

// Writes `bytes` to `path` atomically, replacing an existing file. The directory must
// exist. On failure the temporary file is removed and segslam::Error (FileError naming
// `path` and strerror) is thrown.
void WriteFileAtomically(const std::filesystem::path& path, const std::string& bytes);

// As WriteFileAtomically, for `size` bytes at `data`.
void WriteBytesAtomically(const std::filesystem::path& path, const void* data, size_t size);

// Encodes `image` with cv::imencode using the format given by the extension of `path`
// (".png", ".jpg", ...) and `params` (cv::IMWRITE_* pairs), then writes it atomically.
// Throws segslam::Error if encoding or writing fails.
void WriteImageAtomically(const std::filesystem::path& path, const cv::Mat& image,
                          const std::vector<int>& params = {});

// Says whether a folder already at an output's place is an output of the same kind, which
// segslam wrote and may replace: "" when it is, else what in it segslam did not write
// (for the message, e.g. "notes/t.tex is in no manifest.json").
using OwnOutputCheck = std::function<std::string(const std::filesystem::path& existing)>;

// An output directory assembled under a hidden sibling name
// (".<name>.partial-<pid>@<host>") and renamed into place only when complete: a failure,
// an exception or Ctrl-C leaves nothing that looks like a finished output. The destructor
// removes an uncommitted staging directory; one left by a process killed outright is
// removed by the next StagingDirectory for the same target on the same host.
class StagingDirectory {
 public:
  // Throws segslam::Error (naming `target`) if it is not a folder; if it exists and
  // `overwrite` is false; if it exists, is not empty and `is_own_output` (of an output of
  // kind `kind`, e.g. "dataset") does not recognise it, or none is given; or if the
  // staging directory cannot be made. Never deletes anything of `target` itself.
  StagingDirectory(std::filesystem::path target, bool overwrite, OwnOutputCheck is_own_output = {},
                   std::string kind = "output");
  StagingDirectory(const StagingDirectory&) = delete;
  StagingDirectory& operator=(const StagingDirectory&) = delete;
  ~StagingDirectory();

  // Where to write the output until Commit().
  const std::filesystem::path& path() const { return staging_; }

  // Moves the finished directory to its target. With `overwrite`, an old one is replaced
  // (and put back if the move fails) once it is checked again as in the constructor.
  // Without, a target that appeared since the constructor (e.g. made by a concurrent
  // run) is left alone: throws segslam::Error naming it, and the staging directory stays
  // until destruction.
  void Commit();

 private:
  // Throws unless an existing target may be replaced (see the constructor).
  void CheckReplaceable() const;

  std::filesystem::path target_;
  bool overwrite_ = false;
  OwnOutputCheck is_own_output_;
  std::string kind_;
  std::filesystem::path staging_;
  bool committed_ = false;
};

// What a staging directory's (or a replaced output's) hidden name says about the process
// that made it: ".<target>.partial-<pid>@<host>" or ".<target>.old-<pid>@<host>"; names of
// older builds lack "@<host>".
struct StagingLeftover {
  std::filesystem::path path;
  std::string target_name;
  bool replaced_output = false;  // ".old-": the output a commit was replacing
  long long pid = 0;
  std::string host;  // empty in names without one
};

// Parses `path`'s file name; nullopt when it is no such name.
std::optional<StagingLeftover> ParseStagingLeftover(const std::filesystem::path& path);

// True when the process that made `leftover` has ended: it ran on this host (or the name
// records no host) and no process has its pid. A leftover of another host, on a shared
// file system, is never judged abandoned.
bool IsAbandoned(const StagingLeftover& leftover);

// True when no process of this host has `pid` (or no process can: pid <= 0 or beyond
// pid_t); a process of another user counts as there.
bool NoProcessHasPid(long long pid);

// This machine's host name as staging names record it (characters other than letters,
// digits, '.', '-' and '_' become '_').
std::string StagingHostName();

// Clears what killed processes left beside `target`: abandoned staging directories are
// removed; an abandoned replaced output is put back under `target` when nothing is there
// (the kill fell between the two renames of a commit), else removed. Returns the paths
// removed or put back.
std::vector<std::filesystem::path> ClearAbandonedStaging(const std::filesystem::path& target);

}  // namespace segslam
