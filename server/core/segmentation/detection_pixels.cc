// From a detection box to the object's pixels (paper Sec. III-B, last step): the non-plane
// segments that lie mostly inside the (dilated) box. Among those, the segment whose own image
// box best matches the detection is the object; others join only when they make the union match
// the detection better, so an object occluding part of another (whose box then contains it) is
// not taken along.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "segmentation/segment_index.h"
#include "segmentation/segmenter.h"

namespace objmap {
namespace {

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

BoundingBox2D Grow(const BoundingBox2D& box, float dilation_px, float dilation_fraction) {
  const float grow_u = dilation_px + dilation_fraction * box.Width();
  const float grow_v = dilation_px + dilation_fraction * box.Height();
  return {box.x_min - grow_u, box.y_min - grow_v, box.x_max + grow_u, box.y_max + grow_v};
}

PixelBox DilateAndClip(const BoundingBox2D& box, int width, int height, float dilation_px,
                       float dilation_fraction) {
  const BoundingBox2D grown = Grow(box, dilation_px, dilation_fraction);
  auto clip = [](float x, int hi) {
    return std::clamp(static_cast<int>(std::floor(x)), 0, hi - 1);
  };
  return {clip(grown.x_min, width), clip(grown.y_min, height), clip(grown.x_max, width),
          clip(grown.y_max, height)};
}

// The per-segment statistics from the index; only the `inside` counts need the box's pixels.
std::vector<SegmentStats> CollectStats(const SegmentationResult& seg, const SegmentIndex& index,
                                       const PixelBox& box) {
  std::vector<SegmentStats> stats(seg.num_segments);
  for (int s = 0; s < seg.num_segments; ++s) {
    const SegmentIndex::Segment& segment = index.segments[s];
    stats[s].pixels = segment.pixels;
    stats[s].sum_z = segment.sum_z;
    if (segment.pixels > 0) {
      stats[s].extent = {segment.u_min, segment.v_min, segment.u_max, segment.v_max};
    }
  }
  for (int v = box.v0; v <= box.v1; ++v) {
    const std::int32_t* row = &seg.labels[static_cast<size_t>(v) * seg.width];
    for (int u = box.u0; u <= box.u1; ++u) {
      const int s = row[u];
      if (s >= 0 && s < seg.num_segments) stats[s].inside++;
    }
  }
  return stats;
}

// The pixels of the taken segments in ascending index order (the order a pass over the image
// gives), merged from the index's per-segment lists.
std::vector<int> GatherPixels(const SegmentIndex& index, std::vector<int> taken) {
  std::sort(taken.begin(), taken.end());
  std::vector<int> pixels;
  for (int s : taken) {
    const size_t middle = pixels.size();
    pixels.insert(pixels.end(), index.pixel_ids.begin() + index.offsets[s],
                  index.pixel_ids.begin() + index.offsets[s + 1]);
    std::inplace_merge(pixels.begin(), pixels.begin() + static_cast<std::ptrdiff_t>(middle),
                       pixels.end());
  }
  return pixels;
}

// Segments whose `inside` share reaches `min_fraction`, plane and oversized ones excluded.
std::vector<int> Candidates(const std::vector<SegmentStats>& stats, const SegmentationResult& seg,
                            float box_area, float min_fraction,
                            const DetectionSegmentConfig& config) {
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
std::vector<int> BuildObject(const std::vector<int>& candidates,
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

int MostInside(const std::vector<int>& candidates, const std::vector<SegmentStats>& stats) {
  return *std::max_element(candidates.begin(), candidates.end(),
                           [&](int a, int b) { return stats[a].inside < stats[b].inside; });
}

}  // namespace

bool DetectionSegmentConfig::IsValid(std::string* why) const {
  auto fail = [why](const char* field) {
    if (why) *why = std::string("DetectionSegmentConfig.") + field + " is out of range";
    return false;
  };
  if (!(dilation_px >= 0.f)) return fail("dilation_px");
  if (!(dilation_fraction >= 0.f)) return fail("dilation_fraction");
  if (!(min_inside_fraction > 0.f && min_inside_fraction <= 1.f))
    return fail("min_inside_fraction");
  if (!(max_box_area_ratio > 0.f)) return fail("max_box_area_ratio");
  if (min_segment_px < 0) return fail("min_segment_px");
  if (!(depth_gate_m > 0.f)) return fail("depth_gate_m");
  if (!(min_iou_gain >= 0.f)) return fail("min_iou_gain");
  if (!(fallback_inside_fraction > 0.f && fallback_inside_fraction <= 1.f)) {
    return fail("fallback_inside_fraction");
  }
  return true;
}

BoundingBox2D DilateDetectionBox(const BoundingBox2D& box, const DetectionSegmentConfig& config) {
  return Grow(box, config.dilation_px, config.dilation_fraction);
}

std::vector<int> SelectDetectionPixels(const SegmentationResult& segmentation,
                                       const OrganizedCloud& cloud_C, const BoundingBox2D& box,
                                       const DetectionSegmentConfig& config) {
  return SelectDetectionPixels(segmentation, IndexSegments(segmentation, cloud_C), box, config);
}

std::vector<int> SelectDetectionPixels(const SegmentationResult& segmentation,
                                       const SegmentIndex& index, const BoundingBox2D& box,
                                       const DetectionSegmentConfig& config) {
  const size_t n = static_cast<size_t>(segmentation.width) * segmentation.height;
  if (!config.IsValid(nullptr) || n == 0 || segmentation.labels.size() != n ||
      segmentation.segment_is_plane.size() != static_cast<size_t>(segmentation.num_segments) ||
      !index.Matches(segmentation) || !(box.Area() > 0.f)) {
    return {};
  }
  const PixelBox pixel_box = DilateAndClip(box, segmentation.width, segmentation.height,
                                           config.dilation_px, config.dilation_fraction);
  const std::vector<SegmentStats> stats = CollectStats(segmentation, index, pixel_box);
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
  return GatherPixels(index, BuildObject(chosen, stats, detection_box, config));
}

}  // namespace objmap
