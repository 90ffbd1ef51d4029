#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <functional>
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
  /// Structure rays stop carving free space short of their endpoint by structure_margin_m +
  /// structure_margin_per_m2 * range^2 (the endpoint is still marked occupied). Depth noise puts
  /// about half of the endpoints behind the true surface (sigma and quantization steps of
  /// structured-light and stereo sensors grow with range squared), and a ray carved up to such an
  /// endpoint erases the surface voxel that other rays marked. 0 and 0: stock OctoMap.
  double structure_margin_m = 0.01;
  double structure_margin_per_m2 = 0.005;
  /// Approximation for speed: cast one free-space ray per distinct end voxel (to the first point
  /// in it) instead of one per point. Off: the result equals stock insertPointCloud exactly.
  bool one_ray_per_end_voxel = false;
  /// Threads that carve one depth scan's free space (its blocks are split between them; the map
  /// is the same for any number). IntegrateSequence() on several threads carves each scan on one.
  int threads_per_scan = 2;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// One keyframe's points in the world frame, split by what they belong to.
struct ScanW {
  Eigen::Vector3f origin_W = Eigen::Vector3f::Zero();  ///< camera centre
  std::vector<Eigen::Vector3f> structure_points_W;     ///< endpoints marked occupied
  std::vector<Eigen::Vector3f> object_points_W;        ///< carve free space, endpoint not marked
};

/// One keyframe as an organized depth image: the same rays as the ScanW of its points (ToScanW),
/// but the pixel grid lets OccupancyMap decide whole blocks of free space at once instead of
/// walking every ray through every voxel (projective, coarse-to-fine carving).
struct DepthScanW {
  Eigen::Isometry3f T_W_C = Eigen::Isometry3f::Identity();
  int width = 0;
  int height = 0;
  float fx = 0.f, fy = 0.f, cx = 0.f, cy = 0.f;  ///< pinhole model the points were made with
  /// Row-major, width * height points in the camera frame; pixel (u, v)'s point must lie on its
  /// ray z * ((u - cx) / fx, (v - cy) / fy, 1). Non-finite or z <= 0: no depth at the pixel.
  std::vector<Eigen::Vector3f> points_C;
  /// Row-major, 1 where the pixel belongs to an object (ScanW::object_points_W); empty: none.
  std::vector<std::uint8_t> object_mask;
};

/// The box, in the camera frame, that holds every voxel a scan's rays can update: the camera
/// centre and the scan's points (a ray cut at max range ends between the two), grown by
/// `margin_m` (a voxel diagonal or more, for the voxels they fall in). ReachInWorld() moves it by
/// a pose: a world box holding those voxels for that pose.
[[nodiscard]] Eigen::AlignedBox3d ReachInCameraFrame(const DepthScanW& scan, double margin_m);
[[nodiscard]] Eigen::AlignedBox3d ReachInWorld(const Eigen::AlignedBox3d& reach_C,
                                               const Eigen::Isometry3d& T_W_C);

/// The points of `scan` in the world frame, split as its object mask says: the input with which
/// the ray-by-ray integration gives what the projective one gives for `scan`.
[[nodiscard]] ScanW ToScanW(const DepthScanW& scan);

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
  bool projective = false;          ///< decided block-wise from the depth image (DepthScanW)
  std::size_t blocks_decided = 0;   ///< projective: blocks found all free or all untouched
  std::size_t voxels_tested = 0;    ///< projective: single voxels tested against their rays
  double tree_update_ms = 0.0;      ///< applying the updates to the OcTree
};

/// Occupancy of an axis-aligned box at some resolution (cells of that size, aligned with the
/// OcTree's grid, that intersect the box).
struct RegionOccupancy {
  double resolution_m = 0.0;  ///< cell size actually used (a power-of-two multiple of the leaf)
  std::size_t occupied = 0;
  std::size_t free = 0;
  std::size_t unknown = 0;
  struct Cell {
    Eigen::Vector3d center_W;
    VoxelState state = VoxelState::kUnknown;
  };
  std::vector<Cell> known_cells;  ///< free and occupied cells, when asked for (up to the limit)
  bool truncated = false;         ///< more known cells than the limit
};

