// Atomic file writes: a reader (or a crashed run) never sees a half-written file under
// the final name. The data is written to "<path>.tmp-<pid>" in the same directory and
// then renamed over `path` (rename is atomic within one file system). No fsync: this
// protects against crashes of the process, not against power loss.
#pragma once

#include <filesystem>
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

// An output directory assembled under a hidden sibling name (".<name>.partial-<pid>") and
// renamed into place only when complete: a failure, an exception or Ctrl-C leaves
// nothing that looks like a finished output. The destructor removes an uncommitted
// staging directory.
class StagingDirectory {
 public:
  // Throws segslam::Error (naming `target`) if it exists and `overwrite` is false, or if
  // the staging directory cannot be made.
  StagingDirectory(std::filesystem::path target, bool overwrite);
  StagingDirectory(const StagingDirectory&) = delete;
  StagingDirectory& operator=(const StagingDirectory&) = delete;
  ~StagingDirectory();

  // Where to write the output until Commit().
  const std::filesystem::path& path() const { return staging_; }

  // Moves the finished directory to its target. With `overwrite`, an old one is replaced
  // (and put back if the move fails). Without, a target that appeared since the
  // constructor (e.g. made by a concurrent run) is left alone: throws segslam::Error
  // naming it, and the staging directory stays until destruction.
  void Commit();

 private:
  std::filesystem::path target_;
  bool overwrite_ = false;
  std::filesystem::path staging_;
  bool committed_ = false;
};

}  // namespace segslam
