// Segmentation of a synthetic table-top scene (paper Sec. III-B) and detection-box selection.
#include "segmentation/segmenter.h"

#include <gtest/gtest.h>

#include <map>

#include "segmentation/segmentation_internal.h"
#include "synthetic_scene.h"

namespace objmap {
namespace {

using testing::MakeTableWithTwoBoxes;
using testing::SyntheticScene;

// Pixels per (ground-truth owner, predicted segment).
std::map<std::pair<int, int>, int> Overlaps(const SyntheticScene& scene,
                                            const SegmentationResult& result) {
  std::map<std::pair<int, int>, int> overlaps;
  for (size_t i = 0; i < scene.owner.size(); ++i) {
    if (scene.owner[i] >= 0) overlaps[{scene.owner[i], result.labels[i]}]++;
  }
  return overlaps;
}

// The predicted segment holding most of `owner`'s pixels and the share it holds.
std::pair<int, double> DominantSegment(const std::map<std::pair<int, int>, int>& overlaps,
                                       int owner) {
  int best = -1, best_count = 0, total = 0;
  for (const auto& [key, count] : overlaps) {
    if (key.first != owner) continue;
    total += count;
    if (count > best_count) best = key.second, best_count = count;
  }
  return {best, total > 0 ? static_cast<double>(best_count) / total : 0.0};
}

class SyntheticSegmentationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = MakeTableWithTwoBoxes();
    result_ = Segmenter(SegmenterConfig()).Segment(scene_.cloud_C);
  }
  SyntheticScene scene_;
  SegmentationResult result_;
};

TEST(SegmenterConfigTest, DefaultsAreValidAndBadFieldsAreNamed) {
  std::string why;
  EXPECT_TRUE(SegmenterConfig().IsValid(&why)) << why;
  SegmenterConfig bad;
  bad.cell_px = 0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("cell_px"), std::string::npos) << why;
  DetectionSegmentConfig bad_detection;
  bad_detection.min_inside_fraction = 1.5f;
  EXPECT_FALSE(bad_detection.IsValid(&why));
  EXPECT_NE(why.find("min_inside_fraction"), std::string::npos) << why;
}

TEST_F(SyntheticSegmentationTest, OnePlaneAndTwoObjects) {
  ASSERT_EQ(result_.labels.size(), scene_.owner.size());
  ASSERT_EQ(result_.segment_is_plane.size(), static_cast<size_t>(result_.num_segments));
  for (size_t i = 0; i < scene_.owner.size(); ++i) {
    ASSERT_EQ(result_.labels[i] >= 0, scene_.owner[i] >= 0) << "validity differs at " << i;
  }
  const auto overlaps = Overlaps(scene_, result_);
  const auto [table, table_share] = DominantSegment(overlaps, 0);
  const auto [box1, box1_share] = DominantSegment(overlaps, 1);
  const auto [box2, box2_share] = DominantSegment(overlaps, 2);
  EXPECT_TRUE(result_.segment_is_plane[table]);
  EXPECT_FALSE(result_.segment_is_plane[box1]);
  EXPECT_FALSE(result_.segment_is_plane[box2]);
  EXPECT_NE(box1, box2);
  EXPECT_NE(box1, table);
  EXPECT_NE(box2, table);
  EXPECT_GT(table_share, 0.97);
  EXPECT_GT(box1_share, 0.9);
  EXPECT_GT(box2_share, 0.9);
  int plane_segments = 0;
  for (bool is_plane : result_.segment_is_plane) plane_segments += is_plane ? 1 : 0;
  EXPECT_EQ(plane_segments, 1);
}

