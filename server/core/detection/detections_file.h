#pragma once
// Detections supplied from outside: a robot that runs its own detector, or a recorded run that
// is replayed. File format (JSON):
//   {"frames": {"<frame name or index>": [
//       {"box": [x_min, y_min, x_max, y_max], "class": "cup", "score": 0.8}, ...]}}
// Boxes are in colour-image pixels, classes are COCO names (coco_classes.h), "score" is optional
// (default 1).

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "detection/detector.h"
#include "types/detection.h"

namespace objmap {

/// Detections keyed by frame name or by frame index written as a decimal string.
using DetectionsByFrame = std::map<std::string, std::vector<Detection>>;

/// Parses the JSON text of a detections file. On failure names the frame and entry at fault.
[[nodiscard]] bool ParseDetectionsJson(const std::string& text, DetectionsByFrame* frames,
                                       std::string* why);

/// Reads a detections file; the reason on failure starts with the path.
[[nodiscard]] bool ReadDetectionsFile(const std::string& path, DetectionsByFrame* frames,
                                      std::string* why);

/// Writes detections in the same format, so a run can be replayed. Fails on invalid class ids.
[[nodiscard]] bool WriteDetectionsFile(const std::string& path, const DetectionsByFrame& frames,
                                       std::string* why);

/// Settings of the file-backed detector.
struct DetectionsFileConfig {
  /// JSON file in the format above.
  std::string path;
  /// When true a frame the file does not list is an error; when false it has no detections
  /// (files recorded from a detector often omit empty frames).
  bool require_every_frame = false;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Reads the whole file up front; a frame is looked up by RgbdFrame::name first, then by its
/// frame_index. Returns nullptr and a reason when the file cannot be read or parsed.
[[nodiscard]] std::unique_ptr<Detector> MakeDetectionsFileDetector(
    const DetectionsFileConfig& config, std::string* why);

}  // namespace objmap
