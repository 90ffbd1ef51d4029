// The projective integration (OccupancyMap::Integrate of a DepthScanW) against the ray-by-ray
// reference (Integrate of the same points as a ScanW, itself checked against stock OctoMap in
// occupancy_test): the same voxels free and occupied on rendered depth images with holes,
// silhouettes, object masks, truncated rays and a camera inside the scene.

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy/occupancy_map.h"
#include "occupancy/octree_compare.h"
#include "occupancy/rendered_scans.h"

namespace objmap {
namespace {

using testing::Cameras;
using testing::CameraSetup;
using testing::Render;
using testing::TreeOf;

// Integrates every camera's scan both ways and compares the maps leaf by leaf.
testing::LeafComparison CompareWithRayByRay(const OccupancyConfig& config,
                                            std::size_t* scans_projective) {
  OccupancyMap projective(config), ray_by_ray(config);
  *scans_projective = 0;
  for (const CameraSetup& camera : Cameras()) {
    const DepthScanW scan = Render(camera);
    projective.Integrate(scan);
    if (projective.last_stats().projective && projective.last_stats().blocks_decided > 0) {
      ++*scans_projective;
    }
    ray_by_ray.Integrate(ToScanW(scan));
  }
  const testing::LeafComparison cmp = testing::CompareTrees(TreeOf(projective), TreeOf(ray_by_ray));
  std::printf("known %zu, agree %zu, only projective %zu, only ray by ray %zu, differ %zu\n",
              cmp.known_in_either, cmp.agree, cmp.only_a, cmp.only_b, cmp.state_differs);
  return cmp;
}

TEST(ProjectiveIntegration, SameVoxelsAsRayByRayWithStockCarving) {
  OccupancyConfig config;
  config.structure_margin_m = 0.0;
  config.structure_margin_per_m2 = 0.0;
  std::size_t projective_scans = 0;
  const testing::LeafComparison cmp = CompareWithRayByRay(config, &projective_scans);
  EXPECT_EQ(projective_scans, Cameras().size());
  EXPECT_GT(cmp.known_in_either, 500000u);
  EXPECT_EQ(cmp.state_differs, 0u);
  // Exact but for ray ends within float rounding of a voxel face or segments grazing an edge,
  // where the slab test and the DDA may round differently: a few voxels in a million.
  EXPECT_LE(cmp.only_a + cmp.only_b, cmp.known_in_either / 50000);
}

TEST(ProjectiveIntegration, SameVoxelsWithMarginsAndTruncatedRays) {
  OccupancyConfig config;    // structure and object margins on, as the mapper runs
  config.max_range_m = 1.6;  // the far walls lie beyond: free space only up to 1.6 m
  std::size_t projective_scans = 0;
  const testing::LeafComparison cmp = CompareWithRayByRay(config, &projective_scans);
  EXPECT_EQ(projective_scans, Cameras().size());
  EXPECT_GT(cmp.known_in_either, 200000u);
  EXPECT_EQ(cmp.state_differs, 0u);
  EXPECT_LE(cmp.only_a + cmp.only_b, cmp.known_in_either / 50000);
}

TEST(ProjectiveIntegration, PointsOffTheirPixelRaysAreIntegratedRayByRay) {
  DepthScanW scan = Render(Cameras()[0]);
  for (std::size_t i = 0; i < scan.points_C.size(); i += 97) {
    scan.points_C[i].x() += 0.01f;  // a whole centimetre sideways: not this pixel's ray
  }
  OccupancyConfig config;
  OccupancyMap from_depth(config), from_points(config);
  from_depth.Integrate(scan);
  EXPECT_FALSE(from_depth.last_stats().projective);
  from_points.Integrate(ToScanW(scan));
  const testing::LeafComparison cmp =
      testing::CompareTrees(TreeOf(from_depth), TreeOf(from_points));
  EXPECT_GT(cmp.known_in_either, 10000u);
  EXPECT_EQ(cmp.agree, cmp.known_in_either);
}

TEST(ProjectiveIntegration, ToScanWSplitsByTheMaskAndSkipsPixelsWithoutDepth) {
  const DepthScanW scan = Render(Cameras()[0]);
  const ScanW points = ToScanW(scan);
  std::size_t with_depth = 0, objects = 0;
  for (std::size_t i = 0; i < scan.points_C.size(); ++i) {
    if (!scan.points_C[i].allFinite()) continue;
    ++with_depth;
    objects += scan.object_mask[i];
  }
  EXPECT_GT(objects, 100u);
  EXPECT_LT(with_depth, scan.points_C.size());  // the holes
  EXPECT_EQ(points.object_points_W.size(), objects);
  EXPECT_EQ(points.structure_points_W.size(), with_depth - objects);
  EXPECT_TRUE(points.origin_W.isApprox(scan.T_W_C.translation()));
}

}  // namespace
}  // namespace objmap
