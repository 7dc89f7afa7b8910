#include "core/atomic_file.h"

#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <opencv2/imgcodecs.hpp>

#include "core/error.h"

namespace segslam {

void WriteBytesAtomically(const std::filesystem::path& path, const void* data, size_t size) {
  // Same directory as the target, so the rename stays on one file system and is atomic;
  // the pid keeps two processes writing the same file from sharing a temporary.
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(static_cast<long>(::getpid()));
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (file == nullptr) {
    throw FileError(path, std::string("cannot create file: ") + std::strerror(errno));
  }
  const size_t written = std::fwrite(data, 1, size, file);
  int saved_errno = errno;
  const bool write_ok = written == size;
  const bool close_ok = std::fclose(file) == 0;
  if (!close_ok && write_ok) saved_errno = errno;
  if (!write_ok || !close_ok) {
    std::remove(tmp.c_str());
    throw FileError(path, std::string("cannot write file: ") + std::strerror(saved_errno));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    saved_errno = errno;
    std::remove(tmp.c_str());
    throw FileError(path, std::string("cannot rename temporary file into place: ") +
                              std::strerror(saved_errno));
  }
}

void WriteFileAtomically(const std::filesystem::path& path, const std::string& bytes) {
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

void WriteImageAtomically(const std::filesystem::path& path, const cv::Mat& image,
                          const std::vector<int>& params) {
  if (image.empty()) throw FileError(path, "refusing to write an empty image");
  std::vector<unsigned char> buffer;
  bool ok = false;
  try {
    ok = cv::imencode(path.extension().string(), image, buffer, params);
  } catch (const cv::Exception& e) {
    throw FileError(path, std::string("cannot encode image: ") + e.what());
  }
  if (!ok) throw FileError(path, "cannot encode image");
  WriteBytesAtomically(path, buffer.data(), buffer.size());
}

StagingDirectory::StagingDirectory(std::filesystem::path target, bool overwrite)
    : target_(std::move(target)), overwrite_(overwrite) {
  namespace fs = std::filesystem;
  if (target_.filename().empty()) target_ = target_.parent_path();
  if (fs::exists(target_) && !overwrite) {
    throw FileError(target_, "already exists (use --force to replace it)");
  }
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) throw FileError(parent, "cannot create output directory: " + error.message());
  staging_ = parent / ("." + target_.filename().string() + ".partial-" + std::to_string(::getpid()));
  fs::remove_all(staging_, error);
  if (!fs::create_directory(staging_, error) || error) {
    throw FileError(target_, "cannot write here: " + (error ? error.message() : std::string("unknown reason")));
  }
}

StagingDirectory::~StagingDirectory() {
  if (!committed_) {
    std::error_code ignored;
    std::filesystem::remove_all(staging_, ignored);
  }
}

void StagingDirectory::Commit() {
  namespace fs = std::filesystem;
  if (!overwrite_) {
    // The constructor's check is long past: another run may have made the target since.
    // RENAME_NOREPLACE refuses atomically instead of replacing that run's output.
    int result = ::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, target_.c_str(), RENAME_NOREPLACE);
    if (result != 0 && (errno == EINVAL || errno == ENOSYS || errno == EPERM)) {
      // A file system without RENAME_NOREPLACE (e.g. NFS), or a kernel or sandbox without
      // renameat2 (ENOSYS, or EPERM from some seccomp filters): check, then rename; that
      // leaves a short window for a race, not one as long as the whole run.
      std::error_code ignored;
      if (fs::exists(target_, ignored)) {
        errno = EEXIST;
      } else {
        result = std::rename(staging_.c_str(), target_.c_str());
      }
    }
    if (result != 0) {
      const int saved_errno = errno;
      if (saved_errno == EEXIST) {
        throw FileError(target_, "already exists (made while this output was being written, perhaps by another "
                                 "run); left as it is (use --force to replace it)");
      }
      throw FileError(target_, std::string("cannot move the finished output here: ") + std::strerror(saved_errno));
    }
    committed_ = true;
    return;
  }
  std::error_code error;
  fs::path old;
  if (fs::exists(target_)) {
    old = target_.parent_path() / ("." + target_.filename().string() + ".old-" + std::to_string(::getpid()));
    fs::rename(target_, old, error);
    if (error) throw FileError(target_, "cannot replace: " + error.message());
  }
  fs::rename(staging_, target_, error);
  if (error) {
    // Put the previous output back rather than leave it under a hidden name.
    std::error_code ignored;
    if (!old.empty()) fs::rename(old, target_, ignored);
    throw FileError(target_, "cannot move the finished output here: " + error.message());
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, error);
}

}  // namespace segslam
