#pragma once
// A table with two boxes, ray-cast into an organized cloud: ground truth for segmentation tests.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "types/organized_cloud.h"

namespace objmap::testing {

/// Ground-truth owner of each pixel: -1 nothing, 0 table, 1 first box, 2 second box.
struct SyntheticScene {
  OrganizedCloud cloud_C;
  std::vector<int> owner;
};

struct AxisBox {
  Eigen::Vector3f lo, hi;  // world frame, z up
};

// Slab test: entry distance of the ray into the box, or infinity.
inline float HitBox(const AxisBox& box, const Eigen::Vector3f& origin, const Eigen::Vector3f& dir) {
  float t_near = 0.f;
  float t_far = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 3; ++k) {
    const float inv = 1.f / dir[k];
    float t0 = (box.lo[k] - origin[k]) * inv;
    float t1 = (box.hi[k] - origin[k]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
  }
  return t_near <= t_far && t_near > 0.f ? t_near : std::numeric_limits<float>::infinity();
}

/// 640x480, f = 585, camera 0.7 m above a 2 m x 2 m table looking down by 35 degrees;
/// depth noise of `noise_m` (1 sigma, fixed seed).
inline SyntheticScene MakeTableWithTwoBoxes(float noise_m = 0.001f) {
  const int w = 640, h = 480;
  const float f = 585.f, cx = 320.f, cy = 240.f, tilt = 35.f * 3.14159265f / 180.f;
  const Eigen::Vector3f origin_W(0.f, -0.6f, 0.7f);
  Eigen::Matrix3f R_W_C;
  R_W_C.col(0) = Eigen::Vector3f(1.f, 0.f, 0.f);
  R_W_C.col(2) = Eigen::Vector3f(0.f, std::cos(tilt), -std::sin(tilt));
  R_W_C.col(1) = R_W_C.col(2).cross(R_W_C.col(0));
  const AxisBox boxes[2] = {{{-0.30f, 0.25f, 0.f}, {-0.15f, 0.40f, 0.20f}},
                            {{0.10f, 0.30f, 0.f}, {0.22f, 0.50f, 0.12f}}};
  SyntheticScene scene;
  scene.cloud_C.width = w;
  scene.cloud_C.height = h;
  scene.cloud_C.points_C.assign(w * h, Eigen::Vector3f::Constant(std::nanf("")));
  scene.owner.assign(w * h, -1);
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, noise_m);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3f ray_C((u - cx) / f, (v - cy) / f, 1.f);  // z = 1: t is the depth
      const Eigen::Vector3f ray_W = R_W_C * ray_C;
      float best = std::numeric_limits<float>::infinity();
      int owner = -1;
      if (ray_W.z() < 0.f) {
        const float t = -origin_W.z() / ray_W.z();
        const Eigen::Vector3f hit = origin_W + t * ray_W;
        if (std::abs(hit.x()) < 1.f && hit.y() < 1.4f) best = t, owner = 0;
      }
      for (int b = 0; b < 2; ++b) {
        const float t = HitBox(boxes[b], origin_W, ray_W);
        if (t < best) best = t, owner = b + 1;
      }
      if (owner < 0) continue;
      const float z = best + noise(rng);
      scene.cloud_C.points_C[v * w + u] = z * ray_C;
      scene.owner[v * w + u] = owner;
    }
  }
  return scene;
}

}  // namespace objmap::testing
