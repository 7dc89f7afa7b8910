// RGB-D sequences in the TUM RGB-D layout (Sturm et al., IROS 2012):
//   <dir>/rgb.txt, depth.txt       "timestamp filename" lines, '#' comments
//   <dir>/rgb/<stamp>.png          8-bit colour
//   <dir>/depth/<stamp>.png        16-bit depth, value = metres * depth_factor, 0 = none
//   <dir>/associations.txt         optional "rgb_stamp rgb_file depth_stamp depth_file"
//   <dir>/groundtruth.txt          optional TUM trajectory of T_wc (pose.h)
//   <dir>/camera.yaml              segslam's addition: intrinsics and depth factor
// Everything read is validated at Open(); problems throw segslam::Error naming the file
// (and line or key) and what is wrong.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "core/camera.h"
#include "core/frame.h"
#include "core/lens_distortion.h"
#include "core/pose.h"

namespace segslam {

struct SequenceCamera {
  PinholeCamera intrinsics;   // Of the (registered) colour and depth images.
  double depth_factor = 5000; // Stored depth value per metre, > 0 (5000: TUM indoors).
  // Of the stored images; TumSequence::LoadFrame returns them undistorted (see
  // core/lens_distortion.h). Zero for generated datasets and TUM freiburg3.
  LensDistortion distortion;

  // The one check of every camera segslam reads or generates: the intrinsics
  // (PinholeCamera::IsValid), the depth factor, and a lens that covers the whole image
  // (LensCoversImage).
  bool IsValid(std::string* error) const;
};

// camera.yaml with the keys width, height, fx, fy, cx, cy, depth_factor, and optionally
// the distortion coefficients k1, k2, p1, p2, k3 (OpenCV's, TUM's d0..d4; absent: 0).
// Throws naming the file and key on a missing or unknown key, a wrong type, malformed
// YAML, a repeated key, or invalid values (see SequenceCamera::IsValid).
SequenceCamera ReadCameraYaml(const std::filesystem::path& path);
// Writes camera.yaml atomically; numbers are written with round-trip precision, the
// distortion coefficients only when there is distortion.
void WriteCameraYaml(const std::filesystem::path& path, const SequenceCamera& camera);

// The published TUM RGB-D calibration of the colour camera (640x480, depth factor 5000,
// with the distortion of freiburg1 and freiburg2) if `sequence_name` contains
// "freiburg1", "freiburg2" or "freiburg3"; std::nullopt otherwise.
std::optional<SequenceCamera> TumDefaultCamera(const std::string& sequence_name);

struct TumFrameEntry {
  double rgb_stamp_s = 0;
  std::string rgb_file;    // Relative to the sequence directory, e.g. "rgb/1.000000.png".
  double depth_stamp_s = 0;
  std::string depth_file;  // Relative to the sequence directory.
};

// TUM associate.py's greedy matching: all (rgb, depth) pairs with
// |rgb stamp - depth stamp| < max_difference_s are sorted by that difference and taken
// greedily when neither stamp is used yet; the result is sorted by rgb stamp.
// (associate.py's offset is 0 here.)
std::vector<TumFrameEntry> AssociateByTimestamp(
    const std::vector<std::pair<double, std::string>>& rgb,
    const std::vector<std::pair<double, std::string>>& depth,
    double max_difference_s = 0.02);

// Reads a TUM file list ("timestamp filename" per line, '#' comments, blank lines
// skipped). Throws on a malformed line, NaN or non-increasing stamps, naming file:line.
std::vector<std::pair<double, std::string>> ReadTumFileList(const std::filesystem::path& path);

// Reads associations.txt ("rgb_stamp rgb_file depth_stamp depth_file" per line, rgb
// stamps increasing; the images are not checked). Throws naming file:line.
std::vector<TumFrameEntry> ReadTumAssociations(const std::filesystem::path& associations);

// A TUM-layout sequence opened for reading. Copyable value (lists, and for a distorted
// camera the undistortion maps, shared between copies).
class TumSequence {
 public:
  // Camera from `camera` if given, else <dir>/camera.yaml, else TumDefaultCamera(name of
  // dir), else throws asking the user to add camera.yaml. Reads rgb.txt and depth.txt;
  // frames come from associations.txt if present, else from AssociateByTimestamp.
  // groundtruth.txt is optional. Throws on missing lists, image files listed but
  // missing, non-increasing stamps, malformed lines, an empty sequence.
  static TumSequence Open(const std::filesystem::path& dir,
                          std::optional<SequenceCamera> camera = std::nullopt);
  // Open() with the camera read from camera_yaml when one is named (the commands'
  // --camera, for a real sequence without camera.yaml), else as Open(dir).
  static TumSequence OpenWithCameraFile(const std::filesystem::path& dir, const std::string& camera_yaml);

