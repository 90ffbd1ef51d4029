#pragma once
// The mOSD learn clouds and their ground truth, shared by mosd_segmentation_test and
// segmentation_bench so that both read and score the clouds the same way.
//
// Ground-truth regions: every label >= 20 is one object (mOSD gives disjoint parts of one object
// different labels, which a model-free method cannot join), labels 1-9 together are the table.
//
// Rates (point-weighted over all clouds scored, 0 is perfect):
//  - over-segmentation rate: over the GT objects (table excluded), the share of their points that
//    do not lie in the predicted segment that holds most of the object. A point the method left
//    unlabelled counts as outside.
//  - under-segmentation rate: over the predicted segments, the share of their labelled points
//    (object or table) that belong to another GT region than the segment's dominant one.
//  - object recall: share of GT objects whose best predicted segment has IoU >= 0.5.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace objmap::testing {

/// The .pcd files of an mOSD folder, sorted by name.
inline std::vector<std::string> MosdCloudPaths(const std::string& folder) {
  std::vector<std::string> paths;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    if (entry.path().extension() == ".pcd") paths.push_back(entry.path().string());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

/// Region per point: -1 unlabelled, 0 table, 1.. one per distinct object label.
inline std::vector<int> GroundTruthRegions(const std::vector<std::uint32_t>& labels,
                                           int* num_regions) {
  std::map<std::uint32_t, int> object_ids;
  for (std::uint32_t l : labels) {
    if (l >= 20) object_ids.emplace(l, 0);
  }
  int next = 1;
  for (auto& entry : object_ids) entry.second = next++;
  *num_regions = next;
  std::vector<int> regions(labels.size(), -1);
  for (size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] >= 1 && labels[i] <= 9) regions[i] = 0;
    if (labels[i] >= 20) regions[i] = object_ids[labels[i]];
  }
  return regions;
}

/// Point counts behind the rates, summed over clouds with Add.
struct SegmentationRates {
  long object_points = 0;           ///< GT object points
  long object_points_outside = 0;   ///< of those, outside the object's best segment
  long segment_points = 0;          ///< GT-labelled points inside predicted segments
  long segment_points_foreign = 0;  ///< of those, not from the segment's dominant region
  int objects = 0;
  int objects_found = 0;  ///< best segment IoU >= 0.5

  [[nodiscard]] double OverSegmentation() const {
    return object_points > 0 ? static_cast<double>(object_points_outside) / object_points : 0.0;
  }
  [[nodiscard]] double UnderSegmentation() const {
    return segment_points > 0 ? static_cast<double>(segment_points_foreign) / segment_points : 0.0;
  }
  [[nodiscard]] double Recall() const {
    return objects > 0 ? static_cast<double>(objects_found) / objects : 0.0;
  }

  /// Scores one cloud: `predicted` holds a segment id >= 0 per point or -1 when unlabelled.
  void Add(const std::vector<int>& predicted, const std::vector<std::uint32_t>& labels) {
    int num_regions = 0;
    const std::vector<int> regions = GroundTruthRegions(labels, &num_regions);
    int num_segments = 0;
    for (int s : predicted) num_segments = std::max(num_segments, s + 1);
    std::vector<std::vector<long>> overlap(num_regions, std::vector<long>(num_segments, 0));
    std::vector<long> region_points(num_regions, 0);
    std::vector<long> segment_sizes(num_segments, 0);
    for (size_t i = 0; i < labels.size() && i < predicted.size(); ++i) {
      if (regions[i] < 0) continue;
      ++region_points[regions[i]];
      if (predicted[i] < 0) continue;
      ++overlap[regions[i]][predicted[i]];
      ++segment_sizes[predicted[i]];
    }
    for (int r = 1; r < num_regions; ++r) {
      if (region_points[r] == 0) continue;
      long best = 0;
      double best_iou = 0.0;
      for (int s = 0; s < num_segments; ++s) {
        best = std::max(best, overlap[r][s]);
        const long union_points = region_points[r] + segment_sizes[s] - overlap[r][s];
        if (union_points > 0) {
          best_iou = std::max(best_iou, static_cast<double>(overlap[r][s]) / union_points);
        }
      }
      ++objects;
      objects_found += best_iou >= 0.5 ? 1 : 0;
      object_points += region_points[r];
      object_points_outside += region_points[r] - best;
    }
    for (int s = 0; s < num_segments; ++s) {
      long dominant = 0;
      for (int r = 0; r < num_regions; ++r) dominant = std::max(dominant, overlap[r][s]);
      segment_points += segment_sizes[s];
      segment_points_foreign += segment_sizes[s] - dominant;
    }
  }
};

}  // namespace objmap::testing
