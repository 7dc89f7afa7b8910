#include "core/owner_lock.h"

#include <fcntl.h>  // AT_FDCWD
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace segslam {
namespace {

namespace fs = std::filesystem;

// The start time of process `pid` (field 22 of /proc/PID/stat, clock ticks since boot);
// nullopt when there is no such process or no /proc.
std::optional<unsigned long long> ProcessStartTime(long long pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!stat || !std::getline(stat, line)) return std::nullopt;
  // The command name (field 2) is in parentheses and may hold spaces: count after it.
  const std::size_t name_end = line.rfind(')');
  if (name_end == std::string::npos) return std::nullopt;
  std::istringstream fields(line.substr(name_end + 1));
  std::string field;
  for (int index = 3; index <= 22; ++index) {
    if (!(fields >> field)) return std::nullopt;
    if (index == 22) {
      try {
        return std::stoull(field);
      } catch (const std::exception&) {
        return std::nullopt;
      }
    }
  }
  return std::nullopt;
}

std::string Serialize(const LockOwner& owner) {
  const nlohmann::json json = {{"host", owner.host},
                               {"pid", owner.pid},
                               {"started", owner.started},
                               {"purpose", owner.purpose},
                               {"token", owner.token}};
  return json.dump() + "\n";
}

std::optional<std::string> ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::optional<LockOwner> ParseOwner(const std::string& text) {
  try {
    const nlohmann::json json = nlohmann::json::parse(text);
    LockOwner owner;
    owner.host = json.at("host").get<std::string>();
    owner.pid = json.at("pid").get<long long>();
    owner.started = json.value("started", 0ULL);
    owner.purpose = json.value("purpose", std::string());
    owner.token = json.at("token").get<std::string>();
    return owner;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// Unique among the locks any process takes: host, PID and a count within the process.
std::string NewToken() {
  static std::atomic<unsigned long long> counter{0};
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  return StagingHostName() + "-" + std::to_string(::getpid()) + "-" +
         std::to_string(std::chrono::duration_cast<std::chrono::nanoseconds>(now).count()) + "-" +
         std::to_string(counter.fetch_add(1));
}

// A sibling of `path` that only this process uses.
fs::path PrivateSibling(const fs::path& path, const std::string& kind) {
  static std::atomic<unsigned long long> counter{0};
  return path.parent_path() / ("." + path.filename().string() + "." + kind + "-" + std::to_string(::getpid()) + "@" +
                               StagingHostName() + "-" + std::to_string(counter.fetch_add(1)));
}

enum class TakeResult { kTaken, kHeld };

// Makes the lock file whole under a private name, then links it into place: link() fails
// with EEXIST when a lock is there, atomically, also over NFS.
TakeResult TryTake(const fs::path& path, const LockOwner& owner) {
  const fs::path draft = PrivateSibling(path, "new");
  try {
    WriteFileAtomically(draft, Serialize(owner));
  } catch (const Error& e) {
    throw FileError(path, std::string("cannot make the lock file: ") + e.what());
  }
  const int linked = ::link(draft.c_str(), path.c_str());
  const int link_errno = errno;
  std::error_code ignored;
  fs::remove(draft, ignored);
  if (linked == 0) return TakeResult::kTaken;
  if (link_errno == EEXIST) return TakeResult::kHeld;
  throw FileError(path, std::string("cannot make the lock file: ") + std::strerror(link_errno));
}

// The lock file as one waiter last saw it, to tell a stopped heartbeat from a live one.
struct Observation {
  std::string content;
  fs::file_time_type modified{};
  std::chrono::steady_clock::time_point since{};
  bool valid = false;
};

}  // namespace

std::string LockOwner::Describe() const {
  if (pid == 0) return "an owner its lock file does not name";
  return "pid " + std::to_string(pid) + " on " + (host.empty() ? std::string("an unknown host") : host);
}

std::optional<LockOwner> ReadLockOwner(const fs::path& path) {
  const std::optional<std::string> text = ReadText(path);
  if (!text) return std::nullopt;
  return ParseOwner(*text);
}

std::string WhyOwnerIsGone(const LockOwner& owner) {
  if (owner.host != StagingHostName()) return "";
  if (NoProcessHasPid(owner.pid)) return "no process has its pid on this host";
  // The PID may have been given to another process since: the start time tells.
  const std::optional<unsigned long long> started = ProcessStartTime(owner.pid);
  if (owner.started != 0 && started && *started != owner.started) {
    return "its pid now belongs to another process";
  }
  return "";
}

OwnerLock::OwnerLock(fs::path path, LockOwner owner, std::chrono::milliseconds heartbeat)
    : path_(std::move(path)), owner_(std::move(owner)), heartbeat_(heartbeat) {
  heartbeat_thread_ = std::thread([this] { Beat(); });
}

OwnerLock::~OwnerLock() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  stop_signal_.notify_all();
  heartbeat_thread_.join();
  // Only this lock's own file: one broken as stale and taken by another stays.
  const std::optional<LockOwner> holder = ReadLockOwner(path_);
  if (holder && holder->token == owner_.token) {
    std::error_code ignored;
    fs::remove(path_, ignored);
  }
}

void OwnerLock::Beat() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_signal_.wait_for(lock, heartbeat_, [this] { return stopping_; })) {
    // Touching sets the time to now; a waiter on another host only watches it change.
    ::utimensat(AT_FDCWD, path_.c_str(), nullptr, 0);
  }
}

