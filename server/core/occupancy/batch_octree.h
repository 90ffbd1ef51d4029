#pragma once
// Internal to the occupancy module (includes OctoMap; never include it from a public header).
// An octomap::OcTree that applies one scan in a single depth-first pass: a node whose whole
// volume the scan saw free gets one log-odds update instead of one per leaf, and the occupied
// voxels are updated on the same pass instead of one root-to-leaf descent each. The leaf values
// are those OctoMap's per-voxel updateNode() would give (paper Sec. III-E map, OctoMap
// semantics).

#include <octomap/OcTree.h>

#include <cstdint>
#include <vector>

#include "occupancy/free_space_grid.h"

namespace objmap::occupancy_internal {

/// Thread-safety: none (it is an OcTree).
class BatchOcTree : public octomap::OcTree {
 public:
  explicit BatchOcTree(double resolution_m) : octomap::OcTree(resolution_m) {}

  /// Adds the miss log-odds to every voxel set in `free_space` and the hit log-odds to every
  /// voxel in `occupied` (Morton codes, sorted and distinct, none of them set in `free_space`),
  /// each once. Nodes on the visited paths are pruned or get their inner occupancy refreshed,
  /// as non-lazy updateNode() does.
  void ApplyScan(const FreeSpaceGrid& free_space, const std::vector<std::uint64_t>& occupied);

  /// Deletes every voxel set in `region` (they become unknown); nodes outside keep their
  /// values, and inner nodes on the way get their occupancy refreshed. `region`'s pyramid must
  /// be built.
  void ClearRegion(const FreeSpaceGrid& region);

 private:
  using CodeIterator = std::vector<std::uint64_t>::const_iterator;
  void Visit(octomap::OcTreeNode* node, int depth, const VoxelKey& base, bool full, bool fresh,
             const FreeSpaceGrid& free_space, CodeIterator occupied_begin,
             CodeIterator occupied_end);
  // True when `node` must go (all of it lies in the regions); it is then a leaf.
  bool ClearVisit(octomap::OcTreeNode* node, int depth, const VoxelKey& base,
                  const FreeSpaceGrid& region);
  // Turns `node` into a leaf, its subtree pruned away, so that it can be deleted.
  void CollapseToLeaf(octomap::OcTreeNode* node);
};

}  // namespace objmap::occupancy_internal
