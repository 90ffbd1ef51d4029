#include "occupancy/batch_octree.h"

namespace objmap::occupancy_internal {

void BatchOcTree::ApplyFreeSpace(const FreeSpaceGrid& free_space) {
  const VoxelKey root_key = {0, 0, 0};
  const BlockState root_state = free_space.State(0, root_key);
  if (root_state == BlockState::kEmpty) return;
  const bool fresh = root == nullptr;
  if (fresh) {
    root = new octomap::OcTreeNode();
    ++tree_size;
  }
  Visit(root, 0, root_key, root_state == BlockState::kFull, fresh, free_space);
  size_changed = true;
}

// `node` covers the cube of 2^(16 - depth) voxels starting at `base`; the scan saw all of it
// free (`full`) or part of it. `fresh` nodes were just created for unknown space, so having no
// children means "unknown below", not "pruned block".
void BatchOcTree::Visit(octomap::OcTreeNode* node, int depth, const VoxelKey& base, bool full,
                        bool fresh, const FreeSpaceGrid& free_space) {
  const bool leaf = !nodeHasChildren(node);
  if (leaf && (full || depth == kTreeDepth)) {
    updateNodeLogOdds(node, prob_miss_log);
    return;
  }
  if (leaf && !fresh) expandNode(node);  // a pruned block partly seen: split it first
  const int half = 1 << (kTreeDepth - 1 - depth);
  for (unsigned int c = 0; c < 8; ++c) {
    const VoxelKey child_base = {static_cast<std::uint16_t>(base[0] + ((c & 1) ? half : 0)),
                                 static_cast<std::uint16_t>(base[1] + ((c & 2) ? half : 0)),
                                 static_cast<std::uint16_t>(base[2] + ((c & 4) ? half : 0))};
    const BlockState state = full ? BlockState::kFull : free_space.State(depth + 1, child_base);
    if (state == BlockState::kEmpty) continue;
    const bool child_fresh = !nodeChildExists(node, c);
    octomap::OcTreeNode* child = child_fresh ? createNodeChild(node, c) : getNodeChild(node, c);
    Visit(child, depth + 1, child_base, state == BlockState::kFull, child_fresh, free_space);
  }
  if (!pruneNode(node)) node->updateOccupancyChildren();
}

}  // namespace objmap::occupancy_internal
