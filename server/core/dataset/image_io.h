#pragma once
// Image decoding shared by the sequence readers; OpenCV stays inside image_io.cc.

#include <string>

#include "types/frame.h"

namespace objmap {

/// Decodes a colour image file (JPEG, PNG) into RGB8. False with a reason naming the file.
[[nodiscard]] bool ReadColorImage(const std::string& path, ColorImage* image, std::string* why);

/// Decodes a 16-bit depth PNG; metres = raw / depth_units_per_metre (1000 for 7-Scenes, 5000 for
/// TUM); 0 stays 0 (invalid). False with a reason naming the file when it is not 16-bit.
[[nodiscard]] bool ReadDepthImage(const std::string& path, double depth_units_per_metre,
                                  DepthImage* image, std::string* why);

/// Reads `rows` x `cols` whitespace-separated numbers from a text file (poses, intrinsics).
[[nodiscard]] bool ReadMatrixText(const std::string& path, int rows, int cols, double* values,
                                  std::string* why);

}  // namespace objmap
