#include "grpc_service/keyframe_conversions.h"

#include <cmath>
#include <cstring>
#include <sstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "grpc_service/conversions.h"
#include "types/image_header.h"

namespace objmap::grpc_service {
namespace {

// "JPEG (2)", or "99" for a number outside the enum (proto3 keeps unknown enum values).
std::string EncodingText(int encoding) {
  const std::string name = v1::Image::Encoding_IsValid(encoding)
                               ? v1::Image::Encoding_Name(static_cast<v1::Image::Encoding>(encoding))
                               : std::string();
  return name.empty() ? std::to_string(encoding)
                      : name + " (" + std::to_string(encoding) + ")";
}

std::string SizeText(std::int64_t width, std::int64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Raw encodings carry their size in width/height; it must match the intrinsics and the bytes.
bool CheckRawSize(const v1::Image& image, const std::string& field, int bytes_per_pixel,
                  const CameraIntrinsics& K, std::string* why) {
  if (image.width() != K.width || image.height() != K.height) {
    *why = field + ".width/height are " + SizeText(image.width(), image.height()) +
           " but the intrinsics say " + SizeText(K.width, K.height);
    return false;
  }
  const std::int64_t expected = std::int64_t{K.width} * K.height * bytes_per_pixel;
  if (static_cast<std::int64_t>(image.data().size()) != expected) {
    *why = field + ".data has " + std::to_string(image.data().size()) + " bytes but " +
           SizeText(K.width, K.height) + " x " + std::to_string(bytes_per_pixel) + " needs " +
           std::to_string(expected);
    return false;
  }
  return true;
}

// A JPEG ends with the EOI marker FF D9 (a few bytes of padding may follow). Inside the
// entropy-coded data every FF byte is followed by 00, so FF D9 only marks an end: without it the
// file was cut short, and the decoder would fill the missing rows with grey without an error.
bool EndsWithJpegEndMarker(const std::string& data) {
  constexpr std::size_t kTail = 64;
  const std::size_t from = data.size() > kTail ? data.size() - kTail : 0;
  for (std::size_t i = data.size(); i-- > from + 1;) {
    if (static_cast<unsigned char>(data[i - 1]) == 0xFF &&
        static_cast<unsigned char>(data[i]) == 0xD9) {
      return true;
    }
  }
  return false;
}

// Reads the size from the PNG/JPEG header and checks it before decoding, so that a bad or
// oversized image costs nothing to refuse.
bool CheckEncodedSize(const v1::Image& image, const std::string& field, const CameraIntrinsics& K,
                      std::string* why) {
  const bool png = image.encoding() == v1::Image::PNG;
  const char* format = png ? "PNG" : "JPEG";
  int width = 0;
  int height = 0;
  if (!(png ? ReadPngSize(image.data(), &width, &height)
            : ReadJpegSize(image.data(), &width, &height))) {
    *why = field + ".data (" + std::to_string(image.data().size()) + " bytes) is not a " + format +
           " image";
    return false;
  }
  if (!png && !EndsWithJpegEndMarker(image.data())) {
    *why = field + ".data (" + std::to_string(image.data().size()) +
           " bytes) is a truncated JPEG: no end-of-image marker";
    return false;
  }
  if ((image.width() != 0 || image.height() != 0) &&
      (image.width() != width || image.height() != height)) {
    *why = field + ".width/height say " + SizeText(image.width(), image.height()) + " but the " +
           format + " is " + SizeText(width, height);
    return false;
  }
  if (width != K.width || height != K.height) {
    *why = field + " is " + SizeText(width, height) + " but the intrinsics say " +
           SizeText(K.width, K.height);
    return false;
  }
  return true;
}

// imdecode with OpenCV's exceptions turned into a reason.
bool Decode(const std::string& data, int flags, const std::string& field, cv::Mat* decoded,
            std::string* why) {
  try {
    const cv::Mat buffer(1, static_cast<int>(data.size()), CV_8UC1, const_cast<char*>(data.data()));
    *decoded = cv::imdecode(buffer, flags);
  } catch (const cv::Exception& e) {
    *why = field + ".data could not be decoded: " + e.what();
    return false;
  }
  if (decoded->empty()) {
    *why = field + ".data could not be decoded";
    return false;
  }
  return true;
}

void CopyBgrAsRgb(const cv::Mat& bgr, ColorImage* color) {
  color->rgb.resize(static_cast<std::size_t>(bgr.cols) * bgr.rows * 3);
  for (int v = 0; v < bgr.rows; ++v) {
    const auto* row = bgr.ptr<cv::Vec3b>(v);
    std::uint8_t* rgb = color->rgb.data() + static_cast<std::size_t>(v) * bgr.cols * 3;
    for (int u = 0; u < bgr.cols; ++u) {
      rgb[3 * u] = row[u][2];
      rgb[3 * u + 1] = row[u][1];
      rgb[3 * u + 2] = row[u][0];
    }
  }
}

bool CheckPixelCount(const CameraIntrinsics& K, std::string* why) {
  if (std::int64_t{K.width} * K.height > kMaxImagePixels) {
    *why = "intrinsics: " + SizeText(K.width, K.height) + " exceeds the largest image served (" +
           std::to_string(kMaxImagePixels) + " pixels)";
    return false;
  }
  return true;
}

std::uint32_t ReadLe(const std::string& bytes, std::size_t offset, int size) {
  std::uint32_t value = 0;
  for (int i = 0; i < size; ++i) {
    value |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[offset + i])) << (8 * i);
  }
  return value;
}

// Non-finite, negative and out-of-range depths are no measurement.
float ValidDepth(double depth_m) {
  return std::isfinite(depth_m) && depth_m > 0.0 && depth_m <= kMaxDepthM
             ? static_cast<float>(depth_m)
             : 0.f;
}

bool DepthScale(const v1::Image& image, double* scale, std::string* why) {
  *scale = image.depth_scale() == 0.0 ? kDefaultDepthScale : image.depth_scale();
  // A metre or more per unit is no depth camera; larger scales only overflow.
  if (!(*scale > 0.0 && *scale <= kMaxDepthScale)) {
    std::ostringstream text;
    text << "depth.depth_scale " << image.depth_scale()
         << " must lie in (0, 1] metres per unit (0: millimetres)";
    *why = text.str();
    return false;
  }
  return true;
}

bool DecodeDepthPng(const v1::Image& image, double scale, DepthImage* depth, std::string* why) {
  cv::Mat units;
  if (!Decode(image.data(), cv::IMREAD_UNCHANGED, "depth", &units, why)) return false;
  if (units.type() != CV_16UC1) {
    *why = "depth: the PNG has " + std::to_string(units.elemSize1() * 8) + "-bit samples and " +
           std::to_string(units.channels()) + " channel(s); depth needs 16-bit single-channel";
    return false;
  }
  for (int v = 0; v < units.rows; ++v) {
    const auto* row = units.ptr<std::uint16_t>(v);
    for (int u = 0; u < units.cols; ++u) {
      depth->depth_m[static_cast<std::size_t>(v) * units.cols + u] = ValidDepth(row[u] * scale);
    }
  }
  return true;
}

}  // namespace

