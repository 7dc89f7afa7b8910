#include "seg/coco_detections.h"

#include <algorithm>
#include <optional>
#include <unordered_map>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "core/coco.h"
#include "core/coco_rle.h"
#include "core/error.h"
#include "core/json_file.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;

// A JSON id (integer or string) as text, for lookups and messages.
std::string IdText(const nlohmann::json& id) {
  return id.is_string() ? id.get<std::string>() : id.dump();
}

// The image list and categories that give detections their frame and class.
struct ImageList {
  std::string origin;                                  // the file they came from
  std::unordered_map<std::string, std::string> stem_of;  // image id (IdText) -> file stem
  std::unordered_map<std::string, cv::Size> size_of;     // image id -> width, height, where listed
  std::optional<std::map<long long, std::string>> category_names;  // id -> name, if listed
};

ImageList ReadImageList(const nlohmann::json& json, const std::string& origin) {
  ImageList list;
  list.origin = origin;
  if (!json.is_object() || !json.contains("images") || !json.at("images").is_array()) {
    throw Error(origin + ": expected a COCO dataset object with an \"images\" list");
  }
  const nlohmann::json& images = json.at("images");
  for (size_t k = 0; k < images.size(); ++k) {
    const nlohmann::json& image = images[k];
    if (!image.is_object() || !image.contains("id") || !image.contains("file_name") ||
        !(image.at("id").is_number_integer() || image.at("id").is_string()) || !image.at("file_name").is_string()) {
      throw Error(fmt::format("{}: images[{}] needs an \"id\" and a \"file_name\"", origin, k));
    }
    const std::string stem = fs::path(image.at("file_name").get<std::string>()).stem().string();
    if (!list.stem_of.emplace(IdText(image.at("id")), stem).second) {
      throw Error(fmt::format("{}: images[{}]: id {} appears twice", origin, k, IdText(image.at("id"))));
    }
    if (image.contains("width") || image.contains("height")) {
      if (!image.contains("width") || !image.contains("height") || !image.at("width").is_number_integer() ||
          !image.at("height").is_number_integer()) {
        throw Error(fmt::format("{}: images[{}]: \"width\" and \"height\" must both be integers", origin, k));
      }
      list.size_of[IdText(image.at("id"))] = cv::Size(image.at("width").get<int>(), image.at("height").get<int>());
    }
  }
  if (json.contains("categories")) {
    const nlohmann::json& categories = json.at("categories");
    if (!categories.is_array()) throw Error(origin + ": \"categories\" is not a list");
    list.category_names.emplace();
    for (size_t k = 0; k < categories.size(); ++k) {
      const nlohmann::json& category = categories[k];
      if (!category.is_object() || !category.contains("id") || !category.contains("name") ||
          !category.at("id").is_number_integer() || !category.at("name").is_string()) {
        throw Error(fmt::format("{}: categories[{}] needs an integer \"id\" and a \"name\"", origin, k));
      }
      (*list.category_names)[category.at("id").get<long long>()] = category.at("name").get<std::string>();
    }
  }
  return list;
}

// The COCO category of a detection's category_id: by name through the listed
// categories, else as a COCO id.
int CocoCategoryOf(long long category_id, const std::optional<ImageList>& images, const std::string& origin) {
  if (images.has_value() && images->category_names.has_value()) {
    const auto named = images->category_names->find(category_id);
    if (named == images->category_names->end()) {
      throw Error(fmt::format("{}: category_id {} is not among the categories of {}", origin, category_id,
                              images->origin));
    }
    const CocoCategory* category = FindCocoCategoryByName(named->second);
    if (category == nullptr) {
      throw Error(fmt::format("{}: category_id {} is \"{}\" in {}, which is not a COCO category name", origin,
                              category_id, named->second, images->origin));
    }
    return category->id;
  }
  const CocoCategory* category =
      category_id >= 1 && category_id <= 90 ? FindCocoCategory(static_cast<int>(category_id)) : nullptr;
  if (category == nullptr) {
    throw Error(fmt::format("{}: category_id {} is not a COCO category id (with other ids, give an image list "
                            "whose \"categories\" name them)",
                            origin, category_id));
  }
  return category->id;
}

