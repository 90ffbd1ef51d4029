#include "occupancy/free_space_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace objmap::occupancy_internal {
namespace {

constexpr int kBrickShift = 3;                         // 8 voxels per brick edge
constexpr int kBrickDepth = kTreeDepth - kBrickShift;  // octree depth of one brick (13)
constexpr std::uint64_t kAllOnes = ~std::uint64_t{0};

double KeyToCoord(int key, double resolution_m) {
  return (static_cast<double>(key - kKeyOffset) + 0.5) * resolution_m;
}

// Combines child states: all full -> full, all empty -> empty, otherwise mixed.
struct StateAccumulator {
  bool any_set = false;
  bool all_full = true;
  void Add(BlockState s) {
    any_set |= s != BlockState::kEmpty;
    all_full &= s == BlockState::kFull;
  }
  [[nodiscard]] BlockState Result() const {
    if (all_full) return BlockState::kFull;
    return any_set ? BlockState::kMixed : BlockState::kEmpty;
  }
};

}  // namespace

std::int64_t CoordinateToKey(double coordinate_m, double resolution_m) {
  constexpr double kKeyCount = 1 << kTreeDepth;
  // Clamp before the integer conversion: far-away coordinates must not overflow.
  const double key = std::floor(coordinate_m * (1.0 / resolution_m)) + kKeyOffset;
  return static_cast<std::int64_t>(std::clamp(key, -1.0, kKeyCount));
}

bool KeysOfBox(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W, double resolution_m,
               VoxelKey* lo, VoxelKey* hi) {
  constexpr std::int64_t kKeyCount = std::int64_t{1} << kTreeDepth;
  if (!min_W.allFinite() || !max_W.allFinite()) return false;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t first = CoordinateToKey(min_W[i], resolution_m);
    const std::int64_t last = CoordinateToKey(max_W[i], resolution_m);
    if (first > last || last < 0 || first >= kKeyCount) return false;
    (*lo)[static_cast<std::size_t>(i)] =
        static_cast<std::uint16_t>(std::max<std::int64_t>(first, 0));
    (*hi)[static_cast<std::size_t>(i)] =
        static_cast<std::uint16_t>(std::min<std::int64_t>(last, kKeyCount - 1));
  }
  return true;
}

bool PointToKey(const Eigen::Vector3f& point, double resolution_m, VoxelKey* key) {
  const double factor = 1.0 / resolution_m;
  for (int i = 0; i < 3; ++i) {
    const double scaled = factor * static_cast<double>(point[i]);
    if (!(scaled >= -kKeyOffset && scaled < kKeyOffset)) return false;  // also rejects NaN
    // floor() by truncation: std::floor is a library call in plain SSE2 code, and this runs
    // for every point of every scan.
    const int truncated = static_cast<int>(scaled);
    const int floored = truncated - static_cast<int>(scaled < static_cast<double>(truncated));
    (*key)[i] = static_cast<std::uint16_t>(floored + kKeyOffset);
  }
  return true;
}

void FreeSpaceGrid::Reset(const VoxelKey& min_key, const VoxelKey& max_key) {
  min_key_ = min_key;
  max_key_ = max_key;
  for (int i = 0; i < 3; ++i) {
    lo_[i] = (min_key[i] >> kBrickShift) - 1;
    dims_[i] = (max_key[i] >> kBrickShift) + 1 - lo_[i] + 1;
  }
  cell_to_brick_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2], -1);
  bricks_.clear();
  levels_.clear();
}

std::int64_t FreeSpaceGrid::BrickCell(const VoxelKey& key) const {
  const int bx = (key[0] >> kBrickShift) - lo_[0];
  const int by = (key[1] >> kBrickShift) - lo_[1];
  const int bz = (key[2] >> kBrickShift) - lo_[2];
  if (bx < 0 || by < 0 || bz < 0 || bx >= dims_[0] || by >= dims_[1] || bz >= dims_[2]) {
    return -1;
  }
  return (static_cast<std::int64_t>(bz) * dims_[1] + by) * dims_[0] + bx;
}

