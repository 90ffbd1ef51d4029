#include <gtest/gtest.h>
#include <unistd.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <string>
#include <tuple>

#include "occupancy/occupancy_map.h"
#include "occupancy/octree_compare.h"

namespace objmap {
namespace {

using Vec3d = Eigen::Vector3d;

// Stock OctoMap semantics, which most tests here pin down: rays carve up to their endpoint.
OccupancyConfig TestConfig() {
  OccupancyConfig config;
  config.resolution_m = 0.01;
  config.max_range_m = 4.0;
  config.structure_margin_m = 0.0;
  config.structure_margin_per_m2 = 0.0;
  return config;
}

// Voxel centres are at (k + 0.5) cm; points 5 mm off the grid lines avoid ties on cell borders.
ScanW WallScan(double x_m, double half_extent_m) {
  ScanW scan;
  for (double y = -half_extent_m; y <= half_extent_m + 1e-9; y += 0.005) {
    for (double z = -half_extent_m; z <= half_extent_m + 1e-9; z += 0.005) {
      scan.structure_points_W.emplace_back(x_m, y + 0.0025, z + 0.0025);
    }
  }
  return scan;
}

TEST(OccupancyConfig, IsValidNamesTheBadField) {
  std::string why;
  EXPECT_TRUE(OccupancyConfig{}.IsValid(&why));
  OccupancyConfig config;
  config.resolution_m = 0.0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("resolution_m"), std::string::npos);
  config = OccupancyConfig{};
  config.probability_miss = 0.7;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("probability_miss"), std::string::npos);
  config = OccupancyConfig{};
  config.structure_margin_per_m2 = -0.1;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("structure_margin"), std::string::npos);
  config = OccupancyConfig{};
  config.object_margin_voxels = -1;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("object_margin_voxels"), std::string::npos);
}

