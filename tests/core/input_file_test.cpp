// Every reader of a file names the path when it is given a folder or nothing, and quotes
// what it read from a file in printable text only.
#include "core/input_file.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/pose.h"
#include "core/tum_dataset.h"
#include "core/yaml_file.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using InputFileTest = testing::TempDirTest;

TEST_F(InputFileTest, DirectoryWhereAFileIsExpectedIsNamedByEveryReader) {
  const std::filesystem::path folder = dir() / "folder.json";
  std::filesystem::create_directories(folder);
  const std::string expected = folder.string() + ": is a directory, expected a file";
  for (const std::string& message : {
           ErrorMessage([&] { ReadFileText(folder); }),
           ErrorMessage([&] { ReadJsonFile(folder); }),
           ErrorMessage([&] { LoadYamlFile(folder); }),
           ErrorMessage([&] { ReadCameraYaml(folder); }),
           ErrorMessage([&] { ReadTumTrajectory(folder); }),
           ErrorMessage([&] { ReadTumFileList(folder); }),
           ErrorMessage([&] { ReadColorImage(folder); }),
       }) {
    EXPECT_NE(message.find(expected), std::string::npos) << message;
  }
  EXPECT_NE(ErrorMessage([&] { ReadFileText(dir() / "nowhere.txt"); }).find("nowhere.txt: file does not exist"),
            std::string::npos);
}

TEST(PrintableTextTest, EscapesBytesATerminalWouldInterpret) {
  EXPECT_EQ(PrintableText("plain key_1"), "plain key_1");
  EXPECT_EQ(PrintableText(std::string("\x1b[31mred\x01\xff", 10)), "\\x1b[31mred\\x01\\xff");
  EXPECT_EQ(PrintableText(std::string("a\0b\n", 4)), "a\\x00b\\x0a");
  EXPECT_EQ(PrintableText(std::string(100, 'x'), 5), "xxxxx...");
  // Well-formed UTF-8 is printable (a folder named in another script) and counts as one
  // character each; the cut never splits one.
  EXPECT_EQ(PrintableText("naïve café"), "naïve café");
  EXPECT_EQ(PrintableText("naïve", 3), "naï...");
  EXPECT_EQ(PrintableText(std::string("\xc3", 1), 5), "\\xc3") << "a lone lead byte is escaped";
}

// Binary bytes in a file's field come back escaped, not raw.
TEST_F(InputFileTest, BinaryFieldOfATrajectoryIsQuotedPrintably) {
  const std::filesystem::path file = dir() / "trajectory.txt";
  std::ofstream(file, std::ios::binary) << "\x1b[2J\xfe 1 2 3 0 0 0 1\n";
  const std::string message = ErrorMessage([&] { ReadTumTrajectory(file); });
  EXPECT_NE(message.find("'\\x1b[2J\\xfe'"), std::string::npos) << message;
  EXPECT_EQ(message.find('\x1b'), std::string::npos);
}

}  // namespace
}  // namespace segslam
