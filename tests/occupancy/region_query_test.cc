// OccupancyMap::QueryRegion, CastRay and BinaryBytes on a small map: a 40 cm wall 50 cm in front
// of two nearby camera centres. Expected values come from per-leaf Query() calls and from
// OctoMap's own reader, never from the code under test.

#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <tuple>

#include "occupancy/occupancy_map.h"
#include "occupancy/octree_compare.h"

namespace objmap {
namespace {

using Vec3d = Eigen::Vector3d;
using CellIndex = std::tuple<std::int64_t, std::int64_t, std::int64_t>;

constexpr double kLeaf = 0.01;
constexpr double kWallX = 0.505;  // a voxel centre, so wall points sit inside one voxel layer

// Points every 5 mm, offset from the grid lines to avoid ties on cell borders.
ScanW WallScan(const Eigen::Vector3f& origin_W, double half_extent_m) {
  ScanW scan;
  scan.origin_W = origin_W;
  for (double y = -half_extent_m; y <= half_extent_m + 1e-9; y += 0.005) {
    for (double z = -half_extent_m; z <= half_extent_m + 1e-9; z += 0.005) {
      scan.structure_points_W.emplace_back(kWallX, y + 0.0025, z + 0.0025);
    }
  }
  return scan;
}

OccupancyMap WallMap() {
  OccupancyConfig config;
  config.resolution_m = kLeaf;
  config.structure_margin_m = 0.0;  // stock carving, which the expected counts assume
  config.structure_margin_per_m2 = 0.0;
  OccupancyMap map(config);
  map.Integrate(WallScan(Eigen::Vector3f(0.0f, 0.0f, 0.0f), 0.2));
  map.Integrate(WallScan(Eigen::Vector3f(0.0f, 0.02f, 0.01f), 0.2));
  return map;
}

std::int64_t CellOf(double coordinate_m, double cell_m) {
  return static_cast<std::int64_t>(std::floor(coordinate_m / cell_m + 1e-9));
}

// Truth per coarse cell from its leaves: occupied if any leaf is, free if any is known.
struct CellTruth {
  std::size_t occupied = 0, free = 0, unknown = 0;
  std::map<CellIndex, VoxelState> known;
};

VoxelState CellState(const OccupancyMap& map, const CellIndex& cell, int leaves_per_cell) {
  VoxelState state = VoxelState::kUnknown;
  const auto [cx, cy, cz] = cell;
  for (int i = 0; i < leaves_per_cell; ++i) {
    for (int j = 0; j < leaves_per_cell; ++j) {
      for (int k = 0; k < leaves_per_cell; ++k) {
        const Vec3d leaf_centre_W((cx * leaves_per_cell + i + 0.5) * kLeaf,
                                  (cy * leaves_per_cell + j + 0.5) * kLeaf,
                                  (cz * leaves_per_cell + k + 0.5) * kLeaf);
        const VoxelState leaf = map.Query(leaf_centre_W);
        if (leaf == VoxelState::kOccupied) return leaf;
        if (leaf == VoxelState::kFree) state = leaf;
      }
    }
  }
  return state;
}

CellTruth EvaluateCells(const OccupancyMap& map, const Vec3d& min_W, const Vec3d& max_W,
                        int leaves_per_cell) {
  const double cell_m = kLeaf * leaves_per_cell;
  CellTruth truth;
  for (std::int64_t x = CellOf(min_W.x(), cell_m); x <= CellOf(max_W.x(), cell_m); ++x) {
    for (std::int64_t y = CellOf(min_W.y(), cell_m); y <= CellOf(max_W.y(), cell_m); ++y) {
      for (std::int64_t z = CellOf(min_W.z(), cell_m); z <= CellOf(max_W.z(), cell_m); ++z) {
        const VoxelState state = CellState(map, {x, y, z}, leaves_per_cell);
        if (state == VoxelState::kUnknown) {
          ++truth.unknown;
          continue;
        }
        (state == VoxelState::kOccupied ? truth.occupied : truth.free)++;
        truth.known[{x, y, z}] = state;
      }
    }
  }
  return truth;
}

std::size_t Total(const RegionOccupancy& region) {
  return region.occupied + region.free + region.unknown;
}

void ExpectMatchesLeafQueries(const OccupancyMap& map, const Vec3d& min_W, const Vec3d& max_W,
                              double resolution_m, int leaves_per_cell) {
  const RegionOccupancy region = map.QueryRegion(min_W, max_W, resolution_m, 1000000);
  const CellTruth truth = EvaluateCells(map, min_W, max_W, leaves_per_cell);
  EXPECT_NEAR(region.resolution_m, kLeaf * leaves_per_cell, 1e-12);
  EXPECT_EQ(region.occupied, truth.occupied);
  EXPECT_EQ(region.free, truth.free);
  EXPECT_EQ(region.unknown, truth.unknown);
  EXPECT_FALSE(region.truncated);
  ASSERT_EQ(region.known_cells.size(), truth.known.size());
  const double cell_m = kLeaf * leaves_per_cell;
  for (const RegionOccupancy::Cell& cell : region.known_cells) {
    const CellIndex index{CellOf(cell.center_W.x() - cell_m / 2, cell_m),
                          CellOf(cell.center_W.y() - cell_m / 2, cell_m),
                          CellOf(cell.center_W.z() - cell_m / 2, cell_m)};
    const auto it = truth.known.find(index);
    ASSERT_NE(it, truth.known.end()) << cell.center_W.transpose();
    EXPECT_EQ(cell.state, it->second) << cell.center_W.transpose();
  }
}

TEST(RegionQuery, BoxBetweenOriginAndWallIsFree) {
  const OccupancyMap map = WallMap();
  // 10 x 4 x 4 leaves, all crossed by many rays of both scans.
  const RegionOccupancy region =
      map.QueryRegion(Vec3d(0.205, -0.015, -0.015), Vec3d(0.295, 0.015, 0.015), 0.0, 0);
  EXPECT_EQ(Total(region), 10u * 4u * 4u);
  EXPECT_EQ(region.free, Total(region));
  EXPECT_EQ(region.occupied, 0u);
  EXPECT_EQ(region.unknown, 0u);
  EXPECT_TRUE(region.known_cells.empty());
}

TEST(RegionQuery, BoxAroundWallHasOccupiedCells) {
  const OccupancyMap map = WallMap();
  const Vec3d min_W(0.455, -0.095, -0.095), max_W(0.555, 0.095, 0.095);
  const RegionOccupancy region = map.QueryRegion(min_W, max_W, kLeaf, 0);
  EXPECT_GT(region.occupied, 0u);
  EXPECT_GT(region.free, 0u);
  EXPECT_GT(region.unknown, 0u);  // behind the wall
  EXPECT_EQ(Total(region), 11u * 20u * 20u);
}

TEST(RegionQuery, BoxBehindWallIsUnknown) {
  const OccupancyMap map = WallMap();
  const RegionOccupancy region =
      map.QueryRegion(Vec3d(1.0, -0.2, -0.2), Vec3d(1.2, 0.2, 0.2), 0.04, 100);
  EXPECT_EQ(region.occupied + region.free, 0u);
  EXPECT_GT(region.unknown, 0u);
  EXPECT_TRUE(region.known_cells.empty());
  EXPECT_FALSE(region.truncated);
}

TEST(RegionQuery, PointBoxTouchesOneCell) {
  const OccupancyMap map = WallMap();
  const Vec3d point_W(0.253, 0.001, 0.002);
  for (double resolution_m : {0.0, 0.01, 0.04, 0.32}) {
    const RegionOccupancy region = map.QueryRegion(point_W, point_W, resolution_m, 10);
    EXPECT_EQ(Total(region), 1u) << resolution_m;
    EXPECT_EQ(region.free, 1u) << resolution_m;
    ASSERT_EQ(region.known_cells.size(), 1u);
    EXPECT_LE((region.known_cells[0].center_W - point_W).cwiseAbs().maxCoeff(),
              region.resolution_m / 2 + 1e-9);
  }
}

TEST(RegionQuery, CoarseCellsMatchLeafQueries) {
  const OccupancyMap map = WallMap();
  const Vec3d min_W(0.305, -0.245, -0.245), max_W(0.655, 0.245, 0.245);
  ExpectMatchesLeafQueries(map, min_W, max_W, 0.04, 4);
  ExpectMatchesLeafQueries(map, min_W, max_W, 0.03, 4);  // rounded up to leaf * 4
  ExpectMatchesLeafQueries(map, min_W, max_W, 0.08, 8);
}

TEST(RegionQuery, LeafCellsInPrunedFreeSpaceMatchLeafQueries) {
  const OccupancyMap map = WallMap();
  // Near the camera, the free space of both scans is pruned into nodes larger than a leaf.
  ExpectMatchesLeafQueries(map, Vec3d(0.003, -0.047, -0.047), Vec3d(0.197, 0.047, 0.047), 0.0, 1);
  ExpectMatchesLeafQueries(map, Vec3d(0.003, -0.047, -0.047), Vec3d(0.197, 0.047, 0.047), 0.02, 2);
}

TEST(RegionQuery, HugeBoxCountsWholeMapFromKnownNodes) {
  const OccupancyMap map = WallMap();
  const RegionOccupancy region =
      map.QueryRegion(Vec3d(-50.003, -50.003, -50.003), Vec3d(50.003, 50.003, 50.003), 0.0, 0);
  const OccupancyCounts counts = map.Counts();
  EXPECT_EQ(region.occupied, counts.occupied);
  EXPECT_EQ(region.free, counts.free);
  EXPECT_EQ(Total(region), std::size_t{10002} * 10002 * 10002);
}

TEST(RegionQuery, ListingStopsAtTheLimit) {
  const OccupancyMap map = WallMap();
  const Vec3d min_W(0.305, -0.1, -0.1), max_W(0.555, 0.1, 0.1);
  const RegionOccupancy all = map.QueryRegion(min_W, max_W, 0.02, 1000000);
  ASSERT_GT(all.occupied + all.free, 5u);
  EXPECT_EQ(all.known_cells.size(), all.occupied + all.free);
  EXPECT_FALSE(all.truncated);
  const RegionOccupancy few = map.QueryRegion(min_W, max_W, 0.02, 5);
  EXPECT_EQ(few.known_cells.size(), 5u);
  EXPECT_TRUE(few.truncated);
  EXPECT_EQ(few.occupied, all.occupied);
  EXPECT_EQ(few.free, all.free);
  const RegionOccupancy exact = map.QueryRegion(min_W, max_W, 0.02, all.known_cells.size());
  EXPECT_FALSE(exact.truncated);
}

TEST(RegionQuery, EmptyOrInvalidBoxCountsNothing) {
  const OccupancyMap map = WallMap();
  EXPECT_EQ(Total(map.QueryRegion(Vec3d(1, 0, 0), Vec3d(0, 1, 1), 0.0, 0)), 0u);
  EXPECT_EQ(Total(map.QueryRegion(Vec3d(1e6, 0, 0), Vec3d(2e6, 1, 1), 0.0, 0)), 0u);
  EXPECT_EQ(Total(map.QueryRegion(Vec3d(NAN, 0, 0), Vec3d(1, 1, 1), 0.0, 0)), 0u);
}

TEST(CastRay, HitsTheWallAndNothingElse) {
  const OccupancyMap map = WallMap();
  const Vec3d origin_W(0.005, 0.005, 0.005);
  const RayHit wall = map.CastRay(origin_W, Vec3d(2.0, 0.0, 0.0), 2.0, false);
  ASSERT_TRUE(wall.hit);
  EXPECT_EQ(wall.state, VoxelState::kOccupied);
  EXPECT_NEAR(wall.distance_m, kWallX - origin_W.x(), kLeaf);
  EXPECT_EQ(map.Query(wall.voxel_center_W), VoxelState::kOccupied);
  // Same wall when free space before it must be crossed and unknown space would stop the ray.
  const RayHit stopping = map.CastRay(origin_W, Vec3d(1.0, 0.0, 0.0), 2.0, true);
  ASSERT_TRUE(stopping.hit);
  EXPECT_EQ(stopping.state, VoxelState::kOccupied);
  EXPECT_TRUE(stopping.voxel_center_W.isApprox(wall.voxel_center_W));

  EXPECT_FALSE(map.CastRay(origin_W, Vec3d(-1.0, 0.0, 0.0), 2.0, false).hit);
  EXPECT_FALSE(map.CastRay(origin_W, Vec3d(1.0, 0.0, 0.0), 0.3, false).hit);
  EXPECT_FALSE(map.CastRay(origin_W, Vec3d::Zero(), 2.0, false).hit);
}

TEST(CastRay, UnknownStopsAtTheEndOfTheFreeSpace) {
  const OccupancyMap map = WallMap();
  // Sideways through the free cone (|y| <= ~0.12 m at x = 0.3 m), away from the wall.
  const Vec3d origin_W(0.305, 0.005, 0.005), direction_W(0.0, 1.0, 0.0);
  const RayHit hit = map.CastRay(origin_W, direction_W, 1.0, true);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.state, VoxelState::kUnknown);
  EXPECT_EQ(map.Query(hit.voxel_center_W), VoxelState::kUnknown);
  EXPECT_GT(hit.distance_m, 0.05);
  EXPECT_LT(hit.distance_m, 0.2);
  for (double t = 0.0; t < hit.distance_m - 0.6 * kLeaf; t += 0.002) {
    EXPECT_EQ(map.Query(origin_W + t * direction_W), VoxelState::kFree) << t;
  }
  EXPECT_FALSE(map.CastRay(origin_W, direction_W, 1.0, false).hit);
}

TEST(CastRay, OriginInsideOccupiedVoxelHitsAtOnce) {
  const OccupancyMap map = WallMap();
  const Vec3d origin_W(kWallX + 0.001, 0.005, 0.005);
  ASSERT_EQ(map.Query(origin_W), VoxelState::kOccupied);
  const RayHit hit = map.CastRay(origin_W, Vec3d(-1.0, 0.0, 0.0), 1.0, false);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.state, VoxelState::kOccupied);
  EXPECT_LE(hit.distance_m, std::sqrt(3.0) * kLeaf / 2);
}

