#include "occupancy/projective_carver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

namespace objmap::occupancy_internal {
namespace {

// Blocks are first decided at 32 voxels a side, then halved where they are mixed.
constexpr int kTopBlockLog2 = 5;
// Mixed blocks this small (2^2 voxels a side) are settled voxel by voxel.
constexpr int kVoxelByVoxelLog2 = 2;
// Points closer to the camera plane than this are clipped away when projecting a block: every
// ray leaves the camera with z > 0, so the part of a block behind the plane cannot be crossed.
constexpr float kNearPlaneM = 1e-6f;
// A disk of radius sqrt(2)/2 pixels holds a pixel centre wherever it lies.
constexpr float kSqrtHalf = 0.70711f;
constexpr float kSqrtThreeHalves = 0.86603f;  // half the diagonal of a unit cube
// Margin on the disk-covering argument, for the approximations in the projected disk radius.
constexpr float kCoverSafety = 1.05f;
// Minimum range of a pixel without a ray: it never stops a block from being all free (the hole
// distance accounts for missing rays).
constexpr float kNoRayMinRange = std::numeric_limits<float>::max();
// Projected bounds are widened by this much, for float rounding in the points (which lie on
// their pixel rays within OccupancyMap's check, far below this).
constexpr float kRectMarginPx = 0.05f;

// Projected coordinates are clamped to this, well outside any image and within int range.
constexpr float kFarOutsidePx = 1e7f;

// floor and ceil for values within +-1e7 (projections are clamped there), without the libm
// calls that plain SSE2 code makes for them.
int FloorToInt(float value) {
  const int truncated = static_cast<int>(value);
  return truncated - static_cast<int>(value < static_cast<float>(truncated));
}
int CeilToInt(float value) {
  const int truncated = static_cast<int>(value);
  return truncated + static_cast<int>(value > static_cast<float>(truncated));
}

double KeyToLowerCoord(int key, double resolution_m) {
  return static_cast<double>(key - kKeyOffset) * resolution_m;
}

}  // namespace

void ProjectiveCarver::Reset(const PinholeCamera& camera) {
  camera_ = camera;
  R_C_W_ = camera.T_W_C.linear().transpose();
  origin_W_ = camera.T_W_C.translation().cast<double>();
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  rays_.range.assign(pixels, -1.f);
  for (std::vector<float>& axis : rays_.inverse_direction) axis.assign(pixels, 0.f);
  longest_range_ = -1.f;
  ray_count_ = 0;
  // The caller checked that the camera centre has a key.
  if (!PointToKey(camera.T_W_C.translation(), resolution_m_, &min_key_)) min_key_ = {};
  max_key_ = min_key_;
}

void ProjectiveCarver::SetRay(int pixel, const Eigen::Vector3f& free_end_W) {
  VoxelKey end_key;
  if (!PointToKey(free_end_W, resolution_m_, &end_key)) return;
  const Eigen::Vector3f direction = free_end_W - camera_.T_W_C.translation();
  const float range = direction.norm();
  if (!(range > 0.f)) return;
  const auto i = static_cast<std::size_t>(pixel);
  rays_.range[i] = range;
  for (int a = 0; a < 3; ++a) {
    // An axis the ray does not move along gets a huge slope instead of infinity, so that the
    // slab test never multiplies 0 by infinity.
    const float d = direction[a];
    rays_.inverse_direction[static_cast<std::size_t>(a)][i] =
        std::fabs(d) > 1e-20f ? 1.f / d : std::copysign(1e30f, d == 0.f ? 1.f : d);
  }
  longest_range_ = std::max(longest_range_, range);
  ++ray_count_;
  for (int a = 0; a < 3; ++a) {
    min_key_[a] = std::min(min_key_[a], end_key[a]);
    max_key_[a] = std::max(max_key_[a], end_key[a]);
  }
}

// Chessboard distance from each pixel to the nearest pixel with a ray (two passes), capped.
void ProjectiveCarver::BuildHoleDistance() {
  const int w = camera_.width, h = camera_.height;
  constexpr int kCap = 255;
  hole_distance_.resize(rays_.range.size());
  auto at = [&](int u, int v) -> std::uint8_t& {
    return hole_distance_[static_cast<std::size_t>(v) * w + u];
  };
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      int d = rays_.range[static_cast<std::size_t>(v) * w + u] >= 0.f ? 0 : kCap;
      if (d > 0) {
        if (u > 0) d = std::min(d, at(u - 1, v) + 1);
        if (v > 0) {
          d = std::min(d, at(u, v - 1) + 1);
          if (u > 0) d = std::min(d, at(u - 1, v - 1) + 1);
          if (u + 1 < w) d = std::min(d, at(u + 1, v - 1) + 1);
        }
      }
      at(u, v) = static_cast<std::uint8_t>(std::min(d, kCap));
    }
  }
  for (int v = h - 1; v >= 0; --v) {
    for (int u = w - 1; u >= 0; --u) {
      int d = at(u, v);
      if (d == 0) continue;
      if (u + 1 < w) d = std::min(d, at(u + 1, v) + 1);
      if (v + 1 < h) {
        d = std::min(d, at(u, v + 1) + 1);
        if (u + 1 < w) d = std::min(d, at(u + 1, v + 1) + 1);
        if (u > 0) d = std::min(d, at(u - 1, v + 1) + 1);
      }
      at(u, v) = static_cast<std::uint8_t>(std::min(d, kCap));
    }
  }
}

