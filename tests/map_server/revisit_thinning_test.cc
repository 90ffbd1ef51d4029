// The test that a keyframe repeats stored views (RevisitThinningConfig): rendered views of a
// table with two cups before a wall. A view seen again from nearly the same place is repeated;
// a cup taken away or put down, or a part of the scene no stored view saw, is not.

#include "map_server/revisit_thinning.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "mapper/mapper.h"
#include "test_scenes.h"

namespace objmap {
namespace {

using testing::SceneBox;
using namespace testing::table_visits;

class RevisitThinning : public ::testing::Test {
 protected:
  RgbdFrame Render(const Eigen::Vector3d& eye, const std::vector<SceneBox>& cups,
                   const Eigen::Vector3d& target = kTarget) const {
    std::vector<SceneBox> boxes = {kTable, kWall};
    boxes.insert(boxes.end(), cups.begin(), cups.end());
    return testing::RenderFrame(boxes, K_, testing::LookAt(eye, target), "view");
  }

  // Stores `frame` as keyframe `id`, as the mapper keeps it, and returns it as a stored view
  // (the record is kept).
  StoredView Store(std::int64_t id, const RgbdFrame& frame) {
    const KeyframeRecord& record = records_[id] = RecordOf(frame);
    return StoredView{id, record.T_W_C, &record.intrinsics, &record.depth_mm};
  }

  ViewCoverage Coverage(const RgbdFrame& frame, const std::vector<StoredView>& views) const {
    return CoverageOf(frame.depth, frame.intrinsics, frame.T_W_C, views, config_);
  }

