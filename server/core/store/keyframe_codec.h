#pragma once
// Byte encodings of what the store keeps: images (PNG/JPEG through OpenCV, which stays out of
// every header) and packed little-endian arrays for poses, detections and observations.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "objects/observation_segment.h"
#include "objects/voxel_model.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {
namespace store_internal {

using Bytes = std::vector<std::uint8_t>;

/// Lossless 16-bit PNG of a row-major width x height depth image (millimetres).
[[nodiscard]] bool EncodeDepthPng(const std::vector<std::uint16_t>& depth_mm, int width, int height,
                                  Bytes* png, std::string* why);
/// Lossless 8-bit PNG of a row-major width x height mask.
[[nodiscard]] bool EncodeMaskPng(const std::vector<std::uint8_t>& mask, int width, int height,
                                 Bytes* png, std::string* why);
[[nodiscard]] bool EncodeColorJpeg(const ColorImage& color, int quality, Bytes* jpeg,
                                   std::string* why);

/// Decoders check the decoded size against the expected one (a stored blob that does not match
/// its keyframe's intrinsics is corruption, reported as such).
[[nodiscard]] bool DecodeDepthPng(const std::uint8_t* png, std::size_t bytes, int width, int height,
                                  std::vector<std::uint16_t>* depth_mm, std::string* why);
[[nodiscard]] bool DecodeMaskPng(const std::uint8_t* png, std::size_t bytes, int width, int height,
                                 std::vector<std::uint8_t>* mask, std::string* why);
[[nodiscard]] bool DecodeColorJpeg(const std::uint8_t* jpeg, std::size_t bytes, int width,
                                   int height, ColorImage* color, std::string* why);

/// 16 doubles, column-major: exact round trip.
[[nodiscard]] Bytes PackPose(const Eigen::Isometry3d& T);
/// False when the blob has the wrong size or is not a finite rigid transform (damaged on disk).
[[nodiscard]] bool UnpackPose(const std::uint8_t* data, std::size_t bytes, Eigen::Isometry3d* T);

/// Per detection: box (4 float32), class (int32), score (float32).
[[nodiscard]] Bytes PackDetections(const std::vector<Detection>& detections);
[[nodiscard]] bool UnpackDetections(const std::uint8_t* data, std::size_t bytes,
                                    std::vector<Detection>* detections);

/// Per entry: class (int32), score (float32).
[[nodiscard]] Bytes PackClassScores(const std::vector<std::pair<int, float>>& scores);
[[nodiscard]] bool UnpackClassScores(const std::uint8_t* data, std::size_t bytes,
                                     std::vector<std::pair<int, float>>* scores);

/// Points as float32 xyz triples; colours as uint8 rgb triples (empty or one per point).
[[nodiscard]] Bytes PackPoints(const ColoredPoints& points);
[[nodiscard]] Bytes PackColors(const ColoredPoints& points);
[[nodiscard]] bool UnpackColoredPoints(const std::uint8_t* xyz, std::size_t xyz_bytes,
                                       const std::uint8_t* rgb, std::size_t rgb_bytes,
                                       ColoredPoints* points);

/// An observation's segment as its pixels (ObjectObservation::segment_pixels): the voxel size
/// (float32), the number of points they make (LEB128), then per run the gap from the previous
/// run's end and its length (LEB128 each).
[[nodiscard]] Bytes PackSegmentPixels(const PixelRuns& runs, float voxel_size_m,
                                      std::size_t point_count);
/// False when the blob is cut short, has bytes left over, or its runs overlap or overflow.
[[nodiscard]] bool UnpackSegmentPixels(const std::uint8_t* data, std::size_t bytes, PixelRuns* runs,
                                       float* voxel_size_m, std::size_t* point_count);
/// The colours of a segment kept as pixels, losslessly: an 8-bit three-channel PNG of up to
/// kSegmentColorsPerRow colours a row, the last row padded with black (neighbouring points have
/// about the same colour: PNG's filters and deflate take it to about a third). Empty: none.
inline constexpr std::size_t kSegmentColorsPerRow = 16384;
[[nodiscard]] bool EncodeSegmentColorsPng(const std::vector<std::array<std::uint8_t, 3>>& colors,
                                          Bytes* png, std::string* why);
/// `count` colours; a blob of another size is refused.
[[nodiscard]] bool DecodeSegmentColorsPng(const std::uint8_t* png, std::size_t bytes,
                                          std::size_t count,
                                          std::vector<std::array<std::uint8_t, 3>>* colors,
                                          std::string* why);

}  // namespace store_internal
}  // namespace objmap