// window_max_[l][p]: the longest ray within 2^l pixels (chessboard) of p, by doubling: the
// window of radius 2k is the union of those of radius k at offsets -k and +k, per axis.
void ProjectiveCarver::BuildWindowMax() {
  const int w = camera_.width, h = camera_.height;
  window_max_.resize(kWindowLevels);
  std::vector<float> horizontal(rays_.range.size());
  const std::vector<float>* previous = &rays_.range;
  for (int level = 0; level < kWindowLevels; ++level) {
    // Level 0 has radius 1 (from the rays, offsets -1, 0, +1); level l > 0 doubles level l - 1.
    const int offset = level == 0 ? 1 : 1 << (level - 1);
    const std::vector<float>& from = *previous;
    for (int v = 0; v < h; ++v) {
      const float* row = from.data() + static_cast<std::size_t>(v) * w;
      float* out = horizontal.data() + static_cast<std::size_t>(v) * w;
      for (int u = 0; u < w; ++u) {
        float m = std::max(row[std::max(u - offset, 0)], row[std::min(u + offset, w - 1)]);
        if (level == 0) m = std::max(m, row[u]);
        out[u] = m;
      }
    }
    std::vector<float>& to = window_max_[static_cast<std::size_t>(level)];
    to.resize(rays_.range.size());
    for (int v = 0; v < h; ++v) {
      const float* up = horizontal.data() + static_cast<std::size_t>(std::max(v - offset, 0)) * w;
      const float* down =
          horizontal.data() + static_cast<std::size_t>(std::min(v + offset, h - 1)) * w;
      const float* same = horizontal.data() + static_cast<std::size_t>(v) * w;
      float* out = to.data() + static_cast<std::size_t>(v) * w;
      for (int u = 0; u < w; ++u) {
        float m = std::max(up[u], down[u]);
        if (level == 0) m = std::max(m, same[u]);
        out[u] = m;
      }
    }
    previous = &to;
  }
}

void ProjectiveCarver::BuildRangePyramid() {
  levels_.resize(1);
  RangeLevel& pixels = levels_[0];
  pixels.width = camera_.width;
  pixels.height = camera_.height;
  pixels.max_range = rays_.range;
  pixels.min_range.resize(rays_.range.size());
  for (std::size_t i = 0; i < rays_.range.size(); ++i) {
    pixels.min_range[i] = rays_.range[i] >= 0.f ? rays_.range[i] : kNoRayMinRange;
  }
  pixels.max_hole_distance = hole_distance_;
  while (levels_.back().width > 1 || levels_.back().height > 1) {
    const RangeLevel& fine = levels_.back();
    RangeLevel coarse;
    coarse.width = (fine.width + 1) / 2;
    coarse.height = (fine.height + 1) / 2;
    const std::size_t tiles = static_cast<std::size_t>(coarse.width) * coarse.height;
    coarse.min_range.assign(tiles, kNoRayMinRange);
    coarse.max_range.assign(tiles, -1.f);
    coarse.max_hole_distance.assign(tiles, 0);
    for (int v = 0; v < fine.height; ++v) {
      for (int u = 0; u < fine.width; ++u) {
        const std::size_t from = static_cast<std::size_t>(v) * fine.width + u;
        const std::size_t to = static_cast<std::size_t>(v / 2) * coarse.width + u / 2;
        coarse.min_range[to] = std::min(coarse.min_range[to], fine.min_range[from]);
        coarse.max_range[to] = std::max(coarse.max_range[to], fine.max_range[from]);
        coarse.max_hole_distance[to] =
            std::max(coarse.max_hole_distance[to], fine.max_hole_distance[from]);
      }
    }
    levels_.push_back(std::move(coarse));
  }
}

