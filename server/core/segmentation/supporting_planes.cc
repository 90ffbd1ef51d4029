// Supporting planes (table, floor, walls) in the spirit of Pham et al. 2016 (paper Sec. III-B):
// sequential RANSAC where one pixel and its normal form a hypothesis, refined by PCA; a plane is
// kept only when its metric area is large, so box faces stay ordinary surfaces.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

#include "segmentation/segmentation_internal.h"
#include "segmentation/sse_lanes.h"

namespace objmap::seg {
namespace {

constexpr int kSampleStridePx = 6;
// Hypotheses are scored on at most this many samples (the refit and labelling use all).
constexpr size_t kMaxScoredSamples = 1500;
constexpr float kPi = 3.14159265358979f;

struct Plane {
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
  float offset = 0.f;  // n . p + offset = 0
};

struct InlierTest {
  float distance_m;
  float cos_angle;
  bool operator()(const Plane& plane, const Eigen::Vector3f& p, const Eigen::Vector3f& n) const {
    // Kinect depth noise grows with depth squared; keep a floor for close range.
    const float tolerance = distance_m * std::max(1.f, p.z() * p.z());
    return std::abs(plane.normal.dot(p) + plane.offset) <= tolerance &&
           plane.normal.dot(n) >= cos_angle;
  }
};

Plane FitPlane(const OrganizedCloud& cloud, const std::vector<int>& indices) {
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (int i : indices) mean += cloud.points_C[i];
  mean /= static_cast<float>(indices.size());
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  for (int i : indices) {
    const Eigen::Vector3f d = cloud.points_C[i] - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(cov);
  Plane plane;
  plane.normal = solver.eigenvectors().col(0);
  if (plane.normal.dot(mean) > 0.f) plane.normal = -plane.normal;
  plane.offset = -plane.normal.dot(mean);
  return plane;
}

#if defined(__SSE2__)
// InlierTest::operator() for four points at once, with its float operations in its order.
__m128 InlierLanes(const Plane& plane, const InlierTest& inlier, const Lanes& p, const Lanes& n) {
  const Lanes normal{_mm_set1_ps(plane.normal.x()), _mm_set1_ps(plane.normal.y()),
                     _mm_set1_ps(plane.normal.z())};
  // std::max(1.f, z * z) is z * z when 1 < z * z, else 1: exactly maxps(z * z, 1).
  const __m128 tolerance = _mm_mul_ps(_mm_set1_ps(inlier.distance_m),
                                      _mm_max_ps(_mm_mul_ps(p.z, p.z), _mm_set1_ps(1.f)));
  const __m128 distance =
      _mm_andnot_ps(_mm_set1_ps(-0.f), _mm_add_ps(Dot(normal, p), _mm_set1_ps(plane.offset)));
  return _mm_and_ps(_mm_cmple_ps(distance, tolerance),
                    _mm_cmpge_ps(Dot(normal, n), _mm_set1_ps(inlier.cos_angle)));
}
#endif

size_t CountInliers(const Plane& plane, const InlierTest& inlier,
                    const std::vector<Eigen::Vector3f>& points,
                    const std::vector<Eigen::Vector3f>& normals) {
  size_t count = 0;
  size_t k = 0;
#if defined(__SSE2__)
  for (; k + 4 <= points.size(); k += 4) {
    const int mask =
        _mm_movemask_ps(InlierLanes(plane, inlier, LoadLanes(&points[k]), LoadLanes(&normals[k])));
    count += static_cast<size_t>((mask & 1) + ((mask >> 1) & 1) + ((mask >> 2) & 1) + (mask >> 3));
  }
#endif
  for (; k < points.size(); ++k) count += inlier(plane, points[k], normals[k]) ? 1 : 0;
  return count;
}

// Best point+normal hypothesis over the remaining samples, refined on its inliers.
bool FindPlane(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
               const std::vector<int>& samples, const InlierTest& inlier, int iterations,
               std::mt19937* rng, Plane* plane) {
  std::uniform_int_distribution<size_t> pick(0, samples.size() - 1);
  size_t best_count = 0;
  const size_t stride = std::max<size_t>(1, samples.size() / kMaxScoredSamples);
  // The scored samples side by side: every hypothesis reads all of them.
  std::vector<Eigen::Vector3f> scored_points, scored_normals;
  for (size_t k = 0; k < samples.size(); k += stride) {
    scored_points.push_back(cloud.points_C[samples[k]]);
    scored_normals.push_back(normals[samples[k]]);
  }
  for (int it = 0; it < iterations; ++it) {
    const int seed = samples[pick(*rng)];
    Plane candidate{normals[seed], -normals[seed].dot(cloud.points_C[seed])};
    const size_t count = CountInliers(candidate, inlier, scored_points, scored_normals);
    if (count > best_count) {
      best_count = count;
      *plane = candidate;
    }
  }
  if (best_count < 3) return false;  // too few to refit
  std::vector<int> inliers;
  for (int i : samples) {
    if (inlier(*plane, cloud.points_C[i], normals[i])) inliers.push_back(i);
  }
  *plane = FitPlane(cloud, inliers);
  return true;
}

// Labels every pixel with the first of `planes` it is an inlier of; returns for each plane
// whether its metric area reaches `min_area_m2`. This is what labelling the planes one after the
// other, each taking the inliers still free, gives, in one pass over the image instead of one per
// plane. The area is summed in pixel order and only until it reaches the minimum: the terms are
// positive, so the full sum would reach it too.
std::vector<bool> AssignPlanes(const OrganizedCloud& cloud,
                               const std::vector<Eigen::Vector3f>& normals,
                               const std::vector<Plane>& planes, const InlierTest& inlier,
                               float focal_px, float min_area_m2,
                               std::vector<std::int8_t>* plane_of_pixel) {
  std::vector<float> area_m2(planes.size(), 0.f);
  std::vector<bool> large(planes.size(), false);
  // Pixels take their plane in pixel order, so each plane's area sums in that order.
  auto take = [&](size_t i, size_t k) {
    (*plane_of_pixel)[i] = static_cast<std::int8_t>(k);
    if (!large[k]) {
      area_m2[k] += PixelAreaM2(cloud.points_C[i], planes[k].normal, focal_px);
      large[k] = !(area_m2[k] < min_area_m2);
    }
  };
  size_t i = 0;
#if defined(__SSE2__)
  std::vector<int> plane_of_lane(4);
  for (; i + 4 <= cloud.size(); i += 4) {
    const Lanes p = LoadLanes(&cloud.points_C[i]);
    const Lanes n = LoadLanes(&normals[i]);
    __m128 free =
        _mm_and_ps(Finite(p.z), _mm_and_ps(Finite(n.x), _mm_and_ps(Finite(n.y), Finite(n.z))));
    if (_mm_movemask_ps(free) == 0) continue;
    std::fill(plane_of_lane.begin(), plane_of_lane.end(), -1);
    for (size_t k = 0; k < planes.size(); ++k) {
      const __m128 taken = _mm_and_ps(free, InlierLanes(planes[k], inlier, p, n));
      const int mask = _mm_movemask_ps(taken);
      for (int lane = 0; lane < 4; ++lane) {
        if (mask & (1 << lane)) plane_of_lane[lane] = static_cast<int>(k);
      }
      free = _mm_andnot_ps(taken, free);
      if (_mm_movemask_ps(free) == 0) break;
    }
    for (int lane = 0; lane < 4; ++lane) {
      if (plane_of_lane[lane] >= 0) take(i + lane, static_cast<size_t>(plane_of_lane[lane]));
    }
  }
#endif
  for (; i < cloud.size(); ++i) {
    if (!cloud.IsValid(static_cast<int>(i)) || !normals[i].allFinite()) continue;
    for (size_t k = 0; k < planes.size(); ++k) {
      if (!inlier(planes[k], cloud.points_C[i], normals[i])) continue;
      take(i, k);
      break;
    }
  }
  return large;
}

}  // namespace

int DetectSupportingPlanes(const OrganizedCloud& cloud_C,
                           const std::vector<Eigen::Vector3f>& normals,
                           const SegmenterConfig& config, float focal_px,
                           std::vector<std::int8_t>* plane_of_pixel) {
  plane_of_pixel->assign(cloud_C.size(), -1);
  std::vector<int> samples;
  for (int v = kSampleStridePx / 2; v < cloud_C.height; v += kSampleStridePx) {
    for (int u = kSampleStridePx / 2; u < cloud_C.width; u += kSampleStridePx) {
      const int i = v * cloud_C.width + u;
      if (cloud_C.IsValid(i) && normals[i].allFinite()) samples.push_back(i);
    }
  }
  const InlierTest inlier{config.plane_distance_m,
                          std::cos(config.plane_normal_angle_deg * kPi / 180.f)};

  std::mt19937 rng(12345);  // fixed seed: the same cloud always gives the same planes
  // Hypotheses first, each on the samples the previous ones leave free, then one labelling pass.
  std::vector<Plane> planes;
  while (static_cast<int>(planes.size()) < config.max_planes && samples.size() >= 16) {
    Plane plane;
    if (!FindPlane(cloud_C, normals, samples, inlier, config.plane_iterations, &rng, &plane)) break;
    planes.push_back(plane);
    std::vector<int> rest;
    for (int i : samples) {
      if (!inlier(plane, cloud_C.points_C[i], normals[i])) rest.push_back(i);
    }
    samples.swap(rest);
  }
  const std::vector<bool> large = AssignPlanes(cloud_C, normals, planes, inlier, focal_px,
                                               config.min_plane_area_m2, plane_of_pixel);
  // Hypotheses come largest first: after the first plane too small to support anything, later
  // ones would fail too, so they are dropped with it.
  int found = 0;
  while (found < static_cast<int>(planes.size()) && large[found]) ++found;
  if (found < static_cast<int>(planes.size())) {
    for (std::int8_t& plane : *plane_of_pixel) {
      if (plane >= found) plane = -1;
    }
  }
  return found;
}

}  // namespace objmap::seg
