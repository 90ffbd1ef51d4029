#pragma once
// Internal to the occupancy module: the free space of one depth image, decided block by block
// (coarse to fine) instead of ray by ray. Free space is mostly large empty blocks; a block is
// decided at once when every pixel ray it projects to passes through it (all free) or none
// reaches it (untouched). Only blocks at surfaces and silhouettes are refined, down to single
// voxels, and a single voxel is free exactly when one of its pixels' rays crosses it before the
// ray's end voxel, which is what OcTree::computeRayKeys would have marked.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "occupancy/free_space_grid.h"

namespace objmap::occupancy_internal {

struct PinholeCamera {
  Eigen::Isometry3f T_W_C = Eigen::Isometry3f::Identity();
  int width = 0;
  int height = 0;
  float fx = 0.f, fy = 0.f, cx = 0.f, cy = 0.f;
};

struct CarvingStats {
  std::size_t blocks_decided = 0;  ///< blocks found all free or untouched above voxel size
  std::size_t voxels_tested = 0;   ///< single voxels tested against their pixels' rays
};

/// Thread-safety: none; one carver per integrating thread.
class ProjectiveCarver {
 public:
  explicit ProjectiveCarver(double resolution_m) : resolution_m_(resolution_m) {}

  /// Starts a scan: every pixel without a ray until SetRay().
  void Reset(const PinholeCamera& camera);
  /// Pixel `pixel` (row-major) casts free space from the camera centre up to `free_end_W`
  /// (exclusive of the end's voxel). The end must lie on the pixel's ray.
  void SetRay(int pixel, const Eigen::Vector3f& free_end_W);

  /// Marks in `grid` (already Reset() to a box holding the camera centre and every free end)
  /// the voxels the rays cross; with `region` (pyramid built), blocks outside it are skipped
  /// (the voxels marked outside it are not all of those crossed there).
  /// `threads` > 1 splits the blocks between threads (the same voxels are marked).
  CarvingStats Carve(FreeSpaceGrid* grid, const FreeSpaceGrid* region = nullptr, int threads = 1);

  /// Marks in `region` every octree-aligned block of 2^block_log2 voxels that some ray reaches
  /// (a superset of the voxels Carve() marks, at block granularity).
  void MarkReachedBlocks(int block_log2, FreeSpaceGrid* region);

  /// The keys of the camera centre and of every free end so far, as a box.
  void KeyBox(VoxelKey* min_key, VoxelKey* max_key) const {
    *min_key = min_key_;
    *max_key = max_key_;
  }
  /// Pixels with a ray.
  [[nodiscard]] std::size_t rays() const { return ray_count_; }

 private:
  struct PixelRays {           // structure of arrays over pixels, for vectorized scans of a row
    std::vector<float> range;  // length of the free segment; -1: no ray
    // 1 / (end - camera centre), per axis: the segment is centre + t (end - centre), t in [0, 1].
    std::array<std::vector<float>, 3> inverse_direction;
  };
  struct Rect {
    int u0, v0, u1, v1;  // inclusive pixel bounds
  };
  struct Footprint {
    enum Kind { kOutside, kPartly, kInside } kind = kOutside;
    Rect rect{};
  };
  // Over a set of pixels: the shortest and the longest ray, and the largest distance (in
  // pixels, chessboard) from a pixel to the nearest pixel with a ray.
  struct RangeBounds {
    float min_range;
    float max_range;
    int max_hole_distance;
  };

  void BuildHoleDistance();
  void BuildRangePyramid();
  [[nodiscard]] RangeBounds BoundsOver(const Rect& rect) const;
  [[nodiscard]] float MaxRangeOver(const Rect& rect) const;
  [[nodiscard]] Footprint Project(const Eigen::Vector3f& lo_rel_W, float size_m) const;
  [[nodiscard]] Footprint ProjectCentered(const Eigen::Vector3f& center,
                                          const Eigen::Vector3f& half_x,
                                          const Eigen::Vector3f& half_y,
                                          const Eigen::Vector3f& half_z) const;
  // Per corner of a voxel: the offsets of fx x + cx z, fy y + cy z and z from the voxel centre's.
  struct CornerOffsets {
    std::array<float, 8> u, v, z;
    float z_min;
  };
  [[nodiscard]] CornerOffsets CornerOffsetsOf(const Eigen::Vector3f& half_x,
                                              const Eigen::Vector3f& half_y,
                                              const Eigen::Vector3f& half_z) const;
  [[nodiscard]] Footprint ProjectVoxel(const CornerOffsets& offsets, const Eigen::Vector3f& center,
                                       const Eigen::Vector3f& half_x, const Eigen::Vector3f& half_y,
                                       const Eigen::Vector3f& half_z) const;
  [[nodiscard]] Footprint ProjectClipped(const std::array<float, 8>& x,
                                         const std::array<float, 8>& y,
                                         const std::array<float, 8>& z) const;
  [[nodiscard]] Footprint FootprintOf(float u_min, float u_max, float v_min, float v_max,
                                      bool all_in_front) const;
  void CarveBlock(const VoxelKey& base, int size_log2, const FreeSpaceGrid* region,
                  FreeSpaceGrid* grid, CarvingStats* stats) const;
  void MarkReached(const VoxelKey& base, int size_log2, int block_log2, FreeSpaceGrid* region);
  // Calls visit(base) for each top-level block of the key box.
  template <typename Visit>
  void ForEachTopBlock(Visit visit) const;
  // Distances from the camera centre to the nearest and farthest point of a block, and the
  // block's corner relative to the centre.
  void BlockDistances(const VoxelKey& base, int size_log2, Eigen::Vector3f* to_lo,
                      float* min_distance, float* max_distance) const;
  void CarveVoxels(const VoxelKey& base, const Eigen::Vector3f& lo_rel_W, int size,
                   float block_max_range, FreeSpaceGrid* grid, CarvingStats* stats) const;
  void BuildWindowMax();
  [[nodiscard]] static int WindowLevelCovering(float radius_px);
  [[nodiscard]] static int WindowLevelWithin(float radius_px);
  [[nodiscard]] bool VoxelCrossed(const Eigen::Vector3f& lo_rel_W, const Footprint& footprint,
                                  float min_distance) const;

  double resolution_m_;
  PinholeCamera camera_;
  Eigen::Matrix3f R_C_W_ = Eigen::Matrix3f::Identity();
  Eigen::Vector3d origin_W_ = Eigen::Vector3d::Zero();
  VoxelKey min_key_{}, max_key_{};
  float longest_range_ = -1.f;
  std::size_t ray_count_ = 0;
  PixelRays rays_;
  std::vector<std::uint8_t> hole_distance_;  // per pixel, 0 where there is a ray
  // levels_[l]: RangeBounds over tiles of 2^l x 2^l pixels (level 0: the pixels).
  struct RangeLevel {
    int width = 0, height = 0;
    std::vector<float> min_range, max_range;
    std::vector<std::uint8_t> max_hole_distance;
  };
  std::vector<RangeLevel> levels_;
  // window_max_[l]: per pixel, the longest ray within 2^l pixels of it (chessboard distance).
  static constexpr int kWindowLevels = 5;
  std::vector<std::vector<float>> window_max_;
};

}  // namespace objmap::occupancy_internal
