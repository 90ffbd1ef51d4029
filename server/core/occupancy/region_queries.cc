// Read-only queries of OccupancyMap over boxes and rays: coarse region occupancy, ray casting and
// OctoMap binary export. They walk the OcTree's known nodes (never every cell of a box), so a
// large, mostly unknown box costs what the known part of the map inside it costs.

#include <octomap/OcTree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "occupancy/occupancy_map.h"
#include "occupancy/occupancy_map_impl.h"

namespace objmap {
namespace {

using occupancy_internal::kKeyOffset;
using occupancy_internal::kTreeDepth;
using Key3 = std::array<std::int64_t, 3>;

constexpr std::int64_t kKeyCount = std::int64_t{1} << kTreeDepth;
// Coarsest cell QueryRegion hands out: depth 1 of the tree (depth 0 would be the whole key space).
constexpr int kMaxCellLevel = kTreeDepth - 1;

// Inclusive index ranges along x, y, z (keys at the leaf level, or cells at a coarser level).
struct IndexBox {
  Key3 lo{}, hi{};
};

// Leaf keys of the box [min_W, max_W] clipped to the key space; false when nothing is left.
bool BoxKeys(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W, double resolution_m,
             IndexBox* keys) {
  occupancy_internal::VoxelKey lo{}, hi{};
  if (!occupancy_internal::KeysOfBox(min_W, max_W, resolution_m, &lo, &hi)) return false;
  for (std::size_t i = 0; i < 3; ++i) {
    keys->lo[i] = lo[i];
    keys->hi[i] = hi[i];
  }
  return true;
}

octomap::OcTreeKey ToOcTreeKey(const Key3& k) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(k[0]),
                            static_cast<octomap::key_type>(k[1]),
                            static_cast<octomap::key_type>(k[2]));
}

// Smallest k with leaf * 2^k >= resolution_m, capped; 0 for resolutions at or below the leaf.
int CellLevel(double leaf_m, double resolution_m) {
  int level = 0;
  if (!(resolution_m > leaf_m)) return level;
  // The tolerance keeps 0.04 from becoming 0.08 on a 0.01 leaf through rounding.
  while (level < kMaxCellLevel && std::ldexp(leaf_m, level) < resolution_m * (1.0 - 1e-9)) {
    ++level;
  }
  return level;
}

std::size_t CellCount(const IndexBox& cells) {
  std::size_t count = 1;
  for (int i = 0; i < 3; ++i) count *= static_cast<std::size_t>(cells.hi[i] - cells.lo[i] + 1);
  return count;
}

// The cells (at `level`) that a node covers, clipped to `cells`; false when they do not meet.
bool NodeCells(const octomap::OcTreeKey& key, unsigned node_depth, int level, const IndexBox& cells,
               IndexBox* covered) {
  const int node_level = kTreeDepth - static_cast<int>(node_depth);
  for (int i = 0; i < 3; ++i) {
    const std::int64_t first_key = (std::int64_t{key[i]} >> node_level) << node_level;
    const std::int64_t last_key = first_key + (std::int64_t{1} << node_level) - 1;
    covered->lo[i] = std::max(cells.lo[i], first_key >> level);
    covered->hi[i] = std::min(cells.hi[i], last_key >> level);
    if (covered->lo[i] > covered->hi[i]) return false;
  }
  return true;
}

// Accumulates the known nodes of a region query into counts and the optional cell list.
class RegionAccumulator {
 public:
  RegionAccumulator(const octomap::OcTree& tree, const IndexBox& cells, int level,
                    std::size_t max_cells, RegionOccupancy* result)
      : tree_(tree), cells_(cells), level_(level), max_cells_(max_cells), result_(result) {}

  void Add(const octomap::OcTreeKey& key, unsigned node_depth, bool occupied) {
    IndexBox covered;
    // The bbx iterator also returns nodes that only touch the box; NodeCells drops them.
    if (!NodeCells(key, node_depth, level_, cells_, &covered)) return;
    (occupied ? result_->occupied : result_->free) += CellCount(covered);
    if (max_cells_ > 0) List(covered, occupied ? VoxelState::kOccupied : VoxelState::kFree);
  }

