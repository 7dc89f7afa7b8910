#include "core/instances.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/json_file.h"
#include "core/coco.h"
#include "core/error.h"

namespace segslam {

void InstanceTable::Add(const InstanceInfo& info) {
  if (info.id == 0) throw Error("instance id 0 is reserved for background");
  const CocoCategory* category = FindCocoCategory(info.category_id);
  if (category == nullptr) {
    throw Error(fmt::format("instance {}: unknown COCO category id {}", info.id,
                            info.category_id));
  }
  if (!info.category_name.empty() && info.category_name != category->name) {
    throw Error(fmt::format("instance {}: category name '{}' does not match COCO id {} ('{}')",
                            info.id, PrintableText(info.category_name), info.category_id, category->name));
  }
  const auto it = std::lower_bound(
      instances_.begin(), instances_.end(), info.id,
      [](const InstanceInfo& a, std::uint16_t id) { return a.id < id; });
  if (it != instances_.end() && it->id == info.id) {
    throw Error(fmt::format("duplicate instance id {}", info.id));
  }
  InstanceInfo stored = info;
  stored.category_name = std::string(category->name);
  stored.moveable = IsMoveableCategory(info.category_id);
  instances_.insert(it, stored);
}

const InstanceInfo* InstanceTable::Find(std::uint16_t id) const {
  const auto it = std::lower_bound(
      instances_.begin(), instances_.end(), id,
      [](const InstanceInfo& a, std::uint16_t v) { return a.id < v; });
  return it != instances_.end() && it->id == id ? &*it : nullptr;
}

nlohmann::json InstanceTable::ToJson() const {
  nlohmann::json list = nlohmann::json::array();
  for (const InstanceInfo& info : instances_) {
    list.push_back({{"id", info.id},
                    {"category_id", info.category_id},
                    {"category", info.category_name},
                    {"moveable", info.moveable}});
  }
  return nlohmann::json{{"instances", list}};
}

InstanceTable InstanceTable::FromJson(const nlohmann::json& json, const std::string& origin) {
  if (!json.is_object() || !json.contains("instances") || !json["instances"].is_array()) {
    throw Error(origin + ": expected an object with an \"instances\" array");
  }
  for (const auto& item : json.items()) {
    if (item.key() != "instances") {
      throw Error(origin + ": unknown key \"" + item.key() + "\" (expected only \"instances\")");
    }
  }
  InstanceTable table;
  const auto& list = json["instances"];
  for (size_t i = 0; i < list.size(); ++i) {
    const auto& entry = list[i];
    const std::string where = fmt::format("{}: instances[{}]", origin, i);
    if (!entry.is_object()) throw Error(where + ": expected an object");
    for (const auto& item : entry.items()) {
      const std::string& key = item.key();
      if (key != "id" && key != "category_id" && key != "category" && key != "moveable") {
        throw Error(where + ": unknown key \"" + key + "\"");
      }
    }
    for (const char* key : {"id", "category_id"}) {
      if (!entry.contains(key) || !entry[key].is_number_integer()) {
        throw Error(where + ": \"" + key + "\" must be an integer");
      }
    }
    const std::int64_t id = entry["id"].get<std::int64_t>();
    if (id < 1 || id > 65535) {
      throw Error(fmt::format("{}: id {} is outside 1..65535", where, id));
    }
    const std::int64_t category_id = entry["category_id"].get<std::int64_t>();
    InstanceInfo info;
    info.id = static_cast<std::uint16_t>(id);
    info.category_id = static_cast<int>(
        std::clamp<std::int64_t>(category_id, -1, 1000000));  // Unknown ids fail in Add().
    if (entry.contains("category")) {
      if (!entry["category"].is_string()) throw Error(where + ": \"category\" must be a string");
      info.category_name = entry["category"].get<std::string>();
      if (info.category_name.empty()) throw Error(where + ": \"category\" is empty");
    }
    try {
      table.Add(info);
    } catch (const Error& e) {
      throw Error(where + ": " + e.what());
    }
    if (entry.contains("moveable")) {
      if (!entry["moveable"].is_boolean()) throw Error(where + ": \"moveable\" must be a boolean");
      if (entry["moveable"].get<bool>() != table.Find(info.id)->moveable) {
        throw Error(fmt::format("{}: \"moveable\" is {} but category '{}' is {}moveable", where,
                                entry["moveable"].get<bool>(), table.Find(info.id)->category_name,
                                table.Find(info.id)->moveable ? "" : "not "));
      }
    }
  }
  return table;
}

InstanceTable InstanceTable::Read(const std::filesystem::path& path) {
  return FromJson(ReadJsonFile(path), path.string());
}

void InstanceTable::Write(const std::filesystem::path& path) const {
  WriteFileAtomically(path, ToJson().dump(2) + "\n");
}

void CheckMaskIds(const cv::Mat& mask, const InstanceTable& table, const std::string& origin) {
  if (mask.type() != CV_16UC1) {
    throw Error(origin + ": instance mask must be CV_16UC1");
  }
  // Ids repeat over many pixels; remember which were already checked.
  std::vector<std::uint8_t> known(65536, 0);
  known[0] = 1;
  for (const InstanceInfo& info : table.instances()) known[info.id] = 1;
  for (int r = 0; r < mask.rows; ++r) {
    const auto* row = mask.ptr<std::uint16_t>(r);
    for (int c = 0; c < mask.cols; ++c) {
      if (!known[row[c]]) {
        throw Error(fmt::format("{}: mask value {} at pixel (x={}, y={}) is not in the "
                                "instance table",
                                origin, row[c], c, r));
      }
    }
  }
}

}  // namespace segslam
