#pragma once
// Bounds on what one request may ask of the server, so that no single client can take the
// memory or the mapping thread from the others. Answers beyond a limit are kResourceExhausted
// (RESOURCE_EXHAUSTED over gRPC) with a message naming the field and the limit.

#include <cstdint>
#include <string>

namespace objmap {

struct RequestLimits {
  /// Largest image (width x height of the intrinsics) decoded, checked before decoding: a PNG of
  /// a few hundred kilobytes can expand to gigabytes. 4096 x 3072 is the largest colour mode of
  /// common RGB-D cameras (Azure Kinect).
  std::int64_t max_image_pixels = std::int64_t{4096} * 3072;
  /// Detections one keyframe may bring: each costs a segment search on the mapping thread, which
  /// every other write waits for. Detectors give at most a few hundred.
  int max_detections_per_keyframe = 1000;
  /// Poses one UpdatePoses may carry (a pose graph of this many keyframes).
  int max_poses_per_update = 1000000;
  /// Longest text field (keyframe name, class name), bytes.
  int max_string_bytes = 1024;

  [[nodiscard]] bool IsValid(std::string* why) const {
    if (max_image_pixels < 1 || max_detections_per_keyframe < 0 || max_poses_per_update < 1 ||
        max_string_bytes < 1) {
      *why =
          "server: max_image_pixels, max_poses_per_update and max_string_bytes must be "
          ">= 1 and max_detections_per_keyframe >= 0";
      return false;
    }
    return true;
  }
};

}  // namespace objmap
