// Fuzz target: an instance table (instances.json, core/instances.h) and a 16-bit mask
// PNG (core/image_io.h), as an external segmenter's masks folder holds them. The input is
// the JSON followed by the PNG, split at the PNG signature (byte 0x89 never starts a
// character of valid UTF-8 JSON); without a signature all of it is JSON and the PNG is
// empty. The PNG bytes are also read as a depth and as a colour image; a table and a mask
// that both read are checked against each other.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "core/image_io.h"
#include "core/instances.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace segslam;
  const std::uint8_t* const end = data + size;
  const std::uint8_t* const png = std::find(data, end, std::uint8_t{0x89});

  const auto json_file = fuzz::WriteScratch("instances.json", data, static_cast<std::size_t>(png - data));
  std::optional<InstanceTable> table;
  fuzz::Refused([&] { table = InstanceTable::Read(json_file); });

  const auto png_file = fuzz::WriteScratch("mask.png", png, static_cast<std::size_t>(end - png));
  cv::Mat mask;
  if (!fuzz::Refused([&] { mask = ReadInstanceMask(png_file); })) {
    if (mask.type() != CV_16UC1 || mask.empty()) {
      fuzz::PropertyBroken("ReadInstanceMask returned a " + CvTypeName(mask.type()) + " image of " +
                           std::to_string(mask.cols) + "x" + std::to_string(mask.rows));
    }
    if (table) fuzz::Refused([&] { CheckMaskIds(mask, *table, "mask.png"); });
  }
  fuzz::Refused([&] { ReadDepthImage(png_file, 5000.0); });
  fuzz::Refused([&] { ReadColorImage(png_file); });
  return 0;
}
