#pragma once
// Internal to the occupancy module (includes OctoMap; never include it from a public header).
// The state behind OccupancyMap, shared by the integration (occupancy_map.cc) and the region
// queries (region_queries.cc).

#include <functional>
#include <vector>

#include "occupancy/batch_octree.h"
#include "occupancy/free_space_grid.h"
#include "occupancy/occupancy_map.h"
#include "occupancy/scan_preparer.h"

namespace objmap {

struct OccupancyMap::Impl {
  explicit Impl(const OccupancyConfig& c) : config(c), tree(c.resolution_m), preparer(c) {
    tree.setProbHit(c.probability_hit);
    tree.setProbMiss(c.probability_miss);
    tree.setClampingThresMin(c.clamping_min);
    tree.setClampingThresMax(c.clamping_max);
  }

  /// Writes a prepared scan into the tree and records the scan's stats.
  void Apply(occupancy_internal::ScanPreparer* prepared);

  /// Prepares and applies scans 0 .. count - 1 in order, rays cast on up to `threads` threads;
  /// with `region`, only the updates inside it.
  void IntegrateInOrder(std::size_t count, const std::function<DepthScanW(std::size_t)>& scan_at,
                        int threads, const occupancy_internal::FreeSpaceGrid* region);

  OccupancyConfig config;
  occupancy_internal::BatchOcTree tree;
  occupancy_internal::ScanPreparer preparer;  ///< PrepareScan()'s, kept between scans
  IntegrationStats stats;
};

}  // namespace objmap
