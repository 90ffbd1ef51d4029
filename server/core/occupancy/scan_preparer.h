#pragma once
// Internal to the occupancy module: turns one scan into the voxel updates it makes (free voxels
// in a FreeSpaceGrid, occupied voxels as Morton codes) without touching an OcTree, so that
// scans can be prepared on several threads and applied to the tree in order.

#include <Eigen/Core>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "occupancy/free_space_grid.h"
#include "occupancy/occupancy_map.h"
#include "occupancy/projective_carver.h"

namespace objmap::occupancy_internal {

/// Thread-safety: none; one preparer per thread.
class ScanPreparer {
 public:
  /// `threads`: those that carve one scan (OccupancyConfig::threads_per_scan by default).
  explicit ScanPreparer(const OccupancyConfig& config, int threads = 0)
      : config_(config),
        threads_(threads > 0 ? threads : config.threads_per_scan),
        grid_(config.resolution_m),
        carver_(config.resolution_m) {}

  /// Casts the scan's rays ray by ray (OcTree::computeRayKeys semantics).
  void Prepare(const ScanW& scan);
  /// Carves the scan's free space from the depth image (ProjectiveCarver); ray by ray when its
  /// points do not lie on their pixel rays. With `region`, only the updates inside it are kept
  /// (and little work is spent outside it).
  void Prepare(const DepthScanW& scan, const FreeSpaceGrid* region = nullptr);

  /// Marks in `region` (Reset() to a box holding the scan's camera centre and points) the
  /// octree-aligned blocks of 2^block_log2 voxels the scan can update.
  void MarkReach(const DepthScanW& scan, int block_log2, FreeSpaceGrid* region);

  /// A scan is prepared (and not yet applied).
  [[nodiscard]] bool ready() const { return ready_ && !applied_; }
  void MarkApplied() { applied_ = true; }
  /// The last Prepare() left updates to apply, applied since or not: they stay until the next
  /// Prepare(), so that a copy of the map can take them too.
  [[nodiscard]] bool holds_scan() const { return ready_; }
  [[nodiscard]] const FreeSpaceGrid& free_space() const { return grid_; }
  /// Morton codes, sorted and distinct; none of them is set in free_space().
  [[nodiscard]] const std::vector<std::uint64_t>& occupied() const { return occupied_keys_; }
  /// Stats of the last Prepare(); tree_update_ms is left to whoever applies it.
  [[nodiscard]] const IntegrationStats& stats() const { return stats_; }

 private:
  /// What one point contributes: the end of its free-space ray, and its voxel when occupied.
  struct PointRay {
    bool carves = false;
    Eigen::Vector3f free_end_W = Eigen::Vector3f::Zero();
    bool marks_occupied = false;
    VoxelKey occupied_key{};
  };
  [[nodiscard]] PointRay RayOf(const Eigen::Vector3f& origin, const Eigen::Vector3f& point_W,
                               bool is_object) const;
  void PrepareRayByRay(const ScanW& scan, const FreeSpaceGrid* region);
  // Drops the updates outside `region` (for regenerating only part of a map).
  void DropOutside(const FreeSpaceGrid& region);
  void CollectRays(const ScanW& scan);
  void KeepOneRayPerEndVoxel();
  void CastRays(const Eigen::Vector3f& origin, const VoxelKey& origin_key);
  // Computes the pixels' rays and the occupied voxels; false when the projective path does not
  // apply (points off their pixel rays, or a camera outside the key range).
  bool CollectPixelRays(const DepthScanW& scan);
  void SortOccupied();
  void Finish(std::chrono::steady_clock::time_point start, std::size_t rays);

  OccupancyConfig config_;
  int threads_;
  FreeSpaceGrid grid_;
  ProjectiveCarver carver_;
  IntegrationStats stats_;
  bool ready_ = false;    // the last Prepare() finished with updates
  bool applied_ = false;  // and they were applied
  // Scratch, kept between scans to avoid reallocations.
  std::vector<Eigen::Vector3f> ray_ends_W_;
  std::vector<std::uint64_t> occupied_keys_;
  VoxelKey min_key_{}, max_key_{};
};

}  // namespace objmap::occupancy_internal
