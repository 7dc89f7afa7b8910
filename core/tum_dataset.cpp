#include "core/tum_dataset.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/input_file.h"
#include "core/image_io.h"
#include "core/manifest.h"
#include "core/yaml_file.h"

namespace segslam {
namespace {

// Calls `on_line(tokens, origin)` for each non-comment, non-blank line of a text file.
template <typename OnLine>
void ForEachDataLine(const std::filesystem::path& path, OnLine on_line) {
  std::ifstream file = OpenInputFile(path);
  std::string line;
  for (int line_number = 1; std::getline(file, line); ++line_number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    on_line(SplitTumFields(line), fmt::format("{}:{}", path.string(), line_number));
  }
  if (file.bad()) throw FileError(path, "read error");
}

double ParseStamp(const std::string& token, const std::string& origin) {
  double stamp = 0;
  if (!ParseTumNumber(token, &stamp)) {
    throw Error(fmt::format("{}: timestamp '{}' is not a finite number", origin, PrintableText(token)));
  }
  return stamp;
}

const char* const kCameraKeys[] = {"width", "height", "fx", "fy", "cx", "cy", "depth_factor",
                                   "k1", "k2", "p1", "p2", "k3"};

}  // namespace

bool SequenceCamera::IsValid(std::string* error) const {
  if (!intrinsics.IsValid(error)) return false;
  if (!std::isfinite(depth_factor) || depth_factor <= 0) {
    if (error != nullptr) *error = "depth_factor must be finite and positive";
    return false;
  }
  // The check a scenario's camera passes too (scenes/scenario.cpp), so that a camera
  // generate refuses cannot be given to run or eval.
  return distortion.IsValid(error) && LensCoversImage(distortion, intrinsics, error);
}

namespace {

SequenceCamera CameraFromYaml(const YAML::Node& root, const std::filesystem::path& path) {
  if (!root.IsMap()) throw FileError(path, "expected a map of camera keys");
  for (const auto& item : root) {
    const int line = item.first.Mark().line + 1;
    if (!item.first.IsScalar()) throw FileError(path, fmt::format("line {}: a key must be a plain name", line));
    const std::string& key = item.first.Scalar();
    if (std::find(std::begin(kCameraKeys), std::end(kCameraKeys), key) == std::end(kCameraKeys)) {
      throw FileError(path, "unknown key '" + PrintableText(key) +
                                "' (expected width, height, fx, fy, cx, cy, depth_factor, and "
                                "optionally k1, k2, p1, p2, k3)");
    }
  }
  auto get_double = [&](const char* key) {
    const YAML::Node node = root[key];
    if (!node) throw FileError(path, std::string("missing key '") + key + "'");
    double value = 0;
    if (!node.IsScalar() || !ParseTumNumber(node.Scalar(), &value)) {
      throw FileError(path, std::string("key '") + key + "' must be a finite number");
    }
    return value;
  };
  auto get_int = [&](const char* key) {
    const double value = get_double(key);
    if (value != std::floor(value) || std::abs(value) > 1e9) {
      throw FileError(path, std::string("key '") + key + "' must be an integer");
    }
    return static_cast<int>(value);
  };
  SequenceCamera camera;
  camera.intrinsics.width = get_int("width");
  camera.intrinsics.height = get_int("height");
  camera.intrinsics.fx = get_double("fx");
  camera.intrinsics.fy = get_double("fy");
  camera.intrinsics.cx = get_double("cx");
  camera.intrinsics.cy = get_double("cy");
  camera.depth_factor = get_double("depth_factor");
  auto get_optional = [&](const char* key) { return root[key] ? get_double(key) : 0.0; };
  camera.distortion = {get_optional("k1"), get_optional("k2"), get_optional("p1"), get_optional("p2"),
                       get_optional("k3")};
  std::string error;
  if (!camera.IsValid(&error)) throw FileError(path, "invalid camera: " + error);
  return camera;
}

}  // namespace

SequenceCamera ReadCameraYaml(const std::filesystem::path& path) {
  // LoadYamlFile refuses a missing file, a folder, bad syntax and repeated keys.
  const YAML::Node root = LoadYamlFile(path);
  // Around the whole read: yaml-cpp throws from conversions too, not only from parsing,
  // and its exceptions would reach the CLI as an internal error without the file's name.
  try {
    return CameraFromYaml(root, path);
  } catch (const YAML::Exception& e) {
    throw FileError(path, std::string("malformed YAML: ") + e.what());
  }
}

void WriteCameraYaml(const std::filesystem::path& path, const SequenceCamera& camera) {
  std::string error;
  if (!camera.IsValid(&error)) throw FileError(path, "refusing to write invalid camera: " + error);
  const PinholeCamera& k = camera.intrinsics;
  // fmt's "{}" prints the shortest text that reads back to the same double.
  const std::string text = fmt::format(
      "# Pinhole intrinsics in pixels (OpenCV convention: pixel centres at integers).\n"
      "# depth_factor: stored 16-bit depth value per metre (0 = no depth).\n"
      "width: {}\nheight: {}\nfx: {}\nfy: {}\ncx: {}\ncy: {}\ndepth_factor: {}\n",
      k.width, k.height, k.fx, k.fy, k.cx, k.cy, camera.depth_factor);
  const LensDistortion& d = camera.distortion;
  const std::string distortion =
      d.IsZero() ? ""
                 : fmt::format("# Lens distortion of the stored images (OpenCV's k1, k2, p1, p2, k3).\n"
                               "k1: {}\nk2: {}\np1: {}\np2: {}\nk3: {}\n",
                               d.k1, d.k2, d.p1, d.p2, d.k3);
  WriteFileAtomically(path, text + distortion);
}

std::optional<SequenceCamera> TumDefaultCamera(const std::string& sequence_name) {
  // Published calibrations of the colour cameras from the TUM RGB-D "file formats" page,
  // d0..d4 being OpenCV's k1, k2, p1, p2, k3 (freiburg3: TUM's own calibration, no
  // distortion, as its images are already undistorted).
  struct Known {
    const char* tag;
    double fx, fy, cx, cy;
    LensDistortion distortion;
  };
  static const Known kKnown[] = {
      {"freiburg1", 517.3, 516.5, 318.6, 255.3, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633}},
      {"freiburg2", 520.9, 521.0, 325.1, 249.7, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172}},
      {"freiburg3", 535.4, 539.2, 320.1, 247.6, {}}};
  for (const Known& known : kKnown) {
    if (sequence_name.find(known.tag) != std::string::npos) {
      SequenceCamera camera;
      camera.intrinsics = {640, 480, known.fx, known.fy, known.cx, known.cy};
      camera.depth_factor = 5000;
      camera.distortion = known.distortion;
      return camera;
    }
  }
  return std::nullopt;
}

