#include "detection/tiling.h"

#include <algorithm>
#include <cmath>

#include "detection/centernet_decode.h"

namespace objmap {
namespace {

// Tiles of `per_side` (>= 2) along one image side of `length` pixels: start and length of each.
std::vector<std::pair<int, int>> SideSpans(int length, int per_side, float overlap) {
  // per_side tiles of side s overlapping by overlap * s cover s * (per_side - (per_side - 1) *
  // overlap) = length.
  const double side = length / (per_side - (per_side - 1) * static_cast<double>(overlap));
  const int tile = std::min(length, static_cast<int>(std::ceil(side)));
  std::vector<std::pair<int, int>> spans;
  for (int i = 0; i < per_side; ++i) {
    // The last tile ends at the image border; the others step evenly.
    const int start =
        static_cast<int>(std::lround(static_cast<double>(length - tile) * i / (per_side - 1)));
    spans.emplace_back(start, tile);
  }
  return spans;
}

// True when `box` comes within `margin` of a border of `tile` that lies inside the image.
bool CutByTile(const BoundingBox2D& box, const ImageTile& tile, const TileMergeParams& params) {
  const float margin = params.border_margin_px;
  const float left = static_cast<float>(tile.x), top = static_cast<float>(tile.y);
  const float right = static_cast<float>(tile.x + tile.width);
  const float bottom = static_cast<float>(tile.y + tile.height);
  return (tile.x > 0 && box.x_min <= left + margin) || (tile.y > 0 && box.y_min <= top + margin) ||
         (tile.x + tile.width < params.image_width && box.x_max >= right - 1.f - margin) ||
         (tile.y + tile.height < params.image_height && box.y_max >= bottom - 1.f - margin);
}

}  // namespace

std::vector<ImageTile> TileGrid(int width, int height, int per_side, float overlap) {
  std::vector<ImageTile> tiles;
  if (per_side < 2 || width <= 0 || height <= 0) return tiles;
  overlap = std::clamp(overlap, 0.f, 0.9f);
  const auto columns = SideSpans(width, per_side, overlap);
  const auto rows = SideSpans(height, per_side, overlap);
  for (const auto& [y, tile_height] : rows) {
    for (const auto& [x, tile_width] : columns) tiles.push_back({x, y, tile_width, tile_height});
  }
  return tiles;
}

std::vector<Detection> MergeTileDetections(std::vector<Detection> whole_image,
                                           const std::vector<TileDetections>& tiles,
                                           const TileMergeParams& params) {
  std::vector<Detection> all = std::move(whole_image);
  for (const TileDetections& tile : tiles) {
    for (const Detection& detection : tile.detections) {
      if (!CutByTile(detection.box, tile.tile, params)) all.push_back(detection);
    }
  }
  std::vector<Detection> kept = ClassWiseNms(std::move(all), params.nms_iou);
  if (kept.size() > static_cast<std::size_t>(std::max(params.max_detections, 0))) {
    kept.resize(static_cast<std::size_t>(std::max(params.max_detections, 0)));
  }
  return kept;
}

}  // namespace objmap
