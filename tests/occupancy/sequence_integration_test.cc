// IntegrateSequence (rays cast on several threads) and RegenerateWhereReached (rebuilding only
// where moved keyframes see) against integrating every scan in order: the same log-odds in every
// voxel.

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

// Keyframes 5 and 6 get corrected poses: the map is rebuilt where they reach, before and after,
// from the keyframes whose reach boxes meet theirs.
TEST(SequenceIntegration, RegeneratingWhereMovedKeyframesReachEqualsRebuildingAll) {
  std::vector<DepthScanW> scans = Walk();
  OccupancyConfig config;
  OccupancyMap map(config);
  map.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 2);
  std::vector<DepthScanW> changed;
  for (std::size_t moved : {std::size_t{5}, std::size_t{6}}) {
    changed.push_back(scans[moved]);
    Eigen::Isometry3f correction = Eigen::Isometry3f::Identity();
    correction.translation() = Eigen::Vector3f(0.031f, -0.017f, 0.008f);
    correction.linear() = Eigen::AngleAxisf(0.02f, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    scans[moved].T_W_C = correction * scans[moved].T_W_C;
    changed.push_back(scans[moved]);
  }
  OccupancyMap rebuilt(config);
  rebuilt.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 1);
  OccupancyMap before = map.Clone();
  const std::size_t rebuilt_voxels = map.RegenerateWhereReached(
      changed, scans.size(), [&](std::size_t i) { return scans[i]; }, 2);
  std::size_t known = 0;
  EXPECT_EQ(CountDifferences(map, rebuilt, &known), 0u);
  EXPECT_GT(known, 300000u);
  EXPECT_GT(rebuilt_voxels, 10000u);
  // The correction changed the map (the comparison above is not between two unchanged maps).
  EXPECT_GT(CountDifferences(before, rebuilt, &known), 1000u);
}

// The space one scan reaches, rebuilt from no scans at all, becomes unknown; the rest of the
// map keeps every value.
TEST(SequenceIntegration, RegeneratingLeavesTheSpaceOutsideAlone) {
  const std::vector<DepthScanW> scans = Walk();
  OccupancyConfig config;
  OccupancyMap map(config), first_only(config);
  map.IntegrateSequence(
      scans.size(), [&scans](std::size_t i) { return scans[i]; }, 1);
  first_only.Integrate(scans[0]);
  const OccupancyMap before = map.Clone();
  const std::size_t cleared = map.RegenerateWhereReached(
      {scans[7]}, 0, [&scans](std::size_t i) { return scans[i]; }, 1);
  EXPECT_GT(cleared, 100000u);
  const auto after_values = LeafValues(map), before_values = LeafValues(before);
  EXPECT_LT(after_values.size(), before_values.size());
  // What stays known kept its value exactly.
  std::size_t j = 0, kept = 0;
  for (const auto& [packed, value] : after_values) {
    while (j < before_values.size() && before_values[j].first < packed) ++j;
    ASSERT_LT(j, before_values.size());
    ASSERT_EQ(before_values[j].first, packed) << "no voxel becomes known";
    EXPECT_EQ(before_values[j].second, value);
    ++kept;
  }
  EXPECT_GT(kept, 100000u);
  // Nothing that scan 7 can reach is left: every voxel it marks in a map of its own is unknown.
  OccupancyMap seventh(config);
  seventh.Integrate(scans[7]);
  std::size_t reached_but_known = 0;
  const auto seventh_values = LeafValues(seventh);
  std::size_t k = 0;
  for (const auto& [packed, value] : seventh_values) {
    while (k < after_values.size() && after_values[k].first < packed) ++k;
    if (k < after_values.size() && after_values[k].first == packed) ++reached_but_known;
  }
  EXPECT_EQ(reached_but_known, 0u);
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
