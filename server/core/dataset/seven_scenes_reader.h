#pragma once

#include <memory>
#include <string>

#include "dataset/sequence_reader.h"

namespace objmap {

/// 7-Scenes / 3DMatch layout: frame-NNNNNN.color.{jpg,png}, frame-NNNNNN.depth.png (16-bit mm,
/// 0 invalid), frame-NNNNNN.pose.txt (4x4 camera-to-world, metres), camera-intrinsics.txt (3x3).
/// Without camera-intrinsics.txt the Kinect defaults of 7-Scenes apply (585, 320, 240).
/// Returns nullptr when `folder` has no frame-*.depth.png.
[[nodiscard]] std::unique_ptr<SequenceReader> OpenSevenScenes(const std::string& folder,
                                                              std::string* why);

}  // namespace objmap
