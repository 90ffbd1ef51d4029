#pragma once
// AddKeyframeRequest -> RgbdFrame (+ caller detections): image decoding (OpenCV stays in the .cc)
// and every check that names a request field.

#include <optional>
#include <string>
#include <vector>

#include <grpcpp/support/status_code_enum.h>

#include "map_server/request_limits.h"
#include "objmap.pb.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap::grpc_service {

/// Images larger than this many pixels are refused before decoding whatever the configured
/// limit (RequestLimits::max_image_pixels, checked by FrameFromRequest): a small PNG can expand
/// to gigabytes, and no RGB-D camera comes near this.
inline constexpr std::int64_t kMaxImagePixels = std::int64_t{1} << 26;

/// Metres per unit of 16-bit depth may not exceed this.
inline constexpr double kMaxDepthScale = 1.0;

/// Metres per unit of 16-bit depth when the request leaves depth_scale at 0.
inline constexpr double kDefaultDepthScale = 0.001;

/// Decodes the colour image (PNG, JPEG or RAW_RGB8) into RGB8. Its size must equal the
/// intrinsics'; errors name "color" / "color.data" and both sizes.
[[nodiscard]] bool DecodeColorImage(const v1::Image& image, const CameraIntrinsics& intrinsics,
                                    ColorImage* color, std::string* why);

/// Decodes the depth image (16-bit PNG or RAW_DEPTH_U16 times depth_scale, or RAW_DEPTH_F32
/// metres) into metres; non-finite, negative and farther than kMaxDepthM metres become 0 (no
/// depth). Its size must equal
/// the intrinsics'; errors name "depth" / "depth.data" and both sizes.
[[nodiscard]] bool DecodeDepthImage(const v1::Image& image, const CameraIntrinsics& intrinsics,
                                    DepthImage* depth, std::string* why);

/// The frame of a request (intrinsics, T_W_C, stamp, images) and its detections: set when the
/// request says detections_given, otherwise nullopt (the server's detector runs). False with a
/// reason naming the field ("T_W_C.qw ...", "detections[3].class_name ...") and `code`:
/// RESOURCE_EXHAUSTED beyond `limits` (checked before anything is decoded), INVALID_ARGUMENT
/// otherwise. With `pose_optional` (a server that estimates poses) an unset T_W_C is the
/// identity; a set one is still checked.
[[nodiscard]] bool FrameFromRequest(const v1::AddKeyframeRequest& request,
                                    const RequestLimits& limits, bool pose_optional,
                                    RgbdFrame* frame,
                                    std::optional<std::vector<Detection>>* detections,
                                    grpc::StatusCode* code, std::string* why);

}  // namespace objmap::grpc_service
