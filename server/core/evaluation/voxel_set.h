#pragma once
// Integer voxels of a regular grid with OctoMap's convention (voxel k holds [k, k + 1) * size on
// each axis) and a hash set of them. The simulator's seen surface, the OctoMap evaluation and
// the tests voxelize alike through this one definition, so their voxels are the same voxels.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_set>

namespace objmap {

/// The voxel holding `p` on a grid of `voxel_m`.
[[nodiscard]] inline Eigen::Vector3i VoxelOf(const Eigen::Vector3d& p, double voxel_m) {
  return (p / voxel_m).array().floor().cast<int>();
}

/// A voxel packed into one integer: 21 bits per axis, +-2^20 voxels (+-10 km at 1 cm).
[[nodiscard]] inline std::int64_t PackVoxel(const Eigen::Vector3i& v) {
  constexpr std::int64_t kOffset = std::int64_t{1} << 20;
  return ((v.x() + kOffset) << 42) | ((v.y() + kOffset) << 21) | (v.z() + kOffset);
}

/// A set of voxels of one grid.
class VoxelSet {
 public:
  explicit VoxelSet(double voxel_m) : voxel_m_(voxel_m) {}

  /// Adds the voxel holding `p`; true when it was not in the set yet.
  bool Insert(const Eigen::Vector3d& p) {
    return keys_.insert(PackVoxel(VoxelOf(p, voxel_m_))).second;
  }

  /// True when the voxel of `p` or one within `reach` voxels of it (Chebyshev) is in the set.
  [[nodiscard]] bool HasWithin(const Eigen::Vector3d& p, int reach) const {
    const Eigen::Vector3i centre = VoxelOf(p, voxel_m_);
    for (int dx = -reach; dx <= reach; ++dx) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dz = -reach; dz <= reach; ++dz) {
          if (keys_.count(PackVoxel(centre + Eigen::Vector3i(dx, dy, dz))) > 0) return true;
        }
      }
    }
    return false;
  }

  /// Distance from `p` to the nearest voxel centre of the set among p's voxel and its 26
  /// neighbours; +inf when none of them is in the set.
  [[nodiscard]] double NearestCenterDistance(const Eigen::Vector3d& p) const {
    const Eigen::Vector3i centre = VoxelOf(p, voxel_m_);
    double best = std::numeric_limits<double>::infinity();
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const Eigen::Vector3i v = centre + Eigen::Vector3i(dx, dy, dz);
          if (keys_.count(PackVoxel(v)) == 0) continue;
          best = std::min(
              best, (p - (v.cast<double>() + Eigen::Vector3d::Constant(0.5)) * voxel_m_).norm());
        }
      }
    }
    return best;
  }

 private:
  double voxel_m_;
  std::unordered_set<std::int64_t> keys_;
};

}  // namespace objmap
