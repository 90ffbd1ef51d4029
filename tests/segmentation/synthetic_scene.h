#pragma once
// A table with two boxes, ray-cast into an organized cloud: ground truth for segmentation tests.

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "test_scenes.h"
#include "types/organized_cloud.h"

namespace objmap::testing {

/// Ground-truth owner of each pixel: -1 nothing, 0 table, 1 first box, 2 second box.
struct SyntheticScene {
  OrganizedCloud cloud_C;
  std::vector<int> owner;
};

/// 640x480, f = 585, camera 0.7 m above a 2 m x 2 m table looking down by 35 degrees;
/// depth noise of `noise_m` (1 sigma, fixed seed).
inline SyntheticScene MakeTableWithTwoBoxes(float noise_m = 0.001f) {
  const double tilt = 35.0 * M_PI / 180.0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  T_W_C.linear().col(0) = Eigen::Vector3d(1.0, 0.0, 0.0);
  T_W_C.linear().col(2) = Eigen::Vector3d(0.0, std::cos(tilt), -std::sin(tilt));
  T_W_C.linear().col(1) = T_W_C.linear().col(2).cross(T_W_C.linear().col(0));
  T_W_C.translation() = Eigen::Vector3d(0.0, -0.6, 0.7);
  const std::vector<SceneBox> boxes = {
      {{-1.0, -10.0, -0.001}, {1.0, 1.4, 0.0}},   // table top, z = 0
      {{-0.30, 0.25, 0.0}, {-0.15, 0.40, 0.20}},  // first box
      {{0.10, 0.30, 0.0}, {0.22, 0.50, 0.12}}};   // second box
  SyntheticScene scene;
  RgbdFrame frame = RenderFrame(boxes, CameraIntrinsics{}, T_W_C, "synthetic", &scene.owner);
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, noise_m);
  for (float& depth_m : frame.depth.depth_m) {
    if (depth_m > 0.f) depth_m += noise(rng);
  }
  scene.cloud_C = BackProject(frame.depth, ColorImage{}, frame.intrinsics);
  return scene;
}

}  // namespace objmap::testing
