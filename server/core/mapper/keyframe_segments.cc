#include "mapper/keyframe_segments.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "segmentation/segment_index.h"

namespace objmap {
namespace {

bool Contains(const std::vector<int>& classes, int class_id) {
  return std::find(classes.begin(), classes.end(), class_id) != classes.end();
}

bool Inside(const BoundingBox2D& box, int u, int v) {
  return u >= box.x_min && u <= box.x_max && v >= box.y_min && v <= box.y_max;
}

// A table top is a supporting plane, so SelectDetectionPixels never returns it. Surface classes
// take a plane segment most of which lies in the box (the floor or a wall seen beyond the table
// extends far outside it): of those with a good share of the box (a quarter of the best one's
// pixels), the nearest. The top hides what lies below it, so a patch of floor seen between
// the legs and cut off by them (also mostly inside the box) is always farther than the top.
std::vector<int> SurfacePlanePixels(const SegmentationResult& segmentation,
                                    const SegmentIndex& index, const BoundingBox2D& box) {
  std::vector<int> inside(segmentation.num_segments, 0);
  const int u0 = std::max(0, static_cast<int>(std::ceil(box.x_min)));
  const int v0 = std::max(0, static_cast<int>(std::ceil(box.y_min)));
  const int u1 = std::min(segmentation.width - 1, static_cast<int>(std::floor(box.x_max)));
  const int v1 = std::min(segmentation.height - 1, static_cast<int>(std::floor(box.y_max)));
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const int label = segmentation.labels[v * segmentation.width + u];
      if (label >= 0 && segmentation.segment_is_plane[label]) ++inside[label];
    }
  }
  std::vector<int> candidates;
  int most_inside = 0;
  for (int s = 0; s < segmentation.num_segments; ++s) {
    const int total = segmentation.segment_is_plane[s] ? index.segments[s].pixels : 0;
    if (total == 0 || inside[s] * 2 < total) continue;
    candidates.push_back(s);
    most_inside = std::max(most_inside, inside[s]);
  }
  int best = -1;
  double best_depth = 0.0;
  for (int s : candidates) {
    if (inside[s] * 4 < most_inside) continue;
    const double mean_depth = index.segments[s].sum_z / std::max(1, index.segments[s].pixels);
    if (best < 0 || mean_depth < best_depth) best = s, best_depth = mean_depth;
  }
  if (best < 0) return {};
  return std::vector<int>(index.pixel_ids.begin() + index.offsets[best],
                          index.pixel_ids.begin() + index.offsets[best + 1]);
}

// Flat objects (a screen on a wall, a keyboard on a desk) lie within depth noise of their
// supporting plane, so no segment separates them (the paper's lost keyboards). When one plane
// segment covers most of the box, the object is the part of that plane the box covers, shrunk
// by `shrink_fraction` on every side because colour and depth are not registered. With
// `planes_only` false the dominant segment may be any segment: a wall the segmentation did not
// take for a supporting plane (cupboards around it) still carries the screen hung on it.
std::vector<int> FlatObjectPixels(const SegmentationResult& segmentation, const BoundingBox2D& box,
                                  float shrink_fraction, bool planes_only) {
  const float du = shrink_fraction * box.Width();
  const float dv = shrink_fraction * box.Height();
  const int u0 = std::max(0, static_cast<int>(std::ceil(box.x_min + du)));
  const int v0 = std::max(0, static_cast<int>(std::ceil(box.y_min + dv)));
  const int u1 = std::min(segmentation.width - 1, static_cast<int>(box.x_max - du));
  const int v1 = std::min(segmentation.height - 1, static_cast<int>(box.y_max - dv));
  std::vector<int> count(segmentation.num_segments, 0);
  int valid = 0;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const int label = segmentation.labels[v * segmentation.width + u];
      if (label < 0) continue;
      ++valid;
      if (!planes_only || segmentation.segment_is_plane[label]) ++count[label];
    }
  }
  std::vector<int> pixels;
  if (count.empty()) return pixels;
  const int plane = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  if (count[plane] * 2 < valid) return pixels;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      if (segmentation.labels[v * segmentation.width + u] == plane) {
        pixels.push_back(v * segmentation.width + u);
      }
    }
  }
  return pixels;
}

// Keeps the pixels inside the box grown by the detection-segment dilation. A segment that runs
// beyond its box (two chairs side by side in one segment) cannot belong to the detection there.
std::vector<int> CropToBox(std::vector<int> pixels, const BoundingBox2D& box, int width,
                           const DetectionSegmentConfig& config) {
  const BoundingBox2D grown = DilateDetectionBox(box, config);
  pixels.erase(std::remove_if(pixels.begin(), pixels.end(),
                              [&](int i) {
                                const int v = i / width;
                                return !Inside(grown, i - v * width, v);
                              }),
               pixels.end());
  return pixels;
}

