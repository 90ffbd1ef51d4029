// Supporting planes (table, floor, walls) in the spirit of Pham et al. 2016 (paper Sec. III-B):
// sequential RANSAC where one pixel and its normal form a hypothesis, refined by PCA; a plane is
// kept only when its metric area is large, so box faces stay ordinary surfaces.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

#include "segmentation/segmentation_internal.h"

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

// Best point+normal hypothesis over the remaining samples, refined on its inliers.
bool FindPlane(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
               const std::vector<int>& samples, const InlierTest& inlier, int iterations,
               std::mt19937* rng, Plane* plane) {
  std::uniform_int_distribution<size_t> pick(0, samples.size() - 1);
  size_t best_count = 0;
  const size_t stride = std::max<size_t>(1, samples.size() / kMaxScoredSamples);
  for (int it = 0; it < iterations; ++it) {
    const int seed = samples[pick(*rng)];
    Plane candidate{normals[seed], -normals[seed].dot(cloud.points_C[seed])};
    size_t count = 0;
    for (size_t k = 0; k < samples.size(); k += stride) {
      const int i = samples[k];
      count += inlier(candidate, cloud.points_C[i], normals[i]) ? 1 : 0;
    }
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

// Labels every free inlier pixel with `id` when the plane's metric area is large enough.
bool AssignPlane(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
                 const Plane& plane, const InlierTest& inlier, float focal_px, float min_area_m2,
                 int id, std::vector<std::int8_t>* plane_of_pixel) {
  std::vector<int> members;
  float area_m2 = 0.f;
  for (size_t i = 0; i < cloud.size(); ++i) {
    if ((*plane_of_pixel)[i] >= 0 || !cloud.IsValid(static_cast<int>(i))) continue;
    const Eigen::Vector3f& p = cloud.points_C[i];
    if (!normals[i].allFinite() || !inlier(plane, p, normals[i])) continue;
    members.push_back(static_cast<int>(i));
    area_m2 += PixelAreaM2(p, plane.normal, focal_px);
  }
  if (area_m2 < min_area_m2) return false;
  for (int i : members) (*plane_of_pixel)[i] = static_cast<std::int8_t>(id);
  return true;
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
  int found = 0;
  while (found < config.max_planes && samples.size() >= 16) {
    Plane plane;
    if (!FindPlane(cloud_C, normals, samples, inlier, config.plane_iterations, &rng, &plane)) break;
    if (!AssignPlane(cloud_C, normals, plane, inlier, focal_px, config.min_plane_area_m2, found,
                     plane_of_pixel)) {
      break;  // hypotheses are tried largest first, so smaller ones would fail too
    }
    std::vector<int> rest;
    for (int i : samples) {
      if ((*plane_of_pixel)[i] < 0) rest.push_back(i);
    }
    samples.swap(rest);
    ++found;
  }
  return found;
}

}  // namespace objmap::seg
