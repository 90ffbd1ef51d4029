#include "detection/centernet_decode.h"

#include <algorithm>
#include <cmath>

namespace objmap {
namespace {

/// Peaks handed to NMS per requested detection.
constexpr std::size_t kNmsCandidateFactor = 8;

void SetWhy(std::string* why, const std::string& text) {
  if (why != nullptr) *why = text;
}

/// True when `channel[y * width + x]` is >= each of its (up to 8) neighbours.
bool IsLocalMaximum(const float* channel, int width, int height, int x, int y) {
  const float value = channel[y * width + x];
  for (int dy = -1; dy <= 1; ++dy) {
    const int ny = y + dy;
    if (ny < 0 || ny >= height) continue;
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = x + dx;
      if (nx < 0 || nx >= width || (dx == 0 && dy == 0)) continue;
      if (channel[ny * width + nx] > value) return false;
    }
  }
  return true;
}

Detection MakeDetection(const float* box_chw, const CenterNetDecodeParams& p, int class_id, int x,
                        int y, float score) {
  const int plane = p.grid_width * p.grid_height;
  const int cell = y * p.grid_width + x;
  const float cx = static_cast<float>(x) * p.stride_px;
  const float cy = static_cast<float>(y) * p.stride_px;
  Detection d;
  d.class_id = class_id;
  d.score = score;
  d.box.x_min = std::clamp((cx - box_chw[cell]) * p.scale_x, 0.f, p.image_width);
  d.box.y_min = std::clamp((cy - box_chw[plane + cell]) * p.scale_y, 0.f, p.image_height);
  d.box.x_max = std::clamp((cx + box_chw[2 * plane + cell]) * p.scale_x, 0.f, p.image_width);
  d.box.y_max = std::clamp((cy + box_chw[3 * plane + cell]) * p.scale_y, 0.f, p.image_height);
  return d;
}

bool ByScore(const Detection& a, const Detection& b) { return a.score > b.score; }

}  // namespace

bool CenterNetDecodeParams::IsValid(std::string* why) const {
  if (num_classes <= 0 || grid_height <= 0 || grid_width <= 0) {
    SetWhy(why, "decode: num_classes, grid_height and grid_width must be positive");
    return false;
  }
  if (!(stride_px > 0.f) || !(scale_x > 0.f) || !(scale_y > 0.f)) {
    SetWhy(why, "decode: stride_px, scale_x and scale_y must be positive");
    return false;
  }
  if (!(image_width > 0.f) || !(image_height > 0.f)) {
    SetWhy(why, "decode: image_width and image_height must be positive");
    return false;
  }
  if (!(score_threshold >= 0.f && score_threshold <= 1.f)) {
    SetWhy(why, "decode: score_threshold must lie in [0, 1]");
    return false;
  }
  if (max_detections <= 0 || !(nms_iou > 0.f)) {
    SetWhy(why, "decode: max_detections and nms_iou must be positive");
    return false;
  }
  return true;
}

std::vector<Detection> DecodeCenterNet(const float* heatmap_chw, const float* box_chw,
                                       const CenterNetDecodeParams& params) {
  std::vector<Detection> peaks;
  const int plane = params.grid_width * params.grid_height;
  for (int c = 0; c < params.num_classes; ++c) {
    const float* channel = heatmap_chw + static_cast<std::size_t>(c) * plane;
    for (int y = 0; y < params.grid_height; ++y) {
      for (int x = 0; x < params.grid_width; ++x) {
        const float score = channel[y * params.grid_width + x];
        // NaN fails this comparison too, so a broken output yields no detections.
        if (!(score >= params.score_threshold)) continue;
        if (!IsLocalMaximum(channel, params.grid_width, params.grid_height, x, y)) continue;
        peaks.push_back(MakeDetection(box_chw, params, c, x, y, score));
      }
    }
  }
  // NMS is quadratic; a generous cap keeps a near-zero threshold from stalling a frame.
  const std::size_t cap = static_cast<std::size_t>(params.max_detections) * kNmsCandidateFactor;
  if (peaks.size() > cap) {
    std::partial_sort(peaks.begin(), peaks.begin() + cap, peaks.end(), ByScore);
    peaks.resize(cap);
  }
  std::vector<Detection> kept = ClassWiseNms(std::move(peaks), params.nms_iou);
  if (kept.size() > static_cast<std::size_t>(params.max_detections)) {
    kept.resize(static_cast<std::size_t>(params.max_detections));
  }
  return kept;
}

std::vector<Detection> ClassWiseNms(std::vector<Detection> detections, float iou_threshold) {
  std::stable_sort(detections.begin(), detections.end(), ByScore);
  std::vector<Detection> kept;
  kept.reserve(detections.size());
  for (const Detection& candidate : detections) {
    const bool suppressed = std::any_of(kept.begin(), kept.end(), [&](const Detection& better) {
      return better.class_id == candidate.class_id &&
             BoxIoU(better.box, candidate.box) > iou_threshold;
    });
    if (!suppressed) kept.push_back(candidate);
  }
  return kept;
}

}  // namespace objmap