/// First voxel a ray meets (see OccupancyMap::CastRay).
struct RayHit {
  bool hit = false;
  VoxelState state = VoxelState::kUnknown;  ///< kOccupied, or kUnknown when unknown stops rays
  Eigen::Vector3d voxel_center_W = Eigen::Vector3d::Zero();
  double distance_m = 0.0;  ///< from the origin to the voxel centre
};

/// Thread-safety: none. Callers serialize Integrate() and ApplyPreparedScan() against queries;
/// PrepareScan() may run alongside const queries (not alongside another writer).
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
  /// Integrate() in two steps, for callers that share the map with readers: PrepareScan() casts
  /// the rays into scratch state of its own and never touches the OcTree, so const queries may
  /// run meanwhile; ApplyPreparedScan() writes the OcTree (most of a keyframe's time is the
  /// first step). A second PrepareScan() before the apply replaces the first.
  void PrepareScan(const ScanW& scan);
  void ApplyPreparedScan();
  /// Writes the scan that `source`'s last PrepareScan() prepared (applied there or not) into
  /// this map: a copy kept equal to `source` takes each scan without casting its rays again.
  /// last_stats(): the scan's, with this map's tree_update_ms.
  void ApplyScanPreparedBy(const OccupancyMap& source);

  /// The same for a depth image, an order of magnitude faster: free space is decided for whole
  /// octree blocks from the image (a block that every pixel ray it projects to passes through
  /// is free, one that no ray reaches is untouched) and only blocks at surfaces and silhouettes
  /// are refined down to single voxels, each tested exactly against the rays of the pixels it
  /// projects to. The result equals Integrate(ToScanW(scan)) up to rays that graze a voxel's
  /// edge (tested in tests/occupancy). A scan whose points do not lie on their pixel rays is
  /// integrated ray by ray.
  void Integrate(const DepthScanW& scan);
  void PrepareScan(const DepthScanW& scan);
  [[nodiscard]] const IntegrationStats& last_stats() const;

  /// Integrates scans 0 .. count - 1 in order, the same map as Integrate() of each in turn, with
  /// the rays of up to `threads` scans cast at once (`scan_at` is called on those threads, at
  /// most once per index) while the OcTree takes them in order. last_stats(): the last scan's.
  void IntegrateSequence(std::size_t count, const std::function<DepthScanW(std::size_t)>& scan_at,
                         int threads);

  /// Rebuilds the map where the rays of the `changed` scans reach (give each moved keyframe's
  /// scan twice, with its old and its new pose), in blocks of 16 voxels: every voxel there
  /// becomes unknown, then scans 0 .. count - 1 are integrated in order, each only there (as
  /// IntegrateSequence). Nothing changes elsewhere. When the sequence holds every scan whose
  /// rays reach into that space, the result is the map integrating all scans anew gives: after a
  /// correction that moves a few keyframes, only the space they see is redone, and the other
  /// keyframes only there. Returns the voxels rebuilt (the region's size).
  std::size_t RegenerateWhereReached(const std::vector<DepthScanW>& changed, std::size_t count,
                                     const std::function<DepthScanW(std::size_t)>& scan_at,
                                     int threads);

  /// A copy of the whole map (OcTree and configuration).
  [[nodiscard]] OccupancyMap Clone() const;

  [[nodiscard]] VoxelState Query(const Eigen::Vector3d& point_W) const;
  [[nodiscard]] OccupancyCounts Counts() const;

  /// Occupied / free / unknown cells of the box [min_W, max_W] at `resolution_m` (0 or at most
  /// the leaf: the map resolution; otherwise rounded up to leaf * 2^k, at most 2^15 leaves).
  /// Cells are the OcTree's nodes at that size (aligned with its grid); every cell the closed box
  /// touches counts, so a point-like box counts one cell, and occupied + free + unknown is the
  /// number of such cells. A coarse cell is occupied when any leaf in it is, free when known and
  /// not occupied (OctoMap inner-node semantics: max child occupancy), unknown otherwise. Lists
  /// known cells (in tree order) when `max_cells` > 0, at most `max_cells`, with `truncated` set
  /// when there were more. The box is clipped to the map's key range (+-32768 leaves); a box
  /// that is empty after that (or non-finite, or min > max) counts no cells. Costs the known
  /// nodes inside the box, not its volume.
  [[nodiscard]] RegionOccupancy QueryRegion(const Eigen::Vector3d& min_W,
                                            const Eigen::Vector3d& max_W, double resolution_m,
                                            std::size_t max_cells) const;

  /// Casts a ray from `origin_W` along `direction_W` (non-zero, need not be unit) through the
  /// leaf voxels it enters within `max_range_m` (<= 0 or infinite: until it leaves the map);
  /// returns the first occupied voxel, or the first unknown one when `unknown_stops`. The
  /// origin's own voxel is checked first, whatever the range: an origin inside an occupied (or,
  /// with `unknown_stops`, unknown) voxel is a hit at the distance to that voxel's centre, at most
  /// half a voxel diagonal. distance_m is to the voxel centre, so a hit near the end of the range
  /// may lie up to half a diagonal beyond `max_range_m`. No hit: `hit` false (also for a zero or
  /// non-finite direction, or an origin outside the map).
  [[nodiscard]] RayHit CastRay(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& direction_W,
                               double max_range_m, bool unknown_stops) const;

  /// The map, or the part of it whose leaves intersect [min_W, max_W] when `region` is true, as
  /// the bytes of a standard OctoMap binary file (.bt) at the map resolution. A pruned leaf
  /// larger than a voxel that touches the box is written whole. `leaf_count` (may be null): the
  /// leaves written.
  [[nodiscard]] std::string BinaryBytes(bool region, const Eigen::Vector3d& min_W,
                                        const Eigen::Vector3d& max_W,
                                        std::size_t* leaf_count) const;

  /// The whole OcTree with its log-odds (OctoMap's full node data, as in .ot files, after a
  /// line naming the format and the resolution): a checkpoint. ReadState() of these bytes gives
  /// the same map, and integrating further scans into it gives what integrating them into this
  /// map would.
  [[nodiscard]] std::string WriteState() const;
  /// Replaces the OcTree by one that WriteState() wrote at this map's resolution. False with a
  /// reason, and the map unchanged, when the bytes are not such a state.
  [[nodiscard]] bool ReadState(const std::string& bytes, std::string* why);

  /// Writes the map as a standard OctoMap binary file (.bt, opens in octovis).
  [[nodiscard]] bool WriteBinary(const std::string& path, std::string* why) const;
  /// Replaces the OcTree by the contents of an OctoMap binary file (.bt bytes, as WriteBinary
  /// and BinaryBytes write them). False with a reason, and the map unchanged, when the bytes are
  /// not such a file or its resolution is not this map's.
  [[nodiscard]] bool ReadBinary(const std::string& bytes, std::string* why);

  /// Centres of the occupied voxels at the map resolution (pruned occupied nodes are expanded).
  [[nodiscard]] std::vector<Eigen::Vector3d> OccupiedVoxelCenters() const;

  void Clear();
  /// Memory held by the OcTree's nodes, bytes (OcTree::memoryUsage).
  [[nodiscard]] std::size_t MemoryBytes() const;
  [[nodiscard]] const OccupancyConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A map read from an OctoMap binary file (.bt) at the file's own resolution (other settings:
/// `config`'s). nullptr with a reason naming the file when it cannot be read, or when its header
/// lacks a line of id OcTree, size, res and data (OctoMap itself reads a header without "size"
/// as an empty tree).
[[nodiscard]] std::unique_ptr<OccupancyMap> ReadOctomapFile(const std::string& path,
                                                            OccupancyConfig config,
                                                            std::string* why);

}  // namespace objmap