// Bounds over a superset of `rect`: at most 5 x 5 tiles of the first level whose tiles are at
// least a quarter of the rectangle's extent.
ProjectiveCarver::RangeBounds ProjectiveCarver::BoundsOver(const Rect& rect) const {
  const int extent = std::max(rect.u1 - rect.u0, rect.v1 - rect.v0) + 1;
  int level = 0;
  while ((1 << (level + 2)) < extent && level + 1 < static_cast<int>(levels_.size())) ++level;
  const RangeLevel& tiles = levels_[static_cast<std::size_t>(level)];
  RangeBounds bounds{kNoRayMinRange, -1.f, 0};
  for (int v = rect.v0 >> level; v <= rect.v1 >> level; ++v) {
    for (int u = rect.u0 >> level; u <= rect.u1 >> level; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * tiles.width + u;
      bounds.min_range = std::min(bounds.min_range, tiles.min_range[i]);
      bounds.max_range = std::max(bounds.max_range, tiles.max_range[i]);
      bounds.max_hole_distance =
          std::max<int>(bounds.max_hole_distance, tiles.max_hole_distance[i]);
    }
  }
  return bounds;
}

// The longest ray over a superset of `rect`: at most 3 x 3 tiles (the per-voxel bound, where
// only the longest ray counts).
float ProjectiveCarver::MaxRangeOver(const Rect& rect) const {
  const int extent = std::max(rect.u1 - rect.u0, rect.v1 - rect.v0) + 1;
  int level = 0;
  while ((1 << (level + 1)) < extent && level + 1 < static_cast<int>(levels_.size())) ++level;
  const RangeLevel& tiles = levels_[static_cast<std::size_t>(level)];
  float longest = -1.f;
  for (int v = rect.v0 >> level; v <= rect.v1 >> level; ++v) {
    const float* row = tiles.max_range.data() + static_cast<std::size_t>(v) * tiles.width;
    for (int u = rect.u0 >> level; u <= rect.u1 >> level; ++u) longest = std::max(longest, row[u]);
  }
  return longest;
}

// The pixels whose rays may cross the cube [lo, lo + size] (given relative to the camera
// centre): the bounding rectangle of its projection, clipped to the part in front of the camera.
// kInside: the cube lies wholly in front of the camera and its rectangle wholly in the image, so
// every pixel ray through it is there.
ProjectiveCarver::Footprint ProjectiveCarver::Project(const Eigen::Vector3f& lo_rel_W,
                                                      float size_m) const {
  const Eigen::Vector3f half_x = (0.5f * size_m) * R_C_W_.col(0);
  const Eigen::Vector3f half_y = (0.5f * size_m) * R_C_W_.col(1);
  const Eigen::Vector3f half_z = (0.5f * size_m) * R_C_W_.col(2);
  return ProjectCentered(R_C_W_ * lo_rel_W + half_x + half_y + half_z, half_x, half_y, half_z);
}

