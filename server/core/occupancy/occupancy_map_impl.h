#pragma once
// Internal to the occupancy module (includes OctoMap; never include it from a public header).
// The state behind OccupancyMap, shared by the integration (occupancy_map.cc) and the region
// queries (region_queries.cc).

#include <chrono>
#include <cstdint>
#include <vector>

#include "occupancy/batch_octree.h"
#include "occupancy/free_space_grid.h"
#include "occupancy/occupancy_map.h"
#include "occupancy/projective_carver.h"

namespace objmap {

struct OccupancyMap::Impl {
  explicit Impl(const OccupancyConfig& c)
      : config(c), tree(c.resolution_m), grid(c.resolution_m), carver(c.resolution_m) {
    tree.setProbHit(c.probability_hit);
    tree.setProbMiss(c.probability_miss);
    tree.setClampingThresMin(c.clamping_min);
    tree.setClampingThresMax(c.clamping_max);
  }

  /// What one point contributes: the end of its free-space ray, and its voxel when occupied.
  struct PointRay {
    bool carves = false;
    Eigen::Vector3f free_end_W = Eigen::Vector3f::Zero();
    bool marks_occupied = false;
    occupancy_internal::VoxelKey occupied_key{};
  };
  [[nodiscard]] PointRay RayOf(const Eigen::Vector3f& origin, const Eigen::Vector3f& point_W,
                               bool is_object) const;
  void CollectRays(const ScanW& scan);
  void CarveDepthScan(const DepthScanW& scan);
  /// Clears the occupied voxels from the free set and summarizes it; the scan is then prepared.
  void FinishPreparedScan(std::chrono::steady_clock::time_point start, std::size_t rays);
  void KeepOneRayPerEndVoxel();
  void CastRays(const Eigen::Vector3f& origin, const occupancy_internal::VoxelKey& origin_key);

  OccupancyConfig config;
  occupancy_internal::BatchOcTree tree;
  occupancy_internal::FreeSpaceGrid grid;
  occupancy_internal::ProjectiveCarver carver;
  IntegrationStats stats;
  // Scratch, kept between scans to avoid reallocations.
  std::vector<Eigen::Vector3f> ray_ends_W;
  std::vector<std::uint64_t> occupied_keys;  ///< Morton codes, sorted, distinct
  occupancy_internal::VoxelKey min_key{}, max_key{};
  bool scan_prepared = false;  ///< PrepareScan() filled the scratch; ApplyPreparedScan() not yet
};

}  // namespace objmap
