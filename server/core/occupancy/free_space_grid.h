#pragma once
// Internal to the occupancy module: the set of voxels one scan observes as free, kept as a
// bitmap of 8x8x8 bricks over the scan's bounding box, with a pyramid that says for each octree
// node whether it is empty, partly or fully free. The pyramid lets the OcTree update write whole
// free blocks at coarse depths instead of one leaf at a time.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace objmap::occupancy_internal {

/// OctoMap's key space: 16 levels, keys in [0, 65536) with the origin at 32768.
inline constexpr int kTreeDepth = 16;
inline constexpr int kKeyOffset = 32768;

using VoxelKey = std::array<std::uint16_t, 3>;

/// Leaf key of a coordinate as OcTree::coordToKey, without the range check: it may lie outside
/// [0, 2^16) (clamped to -1 and 2^16, so that far-away coordinates cannot overflow).
[[nodiscard]] std::int64_t CoordinateToKey(double coordinate_m, double resolution_m);

/// Keys of the voxels the closed box [min_W, max_W] touches, clipped to the key range; false
/// when none are left (or a corner is not finite).
[[nodiscard]] bool KeysOfBox(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                             double resolution_m, VoxelKey* lo, VoxelKey* hi);

/// Same discretization as OcTree::coordToKeyChecked; false outside the key range.
[[nodiscard]] bool PointToKey(const Eigen::Vector3f& point, double resolution_m, VoxelKey* key);

[[nodiscard]] inline std::uint64_t PackKey(const VoxelKey& k) {
  return (std::uint64_t{k[0]} << 32) | (std::uint64_t{k[1]} << 16) | k[2];
}
[[nodiscard]] inline VoxelKey UnpackKey(std::uint64_t packed) {
  return {static_cast<std::uint16_t>(packed >> 32), static_cast<std::uint16_t>(packed >> 16),
          static_cast<std::uint16_t>(packed)};
}

/// The corner key of child `child` (OctoMap's order: x -> 1, y -> 2, z -> 4) of the octree node
/// at `base` whose children are `half` voxels a side.
[[nodiscard]] inline VoxelKey ChildKey(const VoxelKey& base, unsigned int child, int half) {
  return {static_cast<std::uint16_t>(base[0] + ((child & 1) ? half : 0)),
          static_cast<std::uint16_t>(base[1] + ((child & 2) ? half : 0)),
          static_cast<std::uint16_t>(base[2] + ((child & 4) ? half : 0))};
}

/// Morton (octree) order of a key: interleaved bits, x lowest, so that sorted codes list the
/// voxels depth-first in OctoMap's child order (x -> 1, y -> 2, z -> 4).
[[nodiscard]] inline std::uint64_t SpreadBitsByThree(std::uint64_t v) {
  v = (v | v << 32) & 0x1F00000000FFFFull;
  v = (v | v << 16) & 0x1F0000FF0000FFull;
  v = (v | v << 8) & 0x100F00F00F00F00Full;
  v = (v | v << 4) & 0x10C30C30C30C30C3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}
[[nodiscard]] inline std::uint16_t GatherBitsByThree(std::uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v ^ (v >> 2)) & 0x10C30C30C30C30C3ull;
  v = (v ^ (v >> 4)) & 0x100F00F00F00F00Full;
  v = (v ^ (v >> 8)) & 0x1F0000FF0000FFull;
  v = (v ^ (v >> 16)) & 0x1F00000000FFFFull;
  v = (v ^ (v >> 32)) & 0x1FFFFFull;
  return static_cast<std::uint16_t>(v);
}
[[nodiscard]] inline std::uint64_t MortonCode(const VoxelKey& k) {
  return SpreadBitsByThree(k[0]) | SpreadBitsByThree(k[1]) << 1 | SpreadBitsByThree(k[2]) << 2;
}
[[nodiscard]] inline VoxelKey KeyOfMortonCode(std::uint64_t code) {
  return {GatherBitsByThree(code), GatherBitsByThree(code >> 1), GatherBitsByThree(code >> 2)};
}

enum class BlockState : std::uint8_t { kEmpty = 0, kMixed = 1, kFull = 2 };

/// Thread-safety: none; one grid per integrating thread.
class FreeSpaceGrid {
 public:
  explicit FreeSpaceGrid(double resolution_m) : resolution_m_(resolution_m) {}

  /// Empties the grid and sizes it for keys in [min_key, max_key] (padded by one brick).
  void Reset(const VoxelKey& min_key, const VoxelKey& max_key);
  [[nodiscard]] const VoxelKey& min_key() const { return min_key_; }
  [[nodiscard]] const VoxelKey& max_key() const { return max_key_; }
  /// Sets every voxel set in `other` (Reset() to the same keys).
  void MergeFrom(const FreeSpaceGrid& other);

  /// Marks the voxels the segment origin->end crosses, excluding the end voxel: the 3D-DDA of
  /// OcTree::computeRayKeys with the same float/double arithmetic, so the sets match exactly.
  /// Both ends must lie inside the Reset() box.
  void AddRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& end);

  /// Marks the whole octree-aligned cube of 2^size_log2 voxels a side at `base` (the part of it
  /// inside the Reset() box).
  void MarkBlock(const VoxelKey& base, int size_log2);

  /// Marks voxels of the cube of `size` (2 or 4) voxels a side at `base` (aligned to `size`):
  /// bit i + size * (j + size * k) of `voxels` is the voxel base + (i, j, k).
  void MarkVoxels(const VoxelKey& base, int size, std::uint64_t voxels);

  void Clear(const VoxelKey& key);
  /// Clears every voxel not set in `region` (another grid, of any box); call BuildPyramid()
  /// after.
  void KeepOnly(const FreeSpaceGrid& region);
  [[nodiscard]] bool Test(const VoxelKey& key) const;

  /// Builds the per-depth summaries; call after the last AddRay/Clear.
  void BuildPyramid();

  /// State of the octree node at `depth` (0 = root, 16 = leaf) that contains `key`.
  [[nodiscard]] BlockState State(int depth, const VoxelKey& key) const;

  /// Number of set voxels (after BuildPyramid it is cheap enough for statistics).
  [[nodiscard]] std::size_t CountSet() const;

 private:
  using Brick = std::array<std::uint64_t, 8>;  // one word per z slice, bit = x + 8 * y

  struct DdaRay {
    int key[3], end[3], step[3];
    double t_max[3], t_delta[3];
    double length;
  };

  [[nodiscard]] std::int64_t BrickCell(const VoxelKey& key) const;
  [[nodiscard]] const Brick* BrickAt(const VoxelKey& key) const;
  void Traverse(const DdaRay& ray);
  std::int32_t NewBrick(std::int64_t cell);
  [[nodiscard]] BlockState SubBrickState(int depth, const VoxelKey& key) const;
  void BuildLevel(int level);

  double resolution_m_;
  VoxelKey min_key_{}, max_key_{};
  std::array<int, 3> lo_ = {0, 0, 0};        // brick coordinates (key >> 3) of the first cell
  std::array<int, 3> dims_ = {0, 0, 0};      // cells per axis
  std::vector<std::int32_t> cell_to_brick_;  // -1 where no voxel is set
  std::vector<Brick> bricks_;
  // levels_[L] summarizes nodes at depth 13 - L; dims and origins per level.
  std::vector<std::vector<BlockState>> levels_;
  std::vector<std::array<int, 3>> level_lo_;
  std::vector<std::array<int, 3>> level_dims_;
};

}  // namespace objmap::occupancy_internal
