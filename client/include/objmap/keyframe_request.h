#pragma once
// Turning a frame of the core (types/frame.h) into an AddKeyframeRequest and back. The image
// codecs (OpenCV) stay inside the library.

#include <string>
#include <vector>

#include "objmap.pb.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// How frames are encoded for the wire.
struct KeyframeEncoding {
  enum class Color { kPng, kJpeg };
  /// PNG is lossless; JPEG is about 10x smaller and fine for detection and colouring.
  Color color = Color::kPng;
  /// JPEG quality, 1..100.
  int jpeg_quality = 95;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Fills `request` from the frame: colour as PNG or JPEG, depth as a 16-bit PNG in millimetres
/// (depth_scale 0.001; NaN, non-positive and beyond 65.535 m become 0, invalid), intrinsics,
/// T_W_C, stamp and name. `detections` null leaves detections_given false (the server detects);
/// otherwise they are copied with class names and detections_given is set. False with a reason
/// naming the frame when it has no depth or an image cannot be encoded.
[[nodiscard]] bool MakeAddKeyframeRequest(const RgbdFrame& frame,
                                          const std::vector<Detection>* detections,
                                          const KeyframeEncoding& encoding,
                                          v1::AddKeyframeRequest* request, std::string* why);

/// Decodes the images of a request made by MakeAddKeyframeRequest (PNG or JPEG colour, 16-bit
/// PNG depth) back into a frame: what the server sees. Used by tests and tools.
[[nodiscard]] bool DecodeAddKeyframeRequest(const v1::AddKeyframeRequest& request, RgbdFrame* frame,
                                            std::string* why);

}  // namespace objmap
