#include "core/owner_lock.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "test_util.h"

namespace segslam {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using OwnerLockTest = testing::TempDirTest;

std::string ReadAll(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream s;
  s << file.rdbuf();
  return s.str();
}

OwnerLockOptions Quick() {
  OwnerLockOptions options;
  options.heartbeat = 20ms;
  options.stale_after = 1500ms;
  options.poll = 10ms;
  return options;
}

TEST_F(OwnerLockTest, NamesItsOwnerAndIsGoneWhenReleased) {
  const fs::path lock_file = dir() / "data.lock";
  {
    const std::unique_ptr<OwnerLock> lock = AcquireOwnerLock(lock_file, "key-1", [] { return false; });
    ASSERT_NE(lock, nullptr);
    const std::optional<LockOwner> owner = ReadLockOwner(lock_file);
    ASSERT_TRUE(owner.has_value());
    EXPECT_EQ(owner->pid, ::getpid());
    EXPECT_EQ(owner->host, StagingHostName());
    EXPECT_EQ(owner->purpose, "key-1");
    EXPECT_GT(owner->started, 0u);
    EXPECT_EQ(WhyOwnerIsGone(*owner), "");
  }
  EXPECT_FALSE(fs::exists(lock_file));
  // No draft or broken lock is left beside it.
  EXPECT_TRUE(fs::is_empty(dir()));
}

TEST_F(OwnerLockTest, HeartbeatMovesTheLocksTime) {
  const fs::path lock_file = dir() / "data.lock";
  const std::unique_ptr<OwnerLock> lock = AcquireOwnerLock(lock_file, "k", {}, Quick());
  const fs::file_time_type first = fs::last_write_time(lock_file);
  std::this_thread::sleep_for(300ms);
  EXPECT_GT(fs::last_write_time(lock_file), first);
}

// Processes that all want the same output: one makes it, the others wait and reuse it.
TEST_F(OwnerLockTest, ConcurrentProcessesMakeTheOutputOnce) {
  const fs::path lock_file = dir() / "data.lock";
  const fs::path output = dir() / "output.txt";
  const fs::path makers = dir() / "makers.txt";
  std::vector<pid_t> children;
  for (int child = 0; child < 4; ++child) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      int code = 0;
      try {
        const auto done = [&] { return fs::exists(output); };
        const std::unique_ptr<OwnerLock> lock = AcquireOwnerLock(lock_file, "k", done, Quick());
        if (lock && !done()) {
          std::ofstream(makers, std::ios::app) << ::getpid() << "\n";
          std::this_thread::sleep_for(400ms);  // long enough for every other process to wait
          WriteFileAtomically(output, "made once\n");
        }
        if (ReadAll(output) != "made once\n") code = 2;
      } catch (...) {
        code = 3;
      }
      ::_exit(code);
    }
    children.push_back(pid);
  }
  for (const pid_t pid : children) {
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "child " << pid;
  }
  std::istringstream lines(ReadAll(makers));
  int count = 0;
  for (std::string line; std::getline(lines, line);) ++count;
  EXPECT_EQ(count, 1);
  EXPECT_FALSE(fs::exists(lock_file));
}

// A process killed while holding the lock leaves it behind; on the same host the next
// process sees that no process has its PID and breaks it at once.
TEST_F(OwnerLockTest, LockOfAKilledOwnerOnThisHostIsBroken) {
  const fs::path lock_file = dir() / "data.lock";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::unique_ptr<OwnerLock> lock = AcquireOwnerLock(lock_file, "k", {});
    ::kill(::getpid(), SIGKILL);
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_TRUE(fs::exists(lock_file));
  ASSERT_EQ(ReadLockOwner(lock_file)->pid, pid);

  std::string why;
  LockWaitEvents events;
  events.broken = [&](const LockOwner& dead, const std::string& reason) {
    EXPECT_EQ(dead.pid, pid);
    why = reason;
  };
  events.waiting = [](const LockOwner& holder) { ADD_FAILURE() << "waited for dead " << holder.Describe(); };
  const std::unique_ptr<OwnerLock> lock = AcquireOwnerLock(lock_file, "k", {}, Quick(), events);
  ASSERT_NE(lock, nullptr);
  EXPECT_EQ(why, "no process has its pid on this host");
  EXPECT_EQ(ReadLockOwner(lock_file)->pid, ::getpid());
}

