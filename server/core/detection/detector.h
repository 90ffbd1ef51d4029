#pragma once

#include <memory>
#include <string>
#include <vector>

#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// Produces COCO detections for a frame's colour image.
/// Implementations are not required to be thread-safe: use one instance per thread.
class Detector {
 public:
  virtual ~Detector() = default;

  /// Fills `detections` (boxes in colour pixels). Returns false with a reason naming the frame
  /// when the frame cannot be processed; an image without objects is success with no detections.
  [[nodiscard]] virtual bool Detect(const RgbdFrame& frame, std::vector<Detection>* detections,
                                    std::string* why) = 0;

  /// Short name for logs ("centernet", "file").
  [[nodiscard]] virtual std::string Name() const = 0;
};

}  // namespace objmap
