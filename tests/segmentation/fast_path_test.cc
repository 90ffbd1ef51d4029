// The segmentation's fast paths against the straightforward references of
// reference_segmentation.h: same inputs, same answer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "dataset/sequence_reader.h"
#include "pointcloud_io/pointcloud_io.h"
#include "segmentation/mosd_ground_truth.h"
#include "segmentation/reference_segmentation.h"
#include "segmentation/segment_index.h"
#include "segmentation/segmentation_internal.h"
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
    ASSERT_EQ(index.segments[s].pixels, static_cast<int>(expected.size()));
    double sum_z = 0.0;
    int u_min = seg.width, v_min = seg.height, u_max = -1, v_max = -1;
    for (int i : expected) {
      sum_z += scene.cloud_C.points_C[i].z();
      u_min = std::min(u_min, i % seg.width);
      u_max = std::max(u_max, i % seg.width);
      v_min = std::min(v_min, i / seg.width);
      v_max = std::max(v_max, i / seg.width);
    }
    EXPECT_EQ(index.segments[s].sum_z, sum_z) << "segment " << s;
    EXPECT_EQ(std::vector<int>({index.segments[s].u_min, index.segments[s].v_min,
                                index.segments[s].u_max, index.segments[s].v_max}),
              std::vector<int>({u_min, v_min, u_max, v_max}))
        << "segment " << s;
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

// Bit-for-bit: the fast steps must do the same float operations in the same order.
bool SameFloat(float a, float b) {
  return std::memcmp(&a, &b, sizeof(float)) == 0 || (std::isnan(a) && std::isnan(b));
}

bool SameVector(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return SameFloat(a.x(), b.x()) && SameFloat(a.y(), b.y()) && SameFloat(a.z(), b.z());
}

// Every step of the Segmenter against its reference, each fed the reference's previous output.
void ExpectSameSteps(const OrganizedCloud& cloud, const SegmenterConfig& config) {
  const std::vector<Eigen::Vector3f> normals =
      reference::ComputeNormals(cloud, config.normal_step_px, config.depth_jump_ratio);
  const std::vector<Eigen::Vector3f> fast_normals =
      seg::ComputeNormals(cloud, config.normal_step_px, config.depth_jump_ratio);
  ASSERT_EQ(fast_normals.size(), normals.size());
  int different_normals = 0;
  for (size_t i = 0; i < normals.size(); ++i) {
    different_normals += SameVector(fast_normals[i], normals[i]) ? 0 : 1;
  }
  EXPECT_EQ(different_normals, 0);

  const float focal_px = seg::EstimateFocalPx(cloud, 525.f);
  std::vector<std::int8_t> planes, fast_planes;
  const int found = reference::DetectSupportingPlanes(cloud, normals, config, focal_px, &planes);
  EXPECT_EQ(seg::DetectSupportingPlanes(cloud, normals, config, focal_px, &fast_planes), found);
  EXPECT_EQ(fast_planes, planes);

  std::vector<int> supervoxel_of_pixel, fast_supervoxel_of_pixel;
  std::vector<seg::Supervoxel> supervoxels, fast_supervoxels;
  reference::BuildSupervoxels(cloud, normals, planes, config, focal_px, &supervoxel_of_pixel,
                              &supervoxels);
  seg::BuildSupervoxels(cloud, normals, planes, config, focal_px, &fast_supervoxel_of_pixel,
                        &fast_supervoxels);
  EXPECT_EQ(fast_supervoxel_of_pixel, supervoxel_of_pixel);
  ASSERT_EQ(fast_supervoxels.size(), supervoxels.size());
  for (size_t s = 0; s < supervoxels.size(); ++s) {
    const seg::Supervoxel& a = fast_supervoxels[s];
    const seg::Supervoxel& b = supervoxels[s];
    ASSERT_TRUE(a.pixels == b.pixels && a.plane == b.plane && a.has_normal == b.has_normal &&
                SameVector(a.centroid, b.centroid) && SameVector(a.normal, b.normal) &&
                SameFloat(a.area_m2, b.area_m2))
        << "supervoxel " << s;
  }

  const std::vector<seg::GraphEdge> edges =
      reference::BuildAdjacencyGraph(cloud, supervoxel_of_pixel, supervoxels, config);
  const std::vector<seg::GraphEdge> fast_edges =
      seg::BuildAdjacencyGraph(cloud, supervoxel_of_pixel, supervoxels, config);
  ASSERT_EQ(fast_edges.size(), edges.size());
  for (size_t e = 0; e < edges.size(); ++e) {
    ASSERT_TRUE(fast_edges[e].a == edges[e].a && fast_edges[e].b == edges[e].b &&
                SameFloat(fast_edges[e].weight, edges[e].weight))
        << "edge " << e;
  }
}