// The pixels of one detection: supporting surfaces take their plane, flat objects the part of
// the plane in their box, everything else the segments SelectDetectionPixels picks.
// Share of `box` that the bounding box of `pixels` covers.
float BoxFill(const std::vector<int>& pixels, int width, const BoundingBox2D& box) {
  if (pixels.empty() || !(box.Area() > 0.f)) return 0.f;
  int u_min = width, v_min = std::numeric_limits<int>::max(), u_max = -1, v_max = -1;
  for (int i : pixels) {
    const int v = i / width, u = i - v * width;
    u_min = std::min(u_min, u), u_max = std::max(u_max, u);
    v_min = std::min(v_min, v), v_max = std::max(v_max, v);
  }
  // Pixel boxes are inclusive: a segment of one pixel spans 1 x 1.
  const float w = std::min<float>(u_max + 1, box.x_max) - std::max<float>(u_min, box.x_min);
  const float h = std::min<float>(v_max + 1, box.y_max) - std::max<float>(v_min, box.y_min);
  if (w <= 0.f || h <= 0.f) return 0.f;
  return std::min(1.f, w * h / box.Area());
}

std::vector<int> DetectionPixels(const SegmentationResult& segmentation, const SegmentIndex& index,
                                 const BoundingBox2D& box, int class_id,
                                 const MapperConfig& config) {
  if (Contains(config.surface_classes, class_id)) {
    std::vector<int> pixels = SurfacePlanePixels(segmentation, index, box);
    if (!pixels.empty()) return pixels;
  }
  const bool flat = Contains(config.flat_classes, class_id);
  if (flat) {
    std::vector<int> pixels =
        FlatObjectPixels(segmentation, box, config.flat_box_shrink_fraction, true);
    if (!pixels.empty()) return pixels;
  }
  std::vector<int> pixels =
      SelectDetectionPixels(segmentation, index, box, config.detection_segment);
  if (flat && BoxFill(pixels, segmentation.width, box) < config.min_segment_box_fill) {
    // Only a fragment of the box stands out from its surroundings: the flat object is the part
    // of the surface that fills its box.
    std::vector<int> surface =
        FlatObjectPixels(segmentation, box, config.flat_box_shrink_fraction, false);
    if (!surface.empty()) return surface;
  }
  return pixels;
}

ColoredPoints SegmentPoints(const OrganizedCloud& cloud_C, const std::vector<int>& pixels,
                            float voxel_size_m) {
  ColoredPoints points;
  points.points.reserve(pixels.size());
  for (int i : pixels) {
    if (!cloud_C.IsValid(i)) continue;
    points.points.push_back(cloud_C.points_C[i]);
    if (!cloud_C.rgb.empty()) points.colors.push_back(cloud_C.rgb[i]);
  }
  return VoxelDownsample(points, voxel_size_m);
}

// The pixels one observation claimed, as a bit per pixel of the frame: cheaper to build and to
// query than a hash set of up to a few 10^4 pixel indices per detection.
class PixelClaim {
 public:
  PixelClaim(const std::vector<int>& pixels, std::size_t frame_pixels) : bits_(frame_pixels) {
    for (int i : pixels) bits_[i] = true;
  }
  [[nodiscard]] bool Has(int i) const { return bits_[i]; }

 private:
  std::vector<bool> bits_;
};

// Fraction of `pixels` already claimed by `claimed`.
float ClaimedFraction(const std::vector<int>& pixels, const PixelClaim& claimed) {
  if (pixels.empty()) return 0.f;
  const auto hits =
      std::count_if(pixels.begin(), pixels.end(), [&](int i) { return claimed.Has(i); });
  return static_cast<float>(hits) / static_cast<float>(pixels.size());
}

float BoxIou(const BoundingBox2D& a, const BoundingBox2D& b) {
  const float w = std::min(a.x_max, b.x_max) - std::max(a.x_min, b.x_min);
  const float h = std::min(a.y_max, b.y_max) - std::max(a.y_min, b.y_min);
  if (w <= 0.f || h <= 0.f) return 0.f;
  const float intersection = w * h;
  return intersection / (a.Area() + b.Area() - intersection);
}

// How far (u, v) lies from the box centre, in half-extents (< 1 inside the box).
float BoxDistance(const BoundingBox2D& box, int u, int v) {
  const float half_w = std::max(0.5f, 0.5f * box.Width());
  const float half_h = std::max(0.5f, 0.5f * box.Height());
  return std::max(std::abs(u - 0.5f * (box.x_min + box.x_max)) / half_w,
                  std::abs(v - 0.5f * (box.y_min + box.y_max)) / half_h);
}

// The pixels of two same-class detections that picked one segment (two cups touching, a stack
// of books), shared out: a pixel in one box only goes to it, any other to the box whose centre is
// nearer in units of the box's half-size.
void SplitBetweenBoxes(const std::vector<int>& pixels, int width, const BoundingBox2D& box_a,
                       const BoundingBox2D& box_b, std::vector<int>* pixels_a,
                       std::vector<int>* pixels_b) {
  for (int i : pixels) {
    const int u = i % width, v = i / width;
    const bool in_a = Inside(box_a, u, v), in_b = Inside(box_b, u, v);
    const bool to_a = in_a != in_b ? in_a : BoxDistance(box_a, u, v) <= BoxDistance(box_b, u, v);
    (to_a ? pixels_a : pixels_b)->push_back(i);
  }
}

