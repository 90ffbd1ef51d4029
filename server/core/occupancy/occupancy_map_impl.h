#pragma once
// Internal to the occupancy module (includes OctoMap; never include it from a public header).
// The state behind OccupancyMap, shared by the integration (occupancy_map.cc) and the region
// queries (region_queries.cc).

#include <cstdint>
#include <vector>

#include "occupancy/batch_octree.h"
#include "occupancy/free_space_grid.h"
#include "occupancy/occupancy_map.h"

namespace objmap {

struct OccupancyMap::Impl {
  explicit Impl(const OccupancyConfig& c) : config(c), tree(c.resolution_m), grid(c.resolution_m) {
    tree.setProbHit(c.probability_hit);
    tree.setProbMiss(c.probability_miss);
    tree.setClampingThresMin(c.clamping_min);
    tree.setClampingThresMax(c.clamping_max);
  }

  void CollectRays(const ScanW& scan);
  void KeepOneRayPerEndVoxel();
  void CastRays(const Eigen::Vector3f& origin, const occupancy_internal::VoxelKey& origin_key);
  void ApplyOccupied();

  OccupancyConfig config;
  occupancy_internal::BatchOcTree tree;
  occupancy_internal::FreeSpaceGrid grid;
  IntegrationStats stats;
  // Scratch, kept between scans to avoid reallocations.
  std::vector<Eigen::Vector3f> ray_ends_W;
  std::vector<std::uint64_t> occupied_keys;
  occupancy_internal::VoxelKey min_key{}, max_key{};
  bool scan_prepared = false;  ///< PrepareScan() filled the scratch; ApplyPreparedScan() not yet
};

}  // namespace objmap