void ExpectSameSegmentation(const OrganizedCloud& cloud, const SegmenterConfig& config) {
  const SegmentationResult expected = reference::Segment(cloud, config);
  const SegmentationResult result = Segmenter(config).Segment(cloud);
  EXPECT_EQ(result.num_segments, expected.num_segments);
  EXPECT_EQ(result.labels, expected.labels);
  EXPECT_EQ(result.segment_is_plane, expected.segment_is_plane);
  EXPECT_GT(expected.num_segments, 1) << "a trivial segmentation proves nothing";
}

// Configs that move every step off its default path.
std::vector<SegmenterConfig> TestConfigs() {
  std::vector<SegmenterConfig> configs(5);
  configs[1].cell_px = 5;
  configs[1].normal_step_px = 2;
  configs[2].max_planes = 1;
  configs[2].min_segment_px = 0;
  configs[3].kruskal_k_px = 2000.f;
  configs[3].convex_tolerance = 0.f;
  configs[4].min_plane_area_m2 = 10.f;  // no plane passes: supervoxels of one kind only
  configs[4].cell_px = 13;
  return configs;
}

TEST(SegmenterFastPathTest, SameAsReferenceOnSyntheticScenes) {
  for (float noise_m : {0.f, 0.001f, 0.004f}) {
    const testing::SyntheticScene scene = testing::MakeTableWithTwoBoxes(noise_m);
    for (const SegmenterConfig& config : TestConfigs()) {
      SCOPED_TRACE("noise " + std::to_string(noise_m) + ", cell " + std::to_string(config.cell_px));
      ExpectSameSteps(scene.cloud_C, config);
      ExpectSameSegmentation(scene.cloud_C, config);
    }
  }
}

TEST(SegmenterFastPathTest, SameAsReferenceOnMosdClouds) {
  const std::string folder = testing::SharedDataPath("mosd-learn");
  OBJMAP_REQUIRE_PATH(folder + "/learn0.pcd");
  const std::vector<std::string> paths = testing::MosdCloudPaths(folder);
  for (size_t k = 0; k < paths.size(); k += 3) {
    SCOPED_TRACE(paths[k]);
    OrganizedCloud cloud;
    std::string why;
    ASSERT_TRUE(LoadOrganizedPcd(paths[k], &cloud, nullptr, &why)) << why;
    ExpectSameSteps(cloud, SegmenterConfig());
    ExpectSameSegmentation(cloud, SegmenterConfig());
  }
}

TEST(SegmenterFastPathTest, SameAsReferenceOnKitchenFrames) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  const auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  for (std::size_t index : {0, 250, 450}) {
    SCOPED_TRACE("frame " + std::to_string(index));
    RgbdFrame frame;
    ASSERT_TRUE(reader->ReadFrame(index, &frame, &why)) << why;
    const OrganizedCloud cloud = BackProject(frame.depth, ColorImage(), frame.intrinsics);
    ExpectSameSteps(cloud, SegmenterConfig());
    ExpectSameSegmentation(cloud, SegmenterConfig());
  }
}

}  // namespace
}  // namespace objmap