void FreeSpaceGrid::AddRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& end) {
  VoxelKey key_origin, key_end;
  if (!PointToKey(origin, resolution_m_, &key_origin) ||
      !PointToKey(end, resolution_m_, &key_end) || key_origin == key_end) {
    return;
  }
  // Float direction and length, double traversal parameters: the arithmetic of
  // OcTree::computeRayKeys (Amanatides & Woo), so the voxel sets agree bit for bit.
  Eigen::Vector3f direction = end - origin;
  const float length = static_cast<float>(std::sqrt(static_cast<double>(
      direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2])));
  direction /= length;
  DdaRay ray;
  for (int i = 0; i < 3; ++i) {
    ray.step[i] = direction[i] > 0.0f ? 1 : (direction[i] < 0.0f ? -1 : 0);
    ray.key[i] = key_origin[i];
    ray.end[i] = key_end[i];
    if (ray.step[i] == 0) {
      ray.t_max[i] = ray.t_delta[i] = std::numeric_limits<double>::max();
      continue;
    }
    double border = KeyToCoord(key_origin[i], resolution_m_);
    border += static_cast<float>(ray.step[i] * resolution_m_ * 0.5);
    ray.t_max[i] = (border - static_cast<double>(origin[i])) / static_cast<double>(direction[i]);
    ray.t_delta[i] = resolution_m_ / std::fabs(static_cast<double>(direction[i]));
  }
  ray.length = length;
  Traverse(ray);
}

// The DDA loop, written without data-dependent branches: which axis steps next is random from
// one voxel to the next, and mispredicted branches dominated the cost.
void FreeSpaceGrid::Traverse(const DdaRay& ray) {
  int kx = ray.key[0], ky = ray.key[1], kz = ray.key[2];
  double tx = ray.t_max[0], ty = ray.t_max[1], tz = ray.t_max[2];
  const std::int64_t stride_y = dims_[0], stride_z = std::int64_t{dims_[0]} * dims_[1];
  const std::int64_t cell_offset = -(lo_[0] + lo_[1] * stride_y + lo_[2] * stride_z);
  while (true) {
    const std::int64_t cell = (kx >> kBrickShift) + (ky >> kBrickShift) * stride_y +
                              (kz >> kBrickShift) * stride_z + cell_offset;
    std::int32_t index = cell_to_brick_[static_cast<std::size_t>(cell)];
    if (index < 0) index = NewBrick(cell);
    bricks_[static_cast<std::size_t>(index)][kz & 7] |= std::uint64_t{1}
                                                        << ((kx & 7) + 8 * (ky & 7));
    // Same tie-breaking as OctoMap: x only on strict minimum, z wins ties with the others.
    const bool x_lt_y = tx < ty;
    const bool pick_x = x_lt_y && tx < tz;
    const bool pick_y = !x_lt_y && ty < tz;
    const bool pick_z = !pick_x && !pick_y;
    kx += pick_x ? ray.step[0] : 0;
    ky += pick_y ? ray.step[1] : 0;
    kz += pick_z ? ray.step[2] : 0;
    tx += pick_x ? ray.t_delta[0] : 0.0;
    ty += pick_y ? ray.t_delta[1] : 0.0;
    tz += pick_z ? ray.t_delta[2] : 0.0;
    if (kx == ray.end[0] && ky == ray.end[1] && kz == ray.end[2]) return;
    // Stop once past the end point: float drift can make the ray miss the end voxel.
    if (std::min(std::min(tx, ty), tz) > ray.length) return;
  }
}

std::int32_t FreeSpaceGrid::NewBrick(std::int64_t cell) {
  const auto index = static_cast<std::int32_t>(bricks_.size());
  cell_to_brick_[static_cast<std::size_t>(cell)] = index;
  bricks_.push_back(Brick{});
  return index;
}

void FreeSpaceGrid::MarkBlock(const VoxelKey& base, int size_log2) {
  if (size_log2 >= kBrickShift) {
    const int bricks = 1 << (size_log2 - kBrickShift);
    for (int z = 0; z < bricks; ++z) {
      for (int y = 0; y < bricks; ++y) {
        for (int x = 0; x < bricks; ++x) {
          const VoxelKey corner = {static_cast<std::uint16_t>(base[0] + (x << kBrickShift)),
                                   static_cast<std::uint16_t>(base[1] + (y << kBrickShift)),
                                   static_cast<std::uint16_t>(base[2] + (z << kBrickShift))};
          const std::int64_t cell = BrickCell(corner);
          if (cell < 0) continue;
          std::int32_t index = cell_to_brick_[static_cast<std::size_t>(cell)];
          if (index < 0) index = NewBrick(cell);
          bricks_[static_cast<std::size_t>(index)].fill(kAllOnes);
        }
      }
    }
    return;
  }
  const std::int64_t cell = BrickCell(base);
  if (cell < 0) return;
  std::int32_t index = cell_to_brick_[static_cast<std::size_t>(cell)];
  if (index < 0) index = NewBrick(cell);
  Brick& brick = bricks_[static_cast<std::size_t>(index)];
  const int size = 1 << size_log2;
  const std::uint64_t row = (std::uint64_t{1} << size) - 1;
  std::uint64_t mask = 0;
  for (int y = 0; y < size; ++y) mask |= row << ((base[0] & 7) + 8 * ((base[1] & 7) + y));
  for (int z = 0; z < size; ++z) brick[(base[2] & 7) + z] |= mask;
}