std::vector<TumFrameEntry> AssociateByTimestamp(
    const std::vector<std::pair<double, std::string>>& rgb,
    const std::vector<std::pair<double, std::string>>& depth, double max_difference_s) {
  // associate.py forms all pairs with |a - b| < max_difference, sorts the tuples
  // (diff, a, b) and takes each whose stamps are both unused. Sorting depth stamps lets
  // us enumerate only the pairs inside the window instead of all N*M.
  std::vector<size_t> depth_order(depth.size());
  for (size_t j = 0; j < depth.size(); ++j) depth_order[j] = j;
  std::sort(depth_order.begin(), depth_order.end(),
            [&](size_t a, size_t b) { return depth[a].first < depth[b].first; });
  std::vector<double> depth_sorted(depth.size());
  for (size_t j = 0; j < depth.size(); ++j) depth_sorted[j] = depth[depth_order[j]].first;

  struct Candidate {
    double diff, a, b;
    size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < rgb.size(); ++i) {
    const double a = rgb[i].first;
    // A window twice as wide as the test, so that rounding of a +- max_difference_s at
    // large stamps (1.3e9 s) cannot cut off a pair whose difference passes the test; its
    // end is inclusive, since at stamps beyond about 1e15 s a + 2 * max_difference_s
    // rounds to a itself.
    auto it = std::lower_bound(depth_sorted.begin(), depth_sorted.end(), a - 2 * max_difference_s);
    for (; it != depth_sorted.end() && *it <= a + 2 * max_difference_s; ++it) {
      const double diff = std::abs(a - *it);
      if (diff < max_difference_s) {
        const size_t k = static_cast<size_t>(it - depth_sorted.begin());
        candidates.push_back({diff, a, *it, i, depth_order[k]});
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.diff, x.a, x.b, x.i, x.j) < std::tie(y.diff, y.a, y.b, y.i, y.j);
  });
  std::vector<bool> rgb_used(rgb.size(), false), depth_used(depth.size(), false);
  std::vector<TumFrameEntry> matches;
  for (const Candidate& c : candidates) {
    if (rgb_used[c.i] || depth_used[c.j]) continue;
    rgb_used[c.i] = depth_used[c.j] = true;
    matches.push_back({rgb[c.i].first, rgb[c.i].second, depth[c.j].first, depth[c.j].second});
  }
  std::sort(matches.begin(), matches.end(), [](const TumFrameEntry& x, const TumFrameEntry& y) {
    return std::tie(x.rgb_stamp_s, x.depth_stamp_s) < std::tie(y.rgb_stamp_s, y.depth_stamp_s);
  });
  return matches;
}

