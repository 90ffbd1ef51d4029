// An observation's points made from a keyframe's depth as stored (millimetres) and the pixels
// it took: what the store rebuilds them from.

#include "objects/observation_segment.h"

#include <gtest/gtest.h>

#include <cmath>

#include "types/organized_cloud.h"

namespace objmap {
namespace {

TEST(PixelRuns, RunsOfSortsJoinsAndDropsRepeatsAndNegatives) {
  const PixelRuns runs = RunsOf({7, 3, 4, 5, 5, 9, -2, 10, 11, 100});
  const PixelRuns expected = {{3, 3}, {7, 1}, {9, 3}, {100, 1}};
  EXPECT_EQ(runs, expected);
  EXPECT_EQ(PixelCount(runs), 8u);
  EXPECT_TRUE(RunsOf({}).empty());
}

TEST(DepthSample, MillimetresRoundAndMarkWhatHasNoDepth) {
  EXPECT_EQ(DepthSampleMillimetres(1.2344f), 1234);
  EXPECT_EQ(DepthSampleMillimetres(1.2346f), 1235);
  EXPECT_EQ(DepthSampleMillimetres(0.f), 0);
  EXPECT_EQ(DepthSampleMillimetres(-1.f), 0);
  EXPECT_EQ(DepthSampleMillimetres(NAN), 0);
  EXPECT_EQ(DepthSampleMillimetres(70.f), 0);
  // Every kept sample converts back to itself.
  for (int mm = 1; mm < 65000; mm += 7) {
    const auto kept = static_cast<std::uint16_t>(mm);
    EXPECT_EQ(DepthSampleMillimetres(DepthSampleMetres(kept)), kept);
  }
}

// For a frame whose depth is whole millimetres, the points are the organized cloud's at those
// pixels, in ascending pixel order, voxel-downsampled: what the mapper had before keeping pixels.
TEST(SegmentPointsFromDepth, IsTheDownsampledCloudOfThePixelsWithDepth) {
  CameraIntrinsics K;
  K.width = 40;
  K.height = 30;
  K.fx = 50.5;
  K.fy = 49.75;
  K.cx = 19.25;
  K.cy = 15.5;
  std::vector<std::uint16_t> depth_mm(40 * 30);
  DepthImage depth;
  depth.width = 40;
  depth.height = 30;
  ColorImage color;
  color.width = 40;
  color.height = 30;
  for (std::size_t i = 0; i < depth_mm.size(); ++i) {
    depth_mm[i] = i % 13 == 0 ? 0 : static_cast<std::uint16_t>(800 + (i * 31) % 700);
    depth.depth_m.push_back(DepthSampleMetres(depth_mm[i]));
    color.rgb.insert(color.rgb.end(),
                     {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(2 * i),
                      static_cast<std::uint8_t>(255 - i)});
  }
  const OrganizedCloud cloud = BackProject(depth, color, K);
  std::vector<int> pixels;
  for (int v = 5; v < 20; ++v) {
    for (int u = 30; u >= 8; --u) pixels.push_back(v * 40 + u);  // any order
  }
  const PixelRuns runs = RunsOf(pixels);
  ColoredPoints expected_input;
  for (const PixelRun& run : runs) {
    for (std::uint32_t i = run.start; i < run.start + run.length; ++i) {
      if (!cloud.IsValid(static_cast<int>(i))) continue;
      expected_input.points.push_back(cloud.points_C[i]);
      expected_input.colors.push_back(cloud.rgb[i]);
    }
  }
  const ColoredPoints expected = VoxelDownsample(expected_input, 0.01f);
  const ColoredPoints points = SegmentPointsFromDepth(depth_mm, K, runs, 0.01f, &cloud.rgb);
  ASSERT_GT(points.size(), 50u);
  EXPECT_EQ(points.points, expected.points);
  EXPECT_EQ(points.colors, expected.colors);
  const ColoredPoints without_color = SegmentPointsFromDepth(depth_mm, K, runs, 0.01f, nullptr);
  EXPECT_EQ(without_color.points, expected.points);
  EXPECT_TRUE(without_color.colors.empty());
  // Runs past the image end are cut, not read.
  const ColoredPoints beyond = SegmentPointsFromDepth(depth_mm, K, {{1190, 50}}, 0.01f, nullptr);
  EXPECT_LE(beyond.size(), 10u);
}

}  // namespace
}  // namespace objmap