void FreeSpaceGrid::MarkVoxels(const VoxelKey& base, int size, std::uint64_t voxels) {
  if (voxels == 0) return;
  const std::int64_t cell = BrickCell(base);
  if (cell < 0) return;
  std::int32_t index = cell_to_brick_[static_cast<std::size_t>(cell)];
  if (index < 0) index = NewBrick(cell);
  Brick& brick = bricks_[static_cast<std::size_t>(index)];
  const int x0 = base[0] & 7, y0 = base[1] & 7, z0 = base[2] & 7;
  const std::uint64_t row_mask = (std::uint64_t{1} << size) - 1;
  for (int k = 0; k < size; ++k) {
    std::uint64_t slice = 0;
    for (int j = 0; j < size; ++j) {
      const std::uint64_t row = (voxels >> (size * (j + size * k))) & row_mask;
      slice |= row << (x0 + 8 * (y0 + j));
    }
    brick[static_cast<std::size_t>(z0 + k)] |= slice;
  }
}

void FreeSpaceGrid::MergeFrom(const FreeSpaceGrid& other) {
  for (std::size_t cell = 0; cell < other.cell_to_brick_.size(); ++cell) {
    const std::int32_t from = other.cell_to_brick_[cell];
    if (from < 0) continue;
    std::int32_t to = cell_to_brick_[cell];
    if (to < 0) to = NewBrick(static_cast<std::int64_t>(cell));
    const Brick& source = other.bricks_[static_cast<std::size_t>(from)];
    Brick& target = bricks_[static_cast<std::size_t>(to)];
    for (std::size_t k = 0; k < 8; ++k) target[k] |= source[k];
  }
}

const FreeSpaceGrid::Brick* FreeSpaceGrid::BrickAt(const VoxelKey& key) const {
  const std::int64_t cell = BrickCell(key);
  if (cell < 0) return nullptr;
  const std::int32_t index = cell_to_brick_[static_cast<std::size_t>(cell)];
  return index < 0 ? nullptr : &bricks_[static_cast<std::size_t>(index)];
}

void FreeSpaceGrid::KeepOnly(const FreeSpaceGrid& region) {
  for (int z = 0; z < dims_[2]; ++z) {
    for (int y = 0; y < dims_[1]; ++y) {
      for (int x = 0; x < dims_[0]; ++x) {
        const std::int32_t index =
            cell_to_brick_[(static_cast<std::size_t>(z) * dims_[1] + y) * dims_[0] + x];
        if (index < 0) continue;
        const VoxelKey corner = {static_cast<std::uint16_t>((lo_[0] + x) << kBrickShift),
                                 static_cast<std::uint16_t>((lo_[1] + y) << kBrickShift),
                                 static_cast<std::uint16_t>((lo_[2] + z) << kBrickShift)};
        const Brick* keep = region.BrickAt(corner);
        Brick& brick = bricks_[static_cast<std::size_t>(index)];
        for (std::size_t k = 0; k < 8; ++k) brick[k] &= keep == nullptr ? 0 : (*keep)[k];
      }
    }
  }
}

void FreeSpaceGrid::Clear(const VoxelKey& key) {
  const std::int64_t cell = BrickCell(key);
  if (cell < 0 || cell_to_brick_[static_cast<std::size_t>(cell)] < 0) return;
  Brick& brick = bricks_[static_cast<std::size_t>(cell_to_brick_[static_cast<std::size_t>(cell)])];
  brick[key[2] & 7] &= ~(std::uint64_t{1} << ((key[0] & 7) + 8 * (key[1] & 7)));
}