  std::map<std::int64_t, KeyframeRecord> records_;
  CameraIntrinsics K_;
  RevisitThinningConfig config_;
  const Eigen::Vector3d eye_{-1.0, 0.0, 1.3};
  const Eigen::Vector3d near_eye_{-1.02, 0.03, 1.31};  // 4 cm away: the same view
};

TEST_F(RevisitThinning, AViewSeenAgainFromNearlyTheSamePlaceIsRepeated) {
  const StoredView stored = Store(7, Render(eye_, {kCupOne, kCupTwo}));
  const ViewCoverage coverage = Coverage(Render(near_eye_, {kCupOne, kCupTwo}), {stored});
  EXPECT_TRUE(coverage.repeated);
  EXPECT_GE(coverage.explained_fraction, 0.95f);
  EXPECT_LE(coverage.largest_changed_patch_px, config_.max_changed_patch_px);
  EXPECT_EQ(coverage.best_keyframe, 7);
  EXPECT_GT(coverage.depth_pixels, 1000);
}

TEST_F(RevisitThinning, ACupTakenAwayOrPutDownIsNotRepeated) {
  const StoredView with_cups = Store(1, Render(eye_, {kCupOne, kCupTwo}));
  // Taken away: the new view sees the table top where the cup stood, behind the stored depth.
  const ViewCoverage taken = Coverage(Render(near_eye_, {kCupTwo}), {with_cups});
  EXPECT_FALSE(taken.repeated);
  EXPECT_GT(taken.largest_changed_patch_px, config_.max_changed_patch_px);
  // Put down: the new view sees the cup in front of the stored table top. Both are small against
  // the frame: the share explained stays high, the patch is what tells.
  const StoredView one_cup = Store(2, Render(eye_, {kCupOne}));
  const ViewCoverage put = Coverage(Render(near_eye_, {kCupOne, kCupTwoMoved}), {one_cup});
  EXPECT_FALSE(put.repeated);
  EXPECT_GT(put.explained_fraction, 0.9f);
  EXPECT_GT(put.largest_changed_patch_px, config_.max_changed_patch_px);
}

TEST_F(RevisitThinning, APartNoStoredViewSawIsNotRepeatedUntilAViewThatSawItIsCompared) {
  const Eigen::Vector3d left_target(0.0, -0.6, 0.7), right_target(0.0, 0.8, 0.7);
  const StoredView left = Store(1, Render(eye_, {kCupOne, kCupTwo}, left_target));
  const RgbdFrame right = Render(near_eye_, {kCupOne, kCupTwo}, right_target);
  const ViewCoverage alone = Coverage(right, {left});
  EXPECT_FALSE(alone.repeated);
  EXPECT_LT(alone.explained_fraction, 0.9f);
  // A second stored view that saw the rest explains it together with the first.
  const StoredView middle = Store(2, Render(eye_, {kCupOne, kCupTwo}, right_target));
  const ViewCoverage together = Coverage(right, {left, middle});
  EXPECT_TRUE(together.repeated);
  EXPECT_EQ(together.best_keyframe, 2);
}

// A later path a little farther back and higher sees around the stored views' borders: the part
// they saw is repeated, the rest is new, and only the new part's depth is kept.
TEST_F(RevisitThinning, AViewFromFartherBackRepeatsThemInPartAndKeepsOnlyItsNewPart) {
  const StoredView stored = Store(1, Render(eye_, {kCupOne, kCupTwo}));
  const Eigen::Vector3d farther = kTarget + 1.25 * (eye_ - kTarget) + Eigen::Vector3d(0, 0, 0.1);
  RgbdFrame frame = Render(farther, {kCupOne, kCupTwo});
  const ViewCoverage coverage = Coverage(frame, {stored});
  EXPECT_FALSE(coverage.repeated);
  EXPECT_TRUE(coverage.repeated_in_part);
  EXPECT_LE(coverage.largest_changed_patch_px, config_.max_changed_patch_px);
  EXPECT_GT(coverage.explained_fraction, config_.min_partial_explained_fraction);
  EXPECT_LT(coverage.explained_fraction, config_.min_explained_fraction);
  auto with_depth = [](const DepthImage& depth) {
    return std::count_if(depth.depth_m.begin(), depth.depth_m.end(),
                         [](float z) { return z > 0.f; });
  };
  const auto before = with_depth(frame.depth);
  KeepUnexplained(coverage, {}, config_, &frame.depth);
  const auto after = with_depth(frame.depth);
  // What is left is the unexplained share, within the blocks' rounding.
  EXPECT_NEAR(static_cast<double>(after) / before, 1.0 - coverage.explained_fraction, 0.02);
  // ... and the stored view explains none of it.
  const ViewCoverage rest = Coverage(frame, {stored});
  EXPECT_LT(rest.explained_fraction, 0.05f);
  // The same path with a cup taken away shows the change: mapped whole.
  const ViewCoverage taken = Coverage(Render(farther, {kCupTwo}), {stored});
  EXPECT_FALSE(taken.repeated || taken.repeated_in_part);
}

// A box on the table hides part of it from the stored view; a view from the side sees behind it.
// That part is new to the stored view, not a change.
TEST_F(RevisitThinning, WhatAStoredViewCouldNotSeeIsNewNotAChange) {
  const SceneBox crate{{-0.25, -0.2, 0.70}, {0.05, 0.1, 1.0}, {90, 90, 90}};
  const StoredView stored = Store(1, Render(eye_, {crate}));
  const ViewCoverage side = Coverage(Render(eye_ + Eigen::Vector3d(0, 0.4, 0), {crate}), {stored});
  EXPECT_LE(side.largest_changed_patch_px, config_.max_changed_patch_px);
  EXPECT_LT(side.explained_fraction, 1.f);
  EXPECT_TRUE(side.repeated || side.repeated_in_part);
  // The crate taken away: the side view looks through where the stored view measured it.
  const ViewCoverage taken = Coverage(Render(eye_ + Eigen::Vector3d(0, 0.4, 0), {}), {stored});
  EXPECT_GT(taken.largest_changed_patch_px, config_.max_changed_patch_px);
}

TEST_F(RevisitThinning, AnAlmostBlankFrameIsNotRepeated) {
  const StoredView stored = Store(1, Render(eye_, {kCupOne}));
  // Looking up over the wall: almost no depth.
  const RgbdFrame blank = Render(near_eye_, {kCupOne}, Eigen::Vector3d(0.0, 0.0, 4.0));
  EXPECT_FALSE(Coverage(blank, {stored}).repeated);
  EXPECT_FALSE(Coverage(Render(near_eye_, {kCupOne}), {}).repeated);  // nothing to compare with
}

TEST_F(RevisitThinning, NearbyViewsLieWithinTheDistanceAndTheAngle) {
  const Eigen::Isometry3d a = testing::LookAt(eye_, kTarget);
  EXPECT_TRUE(IsNearbyView(a, testing::LookAt(near_eye_, kTarget), config_));
  EXPECT_FALSE(
      IsNearbyView(a, testing::LookAt(eye_ + Eigen::Vector3d(0, 0.6, 0), kTarget), config_));
  // Turned by about 45 degrees, in place.
  EXPECT_FALSE(IsNearbyView(a, testing::LookAt(eye_, Eigen::Vector3d(-0.2, 1.2, 0.7)), config_));
}

TEST(RevisitThinningConfig, RejectsValuesOutOfRange) {
  std::string why;
  EXPECT_TRUE(RevisitThinningConfig{}.IsValid(&why)) << why;
  RevisitThinningConfig config;
  config.min_explained_fraction = 0.f;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("min_explained_fraction"), std::string::npos);
  config = {};
  config.pixel_stride = 0;
  EXPECT_FALSE(config.IsValid(&why));
  config = {};
  config.max_distance_m = -1.0;
  EXPECT_FALSE(config.IsValid(&why));
  config = {};
  config.depth_margin_m = -0.01f;
  EXPECT_FALSE(config.IsValid(&why));
  config = {};
  config.min_partial_explained_fraction = 1.5f;
  EXPECT_FALSE(config.IsValid(&why));
}

}  // namespace
}  // namespace objmap