bool DecodeColorImage(const v1::Image& image, const CameraIntrinsics& K, ColorImage* color,
                      std::string* why) {
  if (!CheckPixelCount(K, why)) return false;
  color->width = K.width;
  color->height = K.height;
  switch (image.encoding()) {
    case v1::Image::RAW_RGB8:
      if (!CheckRawSize(image, "color", 3, K, why)) return false;
      color->rgb.assign(image.data().begin(), image.data().end());
      return true;
    case v1::Image::PNG:
    case v1::Image::JPEG:
      break;
    default:
      *why = "color.encoding " + EncodingText(image.encoding()) +
             " is not a colour encoding (PNG, JPEG or RAW_RGB8)";
      return false;
  }
  cv::Mat bgr;
  if (!CheckEncodedSize(image, "color", K, why) ||
      !Decode(image.data(), cv::IMREAD_COLOR, "color", &bgr, why)) {
    return false;
  }
  if (bgr.cols != K.width || bgr.rows != K.height) {  // the header lied
    *why = "color decodes to " + SizeText(bgr.cols, bgr.rows) + " but the intrinsics say " +
           SizeText(K.width, K.height);
    return false;
  }
  CopyBgrAsRgb(bgr, color);
  return true;
}

bool DecodeDepthImage(const v1::Image& image, const CameraIntrinsics& K, DepthImage* depth,
                      std::string* why) {
  if (!CheckPixelCount(K, why)) return false;
  const std::size_t pixels = static_cast<std::size_t>(K.width) * K.height;
  double scale = kDefaultDepthScale;
  if (!DepthScale(image, &scale, why)) return false;
  depth->width = K.width;
  depth->height = K.height;
  depth->depth_m.assign(pixels, 0.f);
  switch (image.encoding()) {
    case v1::Image::RAW_DEPTH_U16:
      if (!CheckRawSize(image, "depth", 2, K, why)) return false;
      for (std::size_t i = 0; i < pixels; ++i) {
        depth->depth_m[i] = ValidDepth(ReadLe(image.data(), 2 * i, 2) * scale);
      }
      return true;
    case v1::Image::RAW_DEPTH_F32:
      if (!CheckRawSize(image, "depth", 4, K, why)) return false;
      for (std::size_t i = 0; i < pixels; ++i) {
        const std::uint32_t bits = ReadLe(image.data(), 4 * i, 4);
        float depth_m;
        std::memcpy(&depth_m, &bits, sizeof(depth_m));
        depth->depth_m[i] = ValidDepth(depth_m);
      }
      return true;
    case v1::Image::PNG:
      if (!CheckEncodedSize(image, "depth", K, why)) return false;
      return DecodeDepthPng(image, scale, depth, why);
    default:
      *why = "depth.encoding " + EncodingText(image.encoding()) +
             " is not a depth encoding (PNG, RAW_DEPTH_U16 or RAW_DEPTH_F32)";
      return false;
  }
}

