#include "types/organized_cloud.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace objmap {

OrganizedCloud BackProject(const DepthImage& depth, const ColorImage& color,
                           const CameraIntrinsics& intrinsics) {
  OrganizedCloud cloud;
  cloud.width = depth.width;
  cloud.height = depth.height;
  const size_t n = static_cast<size_t>(depth.width) * depth.height;
  cloud.points_C.resize(n);
  const bool has_color = !color.empty();
  if (has_color) cloud.rgb.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inv_fx = 1.f / static_cast<float>(intrinsics.fx);
  const float inv_fy = 1.f / static_cast<float>(intrinsics.fy);
  const float cx = static_cast<float>(intrinsics.cx);
  const float cy = static_cast<float>(intrinsics.cy);
  const float color_scale_x = has_color ? static_cast<float>(color.width) / depth.width : 0.f;
  const float color_scale_y = has_color ? static_cast<float>(color.height) / depth.height : 0.f;
  const bool same_size =
      color.width == depth.width && color.height == depth.height && color.rgb.size() >= n * 3;
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const size_t i = static_cast<size_t>(v) * depth.width + u;
      const float z = depth.depth_m[i];
      if (std::isfinite(z) && z > 0.f) {
        cloud.points_C[i] = Eigen::Vector3f((u - cx) * z * inv_fx, (v - cy) * z * inv_fy, z);
      } else {
        cloud.points_C[i] = Eigen::Vector3f(nan, nan, nan);
      }
      if (has_color && !same_size) {
        const int cu = std::min(color.width - 1, static_cast<int>(u * color_scale_x));
        const int cv = std::min(color.height - 1, static_cast<int>(v * color_scale_y));
        const std::uint8_t* p = &color.rgb[(static_cast<size_t>(cv) * color.width + cu) * 3];
        cloud.rgb[i] = {p[0], p[1], p[2]};
      }
    }
  }
  // Registered colour of the depth image's size (7-Scenes, TUM) is a plain copy: the scaled
  // lookup above would pick pixel (u, v) itself.
  if (has_color && same_size) std::memcpy(cloud.rgb.data(), color.rgb.data(), n * 3);
  return cloud;
}

}  // namespace objmap
