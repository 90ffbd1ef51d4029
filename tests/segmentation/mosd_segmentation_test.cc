// Segmentation quality on the modified Object Segmentation Database (mOSD, learn set) and speed
// on a real 7-Scenes depth frame.
//
// Metrics (per cloud, then mean), with the ground-truth regions of mosd_ground_truth.h:
//  - over-segmentation of a GT object: number of predicted segments needed (largest first) to
//    cover 80% of its points, minus 1; 0 is perfect.
//  - under-segmentation: a predicted segment with >= 50 labelled points counts as an error when
//    more than 20% of its points lie on a second GT region (object or table).
//  - object recall: share of GT objects whose best predicted segment has IoU >= 0.5.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <numeric>

#include "dataset/sequence_reader.h"
#include "pointcloud_io/pointcloud_io.h"
#include "segmentation/mosd_ground_truth.h"
#include "segmentation/segmenter.h"
#include "test_data.h"

namespace objmap {
namespace {

struct CloudMetrics {
  int objects = 0;
  double mean_oversegmentation = 0.0;
  int undersegmented = 0;
  double recall = 0.0;
  double ms = 0.0;
  int segments = 0;
};

void ScoreObjects(const std::vector<std::vector<int>>& overlap, const std::vector<int>& pred_sizes,
                  CloudMetrics* m) {
  double overseg_sum = 0.0;
  int found = 0;
  for (size_t r = 1; r < overlap.size(); ++r) {
    std::vector<int> counts = overlap[r];
    const int total = std::accumulate(counts.begin(), counts.end(), 0);
    if (total == 0) continue;
    ++m->objects;
    double best_iou = 0.0;
    for (size_t s = 0; s < counts.size(); ++s) {
      best_iou =
          std::max(best_iou, counts[s] / static_cast<double>(total + pred_sizes[s] - counts[s]));
    }
    found += best_iou >= 0.5 ? 1 : 0;
    std::sort(counts.rbegin(), counts.rend());
    int covered = 0, used = 0;
    while (covered < 0.8 * total && used < static_cast<int>(counts.size()))
      covered += counts[used++];
    overseg_sum += used - 1;
  }
  m->mean_oversegmentation = m->objects > 0 ? overseg_sum / m->objects : 0.0;
  m->recall = m->objects > 0 ? static_cast<double>(found) / m->objects : 0.0;
}

CloudMetrics Evaluate(const SegmentationResult& seg, const std::vector<std::uint32_t>& labels) {
  int num_regions = 0;
  const std::vector<int> regions = testing::GroundTruthRegions(labels, &num_regions);
  std::vector<std::vector<int>> overlap(num_regions, std::vector<int>(seg.num_segments, 0));
  std::vector<int> pred_sizes(seg.num_segments, 0);
  for (size_t i = 0; i < labels.size(); ++i) {
    if (seg.labels[i] < 0 || regions[i] < 0) continue;
    overlap[regions[i]][seg.labels[i]]++;
    pred_sizes[seg.labels[i]]++;
  }
  CloudMetrics m;
  m.segments = seg.num_segments;
  for (int s = 0; s < seg.num_segments; ++s) {
    std::vector<int> shares;
    for (int r = 0; r < num_regions; ++r) shares.push_back(overlap[r][s]);
    std::sort(shares.rbegin(), shares.rend());
    if (pred_sizes[s] >= 50 && shares.size() > 1 && shares[1] > 0.2 * pred_sizes[s]) {
      ++m.undersegmented;
    }
  }
  ScoreObjects(overlap, pred_sizes, &m);
  return m;
}

std::vector<std::string> MosdClouds() {
  return testing::MosdCloudPaths(testing::SharedDataPath("mosd-learn"));
}

TEST(MosdSegmentationTest, MatchesGroundTruth) {
  OBJMAP_REQUIRE_PATH(testing::SharedDataPath("mosd-learn/learn0.pcd"));
  const Segmenter segmenter{SegmenterConfig()};
  CloudMetrics mean;
  int clouds = 0, worst_under = 0;
  double worst_recall = 1.0;
  for (const std::string& path : MosdClouds()) {
    OrganizedCloud cloud;
    std::vector<std::uint32_t> labels;
    std::string why;
    ASSERT_TRUE(LoadOrganizedPcd(path, &cloud, &labels, &why)) << why;
    const auto start = std::chrono::steady_clock::now();
    const SegmentationResult seg = segmenter.Segment(cloud);
    const auto stop = std::chrono::steady_clock::now();
    CloudMetrics m = Evaluate(seg, labels);
    m.ms = std::chrono::duration<double, std::milli>(stop - start).count();
    printf("%-12s objects %2d  overseg %.2f  underseg %d  recall %.2f  segments %3d  %.1f ms\n",
           std::filesystem::path(path).filename().c_str(), m.objects, m.mean_oversegmentation,
           m.undersegmented, m.recall, m.segments, m.ms);
    mean.mean_oversegmentation += m.mean_oversegmentation;
    mean.undersegmented += m.undersegmented;
    mean.recall += m.recall;
    mean.ms += m.ms;
    worst_under = std::max(worst_under, m.undersegmented);
    worst_recall = std::min(worst_recall, m.recall);
    ++clouds;
  }
  ASSERT_GT(clouds, 0);
  const double overseg = mean.mean_oversegmentation / clouds;
  const double underseg = static_cast<double>(mean.undersegmented) / clouds;
  const double recall = mean.recall / clouds;
  printf("MEAN over %d clouds: overseg %.2f  underseg %.2f  recall %.2f  %.1f ms/cloud\n", clouds,
         overseg, underseg, recall, mean.ms / clouds);
  // Bounds from the default config on the 14 learn clouds (measured: mean over-segmentation
  // 0.00, mean under-segmentation 0.36 segments per cloud with at most 2, mean recall 0.94 with a
  // worst cloud of 0.57), with a margin for platform differences; a regression that splits
  // objects or glues them to the table or to each other breaks them. The worst recall comes from
  // pots whose floor mOSD labels as a separate part while we keep it with the pot.
  EXPECT_LE(overseg, 0.25);
  EXPECT_LE(underseg, 0.75);
  EXPECT_GE(recall, 0.85);
  EXPECT_LE(worst_under, 3);
  EXPECT_GE(worst_recall, 0.5);
}

// Ground-truth boxes of whole objects (parts merged: label / 10), shifted as an unregistered
// colour camera would, must select the object's pixels.
TEST(MosdSegmentationTest, DetectionBoxesSelectTheirObjects) {
  OBJMAP_REQUIRE_PATH(testing::SharedDataPath("mosd-learn/learn0.pcd"));
  const Segmenter segmenter{SegmenterConfig()};
  double precision_sum = 0.0, recall_sum = 0.0;
  int objects = 0;
  for (const std::string& path : MosdClouds()) {
    OrganizedCloud cloud;
    std::vector<std::uint32_t> labels;
    std::string why;
    ASSERT_TRUE(LoadOrganizedPcd(path, &cloud, &labels, &why)) << why;
    const SegmentationResult seg = segmenter.Segment(cloud);
    std::map<std::uint32_t, BoundingBox2D> boxes;
    std::map<std::uint32_t, int> sizes;
    for (size_t i = 0; i < labels.size(); ++i) {
      if (labels[i] < 20) continue;
      const float u = static_cast<float>(i % cloud.width), v = static_cast<float>(i / cloud.width);
      auto [it, fresh] = boxes.try_emplace(labels[i] / 10, BoundingBox2D{u, v, u, v});
      it->second = {std::min(it->second.x_min, u), std::min(it->second.y_min, v),
                    std::max(it->second.x_max, u), std::max(it->second.y_max, v)};
      sizes[labels[i] / 10]++;
    }
    for (auto [object, box] : boxes) {
      box = {box.x_min + 10.f, box.y_min - 6.f, box.x_max + 10.f, box.y_max - 6.f};
      const std::vector<int> pixels =
          SelectDetectionPixels(seg, cloud, box, DetectionSegmentConfig());
      int hits = 0;
      for (int i : pixels) hits += labels[i] / 10 == object ? 1 : 0;
      precision_sum += pixels.empty() ? 0.0 : static_cast<double>(hits) / pixels.size();
      recall_sum += static_cast<double>(hits) / sizes[object];
      ++objects;
    }
  }
  ASSERT_GT(objects, 0);
  printf("detection boxes on %d mOSD objects: pixel precision %.3f  recall %.3f\n", objects,
         precision_sum / objects, recall_sum / objects);
  // Measured 0.936 / 0.991 with the default configs; the margin allows platform differences.
  EXPECT_GE(precision_sum / objects, 0.88);
  EXPECT_GE(recall_sum / objects, 0.93);
}

TEST(MosdSegmentationTest, RealKitchenFrame) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  const auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(0, &frame, &why)) << why;
  const OrganizedCloud cloud = BackProject(frame.depth, ColorImage(), frame.intrinsics);
  const Segmenter segmenter{SegmenterConfig()};
  SegmentationResult seg = segmenter.Segment(cloud);  // warm-up
  const int runs = 5;
  const auto start = std::chrono::steady_clock::now();
  for (int r = 0; r < runs; ++r) seg = segmenter.Segment(cloud);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() /
      runs;
  int planes = 0, big = 0;
  std::vector<int> sizes(seg.num_segments, 0);
  for (std::int32_t l : seg.labels) {
    if (l >= 0) sizes[l]++;
  }
  for (int s = 0; s < seg.num_segments; ++s) {
    planes += seg.segment_is_plane[s] ? 1 : 0;
    big += sizes[s] >= 1000 ? 1 : 0;
  }
  printf("redkitchen frame-000000 %dx%d: %.1f ms, %d segments (%d with >= 1000 px), %d planes\n",
         cloud.width, cloud.height, ms, seg.num_segments, big, planes);
  // Measured: 73 segments, 22 of them >= 1000 px, 4 planes (floor, table, walls).
  EXPECT_GE(planes, 2);
  EXPECT_GE(big, 10);
}

}  // namespace
}  // namespace objmap