// Project() of the box center +- half_x +- half_y +- half_z (camera frame).
ProjectiveCarver::Footprint ProjectiveCarver::ProjectCentered(const Eigen::Vector3f& center,
                                                              const Eigen::Vector3f& half_x,
                                                              const Eigen::Vector3f& half_y,
                                                              const Eigen::Vector3f& half_z) const {
  std::array<float, 8> x, y, z;
  for (std::size_t k = 0; k < 8; ++k) {
    const float sx = (k & 1) ? 1.f : -1.f, sy = (k & 2) ? 1.f : -1.f, sz = (k & 4) ? 1.f : -1.f;
    x[k] = center.x() + sx * half_x.x() + sy * half_y.x() + sz * half_z.x();
    y[k] = center.y() + sx * half_x.y() + sy * half_y.y() + sz * half_z.y();
    z[k] = center.z() + sx * half_x.z() + sy * half_y.z() + sz * half_z.z();
  }
  float z_min = z[0];
  for (int k = 1; k < 8; ++k) z_min = std::min(z_min, z[static_cast<std::size_t>(k)]);
  if (z_min < kNearPlaneM) return ProjectClipped(x, y, z);
  // The common case, wholly in front of the camera: eight projections.
  float u_min = std::numeric_limits<float>::max(), v_min = u_min;
  float u_max = -u_min, v_max = -u_min;
  for (int k = 0; k < 8; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const float inverse_z = 1.f / z[i];
    const float u = camera_.fx * x[i] * inverse_z + camera_.cx;
    const float v = camera_.fy * y[i] * inverse_z + camera_.cy;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  return FootprintOf(u_min, u_max, v_min, v_max, /*all_in_front=*/true);
}

ProjectiveCarver::CornerOffsets ProjectiveCarver::CornerOffsetsOf(
    const Eigen::Vector3f& half_x, const Eigen::Vector3f& half_y,
    const Eigen::Vector3f& half_z) const {
  CornerOffsets offsets;
  for (std::size_t k = 0; k < 8; ++k) {
    const Eigen::Vector3f o =
        ((k & 1) ? half_x : -half_x) + ((k & 2) ? half_y : -half_y) + ((k & 4) ? half_z : -half_z);
    offsets.u[k] = camera_.fx * o.x() + camera_.cx * o.z();
    offsets.v[k] = camera_.fy * o.y() + camera_.cy * o.z();
    offsets.z[k] = o.z();
  }
  offsets.z_min = *std::min_element(offsets.z.begin(), offsets.z.end());
  return offsets;
}

// ProjectCentered() for voxels sharing their corner offsets: u = (fx x + cx z) / z at each corner
// is the centre's numerator and denominator plus a fixed offset each.
ProjectiveCarver::Footprint ProjectiveCarver::ProjectVoxel(const CornerOffsets& offsets,
                                                           const Eigen::Vector3f& center,
                                                           const Eigen::Vector3f& half_x,
                                                           const Eigen::Vector3f& half_y,
                                                           const Eigen::Vector3f& half_z) const {
  if (center.z() + offsets.z_min < kNearPlaneM) {
    return ProjectCentered(center, half_x, half_y, half_z);
  }
  const float center_u = camera_.fx * center.x() + camera_.cx * center.z();
  const float center_v = camera_.fy * center.y() + camera_.cy * center.z();
  std::array<float, 8> u, v;
  for (std::size_t k = 0; k < 8; ++k) {
    const float inverse_z = 1.f / (center.z() + offsets.z[k]);
    u[k] = (center_u + offsets.u[k]) * inverse_z;
    v[k] = (center_v + offsets.v[k]) * inverse_z;
  }
  return FootprintOf(*std::min_element(u.begin(), u.end()), *std::max_element(u.begin(), u.end()),
                     *std::min_element(v.begin(), v.end()), *std::max_element(v.begin(), v.end()),
                     /*all_in_front=*/true);
}

// Project() for a cube that reaches behind the near plane: the part in front of it, whose
// projection is bounded by the corners in front and the points where edges cross the plane.
ProjectiveCarver::Footprint ProjectiveCarver::ProjectClipped(const std::array<float, 8>& x,
                                                             const std::array<float, 8>& y,
                                                             const std::array<float, 8>& z) const {
  float u_min = std::numeric_limits<float>::max(), v_min = u_min;
  float u_max = -u_min, v_max = -u_min;
  bool any_in_front = false;
  auto add = [&](float px, float py, float pz) {
    const float inverse_z = 1.f / pz;
    // Clamped, so that points just in front of the camera plane stay finite integers later.
    const float u =
        std::clamp(camera_.fx * px * inverse_z + camera_.cx, -kFarOutsidePx, kFarOutsidePx);
    const float v =
        std::clamp(camera_.fy * py * inverse_z + camera_.cy, -kFarOutsidePx, kFarOutsidePx);
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
    any_in_front = true;
  };
  for (std::size_t k = 0; k < 8; ++k) {
    if (z[k] >= kNearPlaneM) add(x[k], y[k], z[k]);
  }
  for (std::size_t k = 0; k < 8; ++k) {
    for (std::size_t axis_bit = 1; axis_bit < 8; axis_bit <<= 1) {
      if (k & axis_bit) continue;
      const std::size_t other = k | axis_bit;
      if ((z[k] >= kNearPlaneM) == (z[other] >= kNearPlaneM)) continue;
      const float t = (kNearPlaneM - z[k]) / (z[other] - z[k]);
      add(x[k] + t * (x[other] - x[k]), y[k] + t * (y[other] - y[k]), kNearPlaneM);
    }
  }
  if (!any_in_front) return Footprint{};
  return FootprintOf(u_min, u_max, v_min, v_max, /*all_in_front=*/false);
}

// The pixels whose centres (at integer coordinates) lie within projected bounds.
ProjectiveCarver::Footprint ProjectiveCarver::FootprintOf(float u_min, float u_max, float v_min,
                                                          float v_max, bool all_in_front) const {
  Footprint footprint;
  // Corners just in front of the camera plane project far out; kept within int range.
  u_min = std::clamp(u_min, -kFarOutsidePx, kFarOutsidePx);
  u_max = std::clamp(u_max, -kFarOutsidePx, kFarOutsidePx);
  v_min = std::clamp(v_min, -kFarOutsidePx, kFarOutsidePx);
  v_max = std::clamp(v_max, -kFarOutsidePx, kFarOutsidePx);
  const int u0 = CeilToInt(u_min - kRectMarginPx);
  const int u1 = FloorToInt(u_max + kRectMarginPx);
  const int v0 = CeilToInt(v_min - kRectMarginPx);
  const int v1 = FloorToInt(v_max + kRectMarginPx);
  const int last_u = camera_.width - 1, last_v = camera_.height - 1;
  if (u0 > u1 || v0 > v1) return footprint;  // between pixel centres
  if (u1 < 0 || v1 < 0 || u0 > last_u || v0 > last_v) return footprint;
  footprint.rect = {std::max(u0, 0), std::max(v0, 0), std::min(u1, last_u), std::min(v1, last_v)};
  const bool inside = all_in_front && u0 >= 0 && v0 >= 0 && u1 <= last_u && v1 <= last_v;
  footprint.kind = inside ? Footprint::kInside : Footprint::kPartly;
  return footprint;
}

template <typename Visit>
void ProjectiveCarver::ForEachTopBlock(Visit visit) const {
  const int top = 1 << kTopBlockLog2;
  std::array<int, 3> first{}, last{};
  for (int a = 0; a < 3; ++a) {
    first[a] = min_key_[a] & ~(top - 1);
    last[a] = max_key_[a] & ~(top - 1);
  }
  for (int z = first[2]; z <= last[2]; z += top) {
    for (int y = first[1]; y <= last[1]; y += top) {
      for (int x = first[0]; x <= last[0]; x += top) {
        visit(VoxelKey{static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y),
                       static_cast<std::uint16_t>(z)});
      }
    }
  }
}

