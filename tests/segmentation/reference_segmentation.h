#pragma once
// Slow references for the segmentation's fast paths: the straightforward versions, kept here so
// tests can check that the fast ones give the same answer.

#include <algorithm>
#include <cmath>
#include <vector>

#include "segmentation/segmentation_internal.h"
#include "segmentation/segmenter.h"

namespace objmap::reference {

// The steps of Segmenter and the whole of it as whole-image passes (reference_segmenter.cc);
// same signatures as their namesakes in segmentation_internal.h.
[[nodiscard]] std::vector<Eigen::Vector3f> ComputeNormals(const OrganizedCloud& cloud_C,
                                                          int step_px, float jump_ratio);
int DetectSupportingPlanes(const OrganizedCloud& cloud_C,
                           const std::vector<Eigen::Vector3f>& normals,
                           const SegmenterConfig& config, float focal_px,
                           std::vector<std::int8_t>* plane_of_pixel);
void BuildSupervoxels(const OrganizedCloud& cloud_C, const std::vector<Eigen::Vector3f>& normals,
                      const std::vector<std::int8_t>& plane_of_pixel, const SegmenterConfig& config,
                      float focal_px, std::vector<int>* supervoxel_of_pixel,
                      std::vector<seg::Supervoxel>* supervoxels);
[[nodiscard]] std::vector<seg::GraphEdge> BuildAdjacencyGraph(
    const OrganizedCloud& cloud_C, const std::vector<int>& supervoxel_of_pixel,
    const std::vector<seg::Supervoxel>& supervoxels, const SegmenterConfig& config);
[[nodiscard]] SegmentationResult Segment(const OrganizedCloud& cloud_C,
                                         const SegmenterConfig& config);

// Detection to segment by whole-image passes per box (segmentation/detection_pixels.cc computes
// the same from a SegmentIndex built once per frame).
struct PixelBox {
  int u0, v0, u1, v1;  // inclusive
  [[nodiscard]] float Area() const { return static_cast<float>((u1 - u0 + 1) * (v1 - v0 + 1)); }
  [[nodiscard]] PixelBox Union(const PixelBox& o) const {
    return {std::min(u0, o.u0), std::min(v0, o.v0), std::max(u1, o.u1), std::max(v1, o.v1)};
  }
  [[nodiscard]] float IoU(const PixelBox& o) const {
    const int w = std::min(u1, o.u1) - std::max(u0, o.u0) + 1;
    const int h = std::min(v1, o.v1) - std::max(v0, o.v0) + 1;
    const float inter = w > 0 && h > 0 ? static_cast<float>(w * h) : 0.f;
    return inter / (Area() + o.Area() - inter);
  }
};

struct SegmentStats {
  int pixels = 0;
  int inside = 0;
  double sum_z = 0.0;
  PixelBox extent{1 << 30, 1 << 30, -1, -1};
  [[nodiscard]] float MeanZ() const {
    return pixels > 0 ? static_cast<float>(sum_z / pixels) : 0.f;
  }
};

inline BoundingBox2D Grow(const BoundingBox2D& box, float dilation_px, float dilation_fraction) {
  const float grow_u = dilation_px + dilation_fraction * box.Width();
  const float grow_v = dilation_px + dilation_fraction * box.Height();
  return {box.x_min - grow_u, box.y_min - grow_v, box.x_max + grow_u, box.y_max + grow_v};
}

inline PixelBox DilateAndClip(const BoundingBox2D& box, int width, int height, float dilation_px,
                              float dilation_fraction) {
  const BoundingBox2D grown = Grow(box, dilation_px, dilation_fraction);
  auto clip = [](float x, int hi) {
    return std::clamp(static_cast<int>(std::floor(x)), 0, hi - 1);
  };
  return {clip(grown.x_min, width), clip(grown.y_min, height), clip(grown.x_max, width),
          clip(grown.y_max, height)};
}

inline std::vector<SegmentStats> CollectStats(const SegmentationResult& seg,
                                              const OrganizedCloud& cloud, const PixelBox& box) {
  std::vector<SegmentStats> stats(seg.num_segments);
  for (int v = 0; v < seg.height; ++v) {
    for (int u = 0; u < seg.width; ++u) {
      const int i = v * seg.width + u;
      const int s = seg.labels[i];
      if (s < 0 || s >= seg.num_segments) continue;
      stats[s].pixels++;
      stats[s].extent = stats[s].extent.Union({u, v, u, v});
      stats[s].sum_z += cloud.points_C[i].z();
      if (u >= box.u0 && u <= box.u1 && v >= box.v0 && v <= box.v1) stats[s].inside++;
    }
  }
  return stats;
}

// Segments whose `inside` share reaches `min_fraction`, plane and oversized ones excluded.
inline std::vector<int> Candidates(const std::vector<SegmentStats>& stats,
                                   const SegmentationResult& seg, float box_area,
                                   float min_fraction, const DetectionSegmentConfig& config) {
  std::vector<int> out;
  for (int s = 0; s < static_cast<int>(stats.size()); ++s) {
    const SegmentStats& st = stats[s];
    if (seg.segment_is_plane[s] || st.pixels < config.min_segment_px) continue;
    if (st.pixels > config.max_box_area_ratio * box_area) continue;
    if (st.inside >= min_fraction * st.pixels && st.inside > 0) out.push_back(s);
  }
  return out;
}

// Greedy: start from the best-matching segment, add segments at its depth while the union's
// image box matches the detection box better by at least min_iou_gain.
inline std::vector<int> BuildObject(const std::vector<int>& candidates,
                                    const std::vector<SegmentStats>& stats, const PixelBox& box,
                                    const DetectionSegmentConfig& config) {
  const int main = *std::max_element(candidates.begin(), candidates.end(), [&](int a, int b) {
    return stats[a].extent.IoU(box) < stats[b].extent.IoU(box);
  });
  std::vector<int> by_size = candidates;
  std::sort(by_size.begin(), by_size.end(),
            [&](int a, int b) { return stats[a].pixels > stats[b].pixels; });
  std::vector<int> object = {main};
  PixelBox extent = stats[main].extent;
  for (int s : by_size) {
    if (s == main || std::abs(stats[s].MeanZ() - stats[main].MeanZ()) > config.depth_gate_m) {
      continue;
    }
    const PixelBox grown = extent.Union(stats[s].extent);
    if (grown.IoU(box) >= extent.IoU(box) + config.min_iou_gain) {
      object.push_back(s);
      extent = grown;
    }
  }
  return object;
}

inline int MostInside(const std::vector<int>& candidates, const std::vector<SegmentStats>& stats) {
  return *std::max_element(candidates.begin(), candidates.end(),
                           [&](int a, int b) { return stats[a].inside < stats[b].inside; });
}

inline std::vector<int> SelectDetectionPixels(const SegmentationResult& segmentation,
                                              const OrganizedCloud& cloud_C,
                                              const BoundingBox2D& box,
                                              const DetectionSegmentConfig& config) {
  const size_t n = static_cast<size_t>(segmentation.width) * segmentation.height;
  if (!config.IsValid(nullptr) || n == 0 || segmentation.labels.size() != n ||
      cloud_C.points_C.size() != n ||
      segmentation.segment_is_plane.size() != static_cast<size_t>(segmentation.num_segments) ||
      !(box.Area() > 0.f)) {
    return {};
  }
  const PixelBox pixel_box = DilateAndClip(box, segmentation.width, segmentation.height,
                                           config.dilation_px, config.dilation_fraction);
  const std::vector<SegmentStats> stats = CollectStats(segmentation, cloud_C, pixel_box);
  std::vector<int> chosen =
      Candidates(stats, segmentation, pixel_box.Area(), config.min_inside_fraction, config);
  if (chosen.empty()) {
    const std::vector<int> fallback =
        Candidates(stats, segmentation, pixel_box.Area(), config.fallback_inside_fraction, config);
    if (fallback.empty()) return {};
    chosen = {MostInside(fallback, stats)};
  }
  const PixelBox detection_box =
      DilateAndClip(box, segmentation.width, segmentation.height, 0.f, 0.f);
  std::vector<bool> take(stats.size(), false);
  for (int s : BuildObject(chosen, stats, detection_box, config)) take[s] = true;
  std::vector<int> pixels;
  for (size_t i = 0; i < n; ++i) {
    const int s = segmentation.labels[i];
    if (s >= 0 && s < segmentation.num_segments && take[s]) pixels.push_back(static_cast<int>(i));
  }
  return pixels;
}

}  // namespace objmap::reference
