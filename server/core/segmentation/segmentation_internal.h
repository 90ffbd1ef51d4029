#pragma once
// Building blocks of Segmenter, shared between this module's .cc files only.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "segmentation/segmenter.h"
#include "types/organized_cloud.h"

namespace objmap::seg {

/// Two depths `step_px` pixels apart lie on one surface when they differ by less than a fraction
/// of the depth per pixel: the depth-discontinuity test that keeps objects apart.
inline bool DepthContinuous(float z_a, float z_b, float ratio, int step_px) {
  return std::abs(z_a - z_b) <= ratio * static_cast<float>(step_px) * std::min(z_a, z_b);
}

/// Unit normal per pixel facing the camera (n . p < 0); NaN where no continuous neighbours exist.
[[nodiscard]] std::vector<Eigen::Vector3f> ComputeNormals(const OrganizedCloud& cloud_C,
                                                          int step_px, float jump_ratio);

/// Focal length in pixels recovered from the cloud itself (x / z changes by 1 / f per column);
/// `fallback_px` when too few valid points exist.
[[nodiscard]] float EstimateFocalPx(const OrganizedCloud& cloud_C, float fallback_px);

/// Extracts up to config.max_planes large planes; writes a plane id per pixel (-1: none).
/// Returns the number of planes found.
int DetectSupportingPlanes(const OrganizedCloud& cloud_C,
                           const std::vector<Eigen::Vector3f>& normals,
                           const SegmenterConfig& config, float focal_px,
                           std::vector<std::int8_t>* plane_of_pixel);

/// Metric area a pixel covers at `point_C` on a surface with unit normal `normal`.
inline float PixelAreaM2(const Eigen::Vector3f& point_C, const Eigen::Vector3f& normal,
                         float focal_px) {
  // (z / f)^2 facing the camera, more when the surface is seen obliquely (capped at 4x).
  const float cos_view = std::max(0.25f, std::abs(normal.dot(point_C)) / point_C.norm());
  return point_C.z() * point_C.z() / (focal_px * focal_px * cos_view);
}

/// A group of connected pixels inside one image cell.
struct Supervoxel {
  int pixels = 0;
  int plane = -1;  ///< supporting plane id, -1 when not on a plane
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit, facing the camera
  bool has_normal = false;
  float area_m2 = 0.f;  ///< surface area covered by its pixels
};

/// Edge of the supervoxel adjacency graph with the paper's weight.
struct GraphEdge {
  int a = 0;
  int b = 0;
  float weight = 0.f;
};

/// Splits every cell of config.cell_px into depth-continuous pixel groups of one plane id.
void BuildSupervoxels(const OrganizedCloud& cloud_C, const std::vector<Eigen::Vector3f>& normals,
                      const std::vector<std::int8_t>& plane_of_pixel, const SegmenterConfig& config,
                      float focal_px, std::vector<int>* supervoxel_of_pixel,
                      std::vector<Supervoxel>* supervoxels);

/// One edge per pair of supervoxels that touch without a depth discontinuity, weighted as in
/// paper Sec. III-B.
[[nodiscard]] std::vector<GraphEdge> BuildAdjacencyGraph(
    const OrganizedCloud& cloud_C, const std::vector<int>& supervoxel_of_pixel,
    const std::vector<Supervoxel>& supervoxels, const SegmenterConfig& config);

/// Paper Sec. III-B: 0 on one plane, 1 across a plane boundary, (1 - n_i.n_j)^2 convex,
/// (1 - n_i.n_j) concave.
[[nodiscard]] float EdgeWeight(const Supervoxel& s_i, const Supervoxel& s_j,
                               float convex_tolerance);

}  // namespace objmap::seg
