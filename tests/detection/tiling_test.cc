#include "detection/tiling.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace objmap {
namespace {

Detection Make(float x0, float y0, float x1, float y1, int class_id, float score) {
  Detection d;
  d.box = {x0, y0, x1, y1};
  d.class_id = class_id;
  d.score = score;
  return d;
}

TEST(TileGrid, OverlappingTilesCoverTheImageEdgeToEdge) {
  for (int per_side : {2, 3}) {
    for (float overlap : {0.f, 0.25f, 0.5f}) {
      const std::vector<ImageTile> tiles = TileGrid(640, 480, per_side, overlap);
      ASSERT_EQ(tiles.size(), static_cast<std::size_t>(per_side * per_side));
      const ImageTile& first = tiles.front();
      const ImageTile& last = tiles.back();
      EXPECT_EQ(first.x, 0);
      EXPECT_EQ(first.y, 0);
      EXPECT_EQ(last.x + last.width, 640);
      EXPECT_EQ(last.y + last.height, 480);
      for (const ImageTile& tile : tiles) {
        EXPECT_EQ(tile.width, first.width);
        EXPECT_EQ(tile.height, first.height);
        EXPECT_GE(tile.x, 0);
        EXPECT_LE(tile.x + tile.width, 640);
      }
      // Neighbours along a row overlap by about `overlap` of a tile's width, never leave a gap.
      const int shared = tiles[0].x + tiles[0].width - tiles[1].x;
      EXPECT_GE(shared, 0);
      EXPECT_NEAR(shared, overlap * first.width, 2.0) << per_side << " " << overlap;
      // Each tile is about 1 / (per_side - (per_side - 1) * overlap) of the image's side.
      EXPECT_NEAR(first.width, 640.0 / (per_side - (per_side - 1) * overlap), 1.0);
    }
  }
  EXPECT_TRUE(TileGrid(640, 480, 1, 0.25f).empty());
  EXPECT_TRUE(TileGrid(0, 480, 2, 0.25f).empty());
}

TEST(MergeTileDetections, TilesAddSmallObjectsAndDropBoxesTheirBordersCut) {
  const std::vector<ImageTile> grid = TileGrid(640, 480, 2, 0.25f);
  ASSERT_EQ(grid.size(), 4u);
  const ImageTile& top_left = grid[0];
  TileMergeParams params;
  params.image_width = 640;
  params.image_height = 480;

  // The whole image sees a table and a cup; the top-left tile sees the cup better, a mouse the
  // whole image missed, a cup at the image's left border (kept: that border is the image's) and
  // the table cut at the tile's right border (dropped: the tile holds only part of it).
  const int kTable = 60, kCup = 41, kMouse = 64;
  std::vector<Detection> whole = {Make(100, 200, 600, 470, kTable, 0.7f),
                                  Make(50, 50, 90, 100, kCup, 0.4f)};
  TileDetections tile;
  tile.tile = top_left;
  const float right = static_cast<float>(top_left.x + top_left.width - 1);
  tile.detections = {Make(51, 49, 91, 101, kCup, 0.8f), Make(150, 120, 170, 132, kMouse, 0.5f),
                     Make(0, 150, 30, 190, kCup, 0.45f), Make(100, 200, right, 270, kTable, 0.9f)};
  const std::vector<Detection> merged = MergeTileDetections(whole, {tile}, params);

  ASSERT_EQ(merged.size(), 4u);
  EXPECT_TRUE(std::is_sorted(merged.begin(), merged.end(),
                             [](const auto& a, const auto& b) { return a.score > b.score; }));
  EXPECT_EQ(merged[0].class_id, kCup);  // the tile's better view of the cup replaces the whole's
  EXPECT_FLOAT_EQ(merged[0].score, 0.8f);
  EXPECT_EQ(merged[1].class_id, kTable);  // the whole image's table, not the tile's cut one
  EXPECT_FLOAT_EQ(merged[1].box.x_max, 600.f);
  EXPECT_EQ(merged[2].class_id, kMouse);
  EXPECT_EQ(merged[3].class_id, kCup);
  EXPECT_FLOAT_EQ(merged[3].box.x_min, 0.f);
}

TEST(MergeTileDetections, ClassesOfOneBoxStayAndTheCapHolds) {
  const std::vector<ImageTile> grid = TileGrid(640, 480, 2, 0.25f);
  TileMergeParams params;
  TileDetections tile;
  tile.tile = grid[0];
  // A bowl in the tile where the whole image saw a cup: both classes stay, as the whole image's
  // own alternatives do (the object map weighs class scores over views).
  tile.detections = {Make(40, 40, 80, 80, 45, 0.6f)};
  std::vector<Detection> merged =
      MergeTileDetections({Make(40, 41, 80, 80, 41, 0.5f)}, {tile}, params);
  ASSERT_EQ(merged.size(), 2u);
  EXPECT_EQ(merged[0].class_id, 45);
  EXPECT_EQ(merged[1].class_id, 41);

  params.max_detections = 2;
  std::vector<Detection> many;
  for (int i = 0; i < 5; ++i) many.push_back(Make(10.f + 50 * i, 10, 40.f + 50 * i, 40, 41, 0.5f));
  EXPECT_EQ(MergeTileDetections(many, {}, params).size(), 2u);
}

}  // namespace
}  // namespace objmap
