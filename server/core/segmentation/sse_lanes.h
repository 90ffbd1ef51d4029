#pragma once
// Four Eigen::Vector3f as x, y and z lanes of SSE2 registers, for the per-pixel loops that run
// on every pixel of a frame. Only the segmentation's .cc files include this.
#if defined(__SSE2__)
#include <emmintrin.h>

#include <Eigen/Core>
#include <limits>

namespace objmap::seg {

struct Lanes {
  __m128 x, y, z;
};

/// points[0..3] (12 consecutive floats) transposed into lanes.
inline Lanes LoadLanes(const Eigen::Vector3f* points) {
  const float* f = points->data();
  const __m128 a = _mm_loadu_ps(f);      // x0 y0 z0 x1
  const __m128 b = _mm_loadu_ps(f + 4);  // y1 z1 x2 y2
  const __m128 c = _mm_loadu_ps(f + 8);  // z2 x3 y3 z3
  const __m128 x =
      _mm_shuffle_ps(a, _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2)), _MM_SHUFFLE(2, 0, 3, 0));
  const __m128 y =
      _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1)),
                     _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0));
  const __m128 z =
      _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)),
                     _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)), _MM_SHUFFLE(2, 0, 2, 0));
  return {x, y, z};
}

/// a where mask is set, else b.
inline __m128 Select(__m128 mask, __m128 a, __m128 b) {
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}

inline Lanes Select(__m128 mask, const Lanes& a, const Lanes& b) {
  return {Select(mask, a.x, b.x), Select(mask, a.y, b.y), Select(mask, a.z, b.z)};
}

/// a.x * b.x + (a.y * b.y + a.z * b.z): the order of Eigen's dot() and squaredNorm() on
/// Vector3f, so lanes give the scalar code's result to the bit.
inline __m128 Dot(const Lanes& a, const Lanes& b) {
  return _mm_add_ps(_mm_mul_ps(a.x, b.x), _mm_add_ps(_mm_mul_ps(a.y, b.y), _mm_mul_ps(a.z, b.z)));
}

/// Lanes whose value is finite (not NaN, not infinite).
inline __m128 Finite(__m128 value) {
  return _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.f), value),
                      _mm_set1_ps(std::numeric_limits<float>::infinity()));
}

}  // namespace objmap::seg
#endif
