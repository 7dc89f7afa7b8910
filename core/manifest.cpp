#include "core/manifest.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/input_file.h"

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
  std::ifstream in = OpenInputFile(file, std::ios::in | std::ios::binary);
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

std::vector<std::string> CheckListedFiles(const std::filesystem::path& dir, bool hashes) {
  const std::filesystem::path manifest_path = dir / kManifestName;
  std::ifstream in(manifest_path);
  if (!in) return {manifest_path.string() + ": missing"};
  const nlohmann::json manifest = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  const auto files = manifest.is_object() ? manifest.find("files") : manifest.end();
  if (!manifest.is_object() || files == manifest.end() || !files->is_array()) {
    return {manifest_path.string() + ": not a manifest (expected {\"files\": [{\"path\", \"size\", \"sha256\"}, ...]})"};
  }
  std::vector<std::string> problems;
  for (const nlohmann::json& file : *files) {
    const auto text = [&](const char* key) {
      return file.is_object() && file.contains(key) && file.at(key).is_string() ? file.at(key).get<std::string>()
                                                                                 : std::string();
    };
    const std::string path = text("path");
    if (path.empty() || !file.contains("size") || !file.at("size").is_number_unsigned()) {
      problems.push_back(manifest_path.string() + ": an entry without a path or size");
      continue;
    }
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(dir / path, error);
    if (error) {
      problems.push_back(path + ": missing");
    } else if (size != file.at("size").get<std::uintmax_t>()) {
      problems.push_back(path + ": " + std::to_string(size) + " bytes, the manifest lists " +
                         std::to_string(file.at("size").get<std::uintmax_t>()));
    } else if (hashes && Sha256OfFile(dir / path) != text("sha256")) {
      problems.push_back(path + ": its SHA-256 differs from the manifest's");
    }
  }
  return problems;
}

}  // namespace segslam