// An image list written by segslam (a generated sequence's annotations_coco.json, `masks
// images`) names its sequence's first frame and that file's SHA-256: the same first file
// name with another image is another sequence with the same stamps.
void CheckImageListIsForSequence(const nlohmann::json& list, const std::string& origin, const TumSequence& sequence) {
  if (!list.is_object() || !list.contains("info") || !list.at("info").is_object() || sequence.size() == 0) return;
  const nlohmann::json& info = list.at("info");
  const auto first_frame = info.find("first_frame");
  const auto sha = info.find("first_frame_sha256");
  if (first_frame == info.end() || sha == info.end() || !first_frame->is_string() || !sha->is_string()) return;
  if (first_frame->get<std::string>() != sequence.entries().front().rgb_file) return;
  if (sha->get<std::string>() != sequence.FirstFrameSha256()) {
    const auto description = info.find("description");
    throw Error(fmt::format("{}: made for another sequence than {} (its first frame, {}, is another image; info: {})",
                            origin, sequence.dir().string(), first_frame->get<std::string>(),
                            description != info.end() && description->is_string() ? description->get<std::string>()
                                                                                   : std::string("-")));
  }
}

}  // namespace

CocoDetections CocoDetections::Read(const fs::path& file, const TumSequence& sequence,
                                    const CocoImportOptions& options) {
  const nlohmann::json json = ReadJsonFile(file);
  const std::string origin = file.string();
  const bool dataset_file = json.is_object() && json.contains("annotations");
  if (!json.is_array() && !dataset_file) {
    throw Error(origin + ": expected a COCO results list, or a COCO dataset object with \"annotations\"");
  }
  // A network that ran finds something somewhere; an empty list is a failed or wrong export,
  // and its folder of empty masks would pass for "nothing in view" in every frame.
  if (const nlohmann::json& listed = dataset_file ? json.at("annotations") : json; listed.is_array() && listed.empty()) {
    throw Error(origin + (dataset_file ? ": \"annotations\" is an empty list" : ": an empty results list") +
                ": no detection to import (did the network run on this sequence's images?)");
  }
  std::optional<ImageList> images;
  if (!options.images_file.empty()) {
    const nlohmann::json list = ReadJsonFile(options.images_file);
    CheckImageListIsForSequence(list, options.images_file.string(), sequence);
    images = ReadImageList(list, options.images_file.string());
  } else if (dataset_file) {
    CheckImageListIsForSequence(json, origin, sequence);
    images = ReadImageList(json, origin);
  }
  const nlohmann::json& detections = dataset_file ? json.at("annotations") : json;
  if (!detections.is_array()) throw Error(origin + ": \"annotations\" is not a list");

  std::unordered_map<std::string, size_t> frame_of_stem;
  for (size_t i = 0; i < sequence.size(); ++i) {
    frame_of_stem[sequence.FrameStem(i)] = i;
  }

  CocoDetections result;
  result.per_frame_.resize(sequence.size());
  result.image_size_ = cv::Size(sequence.camera().intrinsics.width, sequence.camera().intrinsics.height);
  CocoImportCounts& counts = result.counts_;
  for (size_t k = 0; k < detections.size(); ++k) {
    const nlohmann::json& entry = detections[k];
    ++counts.detections;
    if (!entry.is_object() || !entry.contains("image_id") || !entry.contains("category_id") ||
        !entry.contains("segmentation")) {
      throw Error(fmt::format("{}: detection {} needs \"image_id\", \"category_id\" and \"segmentation\"", origin, k));
    }
    const nlohmann::json& image_id = entry.at("image_id");
    if (!image_id.is_number_integer() && !image_id.is_string()) {
      throw Error(fmt::format("{}: detection {}: image_id is neither an integer nor a string", origin, k));
    }
    const std::string where = fmt::format("{}: detection {} (image_id {})", origin, k, IdText(image_id));
    if (entry.contains("iscrowd")) {
      const nlohmann::json& crowd = entry.at("iscrowd");
      if (!crowd.is_boolean() && !crowd.is_number_integer()) {
        throw Error(where + ": iscrowd is neither 0/1 nor true/false");
      }
      if (crowd.is_boolean() ? crowd.get<bool>() : crowd.get<long long>() != 0) {
        ++counts.crowd;
        continue;
      }
    }

    std::string stem;
    const std::string* listed_stem = nullptr;
    if (images.has_value()) {
      const auto listed = images->stem_of.find(IdText(image_id));
      if (listed != images->stem_of.end()) listed_stem = &listed->second;
    }
    if (listed_stem != nullptr) {
      stem = *listed_stem;
    } else if (image_id.is_string()) {
      stem = image_id.get<std::string>();
    } else if (images.has_value()) {
      throw Error(fmt::format("{}: image_id {} is not in the image list of {}", where, IdText(image_id),
                              images->origin));
    } else {
      throw Error(where + ": an integer image_id needs the image list the segmenter ran on (--images FILE; "
                          "`segslam masks images` writes one for a sequence)");
    }
    const auto frame = frame_of_stem.find(stem);
    if (frame == frame_of_stem.end()) {
      ++counts.other_images;
      continue;
    }
    // Polygons and RLE are in the listed image's pixels: another size is another image.
    if (images.has_value()) {
      const auto size = images->size_of.find(IdText(image_id));
      if (size != images->size_of.end() && size->second != result.image_size_) {
        throw Error(fmt::format("{}: the image list of {} gives its image {}x{}, but the sequence's frames are "
                                "{}x{}",
                                where, images->origin, size->second.width, size->second.height,
                                result.image_size_.width, result.image_size_.height));
      }
    }

    if (!entry.at("category_id").is_number_integer()) throw Error(where + ": category_id is not an integer");
    Detection detection;
    detection.category_id = CocoCategoryOf(entry.at("category_id").get<long long>(), images, where);
    if (entry.contains("score")) {
      const nlohmann::json& score = entry.at("score");
      if (!score.is_number() || !(score.get<double>() >= 0.0 && score.get<double>() <= 1.0)) {
        throw Error(where + ": score is not a number in [0, 1]");
      }
      detection.score = score.get<float>();
    }
    // On the score as written: 0.7f is below 0.7.
    if (entry.contains("score") && entry.at("score").get<double>() < options.min_score) {
      ++counts.below_min_score;
      continue;
    }
    detection.segmentation = entry.at("segmentation");
    detection.origin = where;
    std::vector<Detection>& on_frame = result.per_frame_[frame->second];
    if (on_frame.size() == 65535) throw Error(where + ": more than 65535 detections kept on one frame");
    ++counts.kept;
    ++counts.kept_per_category[detection.category_id];
    on_frame.push_back(std::move(detection));
  }
  if (counts.detections > 0 && counts.kept + counts.below_min_score == 0 && counts.other_images > 0) {
    throw Error(fmt::format("{}: none of its {} detections is on a frame of {} (is it this sequence's file?)", origin,
                            counts.detections, sequence.dir().string()));
  }
  for (std::vector<Detection>& on_frame : result.per_frame_) {
    std::stable_sort(on_frame.begin(), on_frame.end(),
                     [](const Detection& a, const Detection& b) { return a.score > b.score; });
    if (!on_frame.empty()) ++counts.frames_with_detections;
  }
  return result;
}

