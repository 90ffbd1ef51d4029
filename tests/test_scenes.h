#pragma once
// Small geometric fixtures and a ray-cast RGB-D renderer shared by the tests.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "types/detection.h"
#include "types/frame.h"

namespace objmap::testing {

/// Points on the surface of an axis-aligned box [lo, hi] sampled every `step_m`.
inline std::vector<Eigen::Vector3f> BoxSurface(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                                               float step_m) {
  std::vector<Eigen::Vector3f> points;
  for (float x = lo.x(); x <= hi.x() + 1e-6f; x += step_m) {
    for (float y = lo.y(); y <= hi.y() + 1e-6f; y += step_m) {
      for (float z = lo.z(); z <= hi.z() + 1e-6f; z += step_m) {
        const bool on_surface = x - lo.x() < step_m || hi.x() - x < step_m || y - lo.y() < step_m ||
                                hi.y() - y < step_m || z - lo.z() < step_m || hi.z() - z < step_m;
        if (on_surface) points.emplace_back(x, y, z);
      }
    }
  }
  return points;
}

}  // namespace objmap::testing

namespace objmap::testing {

/// An axis-aligned box of a synthetic scene, world frame.
struct SceneBox {
  Eigen::Vector3d lo;
  Eigen::Vector3d hi;
  std::array<std::uint8_t, 3> rgb{128, 128, 128};
};

/// Distance along the ray to the first hit of `box` (slab method), or +inf.
inline double RayBoxHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                        const SceneBox& box) {
  double t_near = 0.0, t_far = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(direction[axis]) < 1e-12) {
      if (origin[axis] < box.lo[axis] || origin[axis] > box.hi[axis]) {
        return std::numeric_limits<double>::infinity();
      }
      continue;
    }
    double t0 = (box.lo[axis] - origin[axis]) / direction[axis];
    double t1 = (box.hi[axis] - origin[axis]) / direction[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return std::numeric_limits<double>::infinity();
  }
  return t_near;
}

/// Renders a pinhole RGB-D frame of `boxes` seen from T_W_C (depth along the optical axis).
/// `owner`, when given, receives per pixel the index of the box it shows (-1 for none).
inline RgbdFrame RenderFrame(const std::vector<SceneBox>& boxes, const CameraIntrinsics& K,
                             const Eigen::Isometry3d& T_W_C, const std::string& name,
                             std::vector<int>* owner = nullptr) {
  RgbdFrame frame;
  frame.name = name;
  frame.intrinsics = K;
  frame.T_W_C = T_W_C;
  frame.depth.width = frame.color.width = K.width;
  frame.depth.height = frame.color.height = K.height;
  frame.depth.depth_m.assign(static_cast<size_t>(K.width) * K.height, 0.f);
  frame.color.rgb.assign(static_cast<size_t>(K.width) * K.height * 3, 0);
  if (owner != nullptr) owner->assign(static_cast<size_t>(K.width) * K.height, -1);
  const Eigen::Vector3d origin = T_W_C.translation();
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_C((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      const Eigen::Vector3d ray_W = T_W_C.linear() * ray_C;
      double best = std::numeric_limits<double>::infinity();
      int hit_index = -1;
      for (size_t b = 0; b < boxes.size(); ++b) {
        const double t = RayBoxHit(origin, ray_W, boxes[b]);
        if (t < best) {
          best = t;
          hit_index = static_cast<int>(b);
        }
      }
      if (hit_index < 0) continue;
      const SceneBox* hit = &boxes[hit_index];
      const size_t i = static_cast<size_t>(v) * K.width + u;
      if (owner != nullptr) (*owner)[i] = hit_index;
      frame.depth.depth_m[i] = static_cast<float>(best);  // ray_C has z = 1: t is the depth
      for (int c = 0; c < 3; ++c) frame.color.rgb[3 * i + c] = hit->rgb[c];
    }
  }
  return frame;
}

/// The detection box of a scene box seen from T_W_C: the bounds of its projected corners.
inline BoundingBox2D ProjectBox(const SceneBox& box, const Eigen::Isometry3d& T_W_C,
                                const CameraIntrinsics& K) {
  BoundingBox2D out{1e9f, 1e9f, -1e9f, -1e9f};
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p_C =
        T_W_C.inverse() * Eigen::Vector3d((corner & 1) ? box.hi.x() : box.lo.x(),
                                          (corner & 2) ? box.hi.y() : box.lo.y(),
                                          (corner & 4) ? box.hi.z() : box.lo.z());
    const float u = static_cast<float>(K.fx * p_C.x() / p_C.z() + K.cx);
    const float v = static_cast<float>(K.fy * p_C.y() / p_C.z() + K.cy);
    out = {std::min(out.x_min, u), std::min(out.y_min, v), std::max(out.x_max, u),
           std::max(out.y_max, v)};
  }
  return out;
}

/// Camera at `eye` looking at `target`, with world +z up (camera y points down).
inline Eigen::Isometry3d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  T_W_C.linear().col(0) = x;
  T_W_C.linear().col(1) = y;
  T_W_C.linear().col(2) = z;
  T_W_C.translation() = eye;
  return T_W_C;
}

}  // namespace objmap::testing

namespace objmap::testing::table_visits {

// A table with two cups before a wall, visited twice from three places each (the change tests'
// scene): every place of a visit is an independent view of the others (ViewGroupingConfig), and
// the second visit's cameras stand elsewhere than the first's.
inline const SceneBox kTable{{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}};
inline const SceneBox kWall{{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}};
inline const SceneBox kCupOne{{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}};  // red
inline const SceneBox kCupTwo{{-0.05, 0.15, 0.70}, {0.05, 0.25, 0.82}, {30, 30, 200}};    // blue
// Where cup two stands after it was moved: on the table, in view of both visits, 30 cm and
// more from anything else.
inline const SceneBox kCupTwoMoved{{0.20, 0.45, 0.70}, {0.30, 0.55, 0.82}, {30, 30, 200}};
inline const std::vector<Eigen::Vector3d> kFirstEyes = {
    {-1.0, 0.0, 1.3}, {-1.0, 0.25, 1.3}, {-0.95, -0.25, 1.35}};
inline const std::vector<Eigen::Vector3d> kSecondEyes = {
    {-1.05, -0.35, 1.25}, {-0.9, 0.35, 1.3}, {-1.1, 0.1, 1.4}};
// Where every camera of both visits looks.
inline const Eigen::Vector3d kTarget{0.0, 0.1, 0.7};

}  // namespace objmap::testing::table_visits
