#include "occupancy/batch_octree.h"

namespace objmap::occupancy_internal {
void BatchOcTree::ApplyScan(const FreeSpaceGrid& free_space,
                            const std::vector<std::uint64_t>& occupied) {
  const VoxelKey root_key = {0, 0, 0};
  const BlockState root_state = free_space.State(0, root_key);
  if (root_state == BlockState::kEmpty && occupied.empty()) return;
  const bool fresh = root == nullptr;
  if (fresh) {
    root = new octomap::OcTreeNode();
    ++tree_size;
  }
  Visit(root, 0, root_key, root_state == BlockState::kFull, fresh, free_space, occupied.begin(),
        occupied.end());
  size_changed = true;
}

// `node` covers the cube of 2^(16 - depth) voxels starting at `base`; the scan saw all of it
// free (`full`) or part of it, and [occupied_begin, occupied_end) are the occupied voxels in it.
// `fresh` nodes were just created for unknown space, so having no children means "unknown
// below", not "pruned block".
void BatchOcTree::Visit(octomap::OcTreeNode* node, int depth, const VoxelKey& base, bool full,
                        bool fresh, const FreeSpaceGrid& free_space, CodeIterator occupied_begin,
                        CodeIterator occupied_end) {
  const bool has_occupied = occupied_begin != occupied_end;
  if (depth == kTreeDepth) {
    updateNodeLogOdds(node, has_occupied ? prob_hit_log : prob_miss_log);
    return;
  }
  const bool leaf = !nodeHasChildren(node);
  if (leaf && full && !has_occupied) {
    updateNodeLogOdds(node, prob_miss_log);
    return;
  }
  if (leaf && !fresh) expandNode(node);  // a pruned block partly seen: split it first
  const int half = 1 << (kTreeDepth - 1 - depth);
  const int child_shift = 3 * (kTreeDepth - 1 - depth);  // the child's bits in a Morton code
  CodeIterator child_begin = occupied_begin;
  for (unsigned int c = 0; c < 8; ++c) {
    CodeIterator child_end = child_begin;
    while (child_end != occupied_end && ((*child_end >> child_shift) & 7u) == c) ++child_end;
    const VoxelKey child_base = ChildKey(base, c, half);
    const BlockState state = full ? BlockState::kFull : free_space.State(depth + 1, child_base);
    if (state != BlockState::kEmpty || child_begin != child_end) {
      const bool child_fresh = !nodeChildExists(node, c);
      octomap::OcTreeNode* child = child_fresh ? createNodeChild(node, c) : getNodeChild(node, c);
      Visit(child, depth + 1, child_base, state == BlockState::kFull, child_fresh, free_space,
            child_begin, child_end);
    }
    child_begin = child_end;
  }
  if (!pruneNode(node)) node->updateOccupancyChildren();
}

void BatchOcTree::ClearRegion(const FreeSpaceGrid& region) {
  if (root == nullptr) return;
  if (ClearVisit(root, 0, {0, 0, 0}, region)) clear();
  size_changed = true;
}

bool BatchOcTree::ClearVisit(octomap::OcTreeNode* node, int depth, const VoxelKey& base,
                             const FreeSpaceGrid& region) {
  const int size = 1 << (kTreeDepth - depth);
  const BlockState overlap = region.State(depth, base);
  if (overlap == BlockState::kEmpty) return false;
  if (overlap == BlockState::kFull) {
    if (nodeHasChildren(node)) CollapseToLeaf(node);
    return true;
  }
  // Partly inside, so bigger than a voxel. A pruned block splits into its eight children first.
  if (!nodeHasChildren(node)) expandNode(node);
  const int half = size / 2;
  for (unsigned int c = 0; c < 8; ++c) {
    if (!nodeChildExists(node, c)) continue;
    if (ClearVisit(getNodeChild(node, c), depth + 1, ChildKey(base, c, half), region)) {
      deleteNodeChild(node, c);
    }
  }
  if (nodeHasChildren(node)) {
    node->updateOccupancyChildren();
    return false;
  }
  // Without children an inner node would read as a known leaf: it goes too.
  CollapseToLeaf(node);
  return true;
}

// OctoMap frees a node's child array only when pruning, and deleting a node that still holds one
// would leak it: so the subtree is filled up to eight equal leaves per node and pruned bottom-up.
void BatchOcTree::CollapseToLeaf(octomap::OcTreeNode* node) {
  for (unsigned int c = 0; c < 8; ++c) {
    if (!nodeChildExists(node, c)) {
      createNodeChild(node, c);
    } else if (nodeHasChildren(getNodeChild(node, c))) {
      CollapseToLeaf(getNodeChild(node, c));
    }
    getNodeChild(node, c)->setLogOdds(0.f);
  }
  pruneNode(node);
}

}  // namespace objmap::occupancy_internal
