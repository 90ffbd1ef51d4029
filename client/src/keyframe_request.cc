#include "objmap/keyframe_request.h"

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "objmap/conversions.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// Depth goes on the wire in millimetres, as RGB-D sensors deliver it.
constexpr double kDepthScale = 0.001;
constexpr double kMaxDepthUnits = 65535.0;

bool EncodeColor(const ColorImage& color, const KeyframeEncoding& encoding, v1::Image* image,
                 std::string* why) {
  if (color.rgb.size() != static_cast<std::size_t>(color.width) * color.height * 3) {
    *why = "colour buffer size does not match its width and height";
    return false;
  }
  cv::Mat bgr(color.height, color.width, CV_8UC3);
  for (int v = 0; v < color.height; ++v) {
    const std::uint8_t* rgb = color.rgb.data() + static_cast<std::size_t>(v) * color.width * 3;
    auto* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < color.width; ++u) row[u] = {rgb[3 * u + 2], rgb[3 * u + 1], rgb[3 * u]};
  }
  const bool jpeg = encoding.color == KeyframeEncoding::Color::kJpeg;
  std::vector<int> params;
  if (jpeg) params = {cv::IMWRITE_JPEG_QUALITY, encoding.jpeg_quality};
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(jpeg ? ".jpg" : ".png", bgr, bytes, params)) {
    *why = "colour image could not be encoded";
    return false;
  }
  image->set_encoding(jpeg ? v1::Image::JPEG : v1::Image::PNG);
  image->set_width(color.width);
  image->set_height(color.height);
  image->set_data(bytes.data(), bytes.size());
  return true;
}

bool EncodeDepth(const DepthImage& depth, v1::Image* image, std::string* why) {
  if (depth.empty() ||
      depth.depth_m.size() != static_cast<std::size_t>(depth.width) * depth.height) {
    *why = "depth image is empty or its buffer does not match its width and height";
    return false;
  }
  cv::Mat units(depth.height, depth.width, CV_16UC1);
  for (int v = 0; v < depth.height; ++v) {
    const float* depth_m = depth.depth_m.data() + static_cast<std::size_t>(v) * depth.width;
    auto* row = units.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth.width; ++u) {
      const double value = std::round(depth_m[u] / kDepthScale);
      // NaN fails both comparisons and becomes 0 too.
      row[u] = value > 0.0 && value <= kMaxDepthUnits ? static_cast<std::uint16_t>(value) : 0;
    }
  }
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".png", units, bytes)) {
    *why = "depth image could not be encoded";
    return false;
  }
  image->set_encoding(v1::Image::PNG);
  image->set_width(depth.width);
  image->set_height(depth.height);
  image->set_depth_scale(kDepthScale);
  image->set_data(bytes.data(), bytes.size());
  return true;
}

void CopyDetections(const std::vector<Detection>& detections, v1::AddKeyframeRequest* request) {
  request->set_detections_given(true);
  for (const Detection& detection : detections) {
    v1::Detection* out = request->add_detections();
    out->set_x_min(detection.box.x_min);
    out->set_y_min(detection.box.y_min);
    out->set_x_max(detection.box.x_max);
    out->set_y_max(detection.box.y_max);
    out->set_class_id(detection.class_id);
    out->set_class_name(std::string(CocoClassName(detection.class_id)));
    out->set_score(detection.score);
  }
}

void CopyIntrinsics(const CameraIntrinsics& K, v1::CameraIntrinsics* out) {
  out->set_width(K.width);
  out->set_height(K.height);
  out->set_fx(K.fx);
  out->set_fy(K.fy);
  out->set_cx(K.cx);
  out->set_cy(K.cy);
}

bool DecodeColor(const v1::Image& image, ColorImage* color, std::string* why) {
  const std::string& data = image.data();
  const cv::Mat bytes(1, static_cast<int>(data.size()), CV_8UC1, const_cast<char*>(data.data()));
  const cv::Mat bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
  if (bgr.empty()) {
    *why = "colour image could not be decoded";
    return false;
  }
  color->width = bgr.cols;
  color->height = bgr.rows;
  color->rgb.resize(static_cast<std::size_t>(bgr.cols) * bgr.rows * 3);
  for (int v = 0; v < bgr.rows; ++v) {
    const auto* row = bgr.ptr<cv::Vec3b>(v);
    std::uint8_t* rgb = color->rgb.data() + static_cast<std::size_t>(v) * bgr.cols * 3;
    for (int u = 0; u < bgr.cols; ++u) {
      for (int c = 0; c < 3; ++c) rgb[3 * u + c] = row[u][2 - c];
    }
  }
  return true;
}

bool DecodeDepth(const v1::Image& image, DepthImage* depth, std::string* why) {
  const std::string& data = image.data();
  const cv::Mat bytes(1, static_cast<int>(data.size()), CV_8UC1, const_cast<char*>(data.data()));
  const cv::Mat units = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  if (units.empty() || units.type() != CV_16UC1) {
    *why = "depth image is not a 16-bit single-channel PNG";
    return false;
  }
  const double scale = image.depth_scale() > 0.0 ? image.depth_scale() : kDepthScale;
  depth->width = units.cols;
  depth->height = units.rows;
  depth->depth_m.resize(static_cast<std::size_t>(units.cols) * units.rows);
  for (int v = 0; v < units.rows; ++v) {
    const auto* row = units.ptr<std::uint16_t>(v);
    for (int u = 0; u < units.cols; ++u) {
      depth->depth_m[static_cast<std::size_t>(v) * units.cols + u] =
          static_cast<float>(row[u] * scale);
    }
  }
  return true;
}

}  // namespace

bool KeyframeEncoding::IsValid(std::string* why) const {
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    *why = "encoding.jpeg_quality must be in 1..100, got " + std::to_string(jpeg_quality);
    return false;
  }
  return true;
}

bool MakeAddKeyframeRequest(const RgbdFrame& frame, const std::vector<Detection>* detections,
                            const KeyframeEncoding& encoding, v1::AddKeyframeRequest* request,
                            std::string* why) {
  std::string reason;
  if (!encoding.IsValid(&reason) ||
      (!frame.color.empty() &&
       !EncodeColor(frame.color, encoding, request->mutable_color(), &reason)) ||
      !EncodeDepth(frame.depth, request->mutable_depth(), &reason)) {
    *why = (frame.name.empty() ? "frame " + std::to_string(frame.frame_index) : frame.name) + ": " +
           reason;
    return false;
  }
  CopyIntrinsics(frame.intrinsics, request->mutable_intrinsics());
  *request->mutable_t_w_c() = PoseToProto(frame.T_W_C);
  request->set_stamp(frame.stamp_s);
  request->set_name(frame.name);
  if (detections != nullptr) CopyDetections(*detections, request);
  return true;
}

bool DecodeAddKeyframeRequest(const v1::AddKeyframeRequest& request, RgbdFrame* frame,
                              std::string* why) {
  std::string reason;
  const bool ok =
      (request.color().data().empty() || DecodeColor(request.color(), &frame->color, &reason)) &&
      DecodeDepth(request.depth(), &frame->depth, &reason) &&
      PoseFromProto(request.t_w_c(), &frame->T_W_C, &reason);
  if (!ok) {
    *why = request.name() + ": " + reason;
    return false;
  }
  const v1::CameraIntrinsics& K = request.intrinsics();
  frame->intrinsics = {K.width(), K.height(), K.fx(), K.fy(), K.cx(), K.cy()};
  frame->stamp_s = request.stamp();
  frame->name = request.name();
  return true;
}

}  // namespace objmap
