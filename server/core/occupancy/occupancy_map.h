#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace objmap {

/// Occupancy of the non-object structure, stored in an octomap::OcTree (paper Sec. III-E).
struct OccupancyConfig {
  /// Leaf size of the OcTree in metres (paper: 1 cm).
  double resolution_m = 0.01;
  /// Rays longer than this only carve free space up to it and mark no endpoint.
  double max_range_m = 4.0;
  /// OctoMap sensor model, the stock defaults.
  double probability_hit = 0.7;
  double probability_miss = 0.4;
  double clamping_min = 0.1192;
  double clamping_max = 0.971;
  /// Object rays stop this many voxels short of the object point, so object surfaces do not
  /// carve the structure they rest on.
  int object_margin_voxels = 2;
  /// Approximation for speed: cast one free-space ray per distinct end voxel (to the first point
  /// in it) instead of one per point. Off: the result equals stock insertPointCloud exactly.
  bool one_ray_per_end_voxel = false;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// One keyframe's points in the world frame, split by what they belong to.
struct ScanW {
  Eigen::Vector3f origin_W = Eigen::Vector3f::Zero();  ///< camera centre
  std::vector<Eigen::Vector3f> structure_points_W;     ///< endpoints marked occupied
  std::vector<Eigen::Vector3f> object_points_W;        ///< carve free space, endpoint not marked
};

enum class VoxelState { kUnknown, kFree, kOccupied };

/// Counts of leaf voxels at the map resolution (pruned nodes are expanded in the count).
struct OccupancyCounts {
  std::size_t occupied = 0;
  std::size_t free = 0;
};

/// What the last Integrate() did; for benchmarks and logs.
struct IntegrationStats {
  std::size_t rays = 0;             ///< rays cast (structure + object points)
  std::size_t free_voxels = 0;      ///< distinct voxels updated as free
  std::size_t occupied_voxels = 0;  ///< distinct voxels updated as occupied
  double cast_ms = 0.0;             ///< ray casting into the scan's voxel set
  double tree_update_ms = 0.0;      ///< applying the updates to the OcTree
};

/// Thread-safety: none. Callers serialize Integrate() against queries.
class OccupancyMap {
 public:
  explicit OccupancyMap(const OccupancyConfig& config);
  ~OccupancyMap();
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;

  /// Ray-casts every point from the origin: cells on the way become more free, structure
  /// endpoints more occupied. Same result as octomap::OcTree::insertPointCloud (each voxel gets
  /// at most one update per scan, occupied wins over free); non-finite points are skipped.
  void Integrate(const ScanW& scan);
  [[nodiscard]] const IntegrationStats& last_stats() const;

  [[nodiscard]] VoxelState Query(const Eigen::Vector3d& point_W) const;
  [[nodiscard]] OccupancyCounts Counts() const;

  /// Writes the map as a standard OctoMap binary file (.bt, opens in octovis).
  [[nodiscard]] bool WriteBinary(const std::string& path, std::string* why) const;

  void Clear();
  [[nodiscard]] const OccupancyConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap
