#pragma once
// Depth scans rendered from a small synthetic room (walls, a table-like box and a ball masked as
// an object, with holes), for checking the occupancy integration paths against each other.

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <vector>

#include "occupancy/occupancy_map.h"

namespace objmap::testing {

struct SceneBox {
  Eigen::Vector3f lo, hi;
};

// Parameter of the first hit of origin + t * direction with the box from outside, or from
// inside (the room's walls); infinity when none.
inline float HitBox(const SceneBox& box, const Eigen::Vector3f& origin,
                    const Eigen::Vector3f& direction, bool from_inside) {
  float enter = 0.f, leave = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    const float t0 = (box.lo[a] - origin[a]) / direction[a];
    const float t1 = (box.hi[a] - origin[a]) / direction[a];
    enter = std::max(enter, std::min(t0, t1));
    leave = std::min(leave, std::max(t0, t1));
  }
  if (enter > leave) return std::numeric_limits<float>::infinity();
  return from_inside ? leave : (enter > 0.f ? enter : std::numeric_limits<float>::infinity());
}

inline float HitSphere(const Eigen::Vector3f& center, float radius, const Eigen::Vector3f& origin,
                       const Eigen::Vector3f& direction) {
  const Eigen::Vector3f to_origin = origin - center;
  const float a = direction.squaredNorm(), b = 2.f * direction.dot(to_origin);
  const float c = to_origin.squaredNorm() - radius * radius;
  const float discriminant = b * b - 4.f * a * c;
  if (discriminant < 0.f) return std::numeric_limits<float>::infinity();
  const float t = (-b - std::sqrt(discriminant)) / (2.f * a);
  return t > 0.f ? t : std::numeric_limits<float>::infinity();
}

struct CameraSetup {
  int width = 160, height = 120;
  float focal = 140.f;
  Eigen::Isometry3f T_W_C = Eigen::Isometry3f::Identity();
};

// A room (the walls seen from inside) with a table-like box and a ball, which is masked as an
// object. Pixels in two hole patterns get no depth: blobs (as dark or shiny surfaces give) and
// a sparse grid of single pixels.
inline DepthScanW Render(const CameraSetup& camera) {
  // Faces off the 1 cm grid lines: a wall exactly on a voxel face puts ray ends on it, where
  // which voxel holds the end is down to float rounding.
  const SceneBox room{{-1.3037f, -1.1071f, -0.5513f}, {2.9043f, 1.3029f, 1.4557f}};
  const SceneBox table{{0.7031f, -0.3533f, -0.5513f}, {1.3047f, 0.4519f, -0.0541f}};
  const Eigen::Vector3f ball_center(0.95f, 0.1f, 0.12f);
  const float ball_radius = 0.17f;
  DepthScanW scan;
  scan.T_W_C = camera.T_W_C;
  scan.width = camera.width;
  scan.height = camera.height;
  scan.fx = scan.fy = camera.focal;
  scan.cx = 0.5f * static_cast<float>(camera.width) - 0.5f;
  scan.cy = 0.5f * static_cast<float>(camera.height) - 0.5f;
  scan.points_C.resize(static_cast<std::size_t>(camera.width) * camera.height);
  scan.object_mask.assign(scan.points_C.size(), 0);
  const Eigen::Vector3f origin = camera.T_W_C.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * camera.width + u;
      const Eigen::Vector3f ray_C((static_cast<float>(u) - scan.cx) / scan.fx,
                                  (static_cast<float>(v) - scan.cy) / scan.fy, 1.f);
      const Eigen::Vector3f direction = camera.T_W_C.linear() * ray_C;
      const float ball = HitSphere(ball_center, ball_radius, origin, direction);
      const float depth = std::min(
          {HitBox(room, origin, direction, true), HitBox(table, origin, direction, false), ball});
      const bool blob = std::hypot(u - 0.7f * camera.width, v - 0.3f * camera.height) < 9.f ||
                        std::hypot(u - 0.2f * camera.width, v - 0.75f * camera.height) < 5.f;
      const bool sparse = u % 7 == 3 && v % 5 == 2;
      if (blob || sparse || !std::isfinite(depth)) {
        scan.points_C[i] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
        continue;
      }
      // The depth image's value, back-projected as BackProject does.
      scan.points_C[i] =
          Eigen::Vector3f((static_cast<float>(u) - scan.cx) * depth / scan.fx,
                          (static_cast<float>(v) - scan.cy) * depth / scan.fy, depth);
      scan.object_mask[i] = ball == depth ? 1 : 0;
    }
  }
  return scan;
}

inline Eigen::Isometry3f Pose(const Eigen::Vector3f& position, float yaw, float pitch, float roll) {
  // Camera z forward along world x at zero angles.
  const Eigen::Matrix3f camera_to_world =
      (Eigen::Matrix3f() << 0.f, 0.f, 1.f, -1.f, 0.f, 0.f, 0.f, -1.f, 0.f).finished();
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = (Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) *
                Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitY()) *
                Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitX()))
                   .toRotationMatrix() *
               camera_to_world;
  T.translation() = position;
  return T;
}

inline std::vector<CameraSetup> Cameras() {
  std::vector<CameraSetup> cameras(4);
  cameras[0].T_W_C = Pose({0.013f, -0.021f, 0.337f}, 0.f, 0.25f, 0.f);
  cameras[1].T_W_C = Pose({0.213f, 0.379f, 0.463f}, -0.4f, 0.5f, 0.1f);
  cameras[2].T_W_C = Pose({-0.6f, -0.3f, 0.2f}, 0.35f, 0.1f, -0.2f);
  // A long lens: far voxels cover under one pixel, so the block decisions stop early.
  cameras[3].T_W_C = Pose({-1.0f, 0.9f, 1.0f}, -0.5f, 0.45f, 0.f);
  cameras[3].focal = 400.f;
  return cameras;
}

inline octomap::OcTree TreeOf(const OccupancyMap& map) {
  std::istringstream bytes(
      map.BinaryBytes(false, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), nullptr));
  octomap::OcTree tree(map.config().resolution_m);
  tree.readBinary(bytes);
  return tree;
}

}  // namespace objmap::testing
