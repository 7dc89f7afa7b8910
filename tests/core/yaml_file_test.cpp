// YAML with a key given twice in one mapping is refused, naming both lines: yaml-cpp
// keeps both and a lookup takes the first, so the second would be ignored unseen.
#include "core/yaml_file.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/tum_dataset.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using YamlFileTest = testing::TempDirTest;

TEST(YamlTextTest, RepeatedKeyIsRefusedNamingBothLines) {
  EXPECT_EQ(ErrorMessage([] { LoadYamlText("seed: 5\nname: a\nseed: 9\n", "my.yaml"); }),
            "my.yaml: line 3: key 'seed' appears twice in one mapping (first on line 1)");
  // In a nested mapping, and in a mapping inside a list.
  EXPECT_EQ(ErrorMessage([] { LoadYamlText("camera:\n  width: 320\n  height: 240\n  width: 640\n", "my.yaml"); }),
            "my.yaml: line 4: key 'width' appears twice in one mapping (first on line 2)");
  EXPECT_EQ(ErrorMessage([] { LoadYamlText("axes:\n  - {key: a, key: b}\n", "my.yaml"); }),
            "my.yaml: line 2: key 'key' appears twice in one mapping (first on line 2)");
  // The same key in two mappings is no repetition.
  EXPECT_EQ(LoadYamlText("a: {x: 1}\nb: {x: 2}\n", "my.yaml")["b"]["x"].as<int>(), 2);
  EXPECT_NE(ErrorMessage([] { LoadYamlText("a: [1, 2\n", "my.yaml"); }).find("my.yaml: line "), std::string::npos);
}

TEST_F(YamlFileTest, CameraFileWithARepeatedKeyIsRefused) {
  const std::filesystem::path file = dir() / "camera.yaml";
  std::ofstream(file) << "width: 640\nheight: 480\nfx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\ndepth_factor: 5000\n"
                         "fx: 600\n";
  EXPECT_EQ(ErrorMessage([&] { ReadCameraYaml(file); }),
            file.string() + ": line 8: key 'fx' appears twice in one mapping (first on line 3)");
}

}  // namespace
}  // namespace segslam
