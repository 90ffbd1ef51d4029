// Untrusted image bytes: the PNG and JPEG header readers, then the colour and depth decoders
// with the size the header claims (bounded, as the server's limits bound it).
#include <cstdint>
#include <string>

#include "types/image_header.h"
#include "grpc_service/keyframe_conversions.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  int width = 0, height = 0;
  const bool png = objmap::ReadPngSize(bytes, &width, &height);
  if (!png && !objmap::ReadJpegSize(bytes, &width, &height)) return 0;
  if (width <= 0 || height <= 0 || static_cast<std::int64_t>(width) * height > (1 << 16)) {
    return 0;
  }
  objmap::CameraIntrinsics K;
  K.width = width;
  K.height = height;
  K.fx = K.fy = 500.0;
  K.cx = width / 2.0;
  K.cy = height / 2.0;
  objmap::v1::Image image;
  image.set_encoding(png ? objmap::v1::Image::PNG : objmap::v1::Image::JPEG);
  image.set_data(bytes);
  std::string why;
  objmap::ColorImage color;
  if (objmap::grpc_service::DecodeColorImage(image, K, &color, &why) &&
      color.rgb.size() != static_cast<std::size_t>(width) * height * 3) {
    __builtin_trap();
  }
  objmap::DepthImage depth;
  if (png && objmap::grpc_service::DecodeDepthImage(image, K, &depth, &why) &&
      depth.depth_m.size() != static_cast<std::size_t>(width) * height) {
    __builtin_trap();
  }
  return 0;
}
