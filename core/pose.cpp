#include "core/pose.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/input_file.h"

namespace segslam {
namespace {

// Quaternion norms in TUM files deviate from 1 by the rounding of 4-7 printed digits;
// anything beyond this is a corrupt line, not rounding.
constexpr double kMaxQuaternionNormError = 1e-2;

}  // namespace

std::vector<std::string> SplitTumFields(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  for (const char c : line) {
    if (c == ' ' || c == ',' || c == '\t' || c == '\r' || c == '\n') {
      if (!field.empty()) fields.push_back(std::move(field));
      field.clear();
    } else {
      field.push_back(c);
    }
  }
  if (!field.empty()) fields.push_back(std::move(field));
  return fields;
}

bool ParseTumNumber(const std::string& token, double* value) {
  // strtod also reads hexadecimal ("0x1p3"), which Python's float() refuses.
  if (token.empty() || token.find_first_of("xX") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size() || !std::isfinite(v)) return false;
  // ERANGE also flags underflow (1e-310), which float() reads; only overflow is an error.
  if (errno == ERANGE && std::abs(v) == HUGE_VAL) return false;
  *value = v;
  return true;
}

std::string FormatTumPoseLine(const StampedPose& pose) {
  Eigen::Quaterniond q(pose.T_wc.rotation());
  q.normalize();
  // q and -q are the same rotation; qw >= 0 makes the written line unique.
  if (q.w() < 0) q.coeffs() *= -1.0;
  const Eigen::Vector3d t = pose.T_wc.translation();
  return fmt::format("{:.6f} {:.9g} {:.9g} {:.9g} {:.9f} {:.9f} {:.9f} {:.9f}", pose.stamp_s,
                     t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
}

StampedPose ParseTumPoseLine(const std::string& line, const std::string& origin_for_errors) {
  const std::vector<std::string> tokens = SplitTumFields(line);
  if (tokens.size() != 8) {
    throw Error(fmt::format(
        "{}: expected 8 fields 'timestamp tx ty tz qx qy qz qw', found {}",
        origin_for_errors, tokens.size()));
  }
  double v[8];
  static const char* const kNames[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  for (int i = 0; i < 8; ++i) {
    if (!ParseTumNumber(tokens[i], &v[i])) {
      throw Error(fmt::format("{}: field {} ({}) is not a finite number: '{}'",
                              origin_for_errors, i + 1, kNames[i], PrintableText(tokens[i])));
    }
  }
  Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > kMaxQuaternionNormError) {
    throw Error(fmt::format("{}: quaternion norm is {:.6g}, expected 1 (corrupt rotation)",
                            origin_for_errors, norm));
  }
  q.normalize();
  StampedPose pose;
  pose.stamp_s = v[0];
  pose.T_wc = Eigen::Isometry3d::Identity();
  pose.T_wc.linear() = q.toRotationMatrix();
  pose.T_wc.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
  return pose;
}

std::vector<StampedPose> ReadTumTrajectory(const std::filesystem::path& path) {
  std::ifstream file = OpenInputFile(path);
  std::vector<StampedPose> poses;
  std::string line;
  for (int line_number = 1; std::getline(file, line); ++line_number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string origin = fmt::format("{}:{}", path.string(), line_number);
    StampedPose pose = ParseTumPoseLine(line, origin);
    if (!poses.empty() && !(pose.stamp_s > poses.back().stamp_s)) {
      throw Error(fmt::format("{}: timestamp {:.6f} does not increase (previous {:.6f})",
                              origin, pose.stamp_s, poses.back().stamp_s));
    }
    poses.push_back(pose);
  }
  if (file.bad()) throw FileError(path, "read error");
  return poses;
}

void WriteTumTrajectory(const std::filesystem::path& path,
                        const std::vector<StampedPose>& poses,
                        const std::string& header_comment) {
  std::string text;
  if (!header_comment.empty()) {
    std::istringstream lines(header_comment);
    for (std::string line; std::getline(lines, line);) text += "# " + line + "\n";
  }
  // Refuse what ReadTumTrajectory would refuse, so a file this writes always reads back.
  std::string previous_stamp;
  for (size_t i = 0; i < poses.size(); ++i) {
    const StampedPose& pose = poses[i];
    if (!std::isfinite(pose.stamp_s) || !pose.T_wc.matrix().allFinite()) {
      throw FileError(path, fmt::format("refusing to write pose {} (stamp {}): not finite", i, pose.stamp_s));
    }
    // Compared as written (%.6f): stamps less than 1 us apart would read back as equal.
    const std::string line = FormatTumPoseLine(pose);
    const std::string stamp = line.substr(0, line.find(' '));
    if (i > 0 && !(std::stod(stamp) > std::stod(previous_stamp))) {
      throw FileError(path, fmt::format("refusing to write pose {}: timestamp {} does not increase (previous {})", i,
                                        stamp, previous_stamp));
    }
    previous_stamp = stamp;
    text += line;
    text += '\n';
  }
  WriteFileAtomically(path, text);
}

Eigen::Isometry3d InterpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double t) {
  const Eigen::Quaterniond qa(a.rotation());
  const Eigen::Quaterniond qb(b.rotation());
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  // Eigen's slerp takes the shorter arc (it flips qb when the dot product is negative).
  result.linear() = qa.slerp(t, qb).normalized().toRotationMatrix();
  result.translation() = (1.0 - t) * a.translation() + t * b.translation();
  return result;
}

}  // namespace segslam
