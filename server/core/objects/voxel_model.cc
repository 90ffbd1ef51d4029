#include "objects/voxel_model.h"

#include <algorithm>
#include <cmath>

#include "types/rounding.h"

namespace objmap {
namespace {

// 21 bits per axis, offset so that +-10 km at 5 mm fits in the signed range.
constexpr std::int64_t kAxisOffset = 1 << 20;
constexpr std::uint64_t kAxisMask = (1u << 21) - 1;

}  // namespace

std::uint64_t VoxelModel::KeyOf(const Eigen::Vector3f& p) const {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const auto index = static_cast<std::int64_t>(std::floor(p[axis] / voxel_size_m_)) + kAxisOffset;
    key |= (static_cast<std::uint64_t>(index) & kAxisMask) << (21 * axis);
  }
  return key;
}

void VoxelModel::Insert(const ColoredPoints& points) {
  const bool has_color = points.colors.size() == points.points.size();
  for (std::size_t i = 0; i < points.points.size(); ++i) {
    const Eigen::Vector3f& p = points.points[i];
    if (!p.allFinite()) continue;
    Accumulator& voxel = voxels_[KeyOf(p)];
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
  }
}

ColoredPoints VoxelModel::Points() const {
  ColoredPoints out;
  out.points.reserve(voxels_.size());
  out.colors.reserve(voxels_.size());
  for (const auto& [key, voxel] : voxels_) {
    const double inv = 1.0 / voxel.count;
    out.points.push_back((voxel.sum_xyz * inv).cast<float>());
    const Eigen::Vector3d rgb = voxel.sum_rgb * inv;
    out.colors.push_back({static_cast<std::uint8_t>(RoundNonNegative(rgb.x())),
                          static_cast<std::uint8_t>(RoundNonNegative(rgb.y())),
                          static_cast<std::uint8_t>(RoundNonNegative(rgb.z()))});
  }
  return out;
}

ColoredPoints VoxelDownsample(const ColoredPoints& points, float voxel_size_m) {
  VoxelModel model(voxel_size_m);
  model.Insert(points);
  ColoredPoints out = model.Points();
  if (points.colors.size() != points.points.size()) out.colors.clear();
  return out;
}

}  // namespace objmap