FrameSegmentation CocoDetections::Frame(size_t i) const {
  if (i >= per_frame_.size()) {
    throw Error(fmt::format("frame {} is out of range (the sequence has {} frames)", i, per_frame_.size()));
  }
  FrameSegmentation segmentation;
  segmentation.frame_index = static_cast<int>(i);
  std::uint16_t next_id = 1;
  for (const Detection& detection : per_frame_[i]) {
    InstanceMask instance;
    instance.track_id = next_id++;
    instance.category_id = detection.category_id;
    instance.score = detection.score;
    instance.mask = DecodeCocoSegmentation(detection.segmentation, image_size_, detection.origin);
    FitBounds(&instance);
    segmentation.instances.push_back(std::move(instance));
  }
  return segmentation;
}

nlohmann::json CocoResultsOfFrame(const FrameSegmentation& masks, int image_id) {
  nlohmann::json results = nlohmann::json::array();
  for (const InstanceMask& instance : masks.instances) {
    const cv::Rect box = cv::boundingRect(instance.mask);
    if (box.area() == 0) continue;
    results.push_back({{"image_id", image_id},
                       {"category_id", instance.category_id},
                       {"segmentation",
                        {{"size", {instance.mask.rows, instance.mask.cols}},
                         {"counts", EncodeCocoRleString(CocoRleCounts(instance.mask))}}},
                       {"bbox", {box.x, box.y, box.width, box.height}},
                       {"score", instance.score}});
  }
  return results;
}

}  // namespace segslam::seg