 private:
  void List(const IndexBox& covered, VoxelState state) {
    const unsigned depth = static_cast<unsigned>(kTreeDepth - level_);
    auto centre = [&](std::int64_t cell) {
      return tree_.keyToCoord(static_cast<octomap::key_type>(cell << level_), depth);
    };
    for (std::int64_t x = covered.lo[0]; x <= covered.hi[0]; ++x) {
      for (std::int64_t y = covered.lo[1]; y <= covered.hi[1]; ++y) {
        for (std::int64_t z = covered.lo[2]; z <= covered.hi[2]; ++z) {
          if (result_->known_cells.size() >= max_cells_) {
            result_->truncated = true;
            return;
          }
          result_->known_cells.push_back({Eigen::Vector3d(centre(x), centre(y), centre(z)), state});
        }
      }
    }
  }

  const octomap::OcTree& tree_;
  IndexBox cells_;
  int level_;
  std::size_t max_cells_;
  RegionOccupancy* result_;
};

// An OcTree that can hold a leaf above the finest depth, to copy pruned nodes as they are.
class RegionTree : public octomap::OcTree {
 public:
  explicit RegionTree(double resolution_m) : octomap::OcTree(resolution_m) {}

  /// Creates the path to the node of `key` at `depth` and gives that node `log_odds`. The
  /// caller never sets a node inside another leaf it set (the source tree's leaves are disjoint).
  void SetLeaf(const octomap::OcTreeKey& key, unsigned depth, float log_odds) {
    if (root == nullptr) {
      root = new octomap::OcTreeNode();  // as OccupancyOcTreeBase::updateNode does
      ++tree_size;
    }
    octomap::OcTreeNode* node = root;
    for (unsigned d = 0; d < depth; ++d) {
      const unsigned child = octomap::computeChildIdx(key, static_cast<int>(tree_depth - 1 - d));
      node =
          nodeChildExists(node, child) ? getNodeChild(node, child) : createNodeChild(node, child);
    }
    node->setLogOdds(log_odds);
  }
};

// Leaf-level centre of a key along one axis, as OcTree::keyToCoord.
double KeyCentre(std::int64_t key, double resolution_m) {
  return (static_cast<double>(key - kKeyOffset) + 0.5) * resolution_m;
}

// Amanatides-Woo traversal state of one ray through the leaf grid.
struct RayWalk {
  Key3 key{};
  std::array<int, 3> step{};
  std::array<double, 3> t_max{}, t_delta{};
};

// False when the origin lies outside the key space.
bool StartWalk(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& unit_W, double resolution_m,
               RayWalk* walk) {
  for (int i = 0; i < 3; ++i) {
    walk->key[i] = occupancy_internal::CoordinateToKey(origin_W[i], resolution_m);
    if (walk->key[i] < 0 || walk->key[i] >= kKeyCount) return false;
    walk->step[i] = unit_W[i] > 0.0 ? 1 : (unit_W[i] < 0.0 ? -1 : 0);
    if (walk->step[i] == 0) {
      walk->t_max[i] = walk->t_delta[i] = std::numeric_limits<double>::infinity();
      continue;
    }
    const double border_m =
        static_cast<double>(walk->key[i] - kKeyOffset + (walk->step[i] > 0 ? 1 : 0)) * resolution_m;
    walk->t_max[i] = (border_m - origin_W[i]) / unit_W[i];
    walk->t_delta[i] = resolution_m / std::abs(unit_W[i]);
  }
  return true;
}

}  // namespace