void AddClassScore(ObjectObservation* observation, int class_id, float score) {
  for (auto& [existing_class, existing_score] : observation->class_scores) {
    if (existing_class == class_id) {
      existing_score = std::max(existing_score, score);  // the same object detected twice
      return;
    }
  }
  observation->class_scores.emplace_back(class_id, score);
}

}  // namespace

BoundingBox2D ToDepthPixels(const BoundingBox2D& box, const ColorImage& color,
                            const DepthImage& depth) {
  if (color.empty() || (color.width == depth.width && color.height == depth.height)) return box;
  const float sx = static_cast<float>(depth.width) / color.width;
  const float sy = static_cast<float>(depth.height) / color.height;
  return {box.x_min * sx, box.y_min * sy, box.x_max * sx, box.y_max * sy};
}

std::vector<SegmentedDetection> SegmentDetections(
    const RgbdFrame& frame, const OrganizedCloud& cloud_C, const SegmentationResult& segmentation,
    const std::vector<Detection>& detections, KeyframeId keyframe_id, const MapperConfig& config) {
  std::vector<int> order(detections.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return detections[a].score > detections[b].score; });
  // Built once: every detection box then costs its own area, not a pass over the image.
  const SegmentIndex index = IndexSegments(segmentation, cloud_C);
  std::vector<SegmentedDetection> segmented;
  const std::size_t frame_pixels = segmentation.labels.size();
  std::vector<PixelClaim> claimed;
  std::vector<BoundingBox2D> depth_boxes;  // of each entry, in depth pixels
  auto make_entry = [&](const Detection& detection, const std::vector<int>& pixels,
                        SegmentedDetection* entry) {
    entry->observation.segment_C =
        SegmentPoints(cloud_C, pixels, config.objects.model_voxel_size_m);
    if (static_cast<int>(entry->observation.segment_C.size()) < config.min_segment_points) {
      return false;
    }
    entry->observation.keyframe_id = keyframe_id;
    entry->observation.box = detection.box;
    entry->observation.class_scores = {{detection.class_id, detection.score}};
    entry->pixels = pixels;
    return true;
  };
  for (int d : order) {
    const Detection& detection = detections[d];
    if (detection.score < config.min_detection_score || detection.box.Area() <= 0.f) continue;
    const BoundingBox2D box = ToDepthPixels(detection.box, frame.color, frame.depth);
    const std::vector<int> pixels =
        CropToBox(DetectionPixels(segmentation, index, box, detection.class_id, config), box,
                  segmentation.width, config.detection_segment);
    if (pixels.empty() ||
        BoxFill(pixels, segmentation.width, box) < config.min_segment_box_fill) {
      continue;
    }
    bool handled = false;
    for (std::size_t k = 0; k < segmented.size() && !handled; ++k) {
      if (ClaimedFraction(pixels, claimed[k]) < 0.5f) continue;
      ObjectObservation& earlier = segmented[k].observation;
      // What lies on a table is not the table, though its pixels are part of the table's plane
      // (a flat keyboard within the plane's depth noise).
      if (Contains(config.surface_classes, earlier.class_scores.front().first) &&
          !Contains(config.surface_classes, detection.class_id)) {
        continue;
      }
      handled = true;
      if (earlier.class_scores.front().first == detection.class_id &&
          BoxIou(depth_boxes[k], box) < config.split_max_box_iou) {
        std::vector<int> joined = segmented[k].pixels;
        for (int i : pixels) {
          if (!claimed[k].Has(i)) joined.push_back(i);
        }
        std::vector<int> pixels_k, pixels_d;
        SplitBetweenBoxes(joined, segmentation.width, depth_boxes[k], box, &pixels_k, &pixels_d);
        SegmentedDetection kept, added;
        if (make_entry(detection, pixels_d, &added) && make_entry(detection, pixels_k, &kept)) {
          kept.observation.box = earlier.box;
          kept.observation.class_scores = earlier.class_scores;
          segmented[k] = std::move(kept);
          claimed[k] = PixelClaim(pixels_k, frame_pixels);
          claimed.emplace_back(pixels_d, frame_pixels);
          depth_boxes.push_back(box);
          segmented.push_back(std::move(added));
          continue;
        }
      }
      AddClassScore(&earlier, detection.class_id, detection.score);
    }
    if (handled) continue;
    SegmentedDetection entry;
    if (!make_entry(detection, pixels, &entry)) continue;
    claimed.emplace_back(pixels, frame_pixels);
    depth_boxes.push_back(box);
    segmented.push_back(std::move(entry));
  }
  return segmented;
}

}  // namespace objmap
