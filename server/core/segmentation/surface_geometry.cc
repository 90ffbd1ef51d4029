// Per-pixel normals and the focal length, straight from the organized grid.
#include <algorithm>
#include <limits>

#include "segmentation/segmentation_internal.h"

namespace objmap::seg {
namespace {

// One row pass: every neighbour test works on the z values, which the cache already holds, and
// the bounds are hoisted out of the pixel loop (this step runs on all 307,200 pixels).
void RowNormals(const OrganizedCloud& cloud, int v, int s, float jump_ratio,
                Eigen::Vector3f* normals_row) {
  const int w = cloud.width;
  const Eigen::Vector3f* row = &cloud.points_C[static_cast<size_t>(v) * w];
  const Eigen::Vector3f* row_up = v - s >= 0 ? row - static_cast<size_t>(s) * w : nullptr;
  const Eigen::Vector3f* row_down =
      v + s < cloud.height ? row + static_cast<size_t>(s) * w : nullptr;
  // A neighbour counts when it lies on the same surface; DepthContinuous is false for NaN depth,
  // so it also rejects invalid neighbours.
  auto continuous = [&](float z, const Eigen::Vector3f* q) {
    return q != nullptr && DepthContinuous(z, q->z(), jump_ratio, s);
  };
  for (int u = 0; u < w; ++u) {
    const Eigen::Vector3f& p = row[u];
    const float z = p.z();
    if (!std::isfinite(z)) continue;
    const Eigen::Vector3f* right = u + s < w ? &row[u + s] : nullptr;
    const Eigen::Vector3f* left = u - s >= 0 ? &row[u - s] : nullptr;
    const Eigen::Vector3f* down = row_down ? &row_down[u] : nullptr;
    const Eigen::Vector3f* up = row_up ? &row_up[u] : nullptr;
    if (!continuous(z, right)) right = nullptr;
    if (!continuous(z, left)) left = nullptr;
    if (!continuous(z, down)) down = nullptr;
    if (!continuous(z, up)) up = nullptr;
    if ((right == nullptr && left == nullptr) || (down == nullptr && up == nullptr)) continue;
    // Central differences where both sides exist, one-sided at borders and depth edges.
    const Eigen::Vector3f dx = (right ? *right : p) - (left ? *left : p);
    const Eigen::Vector3f dy = (down ? *down : p) - (up ? *up : p);
    Eigen::Vector3f n = dx.cross(dy);
    const float norm = n.norm();
    if (!(norm > 0.f)) continue;
    n /= norm;
    normals_row[u] = n.dot(p) > 0.f ? Eigen::Vector3f(-n) : n;
  }
}

}  // namespace

std::vector<Eigen::Vector3f> ComputeNormals(const OrganizedCloud& cloud_C, int step_px,
                                            float jump_ratio) {
  std::vector<Eigen::Vector3f> normals(
      cloud_C.size(), Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  for (int v = 0; v < cloud_C.height; ++v) {
    RowNormals(cloud_C, v, step_px, jump_ratio, &normals[static_cast<size_t>(v) * cloud_C.width]);
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
