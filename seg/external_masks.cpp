#include "seg/external_masks.h"

#include <algorithm>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/output_folders.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;

Error TableError(const std::string& origin, const std::string& what) {
  return Error(origin + ": " + what);
}

}  // namespace

std::map<std::uint16_t, ExternalDetection> ParseExternalMaskTable(const nlohmann::json& json,
                                                                   const std::string& origin) {
  if (!json.is_object() || !json.contains("instances") || !json["instances"].is_array()) {
    throw TableError(origin, "expected an object with an \"instances\" array");
  }
  std::map<std::uint16_t, ExternalDetection> table;
  const auto& entries = json["instances"];
  for (size_t k = 0; k < entries.size(); ++k) {
    const nlohmann::json& entry = entries[k];
    const std::string where = fmt::format("instances[{}]", k);
    if (!entry.is_object()) throw TableError(origin, where + " is not an object");
    for (const auto& item : entry.items()) {
      if (item.key() != "id" && item.key() != "category_id" && item.key() != "category" &&
          item.key() != "score") {
        throw TableError(origin, where + ": unknown key \"" + item.key() +
                                     "\" (known: id, category_id, category, score)");
      }
    }
    // Id.
    if (!entry.contains("id") || !entry["id"].is_number_integer()) {
      throw TableError(origin, where + ": \"id\" is missing or not an integer");
    }
    const auto id = entry["id"].get<long long>();
    if (id < 1 || id > 65535) {
      throw TableError(origin, fmt::format("{}: id {} is outside 1..65535", where, id));
    }
    if (table.count(static_cast<std::uint16_t>(id)) != 0) {
      throw TableError(origin, fmt::format("{}: id {} appears twice", where, id));
    }
    // Category, by COCO id or name (or both, agreeing).
    const CocoCategory* by_id = nullptr;
    const CocoCategory* by_name = nullptr;
    if (entry.contains("category_id")) {
      if (!entry["category_id"].is_number_integer()) {
        throw TableError(origin, where + ": \"category_id\" is not an integer");
      }
      const auto category_id = entry["category_id"].get<long long>();
      by_id = category_id >= 1 && category_id <= 90 ? FindCocoCategory(static_cast<int>(category_id))
                                                    : nullptr;
      if (by_id == nullptr) {
        throw TableError(origin, fmt::format("{} (id {}): unknown COCO category_id {}", where, id,
                                             category_id));
      }
    }
    if (entry.contains("category")) {
      if (!entry["category"].is_string()) {
        throw TableError(origin, where + ": \"category\" is not a string");
      }
      const std::string name = entry["category"].get<std::string>();
      by_name = FindCocoCategoryByName(name);
      if (by_name == nullptr) {
        throw TableError(origin, fmt::format("{} (id {}): unknown COCO category \"{}\"", where, id,
                                             name));
      }
    }
    if (by_id == nullptr && by_name == nullptr) {
      throw TableError(origin, fmt::format("{} (id {}): needs \"category_id\" or \"category\"",
                                           where, id));
    }
    if (by_id != nullptr && by_name != nullptr && by_id->id != by_name->id) {
      throw TableError(origin, fmt::format("{} (id {}): category_id {} is \"{}\", not \"{}\"",
                                           where, id, by_id->id, by_id->name, by_name->name));
    }
    ExternalDetection detection;
    detection.category_id = by_id != nullptr ? by_id->id : by_name->id;
    // Score.
    if (entry.contains("score")) {
      if (!entry["score"].is_number()) throw TableError(origin, where + ": \"score\" is not a number");
      const double score = entry["score"].get<double>();
      if (!(score >= 0.0 && score <= 1.0)) {
        throw TableError(origin, fmt::format("{} (id {}): score {} is outside [0, 1]", where, id,
                                             score));
      }
      detection.score = static_cast<float>(score);
    }
    table[static_cast<std::uint16_t>(id)] = detection;
  }
  return table;
}

FrameSegmentation ExternalMasksToSegmentation(
    const cv::Mat& ids, const std::map<std::uint16_t, ExternalDetection>& table,
    cv::Size frame_size, int frame_index, const std::string& origin) {
  if (ids.type() != CV_16UC1) {
    throw Error(origin + ": instance mask must be 16-bit single-channel (CV_16UC1), found " +
                CvTypeName(ids.type()));
  }
  if (ids.size() != frame_size) {
    throw Error(fmt::format("{}: mask is {}x{}, the frame is {}x{}", origin, ids.cols, ids.rows,
                            frame_size.width, frame_size.height));
  }
  // Which ids occur, and the first pixel of an id missing from the table.
  std::map<std::uint16_t, int> present;
  for (int y = 0; y < ids.rows; ++y) {
    const auto* row = ids.ptr<std::uint16_t>(y);
    for (int x = 0; x < ids.cols; ++x) {
      const std::uint16_t id = row[x];
      if (id == 0) continue;
      if (++present[id] == 1 && table.count(id) == 0) {
        throw Error(fmt::format("{}: id {} at pixel (x={}, y={}) has no entry in the class table",
                                origin, id, x, y));
      }
    }
  }
  FrameSegmentation segmentation;
  segmentation.frame_index = frame_index;
  for (const auto& [id, count] : present) {
    const ExternalDetection& detection = table.at(id);
    InstanceMask instance;
    instance.track_id = id;
    instance.category_id = detection.category_id;
    instance.score = detection.score;
    cv::compare(ids, id, instance.mask, cv::CMP_EQ);
    instance.mask /= 255;
    FitBounds(&instance);
    segmentation.instances.push_back(std::move(instance));
  }
  return segmentation;
}

