#pragma once

#include <algorithm>

namespace objmap {

/// Axis-aligned box in pixel coordinates (x right, y down), inclusive of x_min/y_min.
struct BoundingBox2D {
  float x_min = 0.f;
  float y_min = 0.f;
  float x_max = 0.f;
  float y_max = 0.f;

  [[nodiscard]] float Width() const { return x_max - x_min; }
  [[nodiscard]] float Height() const { return y_max - y_min; }
  [[nodiscard]] float Area() const {
    return Width() > 0.f && Height() > 0.f ? Width() * Height() : 0.f;
  }
};

/// Intersection over union of two boxes; 0 when either is empty.
[[nodiscard]] inline float BoxIoU(const BoundingBox2D& a, const BoundingBox2D& b) {
  const BoundingBox2D overlap{std::max(a.x_min, b.x_min), std::max(a.y_min, b.y_min),
                              std::min(a.x_max, b.x_max), std::min(a.y_max, b.y_max)};
  const float intersection = overlap.Area();
  const float united = a.Area() + b.Area() - intersection;
  return united > 0.f ? intersection / united : 0.f;
}

/// Share of `part`'s area that lies inside `whole`; 0 when `part` is empty.
[[nodiscard]] inline float BoxInsideFraction(const BoundingBox2D& part,
                                             const BoundingBox2D& whole) {
  const BoundingBox2D overlap{std::max(part.x_min, whole.x_min), std::max(part.y_min, whole.y_min),
                              std::min(part.x_max, whole.x_max), std::min(part.y_max, whole.y_max)};
  const float area = part.Area();
  return area > 0.f ? overlap.Area() / area : 0.f;
}

/// One object detection on a colour image.
struct Detection {
  BoundingBox2D box;  ///< in colour-image pixels
  int class_id = -1;  ///< COCO class index 0..79 (see coco_classes.h)
  float score = 0.f;  ///< detector confidence in [0, 1]
};

}  // namespace objmap