std::unique_ptr<OwnerLock> AcquireOwnerLock(const fs::path& path, const std::string& purpose,
                                            const std::function<bool()>& done, const OwnerLockOptions& options,
                                            const LockWaitEvents& events, const std::atomic<bool>* cancel) {
  LockOwner me;
  me.host = StagingHostName();
  me.pid = ::getpid();
  me.started = ProcessStartTime(me.pid).value_or(0);
  me.purpose = purpose;
  me.token = NewToken();

  Observation seen;
  bool announced = false;
  std::string announced_token;
  while (true) {
    if (done && done()) return nullptr;
    if (TryTake(path, me) == TakeResult::kTaken) return std::make_unique<OwnerLock>(path, me, options.heartbeat);

    // Held: by whom, and is it alive?
    const std::optional<std::string> content = ReadText(path);
    std::error_code time_error;
    const fs::file_time_type modified = fs::last_write_time(path, time_error);
    if (time_error) continue;  // released between the two looks: try again at once
    // An unreadable lock names no owner: only its heartbeat can tell.
    const auto now = std::chrono::steady_clock::now();
    const std::string text = content.value_or("");
    if (!seen.valid || seen.content != text || seen.modified != modified) seen = {text, modified, now, true};
    const std::optional<LockOwner> holder = ParseOwner(text);
    std::string why_gone = holder ? WhyOwnerIsGone(*holder) : std::string();
    if (why_gone.empty() && now - seen.since >= options.stale_after) {
      why_gone = "its heartbeat stopped " +
                 std::to_string(std::chrono::duration_cast<std::chrono::seconds>(now - seen.since).count()) +
                 " s ago";
    }
    if (!why_gone.empty()) {
      // Moved aside first, so that only one breaker acts, then checked: the lock moved is
      // the one judged dead, not one taken meanwhile.
      const fs::path aside = PrivateSibling(path, "broken");
      if (::rename(path.c_str(), aside.c_str()) == 0) {
        const std::optional<std::string> moved = ReadText(aside);
        if (moved.value_or("") == text) {
          if (events.broken) events.broken(holder.value_or(LockOwner{}), why_gone);
        } else {
          // A live owner's lock: put it back unless yet another has been taken.
          ::link(aside.c_str(), path.c_str());
        }
        std::error_code ignored;
        fs::remove(aside, ignored);
      }
      seen.valid = false;
      continue;
    }
    if (!announced || (holder ? holder->token : std::string()) != announced_token) {
      announced = true;
      announced_token = holder ? holder->token : std::string();
      if (events.waiting) events.waiting(holder.value_or(LockOwner{}));
    }
    if (cancel && cancel->load()) {
      throw FileError(path, "interrupted while waiting for " +
                                (holder ? holder->Describe() : std::string("its owner")) + " to finish");
    }
    std::this_thread::sleep_for(options.poll);
  }
}

}  // namespace segslam
