#include "detection/centernet_decode.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace objmap {
namespace {

constexpr int kClasses = 3;
constexpr int kGrid = 16;
constexpr int kPlane = kGrid * kGrid;

/// A small synthetic head output: background score 0.01 everywhere, zero box distances.
class DecodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    heatmap_.assign(kClasses * kPlane, 0.01f);
    boxes_.assign(4 * kPlane, 0.f);
    params_.num_classes = kClasses;
    params_.grid_height = kGrid;
    params_.grid_width = kGrid;
    params_.stride_px = 4.f;
    params_.image_width = 1000.f;
    params_.image_height = 1000.f;
    params_.score_threshold = 0.3f;
  }

  float& Score(int c, int x, int y) { return heatmap_[c * kPlane + y * kGrid + x]; }
  void SetBox(int x, int y, float left, float top, float right, float bottom) {
    const float values[4] = {left, top, right, bottom};
    for (int k = 0; k < 4; ++k) boxes_[k * kPlane + y * kGrid + x] = values[k];
  }
  std::vector<Detection> Decode() {
    return DecodeCenterNet(heatmap_.data(), boxes_.data(), params_);
  }

  std::vector<float> heatmap_;
  std::vector<float> boxes_;
  CenterNetDecodeParams params_;
};

TEST_F(DecodeTest, SinglePeakGivesScaledBox) {
  Score(1, 5, 7) = 0.9f;
  for (int dy = -1; dy <= 1; ++dy) {  // neighbours above threshold but below the peak
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx != 0 || dy != 0) Score(1, 5 + dx, 7 + dy) = 0.5f;
    }
  }
  SetBox(5, 7, 8.f, 12.f, 16.f, 20.f);
  params_.scale_x = 2.f;
  params_.scale_y = 0.5f;
  const std::vector<Detection> detections = Decode();
  ASSERT_EQ(detections.size(), 1u);
  EXPECT_EQ(detections[0].class_id, 1);
  EXPECT_FLOAT_EQ(detections[0].score, 0.9f);
  EXPECT_FLOAT_EQ(detections[0].box.x_min, (20.f - 8.f) * 2.f);
  EXPECT_FLOAT_EQ(detections[0].box.y_min, (28.f - 12.f) * 0.5f);
  EXPECT_FLOAT_EQ(detections[0].box.x_max, (20.f + 16.f) * 2.f);
  EXPECT_FLOAT_EQ(detections[0].box.y_max, (28.f + 20.f) * 0.5f);
}

TEST_F(DecodeTest, PeaksBelowThresholdAreDropped) {
  Score(0, 3, 3) = 0.29f;
  Score(2, 10, 10) = 0.31f;
  const std::vector<Detection> detections = Decode();
  ASSERT_EQ(detections.size(), 1u);
  EXPECT_EQ(detections[0].class_id, 2);
}

TEST_F(DecodeTest, PeaksOnTheBorderAreFound) {
  Score(0, 0, 0) = 0.8f;
  Score(0, kGrid - 1, kGrid - 1) = 0.7f;
  EXPECT_EQ(Decode().size(), 2u);
}

TEST_F(DecodeTest, SortedByScoreAndTruncated) {
  Score(0, 2, 2) = 0.4f;
  Score(1, 8, 2) = 0.9f;
  Score(2, 2, 8) = 0.6f;
  params_.max_detections = 2;
  const std::vector<Detection> detections = Decode();
  ASSERT_EQ(detections.size(), 2u);
  EXPECT_EQ(detections[0].class_id, 1);
  EXPECT_EQ(detections[1].class_id, 2);
}

TEST_F(DecodeTest, NmsIsClassWise) {
  // Two separate peaks of class 0 with nearly identical large boxes, and one of class 1.
  Score(0, 4, 4) = 0.9f;
  SetBox(4, 4, 16.f, 16.f, 16.f, 16.f);
  Score(0, 6, 4) = 0.8f;
  SetBox(6, 4, 24.f, 16.f, 8.f, 16.f);
  Score(1, 4, 4) = 0.7f;
  SetBox(4, 4, 16.f, 16.f, 16.f, 16.f);
  std::vector<Detection> detections = Decode();
  ASSERT_EQ(detections.size(), 2u);
  EXPECT_EQ(detections[0].class_id, 0);
  EXPECT_FLOAT_EQ(detections[0].score, 0.9f);
  EXPECT_EQ(detections[1].class_id, 1);

  params_.nms_iou = 1.f;  // disabled: all three peaks survive
  EXPECT_EQ(Decode().size(), 3u);
}

TEST_F(DecodeTest, BoxesAreClippedToTheImage) {
  Score(0, 1, 1) = 0.9f;
  SetBox(1, 1, 100.f, 100.f, 5000.f, 5000.f);
  params_.image_width = 640.f;
  params_.image_height = 480.f;
  const std::vector<Detection> detections = Decode();
  ASSERT_EQ(detections.size(), 1u);
  EXPECT_FLOAT_EQ(detections[0].box.x_min, 0.f);
  EXPECT_FLOAT_EQ(detections[0].box.y_min, 0.f);
  EXPECT_FLOAT_EQ(detections[0].box.x_max, 640.f);
  EXPECT_FLOAT_EQ(detections[0].box.y_max, 480.f);
}

TEST_F(DecodeTest, NanScoresYieldNothing) {
  heatmap_.assign(heatmap_.size(), std::numeric_limits<float>::quiet_NaN());
  EXPECT_TRUE(Decode().empty());
}

TEST(BoxIoUTest, KnownOverlaps) {
  const BoundingBox2D a{0.f, 0.f, 10.f, 10.f};
  EXPECT_FLOAT_EQ(BoxIoU(a, a), 1.f);
  EXPECT_FLOAT_EQ(BoxIoU(a, BoundingBox2D{20.f, 20.f, 30.f, 30.f}), 0.f);
  EXPECT_FLOAT_EQ(BoxIoU(a, BoundingBox2D{5.f, 0.f, 15.f, 10.f}), 50.f / 150.f);
  EXPECT_FLOAT_EQ(BoxIoU(a, BoundingBox2D{3.f, 3.f, 3.f, 3.f}), 0.f);
}

TEST(DecodeParamsTest, RejectsBadValuesByName) {
  CenterNetDecodeParams params;
  std::string why;
  EXPECT_TRUE(params.IsValid(&why));
  params.score_threshold = 1.5f;
  EXPECT_FALSE(params.IsValid(&why));
  EXPECT_NE(why.find("score_threshold"), std::string::npos);
  params = CenterNetDecodeParams();
  params.grid_width = 0;
  EXPECT_FALSE(params.IsValid(&why));
  EXPECT_NE(why.find("grid_width"), std::string::npos);
}

}  // namespace
}  // namespace objmap
