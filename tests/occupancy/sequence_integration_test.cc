// IntegrateSequence (rays cast on several threads) and RegenerateRegions (rebuilding only where
// moved keyframes see) against integrating every scan in order: the same log-odds in every voxel.

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "occupancy/occupancy_map.h"
#include "occupancy/rendered_scans.h"

namespace objmap {
namespace {

using testing::CameraSetup;
using testing::Pose;
using testing::Render;
using testing::TreeOf;

// Every known voxel with its log-odds, pruned blocks expanded, in key order.
std::vector<std::pair<std::uint64_t, float>> LeafValues(const OccupancyMap& map) {
  const octomap::OcTree tree = TreeOf(map);
  std::vector<std::pair<std::uint64_t, float>> values;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const unsigned size = 1u << (tree.getTreeDepth() - it.getDepth());
    const octomap::OcTreeKey key = it.getKey();
    const unsigned mask = ~(size - 1u);
    for (std::uint64_t x = key[0] & mask; x < (key[0] & mask) + size; ++x) {
      for (std::uint64_t y = key[1] & mask; y < (key[1] & mask) + size; ++y) {
        for (std::uint64_t z = key[2] & mask; z < (key[2] & mask) + size; ++z) {
          values.emplace_back((x << 32) | (y << 16) | z, it->getLogOdds());
        }
      }
    }
  }
  std::sort(values.begin(), values.end());
  return values;
}

// Where the two maps differ: voxels known in one only, or with other log-odds.
std::size_t CountDifferences(const OccupancyMap& a, const OccupancyMap& b, std::size_t* known) {
  const auto va = LeafValues(a), vb = LeafValues(b);
  std::size_t i = 0, j = 0, differences = 0;
  *known = 0;
  while (i < va.size() || j < vb.size()) {
    ++*known;
    if (j == vb.size() || (i < va.size() && va[i].first < vb[j].first)) {
      ++differences;
      ++i;
    } else if (i == va.size() || vb[j].first < va[i].first) {
      ++differences;
      ++j;
    } else {
      differences += va[i].second != vb[j].second ? 1 : 0;
      ++i;
      ++j;
    }
  }
  return differences;
}

// A walk through the room: eight keyframes, overlapping.
std::vector<DepthScanW> Walk() {
  std::vector<DepthScanW> scans;
  for (int k = 0; k < 8; ++k) {
    CameraSetup camera;
    camera.T_W_C =
        Pose({-0.8f + 0.2f * static_cast<float>(k), -0.5f + 0.1f * static_cast<float>(k), 0.35f},
             0.6f - 0.15f * static_cast<float>(k), 0.3f, 0.f);
    scans.push_back(Render(camera));
  }
  return scans;
}

TEST(SequenceIntegration, TwoThreadsGiveTheMapOfOneScanAfterTheOther) {
  const std::vector<DepthScanW> scans = Walk();
  OccupancyConfig config;
  OccupancyMap one_by_one(config), sequence(config);
  for (const DepthScanW& scan : scans) one_by_one.Integrate(scan);
  sequence.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 2);
  std::size_t known = 0;
  EXPECT_EQ(CountDifferences(one_by_one, sequence, &known), 0u);
  EXPECT_GT(known, 300000u);
}