octomap::OcTree ReadBytes(const std::string& bytes) {
  octomap::OcTree tree(kLeaf);
  std::istringstream in(bytes);
  EXPECT_TRUE(tree.readBinary(in));
  return tree;
}

VoxelState StateIn(const octomap::OcTree& tree, const Vec3d& point_W) {
  const octomap::OcTreeNode* node = tree.search(point_W.x(), point_W.y(), point_W.z());
  if (node == nullptr) return VoxelState::kUnknown;
  return tree.isNodeOccupied(node) ? VoxelState::kOccupied : VoxelState::kFree;
}

// Every leaf of `part` touches the box and agrees with `map`; every known voxel of `map` in the
// box is in `part`. Returns how many leaves of `part` are coarser than a voxel.
std::size_t ExpectRegionCopy(const OccupancyMap& map, const octomap::OcTree& part,
                             const Vec3d& min_W, const Vec3d& max_W) {
  const octomap::OcTreeKey lo = part.coordToKey(min_W.x(), min_W.y(), min_W.z());
  const octomap::OcTreeKey hi = part.coordToKey(max_W.x(), max_W.y(), max_W.z());
  std::size_t coarse = 0;
  for (auto it = part.begin_leafs(), end = part.end_leafs(); it != end; ++it) {
    const unsigned size = 1u << (part.getTreeDepth() - it.getDepth());
    const octomap::OcTreeKey key = it.getKey();
    for (int i = 0; i < 3; ++i) {
      const unsigned first = key[i] & ~(size - 1u);
      EXPECT_TRUE(first <= hi[i] && first + size - 1 >= lo[i]) << "leaf outside the box";
    }
    const Vec3d centre_W(it.getX(), it.getY(), it.getZ());
    EXPECT_EQ(map.Query(centre_W),
              part.isNodeOccupied(*it) ? VoxelState::kOccupied : VoxelState::kFree);
    if (size > 1) ++coarse;
  }
  for (unsigned x = lo[0]; x <= hi[0]; ++x) {
    for (unsigned y = lo[1]; y <= hi[1]; ++y) {
      for (unsigned z = lo[2]; z <= hi[2]; ++z) {
        const octomap::point3d c = part.keyToCoord(octomap::OcTreeKey(x, y, z));
        const Vec3d centre_W(c.x(), c.y(), c.z());
        EXPECT_EQ(StateIn(part, centre_W), map.Query(centre_W)) << centre_W.transpose();
      }
    }
  }
  return coarse;
}

