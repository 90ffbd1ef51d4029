// VoxelDownsample's flat table against VoxelModel (same means and colours, one point per voxel in
// the order of first arrival) and colour rounding against std::lround.
#include "objects/voxel_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

namespace objmap {
namespace {

// Points over few voxels (several per voxel), one NaN, colours when asked.
ColoredPoints RandomPoints(int count, bool with_colors, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coordinate(-0.04f, 0.06f);
  std::uniform_int_distribution<int> channel(0, 255);
  ColoredPoints points;
  for (int k = 0; k < count; ++k) {
    points.points.emplace_back(coordinate(rng), coordinate(rng), 1.f + coordinate(rng));
    if (with_colors) {
      points.colors.push_back({static_cast<std::uint8_t>(channel(rng)),
                               static_cast<std::uint8_t>(channel(rng)),
                               static_cast<std::uint8_t>(channel(rng))});
    }
  }
  points.points[count / 2].x() = std::numeric_limits<float>::quiet_NaN();
  return points;
}

using Voxel = std::tuple<long, long, long>;

Voxel VoxelOf(const Eigen::Vector3f& p, float size_m) {
  return {static_cast<long>(std::floor(p.x() / size_m)),
          static_cast<long>(std::floor(p.y() / size_m)),
          static_cast<long>(std::floor(p.z() / size_m))};
}

// Point (x, y, z bits) and colour, for comparing two outputs as sets.
std::vector<std::tuple<float, float, float, std::array<std::uint8_t, 3>>> Sorted(
    const ColoredPoints& points) {
  std::vector<std::tuple<float, float, float, std::array<std::uint8_t, 3>>> out;
  for (std::size_t k = 0; k < points.size(); ++k) {
    out.emplace_back(points.points[k].x(), points.points[k].y(), points.points[k].z(),
                     points.colors.empty() ? std::array<std::uint8_t, 3>{} : points.colors[k]);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Points in raster order 1 mm apart, as a segment's pixels arrive: runs share a voxel.
ColoredPoints RasterPoints(int count) {
  ColoredPoints points;
  for (int k = 0; k < count; ++k) {
    points.points.emplace_back(0.001f * static_cast<float>(k % 97),
                               0.001f * static_cast<float>(k / 97), 1.f);
    points.colors.push_back({static_cast<std::uint8_t>(k % 256), 7, 9});
  }
  return points;
}

TEST(VoxelDownsampleTest, SameMeansAsVoxelModelInOrderOfFirstArrival) {
  constexpr float kVoxelM = 0.005f;
  for (bool with_colors : {false, true}) {
    for (int count : {1, 50, 5000, 60000, -5000}) {
      SCOPED_TRACE(std::to_string(count) + (with_colors ? " coloured" : "") + " points");
      ColoredPoints points =
          count > 0 ? RandomPoints(count, with_colors, 17 + count) : RasterPoints(-count);
      if (!with_colors) points.colors.clear();
      const ColoredPoints downsampled = VoxelDownsample(points, kVoxelM);
      VoxelModel model(kVoxelM);
      model.Insert(points);
      ColoredPoints expected = model.Points();
      if (!with_colors) expected.colors.clear();
      EXPECT_EQ(downsampled.colors.size(), with_colors ? downsampled.size() : 0u);
      EXPECT_EQ(Sorted(downsampled), Sorted(expected));
      std::vector<Voxel> first_arrival;
      std::map<Voxel, int> seen;
      for (const Eigen::Vector3f& p : points.points) {
        if (p.allFinite() && seen.emplace(VoxelOf(p, kVoxelM), 0).second) {
          first_arrival.push_back(VoxelOf(p, kVoxelM));
        }
      }
      ASSERT_EQ(downsampled.size(), first_arrival.size());
      for (std::size_t k = 0; k < first_arrival.size(); ++k) {
        ASSERT_EQ(VoxelOf(downsampled.points[k], kVoxelM), first_arrival[k]) << "voxel " << k;
      }
    }
  }
}

TEST(VoxelModelTest, MeanColoursRoundLikeLround) {
  constexpr float kVoxelM = 0.005f;
  const ColoredPoints points = RandomPoints(20000, true, 3);
  std::map<Voxel, std::pair<Eigen::Vector3d, int>> sums;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points.points[i].allFinite()) continue;
    auto& [rgb, count] = sums[VoxelOf(points.points[i], kVoxelM)];
    if (count == 0) rgb.setZero();
    rgb += Eigen::Vector3d(points.colors[i][0], points.colors[i][1], points.colors[i][2]);
    ++count;
  }
  VoxelModel model(kVoxelM);
  model.Insert(points);
  for (const ColoredPoints& out : {model.Points(), VoxelDownsample(points, kVoxelM)}) {
    ASSERT_EQ(out.size(), sums.size());
    for (std::size_t k = 0; k < out.size(); ++k) {
      const auto& [rgb, count] = sums.at(VoxelOf(out.points[k], kVoxelM));
      const Eigen::Vector3d mean = rgb * (1.0 / count);
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(out.colors[k][c], std::lround(mean[c])) << "voxel " << k << " channel " << c;
      }
    }
  }
}

}  // namespace
}  // namespace objmap

namespace objmap {
namespace {

ColoredPoints Points(std::initializer_list<Eigen::Vector3f> list) {
  ColoredPoints points;
  points.points = list;
  return points;
}

TEST(VoxelModelViews, AVoxelCountsEachViewOnceAndThePublishedPointsNeedTwo) {
  VoxelModel model(0.01f);
  const Eigen::Vector3f surface(0.105f, 0.205f, 1.005f), stray(0.5f, 0.5f, 1.5f);
  // View 3 inserts the surface twice (two frames a few millimetres apart) and a stray point once;
  // view 4 sees the surface again. Two views reached the surface voxel, one the stray one.
  model.Insert(Points({surface}), 3);
  model.Insert(Points({surface, stray}), 3);
  model.Insert(Points({surface}), 4);
  EXPECT_EQ(model.size(), 2u);
  EXPECT_EQ(model.CountSeen(2), 1u);
  const ColoredPoints published = model.Points(2);
  ASSERT_EQ(published.size(), 1u);
  EXPECT_TRUE(published.points[0].isApprox(surface));
  EXPECT_EQ(model.Points().size(), 2u) << "every voxel without a minimum";
  // Without views every insertion is a view of its own.
  VoxelModel unviewed(0.01f);
  unviewed.Insert(Points({surface}));
  unviewed.Insert(Points({surface, stray}));
  EXPECT_EQ(unviewed.CountSeen(2), 1u);
  EXPECT_EQ(unviewed.CountSeen(3), 0u);
  // A merged model adds the views of the other.
  model.Insert(unviewed);
  EXPECT_EQ(model.CountSeen(3), 1u);
  EXPECT_EQ(model.CountSeen(2), 2u) << "the stray voxel: once in each model";
}

}  // namespace
}  // namespace objmap
