// A lock file that names its owner, for work that several processes may want done once:
// the datasets of a cache that sweep shards share, on one machine or on the nodes of a
// cluster over a shared file system. The first process takes the lock and does the work;
// the others wait for it and reuse the result.
//
// The lock is made whole under a private name and hard-linked into place, so it is never
// seen half-written, and link() is atomic on NFS as on a local disk. It records the
// owner's host, PID and process start time. A lock whose owner is gone is broken: at once
// when the owner ran on this host (no process has its PID, or another process does), and
// when it ran on another host, once its modification time has not moved for
// `stale_after` (the owner touches it every `heartbeat`; the waiter measures the pause
// on its own clock, so the hosts' clocks need not agree).
//
// The lock saves duplicate work; it is not what keeps outputs whole. Outputs are still
// written under a staging name and renamed into place (core/atomic_file.h), so even the
// rare race it cannot exclude (a lock taken between a breaker's look and its rename)
// costs at most a second generation, never a mixed output.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace segslam {

// Who holds a lock, as its file says.
struct LockOwner {
  std::string host;                // StagingHostName() of the owner
  long long pid = 0;
  unsigned long long started = 0;  // the process's start time, in clock ticks since boot (0: unknown)
  std::string purpose;             // what the owner is making, e.g. a dataset's cache key
  std::string token;               // unique per lock taken

  // "pid 1234 on node7".
  std::string Describe() const;
};

struct OwnerLockOptions {
  std::chrono::milliseconds heartbeat{10'000};     // the owner touches its lock this often
  std::chrono::milliseconds stale_after{120'000};  // a lock of another host whose time stood still this long is broken
  std::chrono::milliseconds poll{500};             // how often a waiter looks again
};

// A held lock: the heartbeat runs until destruction, which removes the file if it is
// still this lock's.
class OwnerLock {
 public:
  OwnerLock(std::filesystem::path path, LockOwner owner, std::chrono::milliseconds heartbeat);
  OwnerLock(const OwnerLock&) = delete;
  OwnerLock& operator=(const OwnerLock&) = delete;
  ~OwnerLock();

  const std::filesystem::path& path() const { return path_; }
  const LockOwner& owner() const { return owner_; }

 private:
  void Beat();

  std::filesystem::path path_;
  LockOwner owner_;
  std::chrono::milliseconds heartbeat_;
  std::mutex mutex_;
  std::condition_variable stop_signal_;
  bool stopping_ = false;
  std::thread heartbeat_thread_;
};

// What a waiter is told while it waits (for messages and progress).
struct LockWaitEvents {
  // A live owner holds the lock: called once per owner waited for. May throw to give up
  // (e.g. when the owner's purpose is not the caller's).
  std::function<void(const LockOwner& holder)> waiting;
  // A dead owner's lock was broken.
  std::function<void(const LockOwner& dead, const std::string& why)> broken;
};

// Takes the lock file `path` for `purpose`, waiting while a live owner holds it. Before
// each try, `done()` is asked whether the work is there already (another process made
// it): then returns nullptr without the lock. A caller that gets the lock asks `done()`
// once more before working, as the previous owner may have finished just before.
// Throws segslam::Error naming `path` when the lock cannot be made (no such folder, no
// permission), and when `cancel` is set while waiting.
std::unique_ptr<OwnerLock> AcquireOwnerLock(const std::filesystem::path& path, const std::string& purpose,
                                            const std::function<bool()>& done, const OwnerLockOptions& options = {},
                                            const LockWaitEvents& events = {},
                                            const std::atomic<bool>* cancel = nullptr);

// The owner recorded in the lock file at `path`; nullopt when there is none or it cannot
// be parsed.
std::optional<LockOwner> ReadLockOwner(const std::filesystem::path& path);

// Why the owner recorded in a lock is known to be gone on this host, or "" when it may be
// alive (it runs here, or on another host, which only the heartbeat can tell).
std::string WhyOwnerIsGone(const LockOwner& owner);

}  // namespace segslam
