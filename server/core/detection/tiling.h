#pragma once
// Tiled inference for small objects: the detector also runs on overlapping tiles of the image,
// each scaled up to the network input, and the tiles' detections join the whole image's. Kept
// free of OpenCV and of the network so the geometry and the merge can be tested on hand-made
// boxes.

#include <vector>

#include "types/detection.h"

namespace objmap {

/// A tile of the image, in image pixels: columns [x, x + width), rows [y, y + height).
struct ImageTile {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
};

/// `per_side` x `per_side` tiles covering a `width` x `height` image, neighbours overlapping by
/// `overlap` of a tile's side (so an object narrower than the overlap lies whole in one tile).
/// Row-major; empty when per_side < 2 (the whole image alone is not a tiling).
[[nodiscard]] std::vector<ImageTile> TileGrid(int width, int height, int per_side, float overlap);

/// Detections of one tile, boxes already in image pixels.
struct TileDetections {
  ImageTile tile;
  std::vector<Detection> detections;
};

struct TileMergeParams {
  int image_width = 640;
  int image_height = 480;
  /// A tile's box within this many pixels of a tile border that lies inside the image is cut by
  /// the tile: the object continues in the next tile, and the whole image or that tile holds it.
  float border_margin_px = 3.f;
  /// Same-class boxes overlapping a better one by more than this IoU are the same object.
  float nms_iou = 0.6f;
  /// At most this many detections, best first.
  int max_detections = 100;
};

/// The whole image's detections joined by the tiles' (less those cut by a tile border), with
/// same-class duplicates (IoU above nms_iou) removed. Best first. Like the whole image's own
/// output, one box may come with several classes: the object map accumulates class scores.
[[nodiscard]] std::vector<Detection> MergeTileDetections(std::vector<Detection> whole_image,
                                                         const std::vector<TileDetections>& tiles,
                                                         const TileMergeParams& params);

}  // namespace objmap