std::vector<std::pair<double, std::string>> ReadTumFileList(const std::filesystem::path& path) {
  std::vector<std::pair<double, std::string>> list;
  ForEachDataLine(path, [&](const std::vector<std::string>& tokens, const std::string& origin) {
    if (tokens.size() != 2) {
      throw Error(fmt::format("{}: expected 'timestamp filename', found {} fields", origin,
                              tokens.size()));
    }
    const double stamp = ParseStamp(tokens[0], origin);
    if (!list.empty() && !(stamp > list.back().first)) {
      throw Error(fmt::format("{}: timestamp {} does not increase (previous {:.6f})", origin,
                              tokens[0], list.back().first));
    }
    list.emplace_back(stamp, tokens[1]);
  });
  return list;
}

namespace {

// Camera: explicit argument, then camera.yaml, then the published TUM calibration.
SequenceCamera ResolveSequenceCamera(const std::filesystem::path& dir,
                                     const std::optional<SequenceCamera>& camera) {
  const std::filesystem::path camera_yaml = dir / "camera.yaml";
  if (camera) {
    std::string error;
    if (!camera->IsValid(&error)) throw FileError(dir, "invalid camera: " + error);
    return *camera;
  }
  if (std::filesystem::exists(camera_yaml)) return ReadCameraYaml(camera_yaml);
  std::filesystem::path normal = std::filesystem::absolute(dir).lexically_normal();
  if (normal.filename().empty()) normal = normal.parent_path();
  const auto known = TumDefaultCamera(normal.filename().string());
  if (!known) {
    throw FileError(camera_yaml,
                    "no camera intrinsics: add camera.yaml with width, height, fx, fy, cx, "
                    "cy, depth_factor (only TUM freiburg1/2/3 sequences have defaults)");
  }
  return *known;
}

}  // namespace

std::vector<TumFrameEntry> ReadTumAssociations(const std::filesystem::path& associations) {
  std::vector<TumFrameEntry> entries;
  ForEachDataLine(associations, [&](const std::vector<std::string>& tokens,
                                    const std::string& origin) {
    if (tokens.size() != 4) {
      throw Error(fmt::format(
          "{}: expected 'rgb_stamp rgb_file depth_stamp depth_file', found {} fields", origin,
          tokens.size()));
    }
    TumFrameEntry entry{ParseStamp(tokens[0], origin), tokens[1],
                        ParseStamp(tokens[2], origin), tokens[3]};
    if (!entries.empty() && !(entry.rgb_stamp_s > entries.back().rgb_stamp_s)) {
      throw Error(fmt::format("{}: rgb timestamp {} does not increase", origin, tokens[0]));
    }
    entries.push_back(entry);
  });
  return entries;
}

namespace {

// Frames: associations.txt if present (then rgb.txt/depth.txt are not needed), else
// associate rgb.txt with depth.txt as TUM's associate.py does. Every listed image must exist.
std::vector<TumFrameEntry> ReadFrameEntries(const std::filesystem::path& dir) {
  const std::filesystem::path associations = dir / "associations.txt";
  std::vector<TumFrameEntry> entries;
  if (std::filesystem::exists(associations)) {
    entries = ReadTumAssociations(associations);
  } else {
    for (const char* list : {"rgb.txt", "depth.txt"}) {
      if (!std::filesystem::exists(dir / list)) {
        throw FileError(dir / list, "file list does not exist (a TUM sequence needs rgb.txt "
                                    "and depth.txt, or associations.txt)");
      }
    }
    entries = AssociateByTimestamp(ReadTumFileList(dir / "rgb.txt"), ReadTumFileList(dir / "depth.txt"));
  }
  if (entries.empty()) {
    throw FileError(std::filesystem::exists(associations) ? associations : dir,
                    "sequence has no frames (no rgb/depth pairs)");
  }
  std::error_code ec;
  for (const TumFrameEntry& entry : entries) {
    for (const std::string* file : {&entry.rgb_file, &entry.depth_file}) {
      if (!std::filesystem::is_regular_file(dir / *file, ec)) {
        throw FileError(dir / *file, "image file listed in the sequence does not exist");
      }
    }
  }
  return entries;
}

}  // namespace

