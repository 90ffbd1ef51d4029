#include "association/proximity_grid.h"

#include <cmath>
#include <limits>

namespace objmap {
namespace {

// 21 bits per axis around an offset, as VoxelModel packs its keys: +-20 km at 2 cm cells. The
// top bit stays clear, so no cell packs to ProximityGrid's empty-slot marker.
constexpr std::int64_t kAxisOffset = 1 << 20;
constexpr std::uint64_t kAxisMask = (1u << 21) - 1;

std::uint64_t Pack(const Eigen::Array3i& cell) {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    key |= (static_cast<std::uint64_t>(cell[axis] + kAxisOffset) & kAxisMask) << (21 * axis);
  }
  return key;
}

// Mixes all bits of the key into the low ones the table uses: neighbouring cells differ in few
// bits, and the z index sits in the key's top bits.
std::size_t HashOf(std::uint64_t cell) {
  cell ^= cell >> 31;
  cell *= 0x7fb5d329728ea185ull;
  cell ^= cell >> 27;
  cell *= 0x81dadef4bc2dd44dull;
  cell ^= cell >> 33;
  return static_cast<std::size_t>(cell);
}

// The cell's search reach along one axis: a point farther than the radius from p in any axis
// cannot match. A relative slack of 1e-6 keeps rounding in the cell arithmetic on the safe side
// (it only ever adds cells to look at).
constexpr double kReachSlack = 1.0 + 1e-6;

}  // namespace

ProximityGrid::ProximityGrid(const std::vector<Eigen::Vector3f>& points, float radius_m)
    : radius_m_(radius_m),
      radius_sq_(radius_m * radius_m),
      cells_per_m_(1.0 / static_cast<double>(radius_m)) {
  if (points.empty()) return;
  std::vector<std::uint64_t> cell_of_point(points.size());
  Eigen::Vector3f lo = points.front(), hi = points.front();
  for (std::size_t i = 0; i < points.size(); ++i) {
    cell_of_point[i] = Pack(CellIndexOf(points[i]));
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  // Count the points per cell, remembering each point's slot; a table that fills up is
  // started again twice as large (a surface has far fewer cells than points, so rarely).
  std::vector<std::uint32_t> slot_of_point(points.size());
  std::size_t capacity = 64;
  while (capacity < points.size() / 4) capacity *= 2;
  for (bool counted = false; !counted; capacity *= 2) {
    slots_.assign(capacity, Slot{});
    used_slots_ = 0;
    counted = true;
    for (std::size_t i = 0; i < points.size() && counted; ++i) {
      const std::optional<std::uint32_t> slot = FindOrInsert(cell_of_point[i]);
      counted = slot.has_value();
      if (counted) {
        slot_of_point[i] = *slot;
        ++slots_[*slot].count;
      }
    }
  }
  std::uint32_t next = 0;
  for (Slot& slot : slots_) {
    slot.begin = next;
    next += slot.count;
    slot.count = 0;
  }
  points_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    Slot& slot = slots_[slot_of_point[i]];
    points_[slot.begin + slot.count++] = points[i];
  }
  const float margin = radius_m * 1.001f + 1e-6f;
  reach_min_ = lo.array() - margin;
  reach_max_ = hi.array() + margin;
}

Eigen::Array3i ProximityGrid::CellIndexOf(const Eigen::Vector3f& p) const {
  return Eigen::Array3i(static_cast<int>(std::floor(p.x() * cells_per_m_)),
                        static_cast<int>(std::floor(p.y() * cells_per_m_)),
                        static_cast<int>(std::floor(p.z() * cells_per_m_)));
}

const ProximityGrid::Slot* ProximityGrid::Find(std::uint64_t cell) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = HashOf(cell) & mask;; i = (i + 1) & mask) {
    if (slots_[i].cell == cell) return &slots_[i];
    if (slots_[i].cell == kNoCell) return nullptr;
  }
}

std::optional<std::uint32_t> ProximityGrid::FindOrInsert(std::uint64_t cell) {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = HashOf(cell) & mask;; i = (i + 1) & mask) {
    if (slots_[i].cell == cell) return static_cast<std::uint32_t>(i);
    if (slots_[i].cell == kNoCell) {
      if (2 * (used_slots_ + 1) > slots_.size()) return std::nullopt;
      slots_[i].cell = cell;
      ++used_slots_;
      return static_cast<std::uint32_t>(i);
    }
  }
}

bool ProximityGrid::AnyWithinCell(std::uint64_t cell, const Eigen::Vector3f& p) const {
  const Slot* slot = Find(cell);
  if (slot == nullptr) return false;
  const Eigen::Vector3f* q = points_.data() + slot->begin;
  for (const Eigen::Vector3f* end = q + slot->count; q != end; ++q) {
    // Summed as FLANN's L2_Simple sums it, so that ties at the radius fall the same way.
    const float dx = p.x() - q->x();
    const float dy = p.y() - q->y();
    const float dz = p.z() - q->z();
    float distance_sq = dx * dx;
    distance_sq += dy * dy;
    distance_sq += dz * dz;
    if (distance_sq <= radius_sq_) return true;
  }
  return false;
}

bool ProximityGrid::AnyWithin(const Eigen::Vector3f& p) const {
  if (points_.empty() || !p.allFinite()) return false;
  if ((p.array() < reach_min_.array()).any() || (p.array() > reach_max_.array()).any()) {
    return false;
  }
  // Most matching points have a model point in their own cell: look there first.
  const Eigen::Array3i own = CellIndexOf(p);
  if (AnyWithinCell(Pack(own), p)) return true;
  const double reach = static_cast<double>(radius_m_) * kReachSlack;
  const double reach_sq = reach * reach;
  Eigen::Array3i first, last;
  Eigen::Array3d gap_below, gap_above;  // from p to the cell below / above its own, per axis
  for (int axis = 0; axis < 3; ++axis) {
    const double x = p[axis];
    first[axis] = static_cast<int>(std::floor((x - reach) * cells_per_m_));
    last[axis] = static_cast<int>(std::floor((x + reach) * cells_per_m_));
    gap_below[axis] = x - own[axis] / cells_per_m_;
    gap_above[axis] = (own[axis] + 1) / cells_per_m_ - x;
  }
  auto gap_sq = [&](int axis, int index) {
    if (index == own[axis]) return 0.0;
    // Cells two or more away are within reach only with a cell smaller than the radius.
    const double gap = index < own[axis] ? gap_below[axis] + (own[axis] - index - 1) / cells_per_m_
                                         : gap_above[axis] + (index - own[axis] - 1) / cells_per_m_;
    return gap > 0.0 ? gap * gap : 0.0;
  };
  for (int x = first.x(); x <= last.x(); ++x) {
    const double gx = gap_sq(0, x);
    for (int y = first.y(); y <= last.y(); ++y) {
      const double gxy = gx + gap_sq(1, y);
      if (gxy > reach_sq) continue;
      for (int z = first.z(); z <= last.z(); ++z) {
        if (x == own.x() && y == own.y() && z == own.z()) continue;
        if (gxy + gap_sq(2, z) > reach_sq) continue;
        if (AnyWithinCell(Pack(Eigen::Array3i(x, y, z)), p)) return true;
      }
    }
  }
  return false;
}

}  // namespace objmap