RegionOccupancy OccupancyMap::QueryRegion(const Eigen::Vector3d& min_W,
                                          const Eigen::Vector3d& max_W, double resolution_m,
                                          std::size_t max_cells) const {
  const octomap::OcTree& tree = impl_->tree;
  const int level = CellLevel(tree.getResolution(), resolution_m);
  RegionOccupancy result;
  result.resolution_m = std::ldexp(tree.getResolution(), level);
  IndexBox cells;
  if (!BoxKeys(min_W, max_W, tree.getResolution(), &cells)) return result;
  for (int i = 0; i < 3; ++i) {
    cells.lo[i] >>= level;
    cells.hi[i] >>= level;
  }
  // Known nodes at the cell depth (or pruned above it); inner nodes hold their children's max
  // occupancy, so a cell node answers for all the leaves below it. The rest is unknown.
  Key3 first_key, last_key;
  for (int i = 0; i < 3; ++i) {
    first_key[i] = cells.lo[i] << level;
    last_key[i] = ((cells.hi[i] + 1) << level) - 1;
  }
  RegionAccumulator accumulator(tree, cells, level, max_cells, &result);
  const auto depth = static_cast<unsigned char>(kTreeDepth - level);
  for (auto it = tree.begin_leafs_bbx(ToOcTreeKey(first_key), ToOcTreeKey(last_key), depth),
            end = tree.end_leafs_bbx();
       it != end; ++it) {
    accumulator.Add(it.getKey(), it.getDepth(), tree.isNodeOccupied(*it));
  }
  result.unknown = CellCount(cells) - result.occupied - result.free;
  return result;
}

RayHit OccupancyMap::CastRay(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& direction_W,
                             double max_range_m, bool unknown_stops) const {
  const octomap::OcTree& tree = impl_->tree;
  const double resolution_m = tree.getResolution();
  RayHit result;
  const double norm = direction_W.norm();
  if (!origin_W.allFinite() || !direction_W.allFinite() || !(norm > 0.0)) return result;
  RayWalk walk;
  if (!StartWalk(origin_W, direction_W / norm, resolution_m, &walk)) return result;
  const bool limited = std::isfinite(max_range_m) && max_range_m > 0.0;
  while (true) {
    const octomap::OcTreeNode* node = tree.search(ToOcTreeKey(walk.key));
    const bool occupied = node != nullptr && tree.isNodeOccupied(node);
    if (occupied || (node == nullptr && unknown_stops)) {
      result.hit = true;
      result.state = occupied ? VoxelState::kOccupied : VoxelState::kUnknown;
      for (int i = 0; i < 3; ++i) result.voxel_center_W[i] = KeyCentre(walk.key[i], resolution_m);
      result.distance_m = (result.voxel_center_W - origin_W).norm();
      return result;
    }
    // Next voxel: across the nearest border; stop when it lies beyond the range or the map.
    const int axis = static_cast<int>(std::min_element(walk.t_max.begin(), walk.t_max.end()) -
                                      walk.t_max.begin());
    if (limited && walk.t_max[axis] > max_range_m) return result;
    walk.key[axis] += walk.step[axis];
    if (walk.key[axis] < 0 || walk.key[axis] >= kKeyCount) return result;
    walk.t_max[axis] += walk.t_delta[axis];
  }
}

std::string OccupancyMap::BinaryBytes(bool region, const Eigen::Vector3d& min_W,
                                      const Eigen::Vector3d& max_W, std::size_t* leaf_count) const {
  const octomap::OcTree& tree = impl_->tree;
  if (leaf_count != nullptr) *leaf_count = 0;
  std::ostringstream bytes;
  if (!region) {
    if (!tree.writeBinaryConst(bytes)) return {};
    if (leaf_count != nullptr) *leaf_count = tree.getNumLeafNodes();
    return bytes.str();
  }
  RegionTree part(tree.getResolution());
  part.setOccupancyThres(tree.getOccupancyThres());
  std::size_t leaves = 0;
  IndexBox keys;
  if (BoxKeys(min_W, max_W, tree.getResolution(), &keys)) {
    for (auto it = tree.begin_leafs_bbx(ToOcTreeKey(keys.lo), ToOcTreeKey(keys.hi)),
              end = tree.end_leafs_bbx();
         it != end; ++it) {
      IndexBox covered;
      if (!NodeCells(it.getKey(), it.getDepth(), 0, keys, &covered)) continue;
      // A pruned node is copied whole, at its own depth: it is one leaf of the source map.
      part.SetLeaf(it.getKey(), it.getDepth(), it->getLogOdds());
      ++leaves;
    }
  }
  part.updateInnerOccupancy();
  if (!part.writeBinaryConst(bytes)) return {};
  if (leaf_count != nullptr) *leaf_count = leaves;
  return bytes.str();
}

}  // namespace objmap
