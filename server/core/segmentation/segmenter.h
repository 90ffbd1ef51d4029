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
  /// Two neighbouring pixels belong to one surface when their depths differ by at most this
  /// fraction of the depth per pixel of image distance (Kinect noise grows with depth).
  float depth_jump_ratio = 0.02f;
  /// Pixel distance to the neighbours whose cross product gives a pixel's normal.
  int normal_step_px = 4;
  /// Maximum number of supporting planes (table, floor, walls) extracted per cloud.
  int max_planes = 4;
  /// A supporting plane must cover at least this area in m^2; smaller planar patches (box faces)
  /// stay ordinary surfaces.
  float min_plane_area_m2 = 0.12f;
  /// A piece of a supporting plane cut off from the rest by depth edges (the floor of a pot, a
  /// tray) is a supporting surface only when it covers at least this area in m^2.
  float min_plane_patch_area_m2 = 0.025f;
  /// Plane inlier distance at 1 m depth, metres; grows with depth squared like Kinect noise.
  float plane_distance_m = 0.012f;
  /// Maximum angle in degrees between a pixel normal and the plane normal for plane inliers.
  float plane_normal_angle_deg = 25.f;
  /// Plane hypotheses (point + normal) tried per extracted plane.
  int plane_iterations = 60;
  /// Side of the square image cells that seed the supervoxels, in pixels.
  int cell_px = 8;
  /// Felzenszwalb-Huttenlocher scale k in pixels: a segment of |C| pixels accepts an edge of
  /// weight w when w <= Int(C) + k / |C|.
  float kruskal_k_px = 400.f;
  /// Two surfaces count as convex when (c_i - c_j).(n_i - n_j) exceeds -this * |c_i - c_j|
  /// (a small tolerance, as in LCCP, keeps nearly flat noisy joints convex).
  float convex_tolerance = 0.05f;
  /// Segments smaller than this many pixels are merged into their cheapest neighbour.
  int min_segment_px = 120;

  /// True when every field is in range; otherwise names the bad field in `why`.
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
/// An invalid config (see SegmenterConfig::IsValid) makes Segment() return every valid point as
/// segment 0, so callers should check the config first.
class Segmenter {
 public:
  explicit Segmenter(const SegmenterConfig& config);
  [[nodiscard]] SegmentationResult Segment(const OrganizedCloud& cloud_C) const;

 private:
  SegmenterConfig config_;
};

/// How a detection box picks its 3D segment(s).
struct DetectionSegmentConfig {
  /// The box grows by this many pixels on every side (7-Scenes depth is not registered to
  /// colour: offsets of 10-20 px).
  float dilation_px = 12.f;
  /// ... plus this fraction of the box width/height on every side.
  float dilation_fraction = 0.05f;
  /// A segment is taken when at least this fraction of its pixels lies in the dilated box.
  float min_inside_fraction = 0.6f;
  /// Segments larger than this multiple of the dilated box area are never the object.
  float max_box_area_ratio = 1.0f;
  /// Segments with fewer pixels are ignored (noise, flying pixels at object borders).
  int min_segment_px = 30;
  /// Extra segments join the main one only when their mean depth is within this many metres
  /// (they are further parts of one object, not background seen through the box).
  float depth_gate_m = 0.5f;
  /// A further segment joins the object only when it raises the IoU between the object's image
  /// box and the detection box by at least this much (parts of a chair do; an object in front,
  /// already inside the box, does not).
  float min_iou_gain = 0.02f;
  /// When nothing passes min_inside_fraction, the largest non-plane segment with at least this
  /// fraction inside is returned alone.
  float fallback_inside_fraction = 0.5f;

  /// True when every field is in range; otherwise names the bad field in `why`.
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// The detection box grown by the config's dilation (not clipped to the image): the region the
/// object's pixels may occupy when colour and depth are not registered.
[[nodiscard]] BoundingBox2D DilateDetectionBox(const BoundingBox2D& box,
                                               const DetectionSegmentConfig& config);

/// Pixel indices (into the organized cloud), ascending, of the object a detection box shows: the
/// non-plane segment(s) that lie mostly inside the box. Box is in depth-image pixels.
/// Empty when nothing in the box qualifies (or when segmentation and cloud sizes differ).
[[nodiscard]] std::vector<int> SelectDetectionPixels(const SegmentationResult& segmentation,
                                                     const OrganizedCloud& cloud_C,
                                                     const BoundingBox2D& box,
                                                     const DetectionSegmentConfig& config);

struct SegmentIndex;  // segmentation/segment_index.h

/// The same from an index of `segmentation` (IndexSegments), built once for all boxes of a
/// frame: each box then costs its own area. Empty when the index is of another segmentation.
[[nodiscard]] std::vector<int> SelectDetectionPixels(const SegmentationResult& segmentation,
                                                     const SegmentIndex& index,
                                                     const BoundingBox2D& box,
                                                     const DetectionSegmentConfig& config);

}  // namespace objmap
