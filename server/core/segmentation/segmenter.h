#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "types/detection.h"
#include "types/organized_cloud.h"

namespace objmap {

/// Parameters of the unsupervised segmentation of an organized cloud (paper Sec. III-B):
/// normals, supporting planes, supervoxels, adjacency graph with convexity weights, Kruskal cut.
struct SegmenterConfig {
  // Fields are added by the implementation; each documented with ///, defaults here.
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Per-pixel segment labels for one organized cloud.
struct SegmentationResult {
  int width = 0;
  int height = 0;
  std::vector<std::int32_t> labels;  ///< row-major; -1 for invalid points, else 0..num_segments-1
  int num_segments = 0;
  std::vector<bool> segment_is_plane;  ///< per segment: true when it is a supporting plane
};

/// Segments organized clouds. Thread-safe: Segment() is const and keeps no state between calls.
class Segmenter {
 public:
  explicit Segmenter(const SegmenterConfig& config);
  [[nodiscard]] SegmentationResult Segment(const OrganizedCloud& cloud_C) const;

 private:
  SegmenterConfig config_;
};

/// How a detection box picks its 3D segment(s).
struct DetectionSegmentConfig {
  // Fields are added by the implementation (box dilation for unregistered depth, overlap votes).
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Pixel indices (into the organized cloud) of the object a detection box shows: the
/// non-plane segment(s) that lie mostly inside the box. Box is in depth-image pixels.
/// Empty when nothing in the box qualifies.
[[nodiscard]] std::vector<int> SelectDetectionPixels(const SegmentationResult& segmentation,
                                                     const OrganizedCloud& cloud_C,
                                                     const BoundingBox2D& box,
                                                     const DetectionSegmentConfig& config);

}  // namespace objmap
