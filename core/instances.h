// The instance table of a sequence: each instance id used in the 16-bit masks maps to
// one COCO category. Ids are stable over a whole sequence (and both passes of a
// scenario); 0 is background and never an instance.
//
// JSON layout (file "instances.json"):
//   {"instances": [{"id": 3, "category_id": 3, "category": "car", "moveable": true}, ...]}
// "moveable" is written for readers' convenience; on reading it must agree with
// IsMoveableCategory(category_id).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

namespace segslam {

struct InstanceInfo {
  std::uint16_t id = 0;       // Mask value, 1..65535.
  int category_id = 0;        // COCO category id (coco.h).
  std::string category_name;  // COCO name; empty in Add() means "fill from the id".
  bool moveable = false;      // IsMoveableCategory(category_id); Add() sets it.
};

class InstanceTable {
 public:
  // Adds an instance. The category name is filled in if empty and `moveable` is set from
  // the category. Throws segslam::Error on id 0, a duplicate id, an unknown COCO id, or
  // a name that does not match the id.
  void Add(const InstanceInfo& info);

  // nullptr if there is no instance with this id.
  const InstanceInfo* Find(std::uint16_t id) const;

  // All instances, sorted by id.
  const std::vector<InstanceInfo>& instances() const { return instances_; }
  bool empty() const { return instances_.empty(); }
  size_t size() const { return instances_.size(); }

  nlohmann::json ToJson() const;

  // Throws segslam::Error starting with `origin` (a file name) on a malformed layout,
  // missing/unknown keys, wrong types, an id outside 1..65535, or any Add() error.
  static InstanceTable FromJson(const nlohmann::json& json, const std::string& origin);

  // Reads and parses a JSON file; errors name the file.
  static InstanceTable Read(const std::filesystem::path& path);

  // Writes the JSON (2-space indent) atomically.
  void Write(const std::filesystem::path& path) const;

 private:
  std::vector<InstanceInfo> instances_;  // Sorted by id.
};

// Throws segslam::Error starting with `origin` and naming the first (row-major) mask
// value that is neither 0 nor an instance of `table`, with its pixel. `mask` must be
// CV_16U (else throws).
void CheckMaskIds(const cv::Mat& mask, const InstanceTable& table, const std::string& origin);

}  // namespace segslam
