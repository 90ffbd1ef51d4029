// Per-pixel normals and the focal length, straight from the organized grid.
#include <algorithm>
#include <limits>

#include "segmentation/segmentation_internal.h"

namespace objmap::seg {
namespace {

// The neighbour `du, dv` away when it is valid and on the same surface, else null.
const Eigen::Vector3f* ContinuousNeighbour(const OrganizedCloud& cloud, int u, int v, int du,
                                           int dv, float jump_ratio, int step_px) {
  const int u2 = u + du;
  const int v2 = v + dv;
  if (u2 < 0 || v2 < 0 || u2 >= cloud.width || v2 >= cloud.height) return nullptr;
  const int i = v * cloud.width + u;
  const int j = v2 * cloud.width + u2;
  if (!cloud.IsValid(j)) return nullptr;
  if (!DepthContinuous(cloud.points_C[i].z(), cloud.points_C[j].z(), jump_ratio, step_px)) {
    return nullptr;
  }
  return &cloud.points_C[j];
}

Eigen::Vector3f PixelNormal(const OrganizedCloud& cloud, int u, int v, int s, float jump_ratio) {
  const Eigen::Vector3f nan3 = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  const Eigen::Vector3f& p = cloud.points_C[v * cloud.width + u];
  const Eigen::Vector3f* right = ContinuousNeighbour(cloud, u, v, s, 0, jump_ratio, s);
  const Eigen::Vector3f* left = ContinuousNeighbour(cloud, u, v, -s, 0, jump_ratio, s);
  const Eigen::Vector3f* down = ContinuousNeighbour(cloud, u, v, 0, s, jump_ratio, s);
  const Eigen::Vector3f* up = ContinuousNeighbour(cloud, u, v, 0, -s, jump_ratio, s);
  if ((right == nullptr && left == nullptr) || (down == nullptr && up == nullptr)) return nan3;
  // Central differences where both sides exist, one-sided at borders and depth edges.
  const Eigen::Vector3f dx = (right ? *right : p) - (left ? *left : p);
  const Eigen::Vector3f dy = (down ? *down : p) - (up ? *up : p);
  Eigen::Vector3f n = dx.cross(dy);
  const float norm = n.norm();
  if (!(norm > 0.f)) return nan3;
  n /= norm;
  return n.dot(p) > 0.f ? Eigen::Vector3f(-n) : n;
}

}  // namespace

std::vector<Eigen::Vector3f> ComputeNormals(const OrganizedCloud& cloud_C, int step_px,
                                            float jump_ratio) {
  std::vector<Eigen::Vector3f> normals(
      cloud_C.size(), Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  for (int v = 0; v < cloud_C.height; ++v) {
    for (int u = 0; u < cloud_C.width; ++u) {
      const int i = v * cloud_C.width + u;
      if (cloud_C.IsValid(i)) normals[i] = PixelNormal(cloud_C, u, v, step_px, jump_ratio);
    }
  }
  return normals;
}

float EstimateFocalPx(const OrganizedCloud& cloud_C, float fallback_px) {
  // x / z = (u - cx) / f, so two valid pixels of one row give f = du / d(x / z).
  std::vector<float> estimates;
  for (int v = 0; v < cloud_C.height; v += 8) {
    int first = -1;
    int last = -1;
    for (int u = 0; u < cloud_C.width; ++u) {
      if (!cloud_C.IsValid(v * cloud_C.width + u)) continue;
      if (first < 0) first = u;
      last = u;
    }
    if (first < 0 || last - first < cloud_C.width / 8) continue;
    const Eigen::Vector3f& a = cloud_C.points_C[v * cloud_C.width + first];
    const Eigen::Vector3f& b = cloud_C.points_C[v * cloud_C.width + last];
    const float slope = b.x() / b.z() - a.x() / a.z();
    if (slope > 0.f) estimates.push_back(static_cast<float>(last - first) / slope);
  }
  if (estimates.empty()) return fallback_px;
  std::nth_element(estimates.begin(), estimates.begin() + estimates.size() / 2, estimates.end());
  return estimates[estimates.size() / 2];
}

}  // namespace objmap::seg
