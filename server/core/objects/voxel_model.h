#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace objmap {

/// A coloured point set.
struct ColoredPoints {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<std::uint8_t, 3>> colors;  ///< empty or one per point

  [[nodiscard]] std::size_t size() const { return points.size(); }
  [[nodiscard]] bool empty() const { return points.empty(); }
};

/// Voxel-grid model: one averaged point (and colour) per occupied voxel. The paper stores object
/// models "downsampled with 5 mm spatial resolution" (Sec. III-D); keeping the per-voxel sums
/// makes repeated insertions exact instead of re-downsampling already downsampled points.
/// Thread-safety: none.
class VoxelModel {
 public:
  explicit VoxelModel(float voxel_size_m = 0.005f) : voxel_size_m_(voxel_size_m) {}

  /// Inserts one observation's points. Observations of one `view` (an id; every observation of a
  /// view inserted before the next view's) reach a voxel once between them: they see the same
  /// surface from about the same place. Without a view, the insertion is a view of its own.
  void Insert(const ColoredPoints& points, std::int64_t view);
  void Insert(const ColoredPoints& points);
  void Insert(const VoxelModel& other);
  void Clear() {
    voxels_.clear();
    own_views_ = 0;
  }

  [[nodiscard]] std::size_t size() const { return voxels_.size(); }
  [[nodiscard]] bool empty() const { return voxels_.empty(); }
  [[nodiscard]] float voxel_size_m() const { return voxel_size_m_; }

  /// One point per voxel (mean of what fell in it). The order is the container's: the same for
  /// the same sequence of insertions.
  [[nodiscard]] ColoredPoints Points() const;
  /// The same, only of the voxels that at least `min_observations` views reached: a voxel one
  /// view put there and no other confirmed is depth noise or a stray border pixel more often
  /// than surface.
  [[nodiscard]] ColoredPoints Points(std::uint32_t min_observations) const;
  /// Voxels that at least `min_observations` views reached.
  [[nodiscard]] std::size_t CountSeen(std::uint32_t min_observations) const;

  /// The most views that reached a voxel within `reach` voxels (per axis) of `p`'s; 0 when none.
  [[nodiscard]] std::uint32_t ObservationsNear(const Eigen::Vector3f& p, int reach) const;

  /// Calls `visit(point, observations, color)` for each voxel, in the order of Points(), where
  /// `color()` gives the voxel's colour (worked out only when asked); stops early when `visit`
  /// returns false.
  template <typename Visit>
  void ForEachVoxel(Visit&& visit) const {
    for (const auto& [key, voxel] : voxels_) {
      const Accumulator& accumulator = voxel;
      if (!visit(MeanOf(voxel), voxel.observations, [&] { return ColorOf(accumulator); })) return;
    }
  }

  /// Calls `visit(point)` with each point of Points(), in the same order and with the same
  /// values, without copying the model; stops early when `visit` returns false.
  template <typename Visit>
  void ForEachPoint(Visit&& visit) const {
    for (const auto& [key, voxel] : voxels_) {
      if (!visit(MeanOf(voxel))) return;
    }
  }

 private:
  struct Accumulator {
    Eigen::Vector3d sum_xyz = Eigen::Vector3d::Zero();
    Eigen::Vector3d sum_rgb = Eigen::Vector3d::Zero();
    std::uint32_t count = 0;
    std::uint32_t observations = 0;  ///< views that reached it
    std::int64_t last_view = std::numeric_limits<std::int64_t>::min();
  };
  [[nodiscard]] std::uint64_t KeyOf(const Eigen::Vector3f& p) const;
  [[nodiscard]] static Eigen::Vector3f MeanOf(const Accumulator& voxel) {
    return (voxel.sum_xyz * (1.0 / voxel.count)).cast<float>();
  }
  [[nodiscard]] static std::array<std::uint8_t, 3> ColorOf(const Accumulator& voxel);

  float voxel_size_m_;
  std::int64_t own_views_ = 0;  ///< views of insertions without one: -1, -2, ...
  std::unordered_map<std::uint64_t, Accumulator> voxels_;
};

/// The key of the grid cell, `voxel_size_m` on a side, that holds `p`: VoxelModel's and
/// VoxelDownsample's voxels, or any coarser grid.
[[nodiscard]] std::uint64_t VoxelKey(const Eigen::Vector3f& p, float voxel_size_m);
/// The key of the cell `dx, dy, dz` cells from the one `key` names.
[[nodiscard]] std::uint64_t OffsetVoxelKey(std::uint64_t key, int dx, int dy, int dz);

/// Voxel-grid downsampling of one point set: the same means as a VoxelModel given these points,
/// one per voxel in the order of each voxel's first point.
[[nodiscard]] ColoredPoints VoxelDownsample(const ColoredPoints& points, float voxel_size_m);

}  // namespace objmap
