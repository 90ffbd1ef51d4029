// Untrusted bytes as the server receives them: an AddKeyframeRequest decoded, held to the
// request limits and validated, with its images' headers read and the images decoded.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "grpc_service/keyframe_conversions.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  objmap::v1::AddKeyframeRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;
  objmap::RequestLimits limits;
  limits.max_image_pixels = 1 << 16;  // large images only cost time, not coverage
  objmap::RgbdFrame frame;
  std::optional<std::vector<objmap::Detection>> detections;
  grpc::StatusCode code = grpc::StatusCode::OK;
  std::string why;
  // Both kinds of server: pose required, and pose estimated (an unset pose allowed).
  const bool pose_optional = size % 2 == 1;
  if (objmap::grpc_service::FrameFromRequest(request, limits, pose_optional, &frame, &detections,
                                             &code, &why)) {
    // What the server does next with an accepted frame.
    if (!objmap::ValidateFrame(frame, &why)) __builtin_trap();
  }
  return 0;
}
