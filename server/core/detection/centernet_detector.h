#pragma once

#include <memory>
#include <string>

#include "detection/detector.h"

namespace objmap {

/// CenterNet (MobileNetV3 backbone, 80 COCO classes) run through OpenCV DNN.
struct CenterNetConfig {
  /// Frozen TensorFlow GraphDef made by scripts/convert_centernet.py.
  std::string model_path = "models/centernet_coco.pb";
  /// Peaks below this score are dropped. Low on purpose: multi-view accumulation in the object
  /// map separates real objects from one-off mistakes (paper Sec. III-D).
  float score_threshold = 0.15f;
  /// Network input side in pixels. The converted graph fixes its upsampling sizes for 512, so
  /// other values only suit other conversions; a mismatch fails Detect() with a reason.
  int input_size = 512;
  /// Upper bound on detections per image, best first.
  int max_detections = 100;
  /// OpenCV DNN threads; 0 keeps OpenCV's default. OpenCV applies this process-wide.
  int num_threads = 0;
  /// Same-class boxes overlapping a better one by more than this IoU are dropped; 1 disables.
  float nms_iou = 0.6f;
  /// Small objects: with N >= 2 the network also runs on N x N overlapping tiles of the image,
  /// each resized to the input (objects appear about N times larger), and the tiles' detections
  /// join the whole image's (detection/tiling.h). Costs N * N more network passes per image;
  /// 1: the whole image only.
  int tiles_per_side = 1;
  /// Neighbouring tiles overlap by this fraction of a tile's side.
  float tile_overlap = 0.25f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Loads the network; returns nullptr and a reason naming the file when it cannot.
[[nodiscard]] std::unique_ptr<Detector> MakeCenterNetDetector(const CenterNetConfig& config,
                                                              std::string* why);

}  // namespace objmap
