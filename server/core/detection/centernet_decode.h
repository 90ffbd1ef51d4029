#pragma once
// Turns CenterNet's raw head outputs into boxes. Kept free of OpenCV and of the network so the
// decoding can be tested on hand-made heatmaps.

#include <string>
#include <vector>

#include "types/detection.h"

namespace objmap {

/// Geometry and thresholds of one decoding pass.
struct CenterNetDecodeParams {
  /// Number of heatmap channels (classes).
  int num_classes = 80;
  /// Heatmap rows and columns.
  int grid_height = 128;
  int grid_width = 128;
  /// Network input pixels per heatmap cell.
  float stride_px = 4.f;
  /// Factors from network input pixels to original image pixels (x and y).
  float scale_x = 1.f;
  float scale_y = 1.f;
  /// Original image size; boxes are clipped to it.
  float image_width = 512.f;
  float image_height = 512.f;
  /// A cell is kept only when its score reaches this value.
  float score_threshold = 0.15f;
  /// At most this many detections are returned, best first.
  int max_detections = 100;
  /// Same-class boxes overlapping a better one by more than this IoU are dropped; >= 1 disables.
  float nms_iou = 0.6f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Decodes a heatmap (CHW: num_classes x grid_height x grid_width, scores in [0, 1]) and box
/// distances (CHW: 4 x grid_height x grid_width; left, top, right, bottom in network input pixels).
/// A cell is a peak when it is the maximum of its 3x3 neighbourhood in its own class channel and
/// reaches the threshold; its box is the cell centre (cell * stride) minus left/top and plus
/// right/bottom, scaled to the original image. Result is sorted by descending score.
[[nodiscard]] std::vector<Detection> DecodeCenterNet(const float* heatmap_chw, const float* box_chw,
                                                     const CenterNetDecodeParams& params);

/// Greedy class-wise non-maximum suppression: walks detections by descending score and drops
/// each one that overlaps a kept detection of the same class by more than `iou_threshold`.
[[nodiscard]] std::vector<Detection> ClassWiseNms(std::vector<Detection> detections,
                                                  float iou_threshold);

}  // namespace objmap
