#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

namespace objmap {

/// The points of one object model bucketed in cubic cells of the query radius, answering "is some
/// model point within the radius of p" from the few cells the radius reaches instead of a k-d
/// tree. The answer is exact, not approximate: a point matches when its squared distance to a
/// model point, summed over x, y, z in that order as a nearest-neighbour search sums it, is at
/// most radius², so it agrees with the paper's k-d tree test (Sec. III-C). Building it is two
/// passes over the points and one hash insertion per point, several times cheaper than a tree.
/// Thread-safety: immutable after construction; const methods may run concurrently.
class ProximityGrid {
 public:
  /// Buckets `points` (an object model's, one per voxel) for queries at `radius_m` > 0.
  ProximityGrid(const std::vector<Eigen::Vector3f>& points, float radius_m);

  /// True when some model point lies within radius_m of `p`.
  [[nodiscard]] bool AnyWithin(const Eigen::Vector3f& p) const;

  [[nodiscard]] bool empty() const { return points_.empty(); }
  [[nodiscard]] std::size_t size() const { return points_.size(); }
  [[nodiscard]] float radius_m() const { return radius_m_; }

 private:
  struct Slot {
    std::uint64_t cell = kNoCell;
    std::uint32_t begin = 0;  ///< first point of the cell in points_
    std::uint32_t count = 0;
  };
  static constexpr std::uint64_t kNoCell = ~std::uint64_t{0};

  [[nodiscard]] Eigen::Array3i CellIndexOf(const Eigen::Vector3f& p) const;
  [[nodiscard]] const Slot* Find(std::uint64_t cell) const;
  /// Index of the cell's slot, inserted when new; nullopt when the table is half full.
  [[nodiscard]] std::optional<std::uint32_t> FindOrInsert(std::uint64_t cell);
  [[nodiscard]] bool AnyWithinCell(std::uint64_t cell, const Eigen::Vector3f& p) const;

  float radius_m_;
  float radius_sq_;
  double cells_per_m_;
  /// Bounds of the model points widened by a little more than the radius: points outside
  /// cannot match, and most points of an unrelated segment are rejected here.
  Eigen::Vector3f reach_min_ = Eigen::Vector3f::Zero();
  Eigen::Vector3f reach_max_ = Eigen::Vector3f::Zero();
  std::vector<Eigen::Vector3f> points_;  ///< grouped by cell
  std::vector<Slot> slots_;              ///< open addressing, linear probing, power-of-two size
  std::size_t used_slots_ = 0;
};

}  // namespace objmap
