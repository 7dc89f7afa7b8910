#include "core/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "test_util.h"

namespace segslam {
namespace {

using AtomicFileTest = testing::TempDirTest;

std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream s;
  s << file.rdbuf();
  return s.str();
}

// An OwnOutputCheck that takes every folder for its own.
std::string AnyFolder(const std::filesystem::path&) { return ""; }

size_t CountFiles(const std::filesystem::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

TEST_F(AtomicFileTest, WritesAndReplacesWithoutLeavingTemp) {
  const auto path = dir() / "a.txt";
  WriteFileAtomically(path, "first");
  WriteFileAtomically(path, std::string("sec\0ond", 7));
  EXPECT_EQ(ReadAll(path), std::string("sec\0ond", 7));
  EXPECT_EQ(CountFiles(dir()), 1u);  // No "a.txt.tmp-<pid>" left over.
}

TEST_F(AtomicFileTest, MissingDirectoryThrowsNamingFile) {
  const auto path = dir() / "no_such_dir" / "a.txt";
  try {
    WriteFileAtomically(path, "x");
    FAIL() << "expected segslam::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
}

TEST_F(AtomicFileTest, UnwritableDirectoryThrowsAndLeavesNothing) {
  if (::geteuid() == 0) GTEST_SKIP() << "root ignores directory permissions";
  const auto locked = dir() / "locked";
  std::filesystem::create_directories(locked);
  ::chmod(locked.c_str(), 0555);
  EXPECT_THROW(WriteFileAtomically(locked / "a.txt", "x"), Error);
  ::chmod(locked.c_str(), 0755);
  EXPECT_EQ(CountFiles(locked), 0u);
}

TEST_F(AtomicFileTest, ParentIsAFileThrows) {
  // Unwritable for root too: a regular file cannot hold directory entries.
  WriteFileAtomically(dir() / "plain", "x");
  EXPECT_THROW(WriteFileAtomically(dir() / "plain" / "a.txt", "x"), Error);
  EXPECT_EQ(CountFiles(dir()), 1u);
}

TEST_F(AtomicFileTest, RenameOntoDirectoryFailsAndRemovesTemp) {
  // Works as root too: renaming a file over a non-empty directory always fails.
  const auto target = dir() / "target";
  std::filesystem::create_directories(target / "inside");
  EXPECT_THROW(WriteFileAtomically(target, "x"), Error);
  EXPECT_EQ(CountFiles(dir()), 1u);
}

TEST_F(AtomicFileTest, WriteImageAtomically) {
  cv::Mat image(4, 5, CV_8UC3, cv::Scalar(1, 2, 3));
  const auto path = dir() / "img.png";
  WriteImageAtomically(path, image);
  const cv::Mat back = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0);
  EXPECT_THROW(WriteImageAtomically(dir() / "img.unknownext", image), Error);
  EXPECT_THROW(WriteImageAtomically(dir() / "empty.png", cv::Mat()), Error);
  EXPECT_EQ(CountFiles(dir()), 1u);
}

// A staged folder appears under its name only when committed, replacing an old one; an
// uncommitted one (an error, Ctrl-C) leaves nothing behind.
TEST_F(AtomicFileTest, StagingDirectoryAppearsOnlyWhenCommitted) {
  const auto target = dir() / "out";
  {
    StagingDirectory staging(target, false);
    WriteFileAtomically(staging.path() / "a.txt", "first");
    EXPECT_FALSE(std::filesystem::exists(target));
  }
  EXPECT_FALSE(std::filesystem::exists(target));
  EXPECT_EQ(CountFiles(dir()), 0u);

  StagingDirectory first(target, false);
  WriteFileAtomically(first.path() / "a.txt", "first");
  first.Commit();
  EXPECT_EQ(ReadAll(target / "a.txt"), "first");

  const std::string refused = testing::ErrorMessage([&] { StagingDirectory again(target, false); });
  EXPECT_NE(refused.find(target.string() + ": already exists (use --force to replace it)"), std::string::npos)
      << refused;
  StagingDirectory second(target, true, AnyFolder);
  WriteFileAtomically(second.path() / "b.txt", "second");
  second.Commit();
  EXPECT_FALSE(std::filesystem::exists(target / "a.txt"));
  EXPECT_EQ(ReadAll(target / "b.txt"), "second");
  EXPECT_EQ(CountFiles(dir()), 1u);  // no staging or old folder left
}

// Without overwrite, a target that appears after the constructor's check (a concurrent
// run without --force) is neither replaced nor deleted, and the staged output survives
// the refusal.
TEST_F(AtomicFileTest, StagingCommitWithoutOverwriteRefusesATargetMadeSinceConstruction) {
  const auto target = dir() / "out";
  StagingDirectory staging(target, false);
  WriteFileAtomically(staging.path() / "b.txt", "this run");
  std::filesystem::create_directory(target);
  WriteFileAtomically(target / "a.txt", "other run");

  const std::string refused = testing::ErrorMessage([&] { staging.Commit(); });
  EXPECT_NE(refused.find(target.string() + ": already exists"), std::string::npos) << refused;
  EXPECT_NE(refused.find("--force"), std::string::npos) << refused;
  EXPECT_EQ(ReadAll(target / "a.txt"), "other run");
  EXPECT_FALSE(std::filesystem::exists(target / "b.txt"));
  EXPECT_EQ(ReadAll(staging.path() / "b.txt"), "this run");
}

// With overwrite, a failed move of the new output puts the old one back under its name
// instead of leaving it only under a hidden ".old" name.
TEST_F(AtomicFileTest, StagingCommitPutsTheOldOutputBackWhenTheMoveFails) {
  const auto target = dir() / "out";
  std::filesystem::create_directory(target);
  WriteFileAtomically(target / "a.txt", "previous");
  StagingDirectory staging(target, true, AnyFolder);
  std::filesystem::remove_all(staging.path());  // makes the second rename fail

  const std::string message = testing::ErrorMessage([&] { staging.Commit(); });
  EXPECT_NE(message.find(target.string() + ": cannot move the finished output here"), std::string::npos) << message;
  EXPECT_EQ(ReadAll(target / "a.txt"), "previous");
  EXPECT_EQ(CountFiles(dir()), 1u);  // no hidden ".old" folder left
}

// With overwrite, a folder that the output's check does not recognise (one holding other
// files) is refused and left whole, and so is a plain file; an empty folder is replaced.
TEST_F(AtomicFileTest, StagingReplacesOnlyAFolderItsCheckRecognises) {
  namespace fs = std::filesystem;
  const auto target = dir() / "out";
  fs::create_directories(target / "sub");
  WriteFileAtomically(target / "sub" / "t.tex", "precious");
  const auto is_own = [](const fs::path& existing) {
    return fs::exists(existing / "mine") ? std::string() : std::string("sub/t.tex is not mine");
  };
  const std::string refused = testing::ErrorMessage([&] { StagingDirectory staging(target, true, is_own, "thing"); });
  EXPECT_NE(refused.find(target.string() + ": holds what segslam did not write (sub/t.tex is not mine)"),
            std::string::npos) << refused;
  EXPECT_NE(refused.find("only a thing that segslam wrote is replaced"), std::string::npos) << refused;
  // Without a check nothing but an empty folder may be replaced.
  EXPECT_NE(testing::ErrorMessage([&] { StagingDirectory staging(target, true); }).find("holds what segslam did not"),
            std::string::npos);
  EXPECT_EQ(ReadAll(target / "sub" / "t.tex"), "precious");
  EXPECT_EQ(CountFiles(dir()), 1u);  // no staging folder left

  // A folder that became foreign after the constructor's check is refused at Commit too.
  WriteFileAtomically(target / "mine", "");
  StagingDirectory staging(target, true, is_own, "thing");
  fs::remove(target / "mine");
  EXPECT_NE(testing::ErrorMessage([&] { staging.Commit(); }).find("holds what segslam did not write"),
            std::string::npos);
  EXPECT_EQ(ReadAll(target / "sub" / "t.tex"), "precious");

  const auto empty = dir() / "empty";
  fs::create_directory(empty);
  StagingDirectory replacing(empty, true);
  WriteFileAtomically(replacing.path() / "new.txt", "new");
  replacing.Commit();
  EXPECT_EQ(ReadAll(empty / "new.txt"), "new");
}

TEST_F(AtomicFileTest, StagingRefusesAFileWhereItsFolderGoes) {
  const auto target = dir() / "out";
  WriteFileAtomically(target, "a plain file");
  for (const bool overwrite : {false, true}) {
    const std::string refused =
        testing::ErrorMessage([&] { StagingDirectory staging(target, overwrite, AnyFolder, "dataset"); });
    EXPECT_NE(refused.find(target.string() + ": is a file, not a folder"), std::string::npos) << refused;
  }
  EXPECT_EQ(ReadAll(target), "a plain file");
  EXPECT_EQ(CountFiles(dir()), 1u);
}

TEST(StagingLeftoverTest, NamesSayTargetProcessAndHost) {
  const auto partial = ParseStagingLeftover("/data/.office-0123456789ab.partial-4242@node-7.cluster");
  ASSERT_TRUE(partial.has_value());
  EXPECT_EQ(partial->target_name, "office-0123456789ab");
  EXPECT_FALSE(partial->replaced_output);
  EXPECT_EQ(partial->pid, 4242);
  EXPECT_EQ(partial->host, "node-7.cluster");
  const auto legacy = ParseStagingLeftover(".x.old-17");
  ASSERT_TRUE(legacy.has_value());
  EXPECT_EQ(legacy->target_name, "x");
  EXPECT_TRUE(legacy->replaced_output);
  EXPECT_EQ(legacy->host, "");
  EXPECT_FALSE(ParseStagingLeftover("x.partial-17").has_value());  // not hidden
  EXPECT_FALSE(ParseStagingLeftover(".x.partial-abc").has_value());
  EXPECT_FALSE(ParseStagingLeftover(".x.partial-17@bad/host").has_value());
}

// What `kill -9` leaves beside an output is cleared by the next output to the same place,
// when its process has ended on this host; another host's (a shared file system), a live
// process's and another target's are kept; a replaced output caught between the two
// renames of a commit is put back.
TEST_F(AtomicFileTest, StagingClearsWhatKilledProcessesOfThisHostLeft) {
  namespace fs = std::filesystem;
  const std::string host = StagingHostName();
  const std::string dead_pid = "2147483000";  // above any pid_max: no process has it
  const auto make = [&](const std::string& name) {
    fs::create_directories(dir() / name);
    WriteFileAtomically(dir() / name / "frame.png", "x");
    return dir() / name;
  };
  const fs::path abandoned = make(".out.partial-" + dead_pid + "@" + host);
  const fs::path abandoned_legacy = make(".out.partial-" + dead_pid);
  const fs::path other_host = make(".out.partial-" + dead_pid + "@not-" + host);
  const fs::path live = make(".out.partial-" + std::to_string(::getppid()) + "@" + host);  // our parent's
  const fs::path other_target = make(".other.partial-" + dead_pid + "@" + host);
  const fs::path replaced = make(".out.old-" + dead_pid + "@" + host);

  StagingDirectory staging(dir() / "out", true, AnyFolder);
  EXPECT_FALSE(fs::exists(abandoned));
  EXPECT_FALSE(fs::exists(abandoned_legacy));
  EXPECT_TRUE(fs::exists(other_host));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(other_target));
  EXPECT_FALSE(fs::exists(replaced));
  EXPECT_EQ(ReadAll(dir() / "out" / "frame.png"), "x");  // the replaced output, put back
}

}  // namespace
}  // namespace segslam
