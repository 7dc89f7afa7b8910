// Tests of core/manifest.h: SHA-256 against a published value, a written manifest that
// verifies, and each kind of damage reported as a problem (never thrown).
#include "core/manifest.h"

#include <fstream>

#include <gtest/gtest.h>

#include "test_util.h"

namespace segslam {
namespace {

using ManifestTest = testing::TempDirTest;

bool AnyContains(const std::vector<std::string>& problems, const std::string& text) {
  for (const std::string& problem : problems) {
    if (problem.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST_F(ManifestTest, Sha256OfAKnownString) {
  std::ofstream(dir() / "abc.txt", std::ios::binary) << "abc";
  // FIPS 180-2, appendix B.1.
  EXPECT_EQ(Sha256OfFile(dir() / "abc.txt"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST_F(ManifestTest, WrittenManifestVerifiesAndDamageIsReported) {
  std::ofstream(dir() / "a.txt") << "first";
  std::filesystem::create_directories(dir() / "sub");
  std::ofstream(dir() / "sub" / "b.txt") << "second";
  WriteManifest(dir(), {{"note", "test"}});
  EXPECT_TRUE(VerifyManifest(dir()).empty());

  std::ofstream(dir() / "a.txt") << "edited";
  std::ofstream(dir() / "extra.txt") << "new";
  std::filesystem::remove(dir() / "sub" / "b.txt");
  const std::vector<std::string> problems = VerifyManifest(dir());
  EXPECT_TRUE(AnyContains(problems, "a.txt: checksum differs from the manifest"));
  EXPECT_TRUE(AnyContains(problems, "extra.txt: not listed in the manifest"));
  EXPECT_TRUE(AnyContains(problems, "sub/b.txt: listed in the manifest but missing"));
}

// A manifest of the wrong shape is a problem naming the file, not an exception.
TEST_F(ManifestTest, MalformedManifestIsAProblemNamingTheFile) {
  for (const char* text : {"[]", R"({"files": [{"path": "a", "size": "12"}]})", "{not json"}) {
    std::ofstream(dir() / "manifest.json") << text;
    std::vector<std::string> problems;
    EXPECT_NO_THROW(problems = VerifyManifest(dir())) << text;
    ASSERT_EQ(problems.size(), 1u) << text;
    EXPECT_NE(problems[0].find((dir() / "manifest.json").string()), std::string::npos) << problems[0];
  }
}

}  // namespace
}  // namespace segslam