TumSequence TumSequence::Open(const std::filesystem::path& dir,
                              std::optional<SequenceCamera> camera) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw FileError(dir, "sequence directory does not exist");
  }
  // A folder with no frame list at all is not a sequence: say so before asking for
  // its camera (a two-pass dataset's root, or the wrong folder).
  if (!std::filesystem::exists(dir / "associations.txt") && !std::filesystem::exists(dir / "rgb.txt") &&
      !std::filesystem::exists(dir / "depth.txt")) {
    throw FileError(dir, "not a TUM-layout sequence: no associations.txt, rgb.txt or depth.txt");
  }
  TumSequence sequence;
  sequence.dir_ = dir;
  sequence.camera_ = ResolveSequenceCamera(dir, camera);
  sequence.entries_ = ReadFrameEntries(dir);
  const std::filesystem::path groundtruth = dir / "groundtruth.txt";
  if (std::filesystem::exists(groundtruth)) {
    sequence.groundtruth_ = ReadTumTrajectory(groundtruth);
  }
  if (!sequence.camera_.distortion.IsZero()) {
    sequence.undistorter_ =
        std::make_shared<const ImageUndistorter>(sequence.camera_.intrinsics, sequence.camera_.distortion);
  }
  return sequence;
}

TumSequence TumSequence::OpenWithCameraFile(const std::filesystem::path& dir, const std::string& camera_yaml) {
  if (camera_yaml.empty()) return Open(dir);
  return Open(dir, ReadCameraYaml(camera_yaml));
}

std::string TumSequence::FirstFrameSha256() const {
  if (entries_.empty()) throw FileError(dir_, "the sequence has no frames");
  return Sha256OfFile(dir_ / entries_.front().rgb_file);
}

const TumFrameEntry& TumSequence::Entry(size_t i) const {
  if (i >= entries_.size()) {
    throw FileError(dir_, fmt::format("frame {} out of range (sequence has {} frames)", i,
                                      entries_.size()));
  }
  return entries_[i];
}

std::string TumSequence::FrameStem(size_t i) const {
  return std::filesystem::path(Entry(i).rgb_file).stem().string();
}

RgbdFrame TumSequence::LoadFrame(size_t i) const {
  const TumFrameEntry& entry = Entry(i);
  RgbdFrame frame;
  frame.index = static_cast<int>(i);
  frame.stamp_s = entry.rgb_stamp_s;
  // The readers refuse another size from a PNG's header, before decoding it.
  const cv::Size size(camera_.intrinsics.width, camera_.intrinsics.height);
  frame.color_bgr = ReadColorImage(dir_ / entry.rgb_file, size);
  frame.depth_m = ReadDepthImage(dir_ / entry.depth_file, camera_.depth_factor, size);
  if (undistorter_ != nullptr) {
    frame.color_bgr = undistorter_->UndistortColour(frame.color_bgr);
    frame.depth_m = undistorter_->UndistortDepth(frame.depth_m);
  }
  return frame;
}

cv::Mat TumSequence::LoadInstanceMask(const std::filesystem::path& png) const {
  return InstanceMaskAsLoaded(ReadInstanceMask(png, cv::Size(camera_.intrinsics.width, camera_.intrinsics.height)));
}

cv::Mat TumSequence::InstanceMaskAsLoaded(const cv::Mat& stored_ids) const {
  return undistorter_ != nullptr ? undistorter_->UndistortIds(stored_ids) : stored_ids;
}

cv::Mat TumSequence::InstanceMaskAsStored(const cv::Mat& ids) const {
  return undistorter_ != nullptr ? undistorter_->DistortIds(ids) : ids;
}

TumSequenceWriter::TumSequenceWriter(std::filesystem::path dir, SequenceCamera camera)
    : dir_(std::move(dir)), camera_(camera) {
  std::string error;
  if (!camera_.IsValid(&error)) throw FileError(dir_, "invalid camera: " + error);
  for (const std::filesystem::path& sub : {dir_, dir_ / "rgb", dir_ / "depth"}) {
    std::error_code ec;
    std::filesystem::create_directories(sub, ec);
    if (ec || !std::filesystem::is_directory(sub)) {
      throw FileError(sub, "cannot create directory: " + ec.message());
    }
  }
}

