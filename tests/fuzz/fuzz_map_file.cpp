// Fuzz target: the long-term map file (slam/map_file.h). The file ends in a SHA-256 of
// its payload, so almost every mutation of a whole file stops at the checksum; to reach
// the payload decoder the target wraps most inputs itself. Input byte 0 chooses:
//   even: bytes 1.. are a payload, written with a valid header (magic, version, size)
//         and checksum, so the decoder sees them;
//   odd:  bytes 1.. are the whole file (header and checksum checks).
// A map that loads must save (SaveLongTermMap refuses only what loading refuses) and
// load again unchanged in its counts, camera and description.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <openssl/sha.h>

#include "slam/map_file.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

void AppendLittleEndian(std::string* out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

std::string WrapPayload(const std::uint8_t* payload, std::size_t size) {
  static constexpr char kMagic[12] = {'S', 'E', 'G', 'S', 'L', 'A', 'M', '-', 'M', 'A', 'P', '\0'};
  std::string file(kMagic, sizeof kMagic);
  AppendLittleEndian(&file, segslam::slam::kMapFormatVersion, 4);
  AppendLittleEndian(&file, size, 8);
  file.append(reinterpret_cast<const char*>(payload), size);
  std::array<unsigned char, SHA256_DIGEST_LENGTH> checksum{};
  SHA256(payload, size, checksum.data());
  file.append(reinterpret_cast<const char*>(checksum.data()), checksum.size());
  return file;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace segslam;
  if (size == 0) return 0;
  const bool whole_file = (data[0] & 1) != 0;
  const auto file = whole_file ? fuzz::WriteScratch("map.bin", data + 1, size - 1)
                               : fuzz::WriteScratch("map.bin", WrapPayload(data + 1, size - 1));
  std::optional<slam::LongTermMapData> map;
  if (fuzz::Refused([&] { map = slam::LoadLongTermMap(file); })) return 0;

  const auto copy = fuzz::ScratchDir() / "map-copy.bin";
  try {
    slam::SaveLongTermMap(copy, *map);
  } catch (const Error& e) {
    fuzz::PropertyBroken(std::string("a map that loaded cannot be saved: ") + e.what());
  }
  slam::LongTermMapData again;
  try {
    again = slam::LoadLongTermMap(copy);
  } catch (const Error& e) {
    fuzz::PropertyBroken(std::string("a map saved from a loaded one does not load: ") + e.what());
  }
  if (again.points.size() != map->points.size() || again.keyframes.size() != map->keyframes.size() ||
      again.description != map->description || again.camera.width != map->camera.width ||
      again.camera.height != map->camera.height || again.camera.fx != map->camera.fx) {
    fuzz::PropertyBroken("a map saved and loaded again differs from the one loaded");
  }
  return 0;
}