CarvingStats ProjectiveCarver::Carve(FreeSpaceGrid* grid, const FreeSpaceGrid* region,
                                     int threads) {
  CarvingStats stats;
  if (longest_range_ <= 0.f) return stats;
  BuildHoleDistance();
  BuildRangePyramid();
  BuildWindowMax();
  std::vector<VoxelKey> top_blocks;
  ForEachTopBlock([&top_blocks](const VoxelKey& base) { top_blocks.push_back(base); });
  const auto workers =
      static_cast<std::size_t>(std::clamp(threads, 1, static_cast<int>(top_blocks.size())));
  if (workers <= 1) {
    for (const VoxelKey& base : top_blocks) CarveBlock(base, kTopBlockLog2, region, grid, &stats);
    return stats;
  }
  // Every worker but the first marks a grid of its own (a grid is not safe to share), merged
  // into `grid` at the end; blocks are dealt out in turn so that the workers' loads match.
  std::vector<FreeSpaceGrid> own_grids(workers - 1, FreeSpaceGrid(resolution_m_));
  std::vector<CarvingStats> own_stats(workers);
  std::vector<std::thread> pool;
  for (std::size_t w = 0; w < workers; ++w) {
    FreeSpaceGrid* marks = grid;
    if (w > 0) {
      marks = &own_grids[w - 1];
      marks->Reset(grid->min_key(), grid->max_key());
    }
    pool.emplace_back([&, w, marks] {
      for (std::size_t b = w; b < top_blocks.size(); b += workers) {
        CarveBlock(top_blocks[b], kTopBlockLog2, region, marks, &own_stats[w]);
      }
    });
  }
  for (std::thread& worker : pool) worker.join();
  for (const FreeSpaceGrid& marks : own_grids) grid->MergeFrom(marks);
  for (const CarvingStats& part : own_stats) {
    stats.blocks_decided += part.blocks_decided;
    stats.voxels_tested += part.voxels_tested;
  }
  return stats;
}

void ProjectiveCarver::MarkReachedBlocks(int block_log2, FreeSpaceGrid* region) {
  if (longest_range_ <= 0.f) return;
  BuildHoleDistance();
  BuildRangePyramid();
  ForEachTopBlock(
      [&](const VoxelKey& base) { MarkReached(base, kTopBlockLog2, block_log2, region); });
}

void ProjectiveCarver::BlockDistances(const VoxelKey& base, int size_log2, Eigen::Vector3f* to_lo,
                                      float* min_distance, float* max_distance) const {
  const auto size_m = static_cast<float>((1 << size_log2) * resolution_m_);
  *to_lo = (Eigen::Vector3d(KeyToLowerCoord(base[0], resolution_m_),
                            KeyToLowerCoord(base[1], resolution_m_),
                            KeyToLowerCoord(base[2], resolution_m_)) -
            origin_W_)
               .cast<float>();
  const Eigen::Vector3f to_hi = *to_lo + Eigen::Vector3f::Constant(size_m);
  *min_distance = to_lo->cwiseMax(-to_hi).cwiseMax(Eigen::Vector3f::Zero()).norm();
  *max_distance = to_lo->cwiseAbs().cwiseMax(to_hi.cwiseAbs()).norm();
}

