// Poses and TUM trajectory files.
//
// Conventions for the whole project:
// - A pose is named `T_<to>_<from>`: it maps coordinates in frame <from> to frame <to>,
//   p_to = T_to_from * p_from. So `T_wc` is camera-to-world (the camera's pose in the
//   world), `T_cw` its inverse, `T_cur_prev` maps the previous camera frame into the
//   current one.
// - Camera optical frame: x right, y down, z forward (OpenCV).
// - World frame: z up.
// - Units: metres, seconds (`stamp_s`).
// - Trajectories are `T_wc` and are stored as TUM lines
//   `timestamp tx ty tz qx qy qz qw` (Hamilton quaternion, scalar last).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace segslam {

struct StampedPose {
  double stamp_s = 0;                                        // Timestamp in seconds.
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();   // Camera-to-world.
};

// One TUM line without newline: stamp as %.6f, translation as %.9g, quaternion
// (normalized, sign chosen so that qw >= 0) as %.9f.
std::string FormatTumPoseLine(const StampedPose& pose);

// The fields of a line of a TUM text file as TUM's scripts split it (associate.py's
// read_file_list): commas and tabs count as spaces, empty fields are dropped.
std::vector<std::string> SplitTumFields(const std::string& line);

// A number as TUM's Python scripts read one (float()), and finite: decimal or scientific
// notation, tiny (subnormal) values included; false for anything else (hex floats, NaN,
// inf, overflow, trailing characters).
bool ParseTumNumber(const std::string& token, double* value);

// Parses one TUM line (8 numbers, split as SplitTumFields does). The quaternion is normalized;
// its norm must lie within 1 +- 1e-2 (files store a few digits only, so small deviations
// are normal; large ones mean a corrupt line). Throws segslam::Error whose message starts
// with `origin_for_errors` (e.g. "traj.txt:12") on wrong field count, a non-number,
// NaN/inf, or a bad quaternion.
StampedPose ParseTumPoseLine(const std::string& line, const std::string& origin_for_errors);

// Reads a TUM trajectory, skipping blank lines and lines starting with '#'.
// Throws segslam::Error naming the file and line number for a missing/unreadable file,
// any malformed line (see ParseTumPoseLine) and timestamps that do not strictly increase.
std::vector<StampedPose> ReadTumTrajectory(const std::filesystem::path& path);

// Writes a TUM trajectory atomically (temporary file, then rename). `header_comment` may
// hold several lines; each is written prefixed by "# ". Throws segslam::Error naming the
// file (and the pose's index) on a non-finite stamp or pose, a stamp that does not
// increase as written (to the microsecond), or a failed write; nothing is written then.
void WriteTumTrajectory(const std::filesystem::path& path,
                        const std::vector<StampedPose>& poses,
                        const std::string& header_comment = "");

// Pose between a (t = 0) and b (t = 1): translation linearly interpolated, rotation by
// quaternion slerp along the shorter arc. t outside [0, 1] extrapolates.
Eigen::Isometry3d InterpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double t);

}  // namespace segslam
