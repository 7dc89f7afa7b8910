// Helpers shared by the pose optimisation and bundle adjustment tests: a VGA camera with
// a stereo baseline, poses from axis-angle, and the errors that compare poses.
#pragma once

#include <cmath>

#include <Eigen/Geometry>

#include "core/camera.h"

namespace segslam::slam::testing {

// The virtual stereo baseline of an RGB-D camera, as ORB-SLAM2 sets it for the Kinect.
constexpr double kBaseline = 0.08;

// 640x480 with the Kinect's focal length; fy may differ to catch an fx/fy mix-up.
inline PinholeCamera TestCamera(double fy = 525) {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = 525;
  camera.fy = fy;
  camera.cx = 319.5;
  camera.cy = 239.5;
  return camera;
}

inline Eigen::Isometry3d MakePose(const Eigen::Vector3d& axis, double angle_deg, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  T.translation() = translation;
  return T;
}

// Distance between the camera centres of two world-to-camera poses.
inline double CentreError(const Eigen::Isometry3d& a_cw, const Eigen::Isometry3d& b_cw) {
  return (a_cw.inverse().translation() - b_cw.inverse().translation()).norm();
}

inline double RotationErrorDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

}  // namespace segslam::slam::testing