  size_t size() const { return entries_.size(); }
  const std::vector<TumFrameEntry>& entries() const { return entries_; }

  // Loads frame i (0 <= i < size(), else throws): colour CV_8UC3 and depth CV_32F
  // metres, stamp = rgb stamp, undistorted when the camera has distortion. Throws naming
  // the file if an image is unreadable, has the wrong type, or a size other than the
  // camera's.
  RgbdFrame LoadFrame(size_t i) const;

  // Frame i's colour file name without folder and extension ("rgb/1.305031.png" ->
  // "1.305031"): the name the frame's other files take, its ground-truth mask
  // masks/<stem>.png and a mask folder's <stem>.png and <stem>.json (seg/external_masks.h).
  // Throws as LoadFrame does for i out of range.
  std::string FrameStem(size_t i) const;

  // SHA-256 of the first frame's colour file, lowercase hex: what tells this sequence
  // from another with the same stamps (the two passes of a generated dataset, or two
  // datasets, share them). Throws naming the file if it cannot be read or there is none.
  std::string FirstFrameSha256() const;

  // An instance mask (16-bit PNG) drawn on this sequence's stored images, e.g. by an
  // external segmenter, in the geometry of LoadFrame's images. Throws naming the file if
  // it is unreadable, not 16-bit single-channel or of a size other than the camera's.
  cv::Mat LoadInstanceMask(const std::filesystem::path& png) const;
  // An id or mask image (any type, the camera's size) of the stored images in LoadFrame's
  // geometry (nearest pixel), and back: what a run writes beside the sequence. The image
  // itself when there is no distortion.
  cv::Mat InstanceMaskAsLoaded(const cv::Mat& stored_ids) const;
  cv::Mat InstanceMaskAsStored(const cv::Mat& ids) const;

  const SequenceCamera& camera() const { return camera_; }
  const std::filesystem::path& dir() const { return dir_; }
  bool has_groundtruth() const { return !groundtruth_.empty(); }
  // T_wc poses at their own (e.g. motion-capture) stamps, not per frame.
  const std::vector<StampedPose>& groundtruth() const { return groundtruth_; }

 private:
  // entries_[i]; throws segslam::FileError naming the folder for i out of range.
  const TumFrameEntry& Entry(size_t i) const;

  std::filesystem::path dir_;
  SequenceCamera camera_;
  std::vector<TumFrameEntry> entries_;
  std::vector<StampedPose> groundtruth_;
  std::shared_ptr<const ImageUndistorter> undistorter_;  // Null without distortion.
};

// Writes a sequence in the TUM layout. Add() per frame, then Finish(); until Finish()
// there are images but no frame lists, and Finish() writes the lists last, so a crashed
// run does not look like a complete sequence. Not copyable; use from one thread.
class TumSequenceWriter {
 public:
  // Creates dir, dir/rgb and dir/depth (throws on failure or an invalid camera).
  TumSequenceWriter(std::filesystem::path dir, SequenceCamera camera);
  TumSequenceWriter(const TumSequenceWriter&) = delete;
  TumSequenceWriter& operator=(const TumSequenceWriter&) = delete;
  TumSequenceWriter(TumSequenceWriter&&) = default;
  TumSequenceWriter& operator=(TumSequenceWriter&&) = default;

  // Writes rgb/<StampName>.png and depth/<StampName>.png (atomically) and records the
  // frame with its pose T_wc. Throws if the stamp does not increase, the images have the
  // wrong type or size, or writing fails.
  void Add(const RgbdFrame& frame, const Eigen::Isometry3d& T_wc);

  // Records a frame whose images the caller writes itself (e.g. in parallel) to
  // RgbPath(stamp_s) and DepthPath(stamp_s) before Finish(). Throws if the stamp does
  // not increase.
  void AddEntry(double stamp_s, const Eigen::Isometry3d& T_wc);

  // Writes camera.yaml, groundtruth.txt, then the frame lists rgb.txt, depth.txt and
  // associations.txt, each atomically: TumSequence::Open accepts the folder only once a
  // list is there, and by then so is everything else. Throws on failure. Add() after
  // Finish() throws.
  void Finish();

  std::filesystem::path RgbPath(double stamp_s) const;    // dir/rgb/<stamp>.png
  std::filesystem::path DepthPath(double stamp_s) const;  // dir/depth/<stamp>.png
  const std::filesystem::path& dir() const { return dir_; }
  const SequenceCamera& camera() const { return camera_; }

  // The stamp as written in file names and lists: "%.6f".
  static std::string StampName(double stamp_s);

 private:
  std::filesystem::path dir_;
  SequenceCamera camera_;
  std::vector<StampedPose> poses_;
  bool finished_ = false;
};

}  // namespace segslam
