#pragma once
// Internal to the occupancy module (includes OctoMap; never include it from a public header).
// An octomap::OcTree that can apply one scan's free space block-wise: a node whose whole volume
// the scan saw free gets one log-odds update instead of one per leaf. The leaf values are the
// same as OctoMap's per-leaf updateNode() would give (paper Sec. III-E map, OctoMap semantics).

#include <octomap/OcTree.h>

#include "occupancy/free_space_grid.h"

namespace objmap::occupancy_internal {

/// Thread-safety: none (it is an OcTree).
class BatchOcTree : public octomap::OcTree {
 public:
  explicit BatchOcTree(double resolution_m) : octomap::OcTree(resolution_m) {}

  /// Adds the miss log-odds to every voxel set in `free_space` (each once). Nodes on the visited
  /// paths are pruned or get their inner occupancy refreshed, as non-lazy updateNode() does.
  void ApplyFreeSpace(const FreeSpaceGrid& free_space);

 private:
  void Visit(octomap::OcTreeNode* node, int depth, const VoxelKey& base, bool full, bool fresh,
             const FreeSpaceGrid& free_space);
};

}  // namespace objmap::occupancy_internal