bool FreeSpaceGrid::Test(const VoxelKey& key) const {
  return SubBrickState(kTreeDepth, key) == BlockState::kFull;
}

BlockState FreeSpaceGrid::SubBrickState(int depth, const VoxelKey& key) const {
  const std::int64_t cell = BrickCell(key);
  if (cell < 0 || cell_to_brick_[static_cast<std::size_t>(cell)] < 0) return BlockState::kEmpty;
  const Brick& brick =
      bricks_[static_cast<std::size_t>(cell_to_brick_[static_cast<std::size_t>(cell)])];
  const int size = 1 << (kTreeDepth - depth);  // 1, 2, 4 or 8 voxels per edge
  const int x0 = key[0] & 7 & ~(size - 1), y0 = key[1] & 7 & ~(size - 1);
  const int z0 = key[2] & 7 & ~(size - 1);
  std::uint64_t mask = 0;
  const std::uint64_t row = (size == 8) ? 0xFF : ((std::uint64_t{1} << size) - 1);
  for (int y = 0; y < size; ++y) mask |= row << (x0 + 8 * (y0 + y));
  StateAccumulator acc;
  for (int z = z0; z < z0 + size; ++z) {
    const std::uint64_t bits = brick[z] & mask;
    acc.Add(bits == mask ? BlockState::kFull
                         : (bits == 0 ? BlockState::kEmpty : BlockState::kMixed));
  }
  return acc.Result();
}

void FreeSpaceGrid::BuildPyramid() {
  levels_.assign(kBrickDepth + 1, {});
  level_lo_.assign(kBrickDepth + 1, {});
  level_dims_.assign(kBrickDepth + 1, {});
  for (int level = 0; level <= kBrickDepth; ++level) BuildLevel(level);
}

void FreeSpaceGrid::BuildLevel(int level) {
  std::array<int, 3>& lo = level_lo_[level];
  std::array<int, 3>& dims = level_dims_[level];
  for (int i = 0; i < 3; ++i) {
    lo[i] = lo_[i] >> level;
    dims[i] = ((lo_[i] + dims_[i] - 1) >> level) - lo[i] + 1;
  }
  std::vector<BlockState>& states = levels_[level];
  states.assign(static_cast<std::size_t>(dims[0]) * dims[1] * dims[2], BlockState::kEmpty);
  for (int z = 0; z < dims[2]; ++z) {
    for (int y = 0; y < dims[1]; ++y) {
      for (int x = 0; x < dims[0]; ++x) {
        // A cell at `level` covers the node whose brick coordinates, shifted, equal its own.
        const int shift = kBrickShift + level;
        const VoxelKey key = {static_cast<std::uint16_t>((lo[0] + x) << shift),
                              static_cast<std::uint16_t>((lo[1] + y) << shift),
                              static_cast<std::uint16_t>((lo[2] + z) << shift)};
        BlockState state = BlockState::kEmpty;
        if (level == 0) {
          state = SubBrickState(kBrickDepth, key);
        } else {
          StateAccumulator acc;
          const int half = 1 << (shift - 1);
          for (int c = 0; c < 8; ++c) {
            const VoxelKey child = ChildKey(key, static_cast<unsigned int>(c), half);
            acc.Add(State(kBrickDepth - level + 1, child));
          }
          state = acc.Result();
        }
        states[(static_cast<std::size_t>(z) * dims[1] + y) * dims[0] + x] = state;
      }
    }
  }
}

BlockState FreeSpaceGrid::State(int depth, const VoxelKey& key) const {
  if (depth > kBrickDepth) return SubBrickState(depth, key);
  const int level = kBrickDepth - depth;
  const int shift = kBrickShift + level;
  const std::array<int, 3>& lo = level_lo_[level];
  const std::array<int, 3>& dims = level_dims_[level];
  int c[3];
  for (int i = 0; i < 3; ++i) {
    c[i] = (key[i] >> shift) - lo[i];
    if (c[i] < 0 || c[i] >= dims[i]) return BlockState::kEmpty;
  }
  return levels_[level][(static_cast<std::size_t>(c[2]) * dims[1] + c[1]) * dims[0] + c[0]];
}

std::size_t FreeSpaceGrid::CountSet() const {
  std::size_t count = 0;
  for (const Brick& brick : bricks_) {
    for (std::uint64_t word : brick) count += static_cast<std::size_t>(__builtin_popcountll(word));
  }
  return count;
}

}  // namespace objmap::occupancy_internal
