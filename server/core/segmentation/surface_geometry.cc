// Per-pixel normals and the focal length, straight from the organized grid.
#include <algorithm>
#include <cmath>
#include <limits>

#include "segmentation/segmentation_internal.h"
#include "segmentation/sse_lanes.h"

namespace objmap::seg {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

// The rows a pixel's normal reads: its own and those `step` above and below (null outside).
struct NormalRows {
  const Eigen::Vector3f* row;
  const Eigen::Vector3f* up;
  const Eigen::Vector3f* down;
};

// The normal of pixel `u` of the row, NaN when it has none. Every neighbour test works on z:
// DepthContinuous is false for NaN depth, so it also rejects invalid neighbours.
Eigen::Vector3f PixelNormal(const NormalRows& rows, int u, int width, int s, float jump_ratio) {
  const Eigen::Vector3f& p = rows.row[u];
  const float z = p.z();
  const Eigen::Vector3f nan3 = Eigen::Vector3f::Constant(kNaN);
  if (!std::isfinite(z)) return nan3;
  auto continuous = [&](const Eigen::Vector3f* q) {
    return q != nullptr && DepthContinuous(z, q->z(), jump_ratio, s) ? q : nullptr;
  };
  const Eigen::Vector3f* right = continuous(u + s < width ? &rows.row[u + s] : nullptr);
  const Eigen::Vector3f* left = continuous(u - s >= 0 ? &rows.row[u - s] : nullptr);
  const Eigen::Vector3f* down = continuous(rows.down ? &rows.down[u] : nullptr);
  const Eigen::Vector3f* up = continuous(rows.up ? &rows.up[u] : nullptr);
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

#if defined(__SSE2__)
// PixelNormal for four pixels that have all four neighbours inside the image, with the same
// float operations in the same order (Eigen's cross, its sum x + (y + z) for dot products and
// norms, a division per component), so the result is the same to the bit.
void FourNormals(const NormalRows& rows, int u, int s, float jump_ratio, Eigen::Vector3f* out) {
  const Lanes p = LoadLanes(&rows.row[u]);
  const Lanes right = LoadLanes(&rows.row[u + s]);
  const Lanes left = LoadLanes(&rows.row[u - s]);
  const Lanes down = LoadLanes(&rows.down[u]);
  const Lanes up = LoadLanes(&rows.up[u]);
  const __m128 sign = _mm_set1_ps(-0.f);
  const __m128 ratio_step = _mm_set1_ps(jump_ratio * static_cast<float>(s));
  // std::min(z, q) is q when q < z, else z: exactly minps(q, z).
  auto continuous = [&](__m128 q) {
    const __m128 difference = _mm_andnot_ps(sign, _mm_sub_ps(p.z, q));
    return _mm_cmple_ps(difference, _mm_mul_ps(ratio_step, _mm_min_ps(q, p.z)));
  };
  const __m128 has_right = continuous(right.z);
  const __m128 has_left = continuous(left.z);
  const __m128 has_down = continuous(down.z);
  const __m128 has_up = continuous(up.z);
  const __m128 finite = Finite(p.z);
  const __m128 usable =
      _mm_and_ps(finite, _mm_and_ps(_mm_or_ps(has_right, has_left), _mm_or_ps(has_down, has_up)));
  const Lanes a = Select(has_right, right, p);
  const Lanes b = Select(has_left, left, p);
  const Lanes c = Select(has_down, down, p);
  const Lanes d = Select(has_up, up, p);
  const Lanes dx{_mm_sub_ps(a.x, b.x), _mm_sub_ps(a.y, b.y), _mm_sub_ps(a.z, b.z)};
  const Lanes dy{_mm_sub_ps(c.x, d.x), _mm_sub_ps(c.y, d.y), _mm_sub_ps(c.z, d.z)};
  Lanes n{_mm_sub_ps(_mm_mul_ps(dx.y, dy.z), _mm_mul_ps(dx.z, dy.y)),
          _mm_sub_ps(_mm_mul_ps(dx.z, dy.x), _mm_mul_ps(dx.x, dy.z)),
          _mm_sub_ps(_mm_mul_ps(dx.x, dy.y), _mm_mul_ps(dx.y, dy.x))};
  const __m128 norm = _mm_sqrt_ps(
      _mm_add_ps(_mm_mul_ps(n.x, n.x), _mm_add_ps(_mm_mul_ps(n.y, n.y), _mm_mul_ps(n.z, n.z))));
  const __m128 valid = _mm_and_ps(usable, _mm_cmpgt_ps(norm, _mm_setzero_ps()));
  n = {_mm_div_ps(n.x, norm), _mm_div_ps(n.y, norm), _mm_div_ps(n.z, norm)};
  const __m128 facing_away = _mm_cmpgt_ps(Dot(n, p), _mm_setzero_ps());
  const __m128 flip = _mm_and_ps(facing_away, sign);
  const __m128 nan = _mm_set1_ps(kNaN);
  alignas(16) float x[4], y[4], z[4];
  _mm_store_ps(x, Select(valid, _mm_xor_ps(n.x, flip), nan));
  _mm_store_ps(y, Select(valid, _mm_xor_ps(n.y, flip), nan));
  _mm_store_ps(z, Select(valid, _mm_xor_ps(n.z, flip), nan));
  for (int k = 0; k < 4; ++k) out[k] = Eigen::Vector3f(x[k], y[k], z[k]);
}
#endif

}  // namespace

std::vector<Eigen::Vector3f> ComputeNormals(const OrganizedCloud& cloud_C, int step_px,
                                            float jump_ratio) {
  const int w = cloud_C.width;
  const int h = cloud_C.height;
  const int s = step_px;
  std::vector<Eigen::Vector3f> normals(cloud_C.size());
  for (int v = 0; v < h; ++v) {
    const size_t offset = static_cast<size_t>(v) * w;
    const NormalRows rows{
        &cloud_C.points_C[offset],
        v - s >= 0 ? &cloud_C.points_C[offset - static_cast<size_t>(s) * w] : nullptr,
        v + s < h ? &cloud_C.points_C[offset + static_cast<size_t>(s) * w] : nullptr};
    Eigen::Vector3f* out = &normals[offset];
    int u = 0;
#if defined(__SSE2__)
    // Four at a time where every neighbour lies inside the image; one at a time elsewhere.
    if (rows.up != nullptr && rows.down != nullptr) {
      for (; u < s; ++u) out[u] = PixelNormal(rows, u, w, s, jump_ratio);
      for (; u + 4 <= w - s; u += 4) FourNormals(rows, u, s, jump_ratio, &out[u]);
    }
#endif
    for (; u < w; ++u) out[u] = PixelNormal(rows, u, w, s, jump_ratio);
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
