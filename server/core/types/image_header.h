#pragma once
// Image sizes read from PNG and JPEG headers without decoding, so that requests and stored blobs
// whose images do not match their intrinsics (or would expand to gigabytes) are refused before
// any decoding.

#include <string_view>

namespace objmap {

/// Width and height from a PNG's IHDR chunk; false when `data` does not start like a PNG.
[[nodiscard]] bool ReadPngSize(std::string_view data, int* width, int* height);

/// Width and height from a JPEG's first start-of-frame segment (baseline, progressive, ...);
/// false when `data` is not a JPEG or ends before one.
[[nodiscard]] bool ReadJpegSize(std::string_view data, int* width, int* height);

}  // namespace objmap
