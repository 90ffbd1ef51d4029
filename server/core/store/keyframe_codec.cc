#include "store/keyframe_codec.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string_view>

#include "types/image_header.h"

namespace objmap {
namespace store_internal {
namespace {

// Blobs are written in the host's byte order with memcpy; every platform we build on is
// little-endian, which keeps files portable between them.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "store blobs assume little-endian");

template <typename T>
void Append(const T& value, Bytes* out) {
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
  out->insert(out->end(), bytes, bytes + sizeof(T));
}

template <typename T>
T Read(const std::uint8_t* data, std::size_t offset) {
  T value;
  std::memcpy(&value, data + offset, sizeof(T));
  return value;
}

// RGB <-> BGR (OpenCV's codecs speak BGR); `bytes` is a multiple of 3.
void SwapRedBlue(const std::uint8_t* in, std::uint8_t* out, std::size_t bytes) {
  for (std::size_t i = 0; i < bytes; i += 3) {
    out[i] = in[i + 2];
    out[i + 1] = in[i + 1];
    out[i + 2] = in[i];
  }
}

// PNG level 1: storing a keyframe sits on the ingest path, where speed matters more than the
// few percent higher levels save on depth images.
bool EncodePng(const cv::Mat& image, Bytes* png, std::string* why) {
  try {
    if (cv::imencode(".png", image, *png, {cv::IMWRITE_PNG_COMPRESSION, 1})) return true;
    *why = "PNG encoding failed";
  } catch (const cv::Exception& e) {
    *why = std::string("PNG encoding failed: ") + e.what();
  }
  return false;
}

enum class BlobFormat { kPng, kJpeg };

// Decodes with `flags` and checks type and size; never throws. Only a blob with a header of
// `format` reaches the decoder: cv::imdecode guesses the format from the bytes, and some of the
// decoders it would pick for a damaged blob abort the process (gdcm's DICOM reader asserts).
bool DecodeImage(const std::uint8_t* data, std::size_t bytes, BlobFormat format, int flags,
                 int type, int width, int height, cv::Mat* image, std::string* why) {
  if (bytes == 0) {
    *why = "empty image blob";
    return false;
  }
  // The header's size first: a damaged blob claiming a huge image would otherwise be decoded
  // (gigabytes) before its size is compared.
  const std::string_view blob(reinterpret_cast<const char*>(data), bytes);
  int header_width = 0, header_height = 0;
  const bool has_header = format == BlobFormat::kPng
                              ? ReadPngSize(blob, &header_width, &header_height)
                              : ReadJpegSize(blob, &header_width, &header_height);
  if (!has_header) {
    *why = std::string("image blob is not a ") + (format == BlobFormat::kPng ? "PNG" : "JPEG") +
           " image";
    return false;
  }
  if (header_width != width || header_height != height) {
    *why = "image blob is " + std::to_string(header_width) + "x" + std::to_string(header_height) +
           ", its keyframe " + std::to_string(width) + "x" + std::to_string(height);
    return false;
  }
  try {
    const cv::Mat encoded(1, static_cast<int>(bytes), CV_8UC1, const_cast<std::uint8_t*>(data));
    *image = cv::imdecode(encoded, flags);
  } catch (const cv::Exception& e) {
    *why = std::string("image decoding failed: ") + e.what();
    return false;
  }
  if (image->empty() || image->type() != type || image->cols != width || image->rows != height) {
    *why = "image blob does not decode to a " + std::to_string(width) + "x" +
           std::to_string(height) + " image of the stored type";
    return false;
  }
  return true;
}

}  // namespace

bool EncodeDepthPng(const std::vector<std::uint16_t>& depth_mm, int width, int height, Bytes* png,
                    std::string* why) {
  const cv::Mat image(height, width, CV_16UC1, const_cast<std::uint16_t*>(depth_mm.data()));
  return EncodePng(image, png, why);
}

bool EncodeMaskPng(const std::vector<std::uint8_t>& mask, int width, int height, Bytes* png,
                   std::string* why) {
  const cv::Mat image(height, width, CV_8UC1, const_cast<std::uint8_t*>(mask.data()));
  return EncodePng(image, png, why);
}

bool EncodeColorJpeg(const ColorImage& color, int quality, Bytes* jpeg, std::string* why) {
  cv::Mat bgr(color.height, color.width, CV_8UC3);
  SwapRedBlue(color.rgb.data(), bgr.data, color.rgb.size());
  try {
    if (cv::imencode(".jpg", bgr, *jpeg, {cv::IMWRITE_JPEG_QUALITY, quality})) return true;
    *why = "JPEG encoding failed";
  } catch (const cv::Exception& e) {
    *why = std::string("JPEG encoding failed: ") + e.what();
  }
  return false;
}

bool DecodeDepthPng(const std::uint8_t* png, std::size_t bytes, int width, int height,
                    std::vector<std::uint16_t>* depth_mm, std::string* why) {
  cv::Mat image;
  if (!DecodeImage(png, bytes, BlobFormat::kPng, cv::IMREAD_UNCHANGED, CV_16UC1, width, height,
                   &image, why)) {
    return false;
  }
  depth_mm->resize(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    std::memcpy(depth_mm->data() + static_cast<std::size_t>(v) * width, image.ptr(v),
                sizeof(std::uint16_t) * width);
  }
  return true;
}

bool DecodeMaskPng(const std::uint8_t* png, std::size_t bytes, int width, int height,
                   std::vector<std::uint8_t>* mask, std::string* why) {
  cv::Mat image;
  if (!DecodeImage(png, bytes, BlobFormat::kPng, cv::IMREAD_UNCHANGED, CV_8UC1, width, height,
                   &image, why)) {
    return false;
  }
  mask->resize(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    std::memcpy(mask->data() + static_cast<std::size_t>(v) * width, image.ptr(v), width);
  }
  return true;
}

bool DecodeColorJpeg(const std::uint8_t* jpeg, std::size_t bytes, int width, int height,
                     ColorImage* color, std::string* why) {
  cv::Mat bgr;
  if (!DecodeImage(jpeg, bytes, BlobFormat::kJpeg, cv::IMREAD_COLOR, CV_8UC3, width, height,
                   &bgr, why)) {
    return false;
  }
  color->width = width;
  color->height = height;
  color->rgb.resize(static_cast<std::size_t>(width) * height * 3);
  for (int v = 0; v < height; ++v) {
    SwapRedBlue(bgr.ptr(v), color->rgb.data() + static_cast<std::size_t>(v) * width * 3,
                static_cast<std::size_t>(width) * 3);
  }
  return true;
}

static_assert(sizeof(std::array<std::uint8_t, 3>) == 3, "colours are packed 3 bytes each");

bool EncodeSegmentColorsPng(const std::vector<std::array<std::uint8_t, 3>>& colors, Bytes* png,
                            std::string* why) {
  png->clear();
  if (colors.empty()) return true;
  const std::size_t width = std::min(colors.size(), kSegmentColorsPerRow);
  const std::size_t height = (colors.size() + width - 1) / width;
  // The channels go in as they are: the decoder gives them back in the same order.
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_8UC3, cv::Scalar::all(0));
  std::memcpy(image.data, colors.data(), colors.size() * 3);
  return EncodePng(image, png, why);
}

bool DecodeSegmentColorsPng(const std::uint8_t* png, std::size_t bytes, std::size_t count,
                            std::vector<std::array<std::uint8_t, 3>>* colors, std::string* why) {
  colors->clear();
  if (count == 0 || bytes == 0) {
    if (count == bytes) return true;
    *why = "segment colours: " + std::to_string(bytes) + " bytes for " + std::to_string(count) +
           " colours";
    return false;
  }
  const std::size_t width = std::min(count, kSegmentColorsPerRow);
  const std::size_t height = (count + width - 1) / width;
  cv::Mat image;
  if (!DecodeImage(png, bytes, BlobFormat::kPng, cv::IMREAD_UNCHANGED, CV_8UC3,
                   static_cast<int>(width), static_cast<int>(height), &image, why)) {
    return false;
  }
  colors->resize(count);
  std::memcpy(colors->data(), image.data, count * 3);  // continuous: decoded whole
  return true;
}

Bytes PackPose(const Eigen::Isometry3d& T) {
  Bytes out(16 * sizeof(double));
  std::memcpy(out.data(), T.matrix().data(), out.size());  // Eigen default: column-major
  return out;
}

bool UnpackPose(const std::uint8_t* data, std::size_t bytes, Eigen::Isometry3d* T) {
  if (bytes != 16 * sizeof(double)) return false;
  std::memcpy(T->matrix().data(), data, bytes);
  // Every pose was validated when it was stored: anything else was damaged on disk.
  return IsValidRigidTransform(T->matrix(), nullptr);
}

Bytes PackDetections(const std::vector<Detection>& detections) {
  Bytes out;
  out.reserve(detections.size() * 24);
  for (const Detection& d : detections) {
    Append(d.box.x_min, &out);
    Append(d.box.y_min, &out);
    Append(d.box.x_max, &out);
    Append(d.box.y_max, &out);
    Append(static_cast<std::int32_t>(d.class_id), &out);
    Append(d.score, &out);
  }
  return out;
}

bool UnpackDetections(const std::uint8_t* data, std::size_t bytes,
                      std::vector<Detection>* detections) {
  if (bytes % 24 != 0) return false;
  detections->resize(bytes / 24);
  for (std::size_t i = 0; i < detections->size(); ++i) {
    const std::size_t at = 24 * i;
    Detection& d = (*detections)[i];
    d.box = {Read<float>(data, at), Read<float>(data, at + 4), Read<float>(data, at + 8),
             Read<float>(data, at + 12)};
    d.class_id = Read<std::int32_t>(data, at + 16);
    d.score = Read<float>(data, at + 20);
  }
  return true;
}

Bytes PackClassScores(const std::vector<std::pair<int, float>>& scores) {
  Bytes out;
  out.reserve(scores.size() * 8);
  for (const auto& [class_id, score] : scores) {
    Append(static_cast<std::int32_t>(class_id), &out);
    Append(score, &out);
  }
  return out;
}

bool UnpackClassScores(const std::uint8_t* data, std::size_t bytes,
                       std::vector<std::pair<int, float>>* scores) {
  if (bytes % 8 != 0) return false;
  scores->resize(bytes / 8);
  for (std::size_t i = 0; i < scores->size(); ++i) {
    (*scores)[i] = {Read<std::int32_t>(data, 8 * i), Read<float>(data, 8 * i + 4)};
  }
  return true;
}

Bytes PackPoints(const ColoredPoints& points) {
  Bytes out(points.points.size() * 3 * sizeof(float));
  for (std::size_t i = 0; i < points.points.size(); ++i) {
    std::memcpy(out.data() + 12 * i, points.points[i].data(), 12);
  }
  return out;
}

Bytes PackColors(const ColoredPoints& points) {
  Bytes out(points.colors.size() * 3);
  for (std::size_t i = 0; i < points.colors.size(); ++i) {
    std::memcpy(out.data() + 3 * i, points.colors[i].data(), 3);
  }
  return out;
}

bool UnpackColoredPoints(const std::uint8_t* xyz, std::size_t xyz_bytes, const std::uint8_t* rgb,
                         std::size_t rgb_bytes, ColoredPoints* points) {
  const std::size_t n = xyz_bytes / 12;
  if (xyz_bytes % 12 != 0 || (rgb_bytes != 0 && rgb_bytes != 3 * n)) return false;
  points->points.resize(n);
  for (std::size_t i = 0; i < n; ++i) std::memcpy(points->points[i].data(), xyz + 12 * i, 12);
  points->colors.resize(rgb_bytes / 3);
  for (std::size_t i = 0; i < points->colors.size(); ++i) {
    std::memcpy(points->colors[i].data(), rgb + 3 * i, 3);
  }
  return true;
}

namespace {

void AppendVarint(std::uint64_t value, Bytes* out) {
  while (value >= 0x80) {
    out->push_back(static_cast<std::uint8_t>(value | 0x80));
    value >>= 7;
  }
  out->push_back(static_cast<std::uint8_t>(value));
}

bool ReadVarint(const std::uint8_t* data, std::size_t bytes, std::size_t* at,
                std::uint64_t* value) {
  *value = 0;
  for (int shift = 0; shift < 64 && *at < bytes; shift += 7) {
    const std::uint8_t byte = data[(*at)++];
    *value |= static_cast<std::uint64_t>(byte & 0x7f) << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

}  // namespace

Bytes PackSegmentPixels(const PixelRuns& runs, float voxel_size_m, std::size_t point_count) {
  Bytes out(sizeof(float));
  std::memcpy(out.data(), &voxel_size_m, sizeof(float));
  AppendVarint(point_count, &out);
  std::uint64_t end = 0;
  for (const PixelRun& run : runs) {
    AppendVarint(run.start - end, &out);
    AppendVarint(run.length, &out);
    end = std::uint64_t{run.start} + run.length;
  }
  return out;
}

bool UnpackSegmentPixels(const std::uint8_t* data, std::size_t bytes, PixelRuns* runs,
                         float* voxel_size_m, std::size_t* point_count) {
  runs->clear();
  if (bytes < sizeof(float)) return false;
  std::memcpy(voxel_size_m, data, sizeof(float));
  if (!std::isfinite(*voxel_size_m) || *voxel_size_m <= 0.f) return false;
  std::size_t at = sizeof(float);
  std::uint64_t count = 0;
  if (!ReadVarint(data, bytes, &at, &count)) return false;
  *point_count = static_cast<std::size_t>(count);
  std::uint64_t end = 0;
  while (at < bytes) {
    std::uint64_t gap = 0, length = 0;
    if (!ReadVarint(data, bytes, &at, &gap) || !ReadVarint(data, bytes, &at, &length) ||
        length == 0 || gap > UINT32_MAX || length > UINT32_MAX || end + gap + length > UINT32_MAX) {
      return false;
    }
    runs->push_back({static_cast<std::uint32_t>(end + gap), static_cast<std::uint32_t>(length)});
    end += gap + length;
  }
  return true;
}

}  // namespace store_internal
}  // namespace objmap
