#include "segmentation/segment_index.h"

#include <algorithm>
#include <cstdint>

namespace objmap {

bool SegmentIndex::Matches(const SegmentationResult& segmentation) const {
  return segments.size() == static_cast<size_t>(segmentation.num_segments) &&
         offsets.size() == segments.size() + 1 &&
         static_cast<size_t>(offsets.back()) == pixel_ids.size();
}

SegmentIndex IndexSegments(const SegmentationResult& segmentation, const OrganizedCloud& cloud_C) {
  SegmentIndex index;
  const size_t n = static_cast<size_t>(segmentation.width) * segmentation.height;
  if (segmentation.num_segments < 0 || segmentation.labels.size() != n ||
      cloud_C.points_C.size() != n) {
    return index;
  }
  index.segments.resize(segmentation.num_segments);
  // Row by row in runs of one label: the extent changes once per run, the depth sum takes every
  // pixel in order.
  const int w = segmentation.width;
  for (int v = 0; v < segmentation.height; ++v) {
    const std::int32_t* labels = &segmentation.labels[static_cast<size_t>(v) * w];
    const Eigen::Vector3f* points = &cloud_C.points_C[static_cast<size_t>(v) * w];
    for (int u = 0; u < w;) {
      const int s = labels[u];
      int end = u + 1;
      while (end < w && labels[end] == s) ++end;
      if (s >= 0 && s < segmentation.num_segments) {
        SegmentIndex::Segment& segment = index.segments[s];
        if (segment.pixels == 0) {
          segment.u_min = u;
          segment.u_max = end - 1;
          segment.v_min = v;
        }
        segment.pixels += end - u;
        for (int k = u; k < end; ++k) segment.sum_z += points[k].z();
        segment.u_min = std::min(segment.u_min, u);
        segment.u_max = std::max(segment.u_max, end - 1);
        segment.v_max = v;  // rows are visited in order
      }
      u = end;
    }
  }
  // Counting sort of the pixels by segment keeps each segment's pixels ascending.
  index.offsets.assign(index.segments.size() + 1, 0);
  for (size_t s = 0; s < index.segments.size(); ++s) {
    index.offsets[s + 1] = index.offsets[s] + index.segments[s].pixels;
  }
  index.pixel_ids.resize(index.offsets.back());
  std::vector<int> next(index.offsets.begin(), index.offsets.end() - 1);
  for (size_t i = 0; i < n; ++i) {
    const int s = segmentation.labels[i];
    if (s >= 0 && s < segmentation.num_segments) index.pixel_ids[next[s]++] = static_cast<int>(i);
  }
  return index;
}

}  // namespace objmap
