#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "types/frame.h"

namespace objmap {

/// Organized point cloud in the camera frame: one point per depth pixel, row-major.
/// Invalid pixels hold NaN coordinates.
struct OrganizedCloud {
  int width = 0;
  int height = 0;
  std::vector<Eigen::Vector3f> points_C;
  std::vector<std::array<std::uint8_t, 3>> rgb;  ///< empty or one colour per point

  [[nodiscard]] bool IsValid(int index) const { return std::isfinite(points_C[index].z()); }
  [[nodiscard]] size_t size() const { return points_C.size(); }
};

/// Back-projects a depth image through the intrinsics. Colour is sampled at the same pixel
/// (scaled when the colour image has another size); `color` may be empty.
[[nodiscard]] OrganizedCloud BackProject(const DepthImage& depth, const ColorImage& color,
                                         const CameraIntrinsics& intrinsics);

}  // namespace objmap