void WriteExternalMaskFiles(const fs::path& dir, const std::string& stem, const cv::Mat& stored_ids,
                            const FrameSegmentation& masks) {
  WriteInstanceMask(dir / (stem + ".png"), stored_ids);
  nlohmann::json table = {{"instances", nlohmann::json::array()}};
  for (const InstanceMask& instance : masks.instances) {
    table["instances"].push_back(
        {{"id", instance.track_id}, {"category_id", instance.category_id}, {"score", instance.score}});
  }
  WriteFileAtomically(dir / (stem + ".json"), table.dump() + "\n");
}

void WriteMaskFolderRecord(const fs::path& dir, const TumSequence& sequence) {
  const nlohmann::json record = {{"sequence", sequence.dir().string()},
                                 {"first_frame", sequence.entries().front().rgb_file},
                                 {"first_frame_sha256", sequence.FirstFrameSha256()}};
  WriteFileAtomically(dir / kMaskFolderRecordFile, record.dump(1) + "\n");
}

namespace {

// A record for another sequence's frames (same first stem, other image) is refused; one
// for a sequence whose first frame this one lacks says nothing, and is let be.
void CheckMaskFolderRecord(const fs::path& dir, const TumSequence& sequence) {
  const fs::path file = dir / kMaskFolderRecordFile;
  if (!fs::exists(file) || sequence.size() == 0) return;
  const nlohmann::json record = ReadJsonFile(file);
  const auto text = [&](const char* key) {
    return record.is_object() && record.contains(key) && record.at(key).is_string() ? record.at(key).get<std::string>()
                                                                                     : std::string();
  };
  if (text("first_frame").empty() || text("first_frame_sha256").empty()) {
    throw FileError(file, "expected {\"first_frame\": \"...\", \"first_frame_sha256\": \"...\"} (strings)");
  }
  if (text("first_frame") != sequence.entries().front().rgb_file) return;
  if (text("first_frame_sha256") != sequence.FirstFrameSha256()) {
    const std::string made_for = text("sequence").empty() ? std::string("another sequence") : text("sequence");
    throw FileError(file, fmt::format("these masks were made for {}, whose frames are not those of {} (the first "
                                      "frame, {}, differs)",
                                      made_for, sequence.dir().string(), sequence.entries().front().rgb_file));
  }
}

}  // namespace

ExternalMaskSegmenter::ExternalMaskSegmenter(const fs::path& dir, const TumSequence& sequence, size_t frames)
    : dir_(dir), sequence_(sequence) {
  if (!fs::is_directory(dir_)) throw FileError(dir_, "external masks folder does not exist");
  CheckMaskFolderRecord(dir_, sequence_);
  const size_t checked = frames > 0 ? std::min(frames, sequence_.size()) : sequence_.size();
  for (size_t i = 0; i < checked; ++i) {
    for (const fs::path& path : {MaskPath(i), TablePath(i)}) {
      if (!fs::is_regular_file(path)) {
        throw FileError(path, fmt::format("missing external mask file for frame {} ({}): every "
                                          "frame needs <stem>.png and <stem>.json",
                                          i, sequence_.entries()[i].rgb_file));
      }
    }
  }
}

fs::path ExternalMaskSegmenter::MaskPath(size_t i) const {
  if (i >= sequence_.size()) {
    throw FileError(dir_, fmt::format("frame {} is out of range (the sequence has {} frames)", i,
                                      sequence_.size()));
  }
  return dir_ / (sequence_.FrameStem(i) + ".png");
}

fs::path ExternalMaskSegmenter::TablePath(size_t i) const {
  fs::path path = MaskPath(i);
  path.replace_extension(".json");
  return path;
}

FrameSegmentation ExternalMaskSegmenter::Segment(const RgbdFrame& frame) {
  if (frame.index < 0) throw FileError(dir_, fmt::format("negative frame index {}", frame.index));
  const size_t i = static_cast<size_t>(frame.index);
  const fs::path mask_path = MaskPath(i);
  const fs::path table_path = TablePath(i);
  const auto table = ParseExternalMaskTable(ReadJsonFile(table_path), table_path.string());
  const cv::Mat ids = sequence_.LoadInstanceMask(mask_path);
  const cv::Size frame_size = !frame.color_bgr.empty()
                                  ? frame.color_bgr.size()
                                  : cv::Size(sequence_.camera().intrinsics.width,
                                             sequence_.camera().intrinsics.height);
  return ExternalMasksToSegmentation(ids, table, frame_size, frame.index,
                                     mask_path.string() + " (table " + table_path.string() + ")");
}

std::string ExternalMaskSegmenter::name() const { return "external:" + dir_.string(); }

}  // namespace segslam::seg
