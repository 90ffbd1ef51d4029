// The segmentation's fast paths against the straightforward references of
// reference_segmentation.h: same inputs, same answer.
#include <gtest/gtest.h>

#include <random>

#include "pointcloud_io/pointcloud_io.h"
#include "segmentation/mosd_ground_truth.h"
#include "segmentation/reference_segmentation.h"
#include "segmentation/segment_index.h"
#include "segmentation/segmenter.h"
#include "segmentation/synthetic_scene.h"
#include "test_data.h"

namespace objmap {
namespace {

// Boxes of every kind: random ones (some reaching past the image), tiny ones, the whole image.
std::vector<BoundingBox2D> TestBoxes(int width, int height, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-40.f, width + 40.f);
  std::uniform_real_distribution<float> v(-40.f, height + 40.f);
  std::uniform_real_distribution<float> size(2.f, 300.f);
  std::vector<BoundingBox2D> boxes = {
      {0.f, 0.f, static_cast<float>(width), static_cast<float>(height)}, {10.f, 10.f, 11.f, 11.f}};
  for (int k = 0; k < count; ++k) {
    const float x = u(rng), y = v(rng);
    boxes.push_back({x, y, x + size(rng), y + size(rng)});
  }
  return boxes;
}

void ExpectSameDetectionPixels(const SegmentationResult& segmentation,
                               const OrganizedCloud& cloud_C,
                               const std::vector<BoundingBox2D>& boxes) {
  const SegmentIndex index = IndexSegments(segmentation, cloud_C);
  DetectionSegmentConfig config;
  int non_empty = 0;
  for (const BoundingBox2D& box : boxes) {
    for (float min_inside : {0.6f, 0.3f}) {
      config.min_inside_fraction = min_inside;
      const std::vector<int> expected =
          reference::SelectDetectionPixels(segmentation, cloud_C, box, config);
      EXPECT_EQ(SelectDetectionPixels(segmentation, index, box, config), expected)
          << "box " << box.x_min << " " << box.y_min << " " << box.x_max << " " << box.y_max;
      EXPECT_EQ(SelectDetectionPixels(segmentation, cloud_C, box, config), expected);
      non_empty += expected.empty() ? 0 : 1;
    }
  }
  EXPECT_GT(non_empty, 0) << "no box selected anything: the comparison proves nothing";
}

TEST(SegmentIndexTest, HoldsEverySegmentsPixelsInOrder) {
  const testing::SyntheticScene scene = testing::MakeTableWithTwoBoxes();
  const SegmentationResult seg = Segmenter(SegmenterConfig()).Segment(scene.cloud_C);
  const SegmentIndex index = IndexSegments(seg, scene.cloud_C);
  ASSERT_TRUE(index.Matches(seg));
  for (int s = 0; s < seg.num_segments; ++s) {
    std::vector<int> expected;
    for (int i = 0; i < static_cast<int>(seg.labels.size()); ++i) {
      if (seg.labels[i] == s) expected.push_back(i);
    }
    const std::vector<int> indexed(index.pixel_ids.begin() + index.offsets[s],
                                   index.pixel_ids.begin() + index.offsets[s + 1]);
    EXPECT_EQ(indexed, expected) << "segment " << s;
    EXPECT_EQ(index.segments[s].pixels, static_cast<int>(expected.size()));
  }
  SegmentationResult other = seg;
  other.num_segments += 1;
  EXPECT_FALSE(index.Matches(other));
}

TEST(DetectionPixelsFastPathTest, SameAsReferenceOnSyntheticScene) {
  const testing::SyntheticScene scene = testing::MakeTableWithTwoBoxes();
  const SegmentationResult seg = Segmenter(SegmenterConfig()).Segment(scene.cloud_C);
  ExpectSameDetectionPixels(seg, scene.cloud_C,
                            TestBoxes(scene.cloud_C.width, scene.cloud_C.height, 200, 3));
}

TEST(DetectionPixelsFastPathTest, SameAsReferenceOnMosdClouds) {
  const std::string folder = testing::SharedDataPath("mosd-learn");
  OBJMAP_REQUIRE_PATH(folder + "/learn0.pcd");
  const std::vector<std::string> paths = testing::MosdCloudPaths(folder);
  for (size_t k = 0; k < paths.size(); k += 4) {
    OrganizedCloud cloud;
    std::string why;
    ASSERT_TRUE(LoadOrganizedPcd(paths[k], &cloud, nullptr, &why)) << why;
    const SegmentationResult seg = Segmenter(SegmenterConfig()).Segment(cloud);
    ExpectSameDetectionPixels(seg, cloud, TestBoxes(cloud.width, cloud.height, 60, 11 + k));
  }
}

}  // namespace
}  // namespace objmap