bool WithinLimits(const v1::AddKeyframeRequest& request, const RequestLimits& limits,
                  std::string* why) {
  const auto too_long = [&](const std::string& text, const std::string& field) {
    if (static_cast<std::int64_t>(text.size()) <= limits.max_string_bytes) return false;
    *why = field + " is " + std::to_string(text.size()) + " bytes; the server takes at most " +
           std::to_string(limits.max_string_bytes) + " (server.max_string_bytes)";
    return true;
  };
  if (too_long(request.name(), "name")) return false;
  if (request.detections_size() > limits.max_detections_per_keyframe) {
    *why = "detections has " + std::to_string(request.detections_size()) +
           " entries; the server takes at most " +
           std::to_string(limits.max_detections_per_keyframe) +
           " per keyframe (server.max_detections_per_keyframe)";
    return false;
  }
  for (int i = 0; i < request.detections_size(); ++i) {
    if (too_long(request.detections(i).class_name(),
                 "detections[" + std::to_string(i) + "].class_name")) {
      return false;
    }
  }
  const std::int64_t pixels =
      std::int64_t{request.intrinsics().width()} * request.intrinsics().height();
  if (pixels > limits.max_image_pixels) {
    *why = "intrinsics: " + SizeText(request.intrinsics().width(), request.intrinsics().height()) +
           " is " + std::to_string(pixels) + " pixels; the server decodes at most " +
           std::to_string(limits.max_image_pixels) + " (server.max_image_pixels)";
    return false;
  }
  return true;
}

bool FrameFromRequest(const v1::AddKeyframeRequest& request, const RequestLimits& limits,
                      bool pose_optional, RgbdFrame* frame,
                      std::optional<std::vector<Detection>>* detections,
                      grpc::StatusCode* code, std::string* why) {
  // The limits first: they cost nothing to check and bound what the rest may cost.
  if (!WithinLimits(request, limits, why)) {
    *code = grpc::StatusCode::RESOURCE_EXHAUSTED;
    return false;
  }
  *code = grpc::StatusCode::INVALID_ARGUMENT;
  if (!IntrinsicsFromProto(request.intrinsics(), &frame->intrinsics, why) ||
      (!(pose_optional && !request.has_t_w_c()) &&
       !PoseFromProto(request.t_w_c(), "T_W_C", &frame->T_W_C, why))) {
    return false;
  }
  if (!std::isfinite(request.stamp())) {
    *why = "stamp must be finite";
    return false;
  }
  frame->stamp_s = request.stamp();
  frame->name = request.name();
  if (!DecodeColorImage(request.color(), frame->intrinsics, &frame->color, why) ||
      !DecodeDepthImage(request.depth(), frame->intrinsics, &frame->depth, why)) {
    return false;
  }
  if (!request.detections_given()) {
    if (request.detections_size() > 0) {
      *why = "detections has " + std::to_string(request.detections_size()) +
             " entries but detections_given is false";
      return false;
    }
    detections->reset();
    return true;
  }
  detections->emplace();
  (*detections)->resize(request.detections_size());
  for (int i = 0; i < request.detections_size(); ++i) {
    if (!DetectionFromProto(request.detections(i), "detections[" + std::to_string(i) + "]",
                            &(**detections)[i], why)) {
      return false;
    }
  }
  return true;
}

}  // namespace objmap::grpc_service
