// A small hand-built world shared by the sim tests: a textured wall facing the camera,
// a textured floor, and one box object (instance 7), seen by a 160x120 camera.
#pragma once

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "scenes/world.h"

namespace segslam::sim::testing {

constexpr double kWallX = 5.0;         // the wall's front face is the plane x = 5
constexpr double kCameraHeight = 1.5;  // camera centre z
constexpr std::uint16_t kBoxInstance = 7;
const Eigen::Vector3d kBoxCentre(3.0, 0.5, 1.0);
const Eigen::Vector3d kBoxHalf(0.25, 0.25, 0.25);

// Camera at (0, 0, 1.5) looking along world +x (optical z), image right = world -y.
inline Eigen::Isometry3d CameraPose() {
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(0, -1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(1, 0, 0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(0, 0, kCameraHeight);
  return T;
}

inline Eigen::Isometry3d Translation(const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = t;
  return T;
}

// Wall texture: top half red, bottom half blue (BGR), one copy per 6 m x 6 m, so the
// wall face (z from -1 to 5) shows red above z = 2 and blue below.
inline scenes::World MakeTestWorld() {
  scenes::World w;
  w.name = "sim_test";
  w.kind = "office";
  w.camera.width = 160;
  w.camera.height = 120;
  w.camera.fovy_deg = 60.0;
  w.camera.near_m = 0.05;
  w.camera.far_m = 100.0;
  w.sky_rgb = Eigen::Vector3f(0.6f, 0.7f, 0.85f);

  scenes::Texture wall_tex;
  wall_tex.name = "red_over_blue";
  wall_tex.image_bgr = cv::Mat(64, 64, CV_8UC3, cv::Scalar(255, 0, 0));
  wall_tex.image_bgr.rowRange(0, 32).setTo(cv::Scalar(0, 0, 255));
  wall_tex.tile_size_m = Eigen::Vector2d(6.0, 6.0);
  scenes::Texture floor_tex;
  floor_tex.name = "checker";
  floor_tex.image_bgr = cv::Mat(32, 32, CV_8UC3, cv::Scalar(60, 60, 60));
  floor_tex.image_bgr(cv::Rect(0, 0, 16, 16)).setTo(cv::Scalar(200, 200, 200));
  floor_tex.image_bgr(cv::Rect(16, 16, 16, 16)).setTo(cv::Scalar(200, 200, 200));
  floor_tex.tile_size_m = Eigen::Vector2d(1.0, 1.0);
  w.textures = {wall_tex, floor_tex};

  scenes::Material wall_mat;
  wall_mat.name = "wall";
  wall_mat.texture = 0;
  scenes::Material floor_mat;
  floor_mat.name = "floor";
  floor_mat.texture = 1;
  scenes::Material box_mat;
  box_mat.name = "box";
  box_mat.rgba = Eigen::Vector4f(0.2f, 0.8f, 0.2f, 1.f);
  w.materials = {wall_mat, floor_mat, box_mat};

  scenes::Geom wall;
  wall.shape = scenes::Shape::kBox;
  wall.size = Eigen::Vector3d(0.1, 5.0, 3.0);
  wall.T_parent_geom = Translation(Eigen::Vector3d(kWallX + 0.1, 0, 2.0));
  wall.material = 0;
  scenes::Geom floor;
  floor.shape = scenes::Shape::kPlane;
  floor.size = Eigen::Vector3d(20, 20, 0);
  floor.material = 1;
  w.static_geoms = {wall, floor};

  scenes::Object box;
  box.instance_id = kBoxInstance;
  box.coco_category_id = 62;
  box.category_name = "chair";
  box.moveable = true;
  scenes::Part part;
  part.name = "body";
  scenes::Geom box_geom;
  box_geom.shape = scenes::Shape::kBox;
  box_geom.size = kBoxHalf;
  box_geom.material = 2;
  part.geoms = {box_geom};
  box.parts = {part};
  box.placement[0].present = true;
  box.placement[0].T_world_object = Translation(kBoxCentre);
  box.placement[1].present = false;
  w.objects = {box};

  scenes::Light light;
  light.direction = Eigen::Vector3d(0.5, -0.3, -1.0);
  w.lights = {light};
  w.frames_per_pass = {3, 3};
  for (int p = 0; p < 2; ++p) {
    w.camera_route[p].keys = {{0.0, CameraPose()}, {10.0, CameraPose()}};
  }
  return w;
}

// Part poses of the test world's box: present at its placement, or hidden.
inline std::vector<std::vector<Eigen::Isometry3d>> BoxPoses(bool present) {
  if (!present) return {{}};
  return {{Translation(kBoxCentre)}};
}

// Fails the current test on any MuJoCo warning.
class MujocoWarningGuard : public ::testing::Test {
 protected:
  void SetUp() override {
    Warnings().clear();
    previous_ = mju_user_warning;
    mju_user_warning = [](const char* msg) { Warnings().push_back(msg); };
  }
  void TearDown() override {
    mju_user_warning = previous_;
    for (const std::string& w : Warnings()) ADD_FAILURE() << "MuJoCo warning: " << w;
  }
  static std::vector<std::string>& Warnings() {
    static std::vector<std::string> warnings;
    return warnings;
  }

 private:
  void (*previous_)(const char*) = nullptr;
};

}  // namespace segslam::sim::testing