std::string TumSequenceWriter::StampName(double stamp_s) { return fmt::format("{:.6f}", stamp_s); }

std::filesystem::path TumSequenceWriter::RgbPath(double stamp_s) const {
  return dir_ / "rgb" / (StampName(stamp_s) + ".png");
}

std::filesystem::path TumSequenceWriter::DepthPath(double stamp_s) const {
  return dir_ / "depth" / (StampName(stamp_s) + ".png");
}

void TumSequenceWriter::AddEntry(double stamp_s, const Eigen::Isometry3d& T_wc) {
  if (finished_) throw FileError(dir_, "frame added after Finish()");
  if (!std::isfinite(stamp_s)) throw FileError(dir_, "frame timestamp is not finite");
  if (!T_wc.matrix().allFinite()) {
    throw FileError(dir_, "pose of frame " + StampName(stamp_s) + " is not finite");
  }
  // Compare the written names: two stamps closer than 1 us would share one file.
  if (!poses_.empty() && !(std::stod(StampName(stamp_s)) >
                           std::stod(StampName(poses_.back().stamp_s)))) {
    throw FileError(dir_, fmt::format("timestamp {} does not increase (previous {})",
                                      StampName(stamp_s), StampName(poses_.back().stamp_s)));
  }
  poses_.push_back({stamp_s, T_wc});
}

void TumSequenceWriter::Add(const RgbdFrame& frame, const Eigen::Isometry3d& T_wc) {
  const int w = camera_.intrinsics.width, h = camera_.intrinsics.height;
  if (frame.color_bgr.type() != CV_8UC3 || frame.color_bgr.cols != w ||
      frame.color_bgr.rows != h) {
    throw FileError(RgbPath(frame.stamp_s),
                    fmt::format("colour must be CV_8UC3 {}x{}, got {} {}x{}", w, h,
                                CvTypeName(frame.color_bgr.type()), frame.color_bgr.cols,
                                frame.color_bgr.rows));
  }
  if (frame.depth_m.type() != CV_32FC1 || frame.depth_m.cols != w || frame.depth_m.rows != h) {
    throw FileError(DepthPath(frame.stamp_s),
                    fmt::format("depth must be CV_32FC1 {}x{}, got {} {}x{}", w, h,
                                CvTypeName(frame.depth_m.type()), frame.depth_m.cols,
                                frame.depth_m.rows));
  }
  // Validate and record first, so a rejected frame writes nothing.
  AddEntry(frame.stamp_s, T_wc);
  WriteColorImage(RgbPath(frame.stamp_s), frame.color_bgr);
  WriteDepthImage(DepthPath(frame.stamp_s), frame.depth_m, camera_.depth_factor);
}

void TumSequenceWriter::Finish() {
  if (finished_) throw FileError(dir_, "Finish() called twice");
  std::string rgb = "# color images\n# file: 'segslam'\n# timestamp filename\n";
  std::string depth = "# depth maps\n# file: 'segslam'\n# timestamp filename\n";
  std::string associations;
  for (const StampedPose& pose : poses_) {
    const std::string name = StampName(pose.stamp_s);
    rgb += fmt::format("{} rgb/{}.png\n", name, name);
    depth += fmt::format("{} depth/{}.png\n", name, name);
    associations += fmt::format("{0} rgb/{0}.png {0} depth/{0}.png\n", name);
  }
  // TumSequence::Open accepts a folder once it has a frame list, and then needs neither
  // camera.yaml nor groundtruth.txt: write those first and the lists last, so an
  // interrupted run leaves a folder Open refuses rather than one without its camera or
  // ground truth. associations.txt, which Open reads in preference, comes last of all.
  WriteCameraYaml(dir_ / "camera.yaml", camera_);
  WriteTumTrajectory(dir_ / "groundtruth.txt", poses_,
                     "ground truth trajectory (camera-to-world T_wc, written by segslam)\n"
                     "timestamp tx ty tz qx qy qz qw");
  WriteFileAtomically(dir_ / "rgb.txt", rgb);
  WriteFileAtomically(dir_ / "depth.txt", depth);
  WriteFileAtomically(dir_ / "associations.txt", associations);
  finished_ = true;
}

}  // namespace segslam
