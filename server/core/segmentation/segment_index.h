#pragma once
// Per-segment statistics and pixel lists of one segmentation, built in one pass over the image so
// that each detection box afterwards costs its own area, not another pass (a keyframe has up to
// ~25 detections).

#include <vector>

#include "segmentation/segmenter.h"
#include "types/organized_cloud.h"

namespace objmap {

/// Immutable after IndexSegments; safe to share between threads.
struct SegmentIndex {
  struct Segment {
    int pixels = 0;
    double sum_z = 0.0;  ///< depth of its points, summed in pixel order
    int u_min = 0, v_min = 0, u_max = -1, v_max = -1;  ///< image extent, inclusive
  };
  std::vector<Segment> segments;  ///< one per segment id
  /// Segment s owns pixel_ids[offsets[s]] .. pixel_ids[offsets[s + 1] - 1], ascending.
  std::vector<int> offsets;
  std::vector<int> pixel_ids;

  /// True when it was built from a segmentation of this size and segment count.
  [[nodiscard]] bool Matches(const SegmentationResult& segmentation) const;
};

/// Indexes `segmentation` with depths from `cloud_C`; empty when their sizes differ.
[[nodiscard]] SegmentIndex IndexSegments(const SegmentationResult& segmentation,
                                         const OrganizedCloud& cloud_C);

}  // namespace objmap
