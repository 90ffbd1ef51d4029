#pragma once
// Voxel-by-voxel comparison of two OctoMap trees at leaf resolution (pruned nodes expanded),
// used to check the objmap integration against stock OcTree::insertPointCloud.

#include <octomap/OcTree.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace objmap::testing {

/// Every known leaf voxel as (packed key << 1 | occupied), sorted.
inline std::vector<std::uint64_t> ExpandLeaves(const octomap::OcTree& tree) {
  std::vector<std::uint64_t> voxels;
  const unsigned depth_max = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const unsigned size = 1u << (depth_max - it.getDepth());
    const octomap::OcTreeKey key = it.getKey();
    const std::uint64_t occupied = tree.isNodeOccupied(*it) ? 1 : 0;
    const unsigned mask = ~(size - 1u);
    const std::uint64_t x0 = key[0] & mask, y0 = key[1] & mask, z0 = key[2] & mask;
    for (std::uint64_t x = x0; x < x0 + size; ++x) {
      for (std::uint64_t y = y0; y < y0 + size; ++y) {
        for (std::uint64_t z = z0; z < z0 + size; ++z) {
          voxels.push_back((((x << 32) | (y << 16) | z) << 1) | occupied);
        }
      }
    }
  }
  std::sort(voxels.begin(), voxels.end());
  return voxels;
}

struct LeafComparison {
  std::size_t known_in_either = 0;  ///< voxels known (free or occupied) in at least one tree
  std::size_t agree = 0;            ///< known in both with the same state
  std::size_t only_a = 0;           ///< known in a, unknown in b
  std::size_t only_b = 0;           ///< known in b, unknown in a
  std::size_t state_differs = 0;    ///< known in both, free in one and occupied in the other

  [[nodiscard]] double Agreement() const {
    return known_in_either == 0 ? 1.0 : static_cast<double>(agree) / known_in_either;
  }
};

inline LeafComparison CompareTrees(const octomap::OcTree& a, const octomap::OcTree& b) {
  const std::vector<std::uint64_t> va = ExpandLeaves(a), vb = ExpandLeaves(b);
  LeafComparison result;
  std::size_t i = 0, j = 0;
  while (i < va.size() || j < vb.size()) {
    ++result.known_in_either;
    if (j == vb.size() || (i < va.size() && (va[i] >> 1) < (vb[j] >> 1))) {
      ++result.only_a;
      ++i;
    } else if (i == va.size() || (vb[j] >> 1) < (va[i] >> 1)) {
      ++result.only_b;
      ++j;
    } else {
      (va[i] == vb[j] ? result.agree : result.state_differs)++;
      ++i;
      ++j;
    }
  }
  return result;
}

}  // namespace objmap::testing