void ProjectiveCarver::MarkReached(const VoxelKey& base, int size_log2, int block_log2,
                                   FreeSpaceGrid* region) {
  const int size = 1 << size_log2;
  for (int a = 0; a < 3; ++a) {
    if (base[a] > max_key_[a] || base[a] + size - 1 < min_key_[a]) return;
  }
  Eigen::Vector3f to_lo;
  float min_distance = 0.f, max_distance = 0.f;
  BlockDistances(base, size_log2, &to_lo, &min_distance, &max_distance);
  if (min_distance > longest_range_) return;
  const Footprint footprint = Project(to_lo, static_cast<float>(size * resolution_m_));
  if (footprint.kind == Footprint::kOutside) return;
  if (BoundsOver(footprint.rect).max_range < min_distance) return;
  if (size_log2 <= block_log2) {
    region->MarkBlock(base, size_log2);
    return;
  }
  const int half = size / 2;
  for (int c = 0; c < 8; ++c) {
    const VoxelKey child = ChildKey(base, static_cast<unsigned int>(c), half);
    MarkReached(child, size_log2 - 1, block_log2, region);
  }
}

void ProjectiveCarver::CarveBlock(const VoxelKey& base, int size_log2, const FreeSpaceGrid* region,
                                  FreeSpaceGrid* grid, CarvingStats* stats) const {
  const int size = 1 << size_log2;
  for (int a = 0; a < 3; ++a) {
    // Rays only cross voxels between the camera and their ends, all inside the key box.
    if (base[a] > max_key_[a] || base[a] + size - 1 < min_key_[a]) return;
  }
  if (region != nullptr && region->State(kTreeDepth - size_log2, base) == BlockState::kEmpty) {
    ++stats->blocks_decided;
    return;
  }
  const auto size_m = static_cast<float>(size * resolution_m_);
  Eigen::Vector3f to_lo;
  float min_distance = 0.f, max_distance = 0.f;
  BlockDistances(base, size_log2, &to_lo, &min_distance, &max_distance);
  const Footprint footprint = min_distance > longest_range_ ? Footprint{} : Project(to_lo, size_m);
  if (footprint.kind == Footprint::kOutside) {
    ++stats->blocks_decided;
    return;
  }
  const RangeBounds bounds = BoundsOver(footprint.rect);
  if (bounds.max_range < min_distance) {  // no ray reaches the block
    ++stats->blocks_decided;
    return;
  }
  if (footprint.kind == Footprint::kInside && bounds.min_range > max_distance) {
    // Every ray in the rectangle passes the block whole and ends beyond it. Each voxel's
    // inscribed sphere projects to a disk of at least this radius, and the disk holds a pixel
    // with a ray when the nearest pixel centre (within sqrt(2)/2) is that close to a ray's.
    const float disk_radius_px =
        std::min(camera_.fx, camera_.fy) * 0.5f * static_cast<float>(resolution_m_) / max_distance;
    const float reach_px =
        kSqrtHalf + std::sqrt(2.f) * static_cast<float>(bounds.max_hole_distance);
    if (reach_px * kCoverSafety <= disk_radius_px) {
      grid->MarkBlock(base, size_log2);
      ++stats->blocks_decided;
      return;
    }
  }
  if (size_log2 <= kVoxelByVoxelLog2) {
    CarveVoxels(base, to_lo, size, bounds.max_range, grid, stats);
    return;
  }
  const int half = size / 2;
  for (int c = 0; c < 8; ++c) {
    const VoxelKey child = ChildKey(base, static_cast<unsigned int>(c), half);
    CarveBlock(child, size_log2 - 1, region, grid, stats);
  }
}

