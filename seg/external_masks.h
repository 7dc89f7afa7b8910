// Instance masks computed by an external network (Mask R-CNN, YOLO-seg, SAM + a
// classifier, ...), read from a folder, so the core runs on real TUM RGB-D sequences.
//
// Folder layout, one pair of files per frame of the sequence, named after the stem of the
// frame's colour file (rgb/1305031102.175304.png -> 1305031102.175304):
//   <dir>/<stem>.png   16-bit single-channel PNG (CV_16U), the frame's size;
//                      0 = background, k > 0 = the detection with id k.
//   <dir>/<stem>.json  {"instances": [{"id": 3, "category_id": 1, "score": 0.93},
//                                     {"id": 4, "category": "cup", "score": 0.41}, ...]}
// Each entry names its class by COCO id ("category_id") or COCO name ("category"), or both
// (then they must agree); "score" is the confidence in [0, 1] (optional, default 1).
// Every nonzero id of the PNG must have an entry; an entry whose id does not occur in
// the PNG is allowed (the detection was hidden by others) and yields no instance.
// Ids need not be stable over frames. The masks lie on the stored colour images; with a
// distorted camera they are undistorted as the frames are (TumSequence::LoadInstanceMask).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "core/tum_dataset.h"
#include "seg/segmenter.h"

namespace segslam::seg {

// One entry of a frame's class table.
struct ExternalDetection {
  int category_id = 0;  // COCO category id.
  float score = 1.0f;   // [0, 1].
};

// Parses a frame's JSON table; `origin` (the file name) starts every error message.
// Throws segslam::Error on a missing "instances" array, an entry that is not an object or
// has unknown keys, an id outside
// 1..65535 or repeated, an unknown COCO id or name, id and name that disagree, or a score
// outside [0, 1].
std::map<std::uint16_t, ExternalDetection> ParseExternalMaskTable(const nlohmann::json& json,
                                                                   const std::string& origin);

// Turns an id image and its table into a segmentation. Throws segslam::Error starting with
// `origin` if `ids` is not CV_16UC1, not of `frame_size`, or holds a nonzero id missing
// from `table`.
FrameSegmentation ExternalMasksToSegmentation(
    const cv::Mat& ids, const std::map<std::uint16_t, ExternalDetection>& table,
    cv::Size frame_size, int frame_index, const std::string& origin);

// Writes one frame's masks in the layout above, each file atomically: <dir>/<stem>.png,
// the id image `stored_ids` (CV_16UC1, on the stored images), and <dir>/<stem>.json, the
// class table of `masks`' instances (their track ids, categories and scores).
void WriteExternalMaskFiles(const std::filesystem::path& dir, const std::string& stem, const cv::Mat& stored_ids,
                            const FrameSegmentation& masks);

// Records in <dir>/segslam_sequence.json which sequence a folder of masks was made for (its
// first frame's colour file and that file's SHA-256), as segslam's own writers do (a
// run's refined_masks/, `masks import`): frames of another sequence often share the stems.
void WriteMaskFolderRecord(const std::filesystem::path& dir, const TumSequence& sequence);

// Reads the masks of a sequence's frames from a folder. Not copyable.
class ExternalMaskSegmenter : public Segmenter {
 public:
  // Checks that `dir` is a folder and holds <stem>.png and <stem>.json for every frame of
  // `sequence`, or for its first `frames` when that is above 0 (a run cut with --frames,
  // fed the masks of an earlier cut run), and that its segslam_sequence.json, where there is one
  // (WriteMaskFolderRecord), names this sequence's first frame; throws segslam::Error
  // naming the first missing file (a folder that skips frames) or the record otherwise.
  // The files' contents are checked frame by frame in Segment().
  ExternalMaskSegmenter(const std::filesystem::path& dir, const TumSequence& sequence, size_t frames = 0);
  ExternalMaskSegmenter(const ExternalMaskSegmenter&) = delete;
  ExternalMaskSegmenter& operator=(const ExternalMaskSegmenter&) = delete;

  // Reads frame.index's files. Throws segslam::Error naming the file and what is wrong:
  // unreadable, not 16-bit single-channel, of another size than the sequence's images or
  // the frame (frame.color_bgr), an id missing from the table, a bad table (see
  // ParseExternalMaskTable), or frame.index out of range.
  FrameSegmentation Segment(const RgbdFrame& frame) override;
  // "external:<dir>".
  std::string name() const override;

  std::filesystem::path MaskPath(size_t i) const;   // <dir>/<stem>.png of frame i.
  std::filesystem::path TablePath(size_t i) const;  // <dir>/<stem>.json of frame i.

 private:
  std::filesystem::path dir_;
  TumSequence sequence_;
};

}  // namespace segslam::seg
