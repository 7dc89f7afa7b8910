// An instance segmenter's detections in COCO's format, mapped onto the frames of a
// sequence, so that any network's output can feed the core (`segslam masks import`
// writes them in the external-mask layout of seg/external_masks.h), and masks written
// back in that format (`segslam masks export`), for COCO's own evaluation tools.
//
// Accepted files:
//   - a results file, as detectron2, MMDetection or ultralytics (save_json) write it for
//     COCO evaluation: a list of {"image_id", "category_id", "segmentation", "score"};
//   - a dataset file: {"images", "annotations", "categories"}, e.g. COCO ground truth or
//     a segslam dataset's annotations_coco.json (crowd annotations are skipped; no score
//     means 1).
// "segmentation" may be compressed or uncompressed RLE or polygons (core/coco_rle.h), on
// the images as stored (distorted, if the camera is).
//
// Which frame a detection is on: an integer image_id is looked up in an image list
// ("images": [{"id", "file_name"}, ...]: the dataset file's own, or the file given as
// CocoImportOptions::images_file, e.g. what `segslam masks images` wrote), and the stem
// of its file_name is matched to the stem of a frame's colour file
// (rgb/1305031102.175304.png -> 1305031102.175304); a string image_id that the list does
// not hold is such a stem itself (ultralytics writes the file's stem where it is not a
// number). Detections on
// images of the list that are not frames of this sequence are counted and skipped.
//
// Categories: category_id is read through the "categories" of the file that has the
// image list, by name (a COCO name, core/coco.h), when it has them; else it must be a
// COCO category id.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "core/tum_dataset.h"
#include "seg/segmentation.h"

namespace segslam::seg {

struct CocoImportOptions {
  // Detections scoring lower are dropped (detectron2's demo shows 0.5 and up; its
  // results files for evaluation go down to 0.05).
  double min_score = 0.5;
  // An image list for a results file with integer image ids; empty: none.
  std::filesystem::path images_file;
};

struct CocoImportCounts {
  int detections = 0;          // entries in the file
  int other_images = 0;        // on images that are not frames of the sequence
  int crowd = 0;               // crowd annotations of a dataset file, skipped
  int below_min_score = 0;
  int kept = 0;                // on the sequence's frames, kept
  int frames_with_detections = 0;
  std::map<int, int> kept_per_category;  // COCO category id -> kept detections
};

class CocoDetections {
 public:
  // Reads and checks the whole file (structure, image ids, categories, scores; the masks
  // are decoded by Frame()). Throws segslam::Error naming the file, the detection's index
  // and what is wrong: unreadable or malformed JSON, a detection without image_id,
  // category_id or segmentation, an integer image_id without an image list, an image_id
  // missing from the list, an unknown category, a score outside [0, 1], more than 65535
  // kept detections on one frame, no detection at all (an empty list), or none on the
  // sequence's frames (the file is for other images).
  static CocoDetections Read(const std::filesystem::path& file, const TumSequence& sequence,
                             const CocoImportOptions& options);

  size_t num_frames() const { return per_frame_.size(); }
  // Frame i's kept detections, decoded, by descending score (file order among equal
  // scores) with track ids 1, 2, ... in that order. Throws segslam::Error naming the
  // file and detection when its segmentation is malformed or made for another image size.
  FrameSegmentation Frame(size_t i) const;
  const CocoImportCounts& counts() const { return counts_; }

 private:
  struct Detection {
    int category_id = 0;  // COCO
    float score = 1.0f;
    nlohmann::json segmentation;
    std::string origin;  // "<file>: detection <k> (image_id <id>)"
  };

  std::vector<std::vector<Detection>> per_frame_;
  cv::Size image_size_;
  CocoImportCounts counts_;
};

// A frame's instances as entries of a COCO results list, the inverse of CocoDetections:
// {"image_id", "category_id", "segmentation" (compressed RLE), "bbox" [x, y, w, h],
// "score"}, in the order of `masks`; instances without a pixel are left out. The masks
// should lie on the stored images (TumSequence::InstanceMaskAsStored), as a network's do.
nlohmann::json CocoResultsOfFrame(const FrameSegmentation& masks, int image_id);

}  // namespace segslam::seg