// The voxels of a mixed block one by one. Most are settled by the pixel nearest the projection
// of their centre: it lies within sqrt(2)/2 pixels of it, so its ray passes through the voxel's
// inscribed sphere when the sphere's projected radius (at least f * r / distance) is that large,
// and a ray that also ends beyond the voxel crosses it. Of the rest, those no ray in a bound of
// their footprint reaches are not crossed, a window of pixels inside the projected sphere settles
// more, and the others get the exact test.
void ProjectiveCarver::CarveVoxels(const VoxelKey& base, const Eigen::Vector3f& lo_rel_W, int size,
                                   float block_max_range, FreeSpaceGrid* grid,
                                   CarvingStats* stats) const {
  const auto voxel = static_cast<float>(resolution_m_);
  const float bounding_radius = kSqrtThreeHalves * voxel;
  const float disk_radius_numerator = std::min(camera_.fx, camera_.fy) * 0.5f * voxel;
  // Beyond this distance the nearest pixel may miss the voxel's inscribed sphere.
  const float center_test_limit = disk_radius_numerator / (kSqrtHalf * kCoverSafety);
  const Eigen::Vector3f step_x = voxel * R_C_W_.col(0), step_y = voxel * R_C_W_.col(1),
                        step_z = voxel * R_C_W_.col(2);
  const Eigen::Vector3f first_center_C =
      R_C_W_ * (lo_rel_W + Eigen::Vector3f::Constant(0.5f * voxel));
  const auto last_u = static_cast<float>(camera_.width) - 0.5f;
  const auto last_v = static_cast<float>(camera_.height) - 0.5f;
  const Eigen::Vector3f half_x = 0.5f * step_x, half_y = 0.5f * step_y, half_z = 0.5f * step_z;
  const CornerOffsets corners = CornerOffsetsOf(half_x, half_y, half_z);
  std::uint64_t crossed = 0;  // bit i + size * (j + size * k)
  stats->voxels_tested += static_cast<std::size_t>(size) * size * size;
  for (int k = 0; k < size; ++k) {
    for (int j = 0; j < size; ++j) {
      const Eigen::Vector3f row_C =
          first_center_C + static_cast<float>(j) * step_y + static_cast<float>(k) * step_z;
      for (int i = 0; i < size; ++i) {
        const std::uint64_t bit = std::uint64_t{1} << (i + size * (j + size * k));
        const Eigen::Vector3f center_C = row_C + static_cast<float>(i) * step_x;
        const float distance = center_C.norm();
        const float min_distance = std::max(0.f, distance - bounding_radius);
        if (min_distance > block_max_range) continue;  // no ray of the block reaches it
        auto voxel_lo = [&] {                          // only the slower paths need the corner
          return Eigen::Vector3f(lo_rel_W.x() + voxel * static_cast<float>(i),
                                 lo_rel_W.y() + voxel * static_cast<float>(j),
                                 lo_rel_W.z() + voxel * static_cast<float>(k));
        };
        if (center_C.z() <= bounding_radius + kNearPlaneM) {
          // At the camera plane: the projection needs clipping.
          const Footprint footprint = Project(voxel_lo(), voxel);
          if (footprint.kind != Footprint::kOutside &&
              VoxelCrossed(voxel_lo(), footprint, min_distance)) {
            crossed |= bit;
          }
          continue;
        }
        const float inverse_z = 1.f / center_C.z();
        const float u = camera_.fx * center_C.x() * inverse_z + camera_.cx;
        const float v = camera_.fy * center_C.y() * inverse_z + camera_.cy;
        const bool nearest_in_image = u >= -0.5f && v >= -0.5f && u < last_u && v < last_v;
        const bool center_test = nearest_in_image && distance <= center_test_limit;
        const std::size_t nearest =
            nearest_in_image
                ? static_cast<std::size_t>(static_cast<int>(v + 0.5f)) * camera_.width +
                      static_cast<std::size_t>(static_cast<int>(u + 0.5f))
                : 0;
        const float beyond_voxel = distance + bounding_radius;
        if (center_test && rays_.range[nearest] > beyond_voxel) {
          crossed |= bit;
          continue;
        }
        // A cheap bound of the footprint, from the bounding sphere:
        // |d(fx x / z)| <= fx r (z + |x|) / (z (z - r)); the window around the nearest pixel is
        // off by up to half a pixel.
        const float to_near_side = 1.f / (center_C.z() - bounding_radius);
        // (Clamped: near the camera plane the bound grows without limit.)
        const float radius_u =
            std::min(kFarOutsidePx, camera_.fx * bounding_radius *
                                        (1.f + std::fabs(center_C.x()) * inverse_z) * to_near_side);
        const float radius_v =
            std::min(kFarOutsidePx, camera_.fy * bounding_radius *
                                        (1.f + std::fabs(center_C.y()) * inverse_z) * to_near_side);
        const int bound_level =
            WindowLevelCovering(std::max(radius_u, radius_v) + 0.5f + kRectMarginPx);
        if (nearest_in_image && bound_level >= 0) {
          if (window_max_[static_cast<std::size_t>(bound_level)][nearest] < min_distance) continue;
        } else {
          Rect rect;
          rect.u0 = std::max(0, CeilToInt(u - radius_u - kRectMarginPx));
          rect.u1 = std::min(camera_.width - 1, FloorToInt(u + radius_u + kRectMarginPx));
          rect.v0 = std::max(0, CeilToInt(v - radius_v - kRectMarginPx));
          rect.v1 = std::min(camera_.height - 1, FloorToInt(v + radius_v + kRectMarginPx));
          if (rect.u0 > rect.u1 || rect.v0 > rect.v1) continue;  // outside the image
          if (MaxRangeOver(rect) < min_distance) continue;
        }
        if (center_test) {
          // A square window around the nearest pixel that lies inside the inscribed sphere's
          // projected disk: (k + 1/2) sqrt(2) <= disk radius.
          const float disk_radius = disk_radius_numerator / distance;
          const int disk_level = WindowLevelWithin(disk_radius * kSqrtHalf - 0.5f);
          if (disk_level >= 0 &&
              window_max_[static_cast<std::size_t>(disk_level)][nearest] > beyond_voxel) {
            crossed |= bit;
            continue;
          }
        }
        const Footprint footprint = ProjectVoxel(corners, center_C, half_x, half_y, half_z);
        if (footprint.kind == Footprint::kOutside) continue;
        if (MaxRangeOver(footprint.rect) < min_distance) continue;
        if (VoxelCrossed(voxel_lo(), footprint, min_distance)) crossed |= bit;
      }
    }
  }
  grid->MarkVoxels(base, size, crossed);
}