// Keyframes 5 and 6 get corrected poses; the regions are where their rays reach before and
// after, and the sequence holds every keyframe reaching into them.
TEST(SequenceIntegration, RegeneratingWhereMovedKeyframesSeeEqualsRebuildingAll) {
  std::vector<DepthScanW> scans = Walk();
  OccupancyConfig config;
  OccupancyMap map(config);
  map.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 2);
  const double margin_m = 2.0 * config.resolution_m;
  std::vector<Eigen::AlignedBox3d> reach_C;
  for (const DepthScanW& scan : scans) reach_C.push_back(ReachInCameraFrame(scan, margin_m));
  std::vector<Eigen::AlignedBox3d> regions;
  for (std::size_t moved : {std::size_t{5}, std::size_t{6}}) {
    regions.push_back(ReachInWorld(reach_C[moved], scans[moved].T_W_C.cast<double>()));
    Eigen::Isometry3f correction = Eigen::Isometry3f::Identity();
    correction.translation() = Eigen::Vector3f(0.031f, -0.017f, 0.008f);
    correction.linear() = Eigen::AngleAxisf(0.02f, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    scans[moved].T_W_C = correction * scans[moved].T_W_C;
    regions.push_back(ReachInWorld(reach_C[moved], scans[moved].T_W_C.cast<double>()));
  }
  std::vector<std::size_t> reaching;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Eigen::AlignedBox3d reach = ReachInWorld(reach_C[i], scans[i].T_W_C.cast<double>());
    for (const Eigen::AlignedBox3d& region : regions) {
      if (reach.intersects(region)) {
        reaching.push_back(i);
        break;
      }
    }
  }
  OccupancyMap rebuilt(config);
  rebuilt.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 1);
  OccupancyMap before = map.Clone();
  map.RegenerateRegions(
      regions, reaching.size(), [&](std::size_t i) { return scans[reaching[i]]; }, 2);
  std::size_t known = 0;
  EXPECT_EQ(CountDifferences(map, rebuilt, &known), 0u);
  EXPECT_GT(known, 300000u);
  // The correction changed the map (the comparison above is not between two unchanged maps).
  EXPECT_GT(CountDifferences(before, rebuilt, &known), 1000u);
}

TEST(SequenceIntegration, RegeneratingARegionLeavesTheRestAlone) {
  const std::vector<DepthScanW> scans = Walk();
  OccupancyConfig config;
  OccupancyMap map(config);
  map.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 1);
  const OccupancyMap before = map.Clone();
  // A box of 40 cm by the table, rebuilt from no scans at all: it becomes unknown, nothing else
  // changes.
  const Eigen::AlignedBox3d box(Eigen::Vector3d(0.6, -0.2, -0.3), Eigen::Vector3d(1.0, 0.2, 0.1));
  map.RegenerateRegions(
      {box}, 0, [&scans](std::size_t i) { return scans[i]; }, 1);
  std::size_t changed = 0, unchanged = 0, known_after_in_box = 0;
  const auto after_values = LeafValues(map), before_values = LeafValues(before);
  std::size_t j = 0;
  const double res = config.resolution_m;
  // The voxels the closed box touches.
  auto touched = [&](std::uint64_t key, int axis) {
    return static_cast<double>(key) >= std::floor(box.min()[axis] / res) + 32768.0 &&
           static_cast<double>(key) <= std::floor(box.max()[axis] / res) + 32768.0;
  };
  for (const auto& [packed, value] : before_values) {
    const bool in_box = touched((packed >> 32) & 0xFFFF, 0) &&
                        touched((packed >> 16) & 0xFFFF, 1) && touched(packed & 0xFFFF, 2);
    while (j < after_values.size() && after_values[j].first < packed) ++j;
    const bool known_after = j < after_values.size() && after_values[j].first == packed;
    if (in_box) {
      known_after_in_box += known_after ? 1 : 0;
    } else if (known_after && after_values[j].second == value) {
      ++unchanged;
    } else {
      ++changed;
    }
  }
  EXPECT_EQ(known_after_in_box, 0u);
  EXPECT_EQ(changed, 0u);
  EXPECT_GT(unchanged, 100000u);
  EXPECT_LT(after_values.size(), before_values.size());  // the box held known voxels
}

TEST(SequenceIntegration, CloneIsADeepCopy) {
  const std::vector<DepthScanW> scans = Walk();
  OccupancyMap map{OccupancyConfig{}};
  map.Integrate(scans[0]);
  OccupancyMap copy = map.Clone();
  map.Integrate(scans[1]);
  std::size_t known = 0;
  OccupancyMap only_first{OccupancyConfig{}};
  only_first.Integrate(scans[0]);
  EXPECT_EQ(CountDifferences(copy, only_first, &known), 0u);
  EXPECT_GT(CountDifferences(copy, map, &known), 0u);
}

}  // namespace
}  // namespace objmap
