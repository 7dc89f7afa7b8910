// Fuzz target: the text files of a TUM-layout sequence (core/tum_dataset.h): the same
// bytes read as a file list (rgb.txt, depth.txt), as associations.txt and as camera.yaml;
// a list that reads is then associated with itself by timestamp.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/tum_dataset.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace segslam;
  const auto list_file = fuzz::WriteScratch("rgb.txt", data, size);
  std::vector<std::pair<double, std::string>> list;
  if (!fuzz::Refused([&] { list = ReadTumFileList(list_file); })) {
    const auto entries = AssociateByTimestamp(list, list);
    if (entries.size() != list.size()) {
      fuzz::PropertyBroken("a file list associated with itself loses frames: " + std::to_string(list.size()) +
                           " stamps, " + std::to_string(entries.size()) + " frames");
    }
  }

  const auto associations_file = fuzz::WriteScratch("associations.txt", data, size);
  fuzz::Refused([&] { ReadTumAssociations(associations_file); });

  const auto camera_file = fuzz::WriteScratch("camera.yaml", data, size);
  fuzz::Refused([&] {
    const SequenceCamera camera = ReadCameraYaml(camera_file);
    std::string error;
    if (!camera.IsValid(&error)) fuzz::PropertyBroken("ReadCameraYaml accepted an invalid camera: " + error);
  });
  return 0;
}