TEST_F(SyntheticSegmentationTest, DetectionBoxSelectsOnlyItsObject) {
  for (int target = 1; target <= 2; ++target) {
    BoundingBox2D box{1e9f, 1e9f, -1e9f, -1e9f};
    int target_pixels = 0;
    for (size_t i = 0; i < scene_.owner.size(); ++i) {
      if (scene_.owner[i] != target) continue;
      const float u = static_cast<float>(i % scene_.cloud_C.width);
      const float v = static_cast<float>(i / scene_.cloud_C.width);
      box = {std::min(box.x_min, u), std::min(box.y_min, v), std::max(box.x_max, u),
             std::max(box.y_max, v)};
      ++target_pixels;
    }
    // Shift the box as an unregistered colour camera would.
    box.x_min += 12.f, box.x_max += 12.f, box.y_min -= 8.f, box.y_max -= 8.f;
    const std::vector<int> pixels =
        SelectDetectionPixels(result_, scene_.cloud_C, box, DetectionSegmentConfig());
    int on_target = 0;
    for (int i : pixels) on_target += scene_.owner[i] == target ? 1 : 0;
    SCOPED_TRACE("box " + std::to_string(target));
    EXPECT_GT(on_target, 0.9 * target_pixels);
    EXPECT_GT(on_target, 0.95 * static_cast<double>(pixels.size()));
  }
}

TEST_F(SyntheticSegmentationTest, BoxOnEmptyTableSelectsNothing) {
  const BoundingBox2D box{20.f, 400.f, 120.f, 470.f};  // bottom-left: table only
  EXPECT_TRUE(
      SelectDetectionPixels(result_, scene_.cloud_C, box, DetectionSegmentConfig()).empty());
}

seg::Supervoxel Patch(float x, float z, float normal_x) {
  seg::Supervoxel sv;
  sv.pixels = 64;
  sv.centroid = Eigen::Vector3f(x, 0.f, z);
  sv.normal = Eigen::Vector3f(normal_x, 0.f, -std::sqrt(1.f - normal_x * normal_x));
  sv.has_normal = true;
  return sv;
}

TEST(EdgeWeightTest, PaperWeightsWithConvexitySign) {
  // Two patches 30 degrees off the viewing axis (n_i.n_j = 0.5). A ridge pointing at the camera
  // (normals turned outwards) is convex: (1 - 0.5)^2; a valley is concave: 1 - 0.5.
  const seg::Supervoxel ridge_left = Patch(-0.05f, 1.0f, -0.5f);
  const seg::Supervoxel ridge_right = Patch(0.05f, 1.0f, 0.5f);
  EXPECT_NEAR(seg::EdgeWeight(ridge_left, ridge_right, 0.05f), 0.25f, 1e-4f);
  const seg::Supervoxel valley_left = Patch(-0.05f, 1.0f, 0.5f);
  const seg::Supervoxel valley_right = Patch(0.05f, 1.0f, -0.5f);
  EXPECT_NEAR(seg::EdgeWeight(valley_left, valley_right, 0.05f), 0.5f, 1e-4f);
  seg::Supervoxel on_plane = ridge_left, on_same_plane = ridge_right, on_other_plane = ridge_right;
  on_plane.plane = on_same_plane.plane = 0;
  on_other_plane.plane = 1;
  EXPECT_EQ(seg::EdgeWeight(on_plane, on_same_plane, 0.05f), 0.f);
  EXPECT_EQ(seg::EdgeWeight(on_plane, on_other_plane, 0.05f), 1.f);
  EXPECT_EQ(seg::EdgeWeight(on_plane, ridge_right, 0.05f), 1.f);
}

TEST(SegmenterTest, DegenerateInputGivesNoSegments) {
  OrganizedCloud empty;
  const SegmentationResult result = Segmenter(SegmenterConfig()).Segment(empty);
  EXPECT_EQ(result.num_segments, 0);
  OrganizedCloud all_invalid;
  all_invalid.width = 16;
  all_invalid.height = 8;
  all_invalid.points_C.assign(128, Eigen::Vector3f::Constant(std::nanf("")));
  const SegmentationResult none = Segmenter(SegmenterConfig()).Segment(all_invalid);
  EXPECT_EQ(none.num_segments, 0);
  EXPECT_EQ(none.labels, std::vector<std::int32_t>(128, -1));
}

}  // namespace
}  // namespace objmap