TEST(OccupancyMap, SingleRayFreeAlongOccupiedAtEndUnknownElsewhere) {
  OccupancyMap map(TestConfig());
  ScanW scan;
  scan.structure_points_W.emplace_back(0.505f, 0.005f, 0.005f);
  map.Integrate(scan);
  EXPECT_EQ(map.Query(Vec3d(0.505, 0.005, 0.005)), VoxelState::kOccupied);
  for (double x = 0.005; x < 0.5; x += 0.01) {
    EXPECT_EQ(map.Query(Vec3d(x, 0.005, 0.005)), VoxelState::kFree) << "x=" << x;
  }
  EXPECT_EQ(map.Query(Vec3d(0.515, 0.005, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Query(Vec3d(1.0, 0.005, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Query(Vec3d(0.25, 0.015, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Query(Vec3d(0.25, 0.005, -0.005)), VoxelState::kUnknown);
  const OccupancyCounts counts = map.Counts();
  EXPECT_EQ(counts.occupied, 1u);
  EXPECT_EQ(counts.free, 50u);  // voxels 0..49 along +x, the endpoint's voxel 50 is occupied
  EXPECT_EQ(map.last_stats().rays, 1u);
}

TEST(OccupancyMap, WallIsOccupiedAndTheSpaceBeforeItFree) {
  OccupancyMap map(TestConfig());
  const ScanW scan = WallScan(2.005, 0.3);
  map.Integrate(scan);
  std::set<std::tuple<int, int, int>> wall_voxels;
  for (const Eigen::Vector3f& p : scan.structure_points_W) {
    EXPECT_EQ(map.Query(p.cast<double>()), VoxelState::kOccupied);
    wall_voxels.emplace(std::floor(p.x() / 0.01), std::floor(p.y() / 0.01),
                        std::floor(p.z() / 0.01));
    for (double f : {0.1, 0.5, 0.9, 0.99}) {
      EXPECT_EQ(map.Query(p.cast<double>() * f), VoxelState::kFree) << "f=" << f;
    }
    EXPECT_EQ(map.Query(p.cast<double>() * 1.02), VoxelState::kUnknown);
  }
  EXPECT_EQ(map.Counts().occupied, wall_voxels.size());
  EXPECT_GT(map.Counts().free, 100000u);
}

// A wall 2 m away seen four times with depth noise: each time three of four points lie 1.5 cm
// behind it (a quantization step can do that to a whole patch). Carving up to those endpoints
// erases the wall voxels the other points marked; rays that stop short by the noise margin
// leave the wall whole and still carve the space before it.
TEST(OccupancyMap, TheStructureMarginKeepsNoisySurfacesFromBeingCarved) {
  auto noisy_wall = [](int shift) {
    ScanW scan;
    for (int iy = -20; iy < 20; ++iy) {
      for (int iz = -20; iz < 20; ++iz) {
        const bool behind = ((iy + iz + 40 + shift) % 4) != 0;
        scan.structure_points_W.emplace_back(2.005f + (behind ? 0.015f : 0.f), 0.01f * iy + 0.005f,
                                             0.01f * iz + 0.005f);
      }
    }
    return scan;
  };
  auto wall_voxels_occupied = [](const OccupancyMap& map) {
    int occupied = 0;
    for (int iy = -20; iy < 20; ++iy) {
      for (int iz = -20; iz < 20; ++iz) {
        occupied +=
            map.Query({2.005, 0.01 * iy + 0.005, 0.01 * iz + 0.005}) == VoxelState::kOccupied;
      }
    }
    return occupied;
  };
  OccupancyMap stock(TestConfig());
  OccupancyConfig with_margin_config = TestConfig();
  with_margin_config.structure_margin_m = 0.01;
  with_margin_config.structure_margin_per_m2 = 0.005;  // 3 cm at 2 m
  OccupancyMap with_margin(with_margin_config);
  for (int shift = 0; shift < 4; ++shift) {
    stock.Integrate(noisy_wall(shift));
    with_margin.Integrate(noisy_wall(shift));
  }
  EXPECT_EQ(wall_voxels_occupied(with_margin), 1600);
  EXPECT_LT(wall_voxels_occupied(stock), 1600) << "carved by the rays to the points behind";
  EXPECT_EQ(with_margin.Query({1.9, 0.005, 0.005}), VoxelState::kFree);
  EXPECT_EQ(with_margin.Query({1.985, 0.005, 0.005}), VoxelState::kUnknown) << "inside the margin";
}

TEST(OccupancyMap, PreparedScanLeavesTheTreeAloneUntilApplied) {
  OccupancyMap whole(TestConfig()), in_steps(TestConfig());
  const ScanW first = WallScan(2.005, 0.3), second = WallScan(1.505, 0.2);
  whole.Integrate(first);
  whole.Integrate(second);
  in_steps.Integrate(first);
  const OccupancyCounts before = in_steps.Counts();
  in_steps.PrepareScan(second);
  // Casting the rays does not touch the OcTree, which readers may be reading meanwhile.
  EXPECT_EQ(in_steps.Counts().occupied, before.occupied);
  EXPECT_EQ(in_steps.Counts().free, before.free);
  in_steps.ApplyPreparedScan();
  EXPECT_EQ(in_steps.Counts().occupied, whole.Counts().occupied);
  EXPECT_EQ(in_steps.Counts().free, whole.Counts().free);
  EXPECT_NE(in_steps.Counts().occupied, before.occupied);
}

TEST(OccupancyMap, StateRoundTripContinuesAsTheOriginal) {
  OccupancyMap original(TestConfig());
  original.Integrate(WallScan(2.005, 0.3));
  OccupancyMap restored(TestConfig());
  std::string why;
  ASSERT_TRUE(restored.ReadState(original.WriteState(), &why)) << why;
  EXPECT_EQ(restored.BinaryBytes(false, {}, {}, nullptr),
            original.BinaryBytes(false, {}, {}, nullptr));
  // Log-odds, not only occupancy bits, came back: further scans give the same map.
  const ScanW again = WallScan(1.505, 0.2);
  original.Integrate(again);
  restored.Integrate(again);
  EXPECT_EQ(restored.WriteState(), original.WriteState());
  EXPECT_GT(restored.Counts().occupied, 0u);

  // An empty map round-trips too.
  OccupancyMap empty(TestConfig());
  ASSERT_TRUE(restored.ReadState(empty.WriteState(), &why)) << why;
  EXPECT_EQ(restored.Counts().occupied + restored.Counts().free, 0u);
}

TEST(OccupancyMap, CorruptOrForeignStateIsRefusedAndTheMapKept) {
  OccupancyMap original(TestConfig());
  original.Integrate(WallScan(2.005, 0.3));
  const std::string state = original.WriteState();
  OccupancyMap target(TestConfig());
  target.Integrate(WallScan(1.505, 0.2));
  const OccupancyCounts before = target.Counts();
  std::string flipped = state;
  flipped[flipped.size() / 2] ^= 0x10;
  std::string why;
  EXPECT_FALSE(target.ReadState(flipped, &why));
  EXPECT_NE(why.find("corrupt"), std::string::npos) << why;
  EXPECT_FALSE(target.ReadState(state.substr(0, state.size() - 100), &why));
  EXPECT_FALSE(target.ReadState("", &why));
  OccupancyConfig coarse = TestConfig();
  coarse.resolution_m = 0.02;
  OccupancyMap other_resolution(coarse);
  EXPECT_FALSE(other_resolution.ReadState(state, &why));
  EXPECT_NE(why.find("another resolution"), std::string::npos) << why;
  EXPECT_EQ(target.Counts().occupied, before.occupied);
  EXPECT_EQ(target.Counts().free, before.free);
}

TEST(OccupancyMap, MaxRangeTruncatesFreeSpaceAndDropsTheEndpoint) {
  OccupancyConfig config = TestConfig();
  config.max_range_m = 1.0;
  OccupancyMap map(config);
  ScanW scan;
  scan.structure_points_W.emplace_back(2.005f, 0.005f, 0.005f);
  map.Integrate(scan);
  EXPECT_EQ(map.Query(Vec3d(0.505, 0.005, 0.005)), VoxelState::kFree);
  EXPECT_EQ(map.Query(Vec3d(0.975, 0.005, 0.005)), VoxelState::kFree);
  EXPECT_EQ(map.Query(Vec3d(1.015, 0.005, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Query(Vec3d(1.5, 0.005, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Query(Vec3d(2.005, 0.005, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Counts().occupied, 0u);
  // Voxels from the origin up to the one holding the 1 m mark (excluded, as in OctoMap).
  EXPECT_NEAR(static_cast<double>(map.Counts().free), 100.0, 1.0);
}

TEST(OccupancyMap, ObjectPointsCarveButAreNotOccupied) {
  OccupancyMap map(TestConfig());
  ScanW scan;
  scan.object_points_W.emplace_back(1.005f, 0.005f, 0.005f);
  map.Integrate(scan);
  EXPECT_EQ(map.Query(Vec3d(0.505, 0.005, 0.005)), VoxelState::kFree);
  EXPECT_EQ(map.Query(Vec3d(1.005, 0.005, 0.005)), VoxelState::kUnknown);
  EXPECT_EQ(map.Query(Vec3d(0.995, 0.005, 0.005)), VoxelState::kUnknown);  // margin
  EXPECT_EQ(map.Query(Vec3d(0.985, 0.005, 0.005)), VoxelState::kUnknown);  // margin
  EXPECT_EQ(map.Counts().occupied, 0u);
}

TEST(OccupancyMap, ObjectInFrontOfAWallDoesNotEraseIt) {
  OccupancyMap map(TestConfig());
  const ScanW wall = WallScan(1.505, 0.2);
  map.Integrate(wall);
  const std::size_t wall_occupied = map.Counts().occupied;
  // An object lying against the wall, seen many times: its rays stop short of the wall.
  ScanW object;
  for (const Eigen::Vector3f& p : wall.structure_points_W) {
    object.object_points_W.push_back(p - Eigen::Vector3f(0.01f, 0.0f, 0.0f));
  }
  for (int i = 0; i < 10; ++i) map.Integrate(object);
  EXPECT_EQ(map.Counts().occupied, wall_occupied);
  for (const Eigen::Vector3f& p : wall.structure_points_W) {
    ASSERT_EQ(map.Query(p.cast<double>()), VoxelState::kOccupied);
  }
}

TEST(OccupancyMap, NonFinitePointsAreSkipped) {
  OccupancyMap map(TestConfig());
  ScanW scan;
  scan.structure_points_W.emplace_back(NAN, 0.0f, 1.0f);
  scan.structure_points_W.emplace_back(INFINITY, 0.0f, 1.0f);
  scan.object_points_W.emplace_back(0.0f, NAN, 1.0f);
  map.Integrate(scan);
  EXPECT_EQ(map.Counts().occupied + map.Counts().free, 0u);
  scan.origin_W = Eigen::Vector3f(NAN, 0.0f, 0.0f);
  scan.structure_points_W.assign(1, Eigen::Vector3f(0.5f, 0.0f, 0.0f));
  map.Integrate(scan);
  EXPECT_EQ(map.Counts().occupied + map.Counts().free, 0u);
}

// A few thousand points on three planes and a box, some beyond max range, seen from three
// origins, so later scans hit pruned blocks and earlier updates.
ScanW SyntheticScan(int seed, const Eigen::Vector3f& origin) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  ScanW scan;
  scan.origin_W = origin;
  for (int i = 0; i < 1500; ++i) {
    scan.structure_points_W.emplace_back(1.2f + 0.05f * u(rng), 0.6f * u(rng), 0.4f * u(rng));
    scan.structure_points_W.emplace_back(0.8f * u(rng) + 0.4f, 0.6f * u(rng), -0.45f);
  }
  for (int i = 0; i < 300; ++i) {  // beyond max range: free space only
    scan.structure_points_W.emplace_back(2.5f, 0.5f * u(rng), 0.3f * u(rng));
  }
  return scan;
}

// Integrates three synthetic scans into both maps and compares them voxel by voxel.
testing::LeafComparison CompareWithStock(const OccupancyConfig& config) {
  OccupancyMap map(config);
  octomap::OcTree stock(config.resolution_m);
  stock.setProbHit(config.probability_hit);
  stock.setProbMiss(config.probability_miss);
  stock.setClampingThresMin(config.clamping_min);
  stock.setClampingThresMax(config.clamping_max);
  const Eigen::Vector3f origins[] = {
      {0.013f, -0.021f, 0.037f}, {0.113f, 0.079f, -0.063f}, {0.013f, -0.021f, 0.037f}};
  for (int s = 0; s < 3; ++s) {
    const ScanW scan = SyntheticScan(7 + s, origins[s]);
    map.Integrate(scan);
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3f& p : scan.structure_points_W) cloud.push_back(p.x(), p.y(), p.z());
    stock.insertPointCloud(cloud, octomap::point3d(origins[s].x(), origins[s].y(), origins[s].z()),
                           config.max_range_m);
  }
  const std::string path = ::testing::TempDir() + "/objmap_occupancy_compare_" + std::to_string(::getpid()) + ".bt";
  std::string why;
  EXPECT_TRUE(map.WriteBinary(path, &why)) << why;
  octomap::OcTree ours(path);
  std::remove(path.c_str());
  const testing::LeafComparison cmp = testing::CompareTrees(ours, stock);
  std::printf("known voxels %zu, agree %zu, only ours %zu, only stock %zu, state differs %zu\n",
              cmp.known_in_either, cmp.agree, cmp.only_a, cmp.only_b, cmp.state_differs);
  return cmp;
}

TEST(OccupancyMap, MatchesStockInsertPointCloudVoxelForVoxel) {
  OccupancyConfig config = TestConfig();
  config.max_range_m = 1.5;  // the scans have points beyond it
  const testing::LeafComparison cmp = CompareWithStock(config);
  EXPECT_GT(cmp.known_in_either, 100000u);
  EXPECT_EQ(cmp.agree, cmp.known_in_either);  // the design is exact, not approximate
}

TEST(OccupancyMap, OneRayPerEndVoxelStaysCloseToStock) {
  OccupancyConfig config = TestConfig();
  config.max_range_m = 1.5;
  config.one_ray_per_end_voxel = true;
  const testing::LeafComparison cmp = CompareWithStock(config);
  EXPECT_GT(cmp.Agreement(), 0.98);
  EXPECT_EQ(cmp.only_a, 0u);  // it can only miss free voxels, never invent them
  EXPECT_EQ(cmp.state_differs, 0u);
}

TEST(OccupancyMap, WriteBinaryReadsBackWithTheSameCounts) {
  OccupancyMap map(TestConfig());
  map.Integrate(SyntheticScan(3, Eigen::Vector3f(0.0f, 0.0f, 0.0f)));
  const OccupancyCounts counts = map.Counts();
  ASSERT_GT(counts.occupied, 0u);
  const std::string path = ::testing::TempDir() + "/objmap_occupancy_roundtrip_" + std::to_string(::getpid()) + ".bt";
  std::string why;
  ASSERT_TRUE(map.WriteBinary(path, &why)) << why;
  octomap::OcTree read_back(path);
  std::size_t occupied = 0, free = 0;
  for (std::uint64_t v : testing::ExpandLeaves(read_back)) ((v & 1) ? occupied : free)++;
  EXPECT_EQ(occupied, counts.occupied);
  EXPECT_EQ(free, counts.free);
  EXPECT_DOUBLE_EQ(read_back.getResolution(), 0.01);
  std::remove(path.c_str());
  EXPECT_FALSE(map.WriteBinary("/nonexistent_dir/x.bt", &why));
  EXPECT_NE(why.find("/nonexistent_dir/x.bt"), std::string::npos);
  map.Clear();
  EXPECT_EQ(map.Counts().occupied + map.Counts().free, 0u);
}

TEST(OccupancyMap, ReadBinaryGivesTheWrittenMapAndRefusesOtherBytes) {
  OccupancyMap map(TestConfig());
  map.Integrate(WallScan(2.005, 0.3));
  const std::string bytes = map.BinaryBytes(false, Vec3d::Zero(), Vec3d::Zero(), nullptr);
  OccupancyMap read_back(TestConfig());
  std::string why;
  ASSERT_TRUE(read_back.ReadBinary(bytes, &why)) << why;
  EXPECT_EQ(read_back.Counts().occupied, map.Counts().occupied);
  EXPECT_EQ(read_back.Counts().free, map.Counts().free);
  EXPECT_EQ(read_back.Query({2.005, 0.0025, 0.0025}), VoxelState::kOccupied);

  EXPECT_FALSE(read_back.ReadBinary("not an octree", &why));
  EXPECT_NE(why.find("not an OctoMap binary"), std::string::npos) << why;
  OccupancyConfig coarse = TestConfig();
  coarse.resolution_m = 0.05;
  OccupancyMap other(coarse);
  EXPECT_FALSE(other.ReadBinary(bytes, &why));
  EXPECT_NE(why.find("resolution"), std::string::npos) << why;
  EXPECT_EQ(read_back.Counts().occupied, map.Counts().occupied) << "a refused file changes nothing";
}

TEST(OccupancyMap, OccupiedVoxelCentersAreTheOccupiedLeavesPrunedOnesExpanded) {
  OccupancyConfig config = TestConfig();
  config.clamping_max = 0.7;  // one hit saturates, so a solid block prunes into larger nodes
  OccupancyMap map(config);
  ScanW block;
  // A 4 cm solid cube of endpoints, aligned with the grid: prunes into 2 cm nodes.
  for (int x = 0; x < 8; ++x) {
    for (int y = 0; y < 8; ++y) {
      for (int z = 0; z < 8; ++z) {
        block.structure_points_W.emplace_back(1.0025f + 0.005f * x, 0.0025f + 0.005f * y,
                                              0.0025f + 0.005f * z);
      }
    }
  }
  map.Integrate(block);
  const std::vector<Vec3d> centers = map.OccupiedVoxelCenters();
  EXPECT_EQ(centers.size(), map.Counts().occupied);
  std::set<std::tuple<int, int, int>> distinct;
  for (const Vec3d& c : centers) {
    EXPECT_EQ(map.Query(c), VoxelState::kOccupied);
    distinct.emplace(std::lround(c.x() * 1000), std::lround(c.y() * 1000),
                     std::lround(c.z() * 1000));
  }
  EXPECT_EQ(distinct.size(), centers.size());
  EXPECT_GE(centers.size(), 64u) << "the 4 cm cube is 64 voxels, a few rays end inside it";
}

}  // namespace
}  // namespace objmap
