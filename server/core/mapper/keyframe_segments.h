#pragma once
// Turning one keyframe's detections into object observations (paper Sec. III-B, last step):
// each detection box picks its 3D segment; detections that pick the same segment are fused.

#include <vector>

#include "mapper/mapper.h"
#include "objects/object_map.h"
#include "segmentation/segmenter.h"
#include "types/organized_cloud.h"

namespace objmap {

/// One detection with its segment, ready for association.
struct SegmentedDetection {
  ObjectObservation observation;  ///< segment in the camera frame, model resolution
  std::vector<int> pixels;        ///< indices into the organized cloud
};

/// True when detection `d` is of one of MapperConfig::part_classes and its box lies
/// part_inside_fraction inside the box, min_whole_to_part_area times larger, of another usable
/// detection of one of whole_classes.
[[nodiscard]] bool IsPartOfAnotherDetection(const std::vector<Detection>& detections, std::size_t d,
                                            const MapperConfig& config);

/// Scales a colour-image box into depth-image pixels.
[[nodiscard]] BoundingBox2D ToDepthPixels(const BoundingBox2D& box, const ColorImage& color,
                                          const DepthImage& depth);

/// Picks the segment of every usable detection and fuses detections of one segment: a segment
/// claimed >= 50 % by an earlier (higher-scoring) detection adds the later detection's class score
/// to that observation instead of becoming a second observation of the same thing. Exceptions:
/// two same-class detections with distinct boxes (IoU below MapperConfig::split_max_box_iou)
/// share the segment out by box; detections of a stack class (MapperConfig::stack_classes) that
/// pick one segment cut it by height above the supporting plane under it, one layer per box at a
/// distinct height; and nothing fuses into a surface-class (table) observation. Detections of a
/// part inside a whole (IsPartOfAnotherDetection) are left out.
/// `index` is IndexSegments(segmentation, cloud_C), built once per keyframe for this and
/// UnclassifiedSegments. Observations' points are made from `depth_mm`, the frame's depth as the
/// keyframe keeps it (DepthMillimetres), with SegmentPointsFromDepth: the store rebuilds them
/// from the same.
[[nodiscard]] std::vector<SegmentedDetection> SegmentDetections(
    const RgbdFrame& frame, const OrganizedCloud& cloud_C,
    const std::vector<std::uint16_t>& depth_mm, const SegmentationResult& segmentation,
    const SegmentIndex& index, const std::vector<Detection>& detections, KeyframeId keyframe_id,
    const MapperConfig& config);

/// Object-like segments of a keyframe that no detection picked (SegmentDetections' `detected`):
/// non-plane segments that lie whole in the image, stand on an up-facing supporting plane and
/// are free at their top (no surface they hold up, not hidden, not continuing into something
/// else); those that meet with continuous depth are one thing, kept when it has an object's
/// size (UnknownObjectConfig). Each becomes an observation of class kUnknownClassId with score
/// 0, boxed by its pixels' extent in colour pixels. Segments mostly inside a detection's
/// (dilated) box are parts of what the detector named (a chair's legs, the lower part of a
/// table) and are left out; so are those that detections claimed a share of.
[[nodiscard]] std::vector<SegmentedDetection> UnclassifiedSegments(
    const RgbdFrame& frame, const OrganizedCloud& cloud_C,
    const std::vector<std::uint16_t>& depth_mm, const SegmentationResult& segmentation,
    const SegmentIndex& index, const std::vector<Detection>& detections,
    const std::vector<SegmentedDetection>& detected, KeyframeId keyframe_id,
    const MapperConfig& config);

}  // namespace objmap
