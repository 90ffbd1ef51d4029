#include "segmentation/segment_index.h"

#include <algorithm>

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
  for (int v = 0, i = 0; v < segmentation.height; ++v) {
    for (int u = 0; u < segmentation.width; ++u, ++i) {
      const int s = segmentation.labels[i];
      if (s < 0 || s >= segmentation.num_segments) continue;
      SegmentIndex::Segment& segment = index.segments[s];
      if (segment.pixels == 0) {
        segment.u_min = segment.u_max = u;
        segment.v_min = segment.v_max = v;
      }
      ++segment.pixels;
      segment.sum_z += cloud_C.points_C[i].z();
      segment.u_min = std::min(segment.u_min, u);
      segment.u_max = std::max(segment.u_max, u);
      segment.v_max = v;  // rows are visited in order
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