// The first window level whose radius (1, 2, 4, ...) is at least `radius_px`; -1 when none.
int ProjectiveCarver::WindowLevelCovering(float radius_px) {
  if (radius_px <= 1.f) return 0;
  if (!(radius_px <= static_cast<float>(1 << (kWindowLevels - 1)))) return -1;
  int level = 1;
  while (static_cast<float>(1 << level) < radius_px) ++level;
  return level;
}

// The last window level whose radius is at most `radius_px`; -1 when none.
int ProjectiveCarver::WindowLevelWithin(float radius_px) {
  if (!(radius_px >= 1.f)) return -1;
  int level = 0;
  while (level + 1 < kWindowLevels && static_cast<float>(2 << level) <= radius_px) ++level;
  return level;
}

// Whether one pixel ray in the footprint crosses the voxel and ends beyond it: the voxels
// computeRayKeys lists for a ray are those its segment passes through, except the one holding
// its end. With the segment as t in [0, 1], that is entry < exit < 1 for the slab test's
// parameters (exit >= 1: the segment ends inside). Rows are scanned without early exit, so that
// the loop vectorizes.
bool ProjectiveCarver::VoxelCrossed(const Eigen::Vector3f& lo_rel_W, const Footprint& footprint,
                                    float min_distance) const {
  const Eigen::Vector3f hi_rel_W =
      lo_rel_W + Eigen::Vector3f::Constant(static_cast<float>(resolution_m_));
  const Rect& rect = footprint.rect;
  const float lo_x = lo_rel_W.x(), lo_y = lo_rel_W.y(), lo_z = lo_rel_W.z();
  const float hi_x = hi_rel_W.x(), hi_y = hi_rel_W.y(), hi_z = hi_rel_W.z();
  for (int v = rect.v0; v <= rect.v1; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * camera_.width;
    const float* range = rays_.range.data() + row;
    const float* inverse_x = rays_.inverse_direction[0].data() + row;
    const float* inverse_y = rays_.inverse_direction[1].data() + row;
    const float* inverse_z = rays_.inverse_direction[2].data() + row;
    int crossed = 0;
    for (int u = rect.u0; u <= rect.u1; ++u) {
      const float x0 = lo_x * inverse_x[u], x1 = hi_x * inverse_x[u];
      const float y0 = lo_y * inverse_y[u], y1 = hi_y * inverse_y[u];
      const float z0 = lo_z * inverse_z[u], z1 = hi_z * inverse_z[u];
      const float entry =
          std::max(std::max(std::min(x0, x1), std::min(y0, y1)), std::max(std::min(z0, z1), 0.f));
      const float exit = std::min(std::min(std::max(x0, x1), std::max(y0, y1)), std::max(z0, z1));
      crossed |= static_cast<int>(range[u] >= min_distance) & static_cast<int>(entry < exit) &
                 static_cast<int>(exit < 1.f);
    }
    if (crossed != 0) return true;
  }
  return false;
}

}  // namespace objmap::occupancy_internal