TEST(BinaryBytes, RegionAroundWallRoundTrips) {
  const OccupancyMap map = WallMap();
  const Vec3d min_W(0.455, -0.095, -0.095), max_W(0.555, 0.095, 0.095);
  std::size_t leaf_count = 0;
  const std::string bytes = map.BinaryBytes(true, min_W, max_W, &leaf_count);
  const octomap::OcTree part = ReadBytes(bytes);
  EXPECT_GT(leaf_count, 0u);
  EXPECT_EQ(part.getNumLeafNodes(), leaf_count);
  ExpectRegionCopy(map, part, min_W, max_W);
}

TEST(BinaryBytes, RegionKeepsPrunedFreeSpaceWhole) {
  const OccupancyMap map = WallMap();
  const Vec3d min_W(0.103, -0.033, -0.033), max_W(0.197, 0.033, 0.033);
  std::size_t leaf_count = 0;
  const octomap::OcTree part = ReadBytes(map.BinaryBytes(true, min_W, max_W, &leaf_count));
  EXPECT_EQ(part.getNumLeafNodes(), leaf_count);
  EXPECT_GT(ExpectRegionCopy(map, part, min_W, max_W), 0u) << "no pruned node in the region";
}

TEST(BinaryBytes, RegionWithoutKnownSpaceIsAnEmptyMap) {
  const OccupancyMap map = WallMap();
  std::size_t leaf_count = 1;
  const octomap::OcTree part =
      ReadBytes(map.BinaryBytes(true, Vec3d(3, 3, 3), Vec3d(4, 4, 4), &leaf_count));
  EXPECT_EQ(leaf_count, 0u);
  EXPECT_EQ(part.size(), 0u);
}

TEST(BinaryBytes, WholeMapEqualsTheWrittenFile) {
  const OccupancyMap map = WallMap();
  std::size_t leaf_count = 0;
  const octomap::OcTree from_bytes =
      ReadBytes(map.BinaryBytes(false, Vec3d::Zero(), Vec3d::Zero(), &leaf_count));
  const std::string path = ::testing::TempDir() +
                           "/objmap_region_query_WholeMapEqualsTheWrittenFile_" +
                           std::to_string(::getpid()) + ".bt";
  std::string why;
  ASSERT_TRUE(map.WriteBinary(path, &why)) << why;
  octomap::OcTree from_file(kLeaf);
  ASSERT_TRUE(from_file.readBinary(path));
  std::remove(path.c_str());
  EXPECT_EQ(from_bytes.getNumLeafNodes(), leaf_count);
  const testing::LeafComparison comparison = testing::CompareTrees(from_bytes, from_file);
  EXPECT_GT(comparison.known_in_either, 0u);
  EXPECT_EQ(comparison.agree, comparison.known_in_either);
  const OccupancyCounts counts = map.Counts();
  EXPECT_EQ(comparison.known_in_either, counts.occupied + counts.free);
}

}  // namespace
}  // namespace objmap
