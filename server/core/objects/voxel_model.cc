#include "objects/voxel_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "types/rounding.h"

namespace objmap {
namespace {

// 21 bits per axis, offset so that +-10 km at 5 mm fits in the signed range.
constexpr std::int64_t kAxisOffset = 1 << 20;
constexpr std::uint64_t kAxisMask = (1u << 21) - 1;

// Sums of one voxel of VoxelDownsample, as VoxelModel keeps them.
struct VoxelSums {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
  std::uint32_t count = 0;
};

// Open addressing over a power-of-two table of slot ids, -1 where free: one multiply per lookup,
// where the node-based map takes a 64-bit division and, per new voxel, an allocation.
class VoxelSlots {
 public:
  explicit VoxelSlots(std::size_t max_voxels) {
    std::size_t size = 16;
    while (size < 2 * max_voxels) size *= 2;
    slot_of_cell_.assign(size, -1);
    mask_ = size - 1;
    for (std::size_t s = size; s > 1; s /= 2) --shift_;
  }

  // The slot of `key`, a new one (numbered in order of arrival) when it is new.
  std::size_t SlotOf(std::uint64_t key, std::vector<std::uint64_t>* keys) {
    std::size_t cell = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
    while (slot_of_cell_[cell] >= 0 && (*keys)[slot_of_cell_[cell]] != key) {
      cell = (cell + 1) & mask_;
    }
    if (slot_of_cell_[cell] < 0) {
      slot_of_cell_[cell] = static_cast<int>(keys->size());
      keys->push_back(key);
    }
    return static_cast<std::size_t>(slot_of_cell_[cell]);
  }

 private:
  std::vector<int> slot_of_cell_;
  std::size_t mask_ = 0;
  int shift_ = 64;
};

}  // namespace

std::uint64_t VoxelKey(const Eigen::Vector3f& p, float voxel_size_m) {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const auto index = static_cast<std::int64_t>(std::floor(p[axis] / voxel_size_m)) + kAxisOffset;
    key |= (static_cast<std::uint64_t>(index) & kAxisMask) << (21 * axis);
  }
  return key;
}

std::uint64_t OffsetVoxelKey(std::uint64_t key, int dx, int dy, int dz) {
  const int offsets[3] = {dx, dy, dz};
  std::uint64_t moved = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::uint64_t index = ((key >> (21 * axis)) & kAxisMask) + offsets[axis];
    moved |= (index & kAxisMask) << (21 * axis);
  }
  return moved;
}

std::uint64_t VoxelModel::KeyOf(const Eigen::Vector3f& p) const {
  return VoxelKey(p, voxel_size_m_);
}

void VoxelModel::Insert(const ColoredPoints& points) { Insert(points, --own_views_); }

void VoxelModel::Insert(const ColoredPoints& points, std::int64_t view) {
  const bool has_color = points.colors.size() == points.points.size();
  for (std::size_t i = 0; i < points.points.size(); ++i) {
    const Eigen::Vector3f& p = points.points[i];
    if (!p.allFinite()) continue;
    Accumulator& voxel = voxels_[KeyOf(p)];
    if (voxel.last_view != view) {
      voxel.last_view = view;
      ++voxel.observations;
    }
    voxel.sum_xyz += p.cast<double>();
    if (has_color) {
      voxel.sum_rgb +=
          Eigen::Vector3d(points.colors[i][0], points.colors[i][1], points.colors[i][2]);
    }
    ++voxel.count;
  }
}

void VoxelModel::Insert(const VoxelModel& other) {
  for (const auto& [key, source] : other.voxels_) {
    Accumulator& voxel = voxels_[key];
    voxel.sum_xyz += source.sum_xyz;
    voxel.sum_rgb += source.sum_rgb;
    voxel.count += source.count;
    voxel.observations += source.observations;
    voxel.last_view = std::max(voxel.last_view, source.last_view);
  }
  own_views_ = std::min(own_views_, other.own_views_);
}

ColoredPoints VoxelModel::Points() const { return Points(0); }

std::size_t VoxelModel::CountSeen(std::uint32_t min_observations) const {
  return static_cast<std::size_t>(std::count_if(
      voxels_.begin(), voxels_.end(),
      [&](const auto& entry) { return entry.second.observations >= min_observations; }));
}

std::array<std::uint8_t, 3> VoxelModel::ColorOf(const Accumulator& voxel) {
  const Eigen::Vector3d rgb = voxel.sum_rgb * (1.0 / voxel.count);
  return {static_cast<std::uint8_t>(RoundNonNegative(rgb.x())),
          static_cast<std::uint8_t>(RoundNonNegative(rgb.y())),
          static_cast<std::uint8_t>(RoundNonNegative(rgb.z()))};
}

std::uint32_t VoxelModel::ObservationsNear(const Eigen::Vector3f& p, int reach) const {
  std::uint32_t most = 0;
  for (int dx = -reach; dx <= reach; ++dx) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dz = -reach; dz <= reach; ++dz) {
        const Eigen::Vector3f q = p + voxel_size_m_ * Eigen::Vector3f(dx, dy, dz);
        auto it = voxels_.find(KeyOf(q));
        if (it != voxels_.end()) most = std::max(most, it->second.observations);
      }
    }
  }
  return most;
}

ColoredPoints VoxelModel::Points(std::uint32_t min_observations) const {
  ColoredPoints out;
  out.points.reserve(voxels_.size());
  out.colors.reserve(voxels_.size());
  for (const auto& [key, voxel] : voxels_) {
    if (voxel.observations < min_observations) continue;
    out.points.push_back(MeanOf(voxel));
    out.colors.push_back(ColorOf(voxel));
  }
  return out;
}

ColoredPoints VoxelDownsample(const ColoredPoints& points, float voxel_size_m) {
  const bool has_color = points.colors.size() == points.points.size();
  VoxelSlots slots(points.size());
  std::vector<std::uint64_t> keys;
  std::vector<VoxelSums> sums;
  // Neighbouring pixels often share a voxel: the last one is tried before the table.
  std::uint64_t last_key = 0;
  std::size_t last_slot = SIZE_MAX;
  for (std::size_t i = 0; i < points.points.size(); ++i) {
    const Eigen::Vector3f& p = points.points[i];
    if (!p.allFinite()) continue;
    const std::uint64_t key = VoxelKey(p, voxel_size_m);
    const std::size_t slot =
        last_slot != SIZE_MAX && key == last_key ? last_slot : slots.SlotOf(key, &keys);
    last_key = key;
    last_slot = slot;
    if (slot == sums.size()) sums.emplace_back();
    VoxelSums& voxel = sums[slot];
    voxel.xyz += p.cast<double>();
    if (has_color) {
      voxel.rgb += Eigen::Vector3d(points.colors[i][0], points.colors[i][1], points.colors[i][2]);
    }
    ++voxel.count;
  }
  ColoredPoints out;
  out.points.reserve(sums.size());
  if (has_color) out.colors.reserve(sums.size());
  for (const VoxelSums& voxel : sums) {
    const double inv = 1.0 / voxel.count;
    out.points.push_back((voxel.xyz * inv).cast<float>());
    if (!has_color) continue;
    const Eigen::Vector3d rgb = voxel.rgb * inv;
    out.colors.push_back({static_cast<std::uint8_t>(RoundNonNegative(rgb.x())),
                          static_cast<std::uint8_t>(RoundNonNegative(rgb.y())),
                          static_cast<std::uint8_t>(RoundNonNegative(rgb.z()))});
  }
  return out;
}

}  // namespace objmap
