#include "core/atomic_file.h"

#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <signal.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <regex>

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

namespace {

std::string PidAndHost() { return std::to_string(static_cast<long>(::getpid())) + "@" + StagingHostName(); }

}  // namespace

StagingDirectory::StagingDirectory(std::filesystem::path target, bool overwrite, OwnOutputCheck is_own_output,
                                   std::string kind)
    : target_(std::move(target)),
      overwrite_(overwrite),
      is_own_output_(std::move(is_own_output)),
      kind_(std::move(kind)) {
  namespace fs = std::filesystem;
  if (target_.filename().empty()) target_ = target_.parent_path();
  // First, so that an output put back from a killed commit is judged as any other.
  ClearAbandonedStaging(target_);
  std::error_code error;
  if (fs::exists(target_, error)) {
    if (!overwrite && fs::is_directory(target_, error)) {
      throw FileError(target_, "already exists (use --force to replace it)");
    }
    CheckReplaceable();
  }
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  fs::create_directories(parent, error);
  if (error) throw FileError(parent, "cannot create output directory: " + error.message());
  staging_ = parent / ("." + target_.filename().string() + ".partial-" + PidAndHost());
  fs::remove_all(staging_, error);
  if (!fs::create_directory(staging_, error) || error) {
    throw FileError(target_, "cannot write here: " + (error ? error.message() : std::string("unknown reason")));
  }
}

void StagingDirectory::CheckReplaceable() const {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::exists(target_, error)) return;
  if (!fs::is_directory(target_, error)) {
    throw FileError(target_, "is a file, not a folder (a " + kind_ + " is a folder); give another path");
  }
  if (fs::is_empty(target_, error) && !error) return;
  const std::string foreign =
      is_own_output_ ? is_own_output_(target_) : std::string("nothing tells it from a folder of other files");
  if (!foreign.empty()) {
    throw FileError(target_, "holds what segslam did not write (" + foreign + "); only a " + kind_ +
                                 " that segslam wrote is replaced: choose another folder, or remove this one "
                                 "yourself");
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
  // What is there now is checked again: the constructor's check is long past.
  CheckReplaceable();
  std::error_code error;
  fs::path old;
  if (fs::exists(target_)) {
    const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
    old = parent / ("." + target_.filename().string() + ".old-" + PidAndHost());
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

std::optional<StagingLeftover> ParseStagingLeftover(const std::filesystem::path& path) {
  // The target's name is greedy: a name that itself ends in ".partial-N" still parses.
  static const std::regex kLeftover(R"(\.(.+)\.(partial|old)-([0-9]{1,10})(@([A-Za-z0-9._-]+))?)");
  const std::string name = path.filename().string();
  std::smatch match;
  if (!std::regex_match(name, match, kLeftover)) return std::nullopt;
  StagingLeftover leftover;
  leftover.path = path;
  leftover.target_name = match[1].str();
  leftover.replaced_output = match[2].str() == "old";
  leftover.pid = std::stoll(match[3].str());
  leftover.host = match[5].str();
  return leftover;
}

bool NoProcessHasPid(long long pid) {
  // Signal 0 only asks whether the process exists; a number no pid can be names none.
  if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return true;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

bool IsAbandoned(const StagingLeftover& leftover) {
  if (!leftover.host.empty() && leftover.host != StagingHostName()) return false;
  return NoProcessHasPid(leftover.pid);
}

std::string StagingHostName() {
  char buffer[256] = {};
  if (::gethostname(buffer, sizeof(buffer) - 1) != 0 || buffer[0] == '\0') return "unknown-host";
  std::string host(buffer);
  for (char& c : host) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  }
  return host;
}

std::vector<std::filesystem::path> ClearAbandonedStaging(const std::filesystem::path& target) {
  namespace fs = std::filesystem;
  std::vector<fs::path> cleared;
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code error;
  std::vector<StagingLeftover> abandoned;
  for (fs::directory_iterator it(parent, error), end; !error && it != end; it.increment(error)) {
    const std::optional<StagingLeftover> leftover = ParseStagingLeftover(it->path());
    if (leftover && leftover->target_name == target.filename().string() && IsAbandoned(*leftover)) {
      abandoned.push_back(*leftover);
    }
  }
  for (const StagingLeftover& leftover : abandoned) {
    std::error_code step_error;
    if (leftover.replaced_output && !fs::exists(target, step_error)) {
      fs::rename(leftover.path, target, step_error);
    } else {
      fs::remove_all(leftover.path, step_error);
    }
    if (!step_error) cleared.push_back(leftover.path);
  }
  return cleared;
}

}  // namespace segslam