TEST_F(OwnerLockTest, ReusedPidIsToldApartByItsStartTime) {
  LockOwner owner;
  owner.host = StagingHostName();
  owner.pid = ::getpid();  // alive, but started at another time than the lock says
  owner.started = 1;
  EXPECT_EQ(WhyOwnerIsGone(owner), "its pid now belongs to another process");
  owner.started = 0;  // unknown: the PID alone decides
  EXPECT_EQ(WhyOwnerIsGone(owner), "");
  owner.host = "another-node";  // only the heartbeat can tell
  owner.started = 1;
  EXPECT_EQ(WhyOwnerIsGone(owner), "");
}

// Another host's owner cannot be asked: its lock is broken only when the heartbeat stops.
TEST_F(OwnerLockTest, LockOfAnotherHostIsBrokenOnlyWhenItsHeartbeatStops) {
  const fs::path lock_file = dir() / "data.lock";
  WriteFileAtomically(lock_file, R"({"host":"node-far-away","pid":1,"started":5,"purpose":"k","token":"t"})");
  std::atomic<bool> beating{true};
  std::thread owner([&] {
    while (beating) {
      fs::last_write_time(lock_file, fs::file_time_type::clock::now());
      std::this_thread::sleep_for(20ms);
    }
  });
  std::atomic<bool> acquired{false};
  std::string waited_for;
  std::string why;
  std::thread waiter([&] {
    LockWaitEvents events;
    events.waiting = [&](const LockOwner& holder) { waited_for = holder.Describe(); };
    events.broken = [&](const LockOwner&, const std::string& reason) { why = reason; };
    const std::unique_ptr<OwnerLock> lock = AcquireOwnerLock(lock_file, "k", {}, Quick(), events);
    acquired = lock != nullptr;
  });
  std::this_thread::sleep_for(2500ms);  // longer than stale_after, but the owner beats
  EXPECT_FALSE(acquired.load());
  beating = false;
  owner.join();
  waiter.join();
  EXPECT_TRUE(acquired.load());
  EXPECT_EQ(waited_for, "pid 1 on node-far-away");
  EXPECT_NE(why.find("heartbeat stopped"), std::string::npos) << why;
}

TEST_F(OwnerLockTest, WaiterGivesUpWhenTheOutputAppearsOrItIsInterrupted) {
  const fs::path lock_file = dir() / "data.lock";
  std::unique_ptr<OwnerLock> held = AcquireOwnerLock(lock_file, "k", {});
  std::atomic<bool> made{false};
  std::thread maker([&] {
    std::this_thread::sleep_for(100ms);
    made = true;
  });
  EXPECT_EQ(AcquireOwnerLock(lock_file, "k", [&] { return made.load(); }, Quick()), nullptr);
  maker.join();

  std::atomic<bool> cancel{true};
  try {
    AcquireOwnerLock(lock_file, "k", {}, Quick(), {}, &cancel);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("interrupted while waiting for pid"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(lock_file.string()), std::string::npos) << e.what();
  }
  // A waiter that may not wait for another purpose says so through `waiting`.
  LockWaitEvents refuse;
  refuse.waiting = [](const LockOwner& holder) { throw Error("held for " + holder.purpose); };
  EXPECT_THROW(AcquireOwnerLock(lock_file, "other", {}, Quick(), refuse), Error);
  held.reset();
  EXPECT_NE(AcquireOwnerLock(lock_file, "k", {}, Quick()), nullptr);
}

TEST_F(OwnerLockTest, LockInAMissingFolderIsAnErrorNamingIt) {
  const fs::path lock_file = dir() / "no" / "such" / "data.lock";
  try {
    AcquireOwnerLock(lock_file, "k", {});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(lock_file.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace segslam
