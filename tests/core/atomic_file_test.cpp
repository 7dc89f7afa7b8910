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
  StagingDirectory second(target, true);
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
  StagingDirectory staging(target, true);
  std::filesystem::remove_all(staging.path());  // makes the second rename fail

  const std::string message = testing::ErrorMessage([&] { staging.Commit(); });
  EXPECT_NE(message.find(target.string() + ": cannot move the finished output here"), std::string::npos) << message;
  EXPECT_EQ(ReadAll(target / "a.txt"), "previous");
  EXPECT_EQ(CountFiles(dir()), 1u);  // no hidden ".old" folder left
}

}  // namespace
}  // namespace segslam
