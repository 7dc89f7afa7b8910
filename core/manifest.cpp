#include "core/manifest.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <set>

namespace segslam {
namespace {

constexpr const char* kManifestName = "manifest.json";

struct EvpContextDeleter {
  void operator()(EVP_MD_CTX* context) const { EVP_MD_CTX_free(context); }
};

}  // namespace

std::string Sha256OfFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FileError(file, "cannot open for reading");
  std::unique_ptr<EVP_MD_CTX, EvpContextDeleter> context(EVP_MD_CTX_new());
  if (!context || EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr) != 1) {
    throw FileError(file, "cannot initialise SHA-256");
  }
  std::array<char, 1 << 16> buffer{};
  while (in) {
    in.read(buffer.data(), buffer.size());
    if (in.gcount() > 0) {
      EVP_DigestUpdate(context.get(), buffer.data(), static_cast<size_t>(in.gcount()));
    }
  }
  if (in.bad()) throw FileError(file, "read error");
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int digest_size = 0;
  EVP_DigestFinal_ex(context.get(), digest.data(), &digest_size);
  std::string hex;
  hex.reserve(2 * digest_size);
  for (unsigned int i = 0; i < digest_size; ++i) {
    char byte_hex[3];
    std::snprintf(byte_hex, sizeof(byte_hex), "%02x", digest[i]);
    hex += byte_hex;
  }
  return hex;
}

std::vector<ManifestEntry> ListDirectoryWithChecksums(const std::filesystem::path& dir,
                                                      const std::vector<std::string>& exclude) {
  namespace fs = std::filesystem;
  const std::set<std::string> excluded(exclude.begin(), exclude.end());
  std::vector<ManifestEntry> entries;
  for (const auto& item : fs::recursive_directory_iterator(dir)) {
    if (!item.is_regular_file()) continue;
    const std::string relative = fs::relative(item.path(), dir).generic_string();
    if (excluded.count(relative)) continue;
    entries.push_back({relative, item.file_size(), ""});
  }
  // Sorted so the manifest's bytes do not depend on the file system's listing order.
  std::sort(entries.begin(), entries.end(),
            [](const ManifestEntry& a, const ManifestEntry& b) { return a.path < b.path; });
  for (auto& entry : entries) entry.sha256 = Sha256OfFile(dir / entry.path);
  return entries;
}

void WriteManifest(const std::filesystem::path& dir, const nlohmann::json& extra) {
  nlohmann::json files = nlohmann::json::array();
  for (const auto& entry : ListDirectoryWithChecksums(dir, {kManifestName})) {
    files.push_back({{"path", entry.path}, {"size", entry.size_bytes}, {"sha256", entry.sha256}});
  }
  nlohmann::json manifest = {{"format", "segslam-manifest-1"}, {"extra", extra}, {"files", files}};
  WriteFileAtomically(dir / kManifestName, manifest.dump(1) + "\n");
}

std::vector<std::string> VerifyManifest(const std::filesystem::path& dir) {
  const std::filesystem::path manifest_path = dir / kManifestName;
  std::ifstream in(manifest_path);
  if (!in) return {manifest_path.string() + ": missing"};
  nlohmann::json manifest;
  try {
    manifest = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    return {manifest_path.string() + ": not valid JSON: " + e.what()};
  }
  std::map<std::string, ManifestEntry> listed;
  try {
    for (const auto& file : manifest.value("files", nlohmann::json::array())) {
      ManifestEntry entry{file.value("path", ""), file.value("size", std::uintmax_t{0}),
                          file.value("sha256", "")};
      listed[entry.path] = entry;
    }
  } catch (const nlohmann::json::exception& e) {
    return {manifest_path.string() + ": not a manifest (expected {\"files\": [{\"path\", \"size\", "
                                     "\"sha256\"}, ...]}): " + e.what()};
  }
  std::vector<std::string> problems;
  std::set<std::string> seen;
  for (const auto& actual : ListDirectoryWithChecksums(dir, {kManifestName})) {
    seen.insert(actual.path);
    const auto it = listed.find(actual.path);
    if (it == listed.end()) {
      problems.push_back(actual.path + ": not listed in the manifest");
    } else if (it->second.size_bytes != actual.size_bytes || it->second.sha256 != actual.sha256) {
      problems.push_back(actual.path + ": checksum differs from the manifest");
    }
  }
  for (const auto& [path, entry] : listed) {
    if (!seen.count(path)) problems.push_back(path + ": listed in the manifest but missing");
  }
  return problems;
}

}  // namespace segslam
