#include "objects/object_map.h"

#include <gtest/gtest.h>

#include "test_scenes.h"

namespace objmap {
namespace {

ObjectObservation Observation(KeyframeId keyframe, int class_id, float score,
                              const std::vector<Eigen::Vector3f>& points_C) {
  ObjectObservation observation;
  observation.keyframe_id = keyframe;
  observation.class_scores = {{class_id, score}};
  observation.segment_C.points = points_C;
  return observation;
}

const Eigen::Isometry3d kIdentity = Eigen::Isometry3d::Identity();
const int kCup = CocoClassId("cup");
const int kBowl = CocoClassId("bowl");

TEST(VoxelModel, AveragesPointsPerVoxel) {
  VoxelModel model(0.01f);
  ColoredPoints points;
  points.points = {{0.001f, 0.001f, 0.001f}, {0.003f, 0.003f, 0.003f}, {0.015f, 0.f, 0.f}};
  points.colors = {{0, 0, 0}, {200, 100, 50}, {9, 9, 9}};
  model.Insert(points);
  ASSERT_EQ(model.size(), 2u);
  const ColoredPoints out = model.Points();
  ASSERT_EQ(out.size(), 2u);
  const size_t first = out.points[0].x() < 0.01f ? 0 : 1;  // the voxel at the origin
  EXPECT_NEAR(out.points[first].x(), 0.002f, 1e-6);
  EXPECT_EQ(out.colors[first][0], 100);
  EXPECT_EQ(out.colors[first][1], 50);
  EXPECT_NEAR(out.points[1 - first].x(), 0.015f, 1e-6);
}

TEST(ObjectMap, AccumulatesScoresAsThePaper) {
  ObjectMap map;
  const auto cup_points = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  const ObjectId id =
      map.AddObject(Observation(1, kCup, 0.6f, cup_points), Eigen::Isometry3d::Identity());
  EXPECT_TRUE(map.AddObservation(id, Observation(2, kBowl, 0.7f, cup_points),
                                 Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(map.AddObservation(id, Observation(3, kCup, 0.5f, cup_points),
                                 Eigen::Isometry3d::Identity()));
  const MapObject& object = *map.Find(id);
  EXPECT_EQ(object.Label(), kCup);                     // 1.1 (cup) beats 0.7 (bowl)
  EXPECT_NEAR(object.Confidence(), 1.1f / 3.f, 1e-6);  // max score / observations
  EXPECT_EQ(object.Keyframes(), (std::vector<KeyframeId>{1, 2, 3}));
  EXPECT_FALSE(map.AddObservation(999, Observation(4, kCup, 0.5f, cup_points),
                                  Eigen::Isometry3d::Identity()));
}

TEST(ObjectMap, ModelIsInWorldFrameAndRebuildsWithNewPoses) {
  ObjectMap map;
  const auto points_C = testing::BoxSurface({-0.05f, -0.05f, 1.f}, {0.05f, 0.05f, 1.1f}, 0.005f);
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  T_W_C.translation() = Eigen::Vector3d(1, 2, 3);
  const ObjectId id = map.AddObject(Observation(7, kCup, 0.9f, points_C), T_W_C);
  EXPECT_NEAR(map.Find(id)->centroid_W.x(), 1.f, 0.01f);
  EXPECT_NEAR(map.Find(id)->centroid_W.z(), 4.05f, 0.01f);

  Eigen::Isometry3d corrected = T_W_C;
  corrected.translation().x() += 0.5;
  map.Rebuild([&](KeyframeId k) -> std::optional<Eigen::Isometry3d> {
    if (k == 7) return corrected;
    return std::nullopt;
  });
  EXPECT_NEAR(map.Find(id)->centroid_W.x(), 1.5f, 0.01f);
  EXPECT_EQ(map.Find(id)->id, id);
}

TEST(ObjectMap, MergeMovesObservationsAndScores) {
  ObjectMap map;
  const auto points = testing::BoxSurface({0, 0, 0}, {0.1f, 0.1f, 0.1f}, 0.01f);
  const ObjectId a = map.AddObject(Observation(1, kCup, 0.5f, points), kIdentity);
  const ObjectId b = map.AddObject(Observation(2, kCup, 0.4f, points), kIdentity);
  ASSERT_TRUE(map.Merge(a, b));
  EXPECT_EQ(map.size(), 1u);
  EXPECT_EQ(map.Find(b), nullptr);
  EXPECT_EQ(map.Find(a)->observations.size(), 2u);
  EXPECT_NEAR(map.Find(a)->accumulated_scores[kCup], 0.9f, 1e-6);
  EXPECT_FALSE(map.Merge(a, b));
  // Ids are never reused.
  EXPECT_GT(map.AddObject(Observation(3, kCup, 0.4f, points), {}), b);
}

TEST(ObjectMap, ThePublishedModelKeepsVoxelsTwoViewsReached) {
  ObjectMap map;
  const std::vector<Eigen::Vector3f> surface = {{0.0f, 0.0f, 1.0f}, {0.02f, 0.0f, 1.0f}};
  ObjectObservation first = Observation(1, kCup, 0.6f, surface);
  first.segment_C.points.emplace_back(0.3f, 0.3f, 1.0f);  // a stray border pixel, seen once
  first.view = 0;
  const ObjectId id = map.AddObject(first, kIdentity);
  // Seen once: the model is all there is.
  EXPECT_EQ(map.ModelPoints(*map.Find(id)).size(), 3u);
  ObjectObservation same_view = Observation(2, kCup, 0.6f, surface);
  same_view.segment_C.points.emplace_back(0.3f, 0.3f, 1.0f);
  same_view.view = 0;  // a frame a few millimetres on: still one view
  ASSERT_TRUE(map.AddObservation(id, same_view, kIdentity));
  EXPECT_EQ(map.Find(id)->Views(), 1);
  EXPECT_EQ(map.ModelPoints(*map.Find(id)).size(), 3u);
  ObjectObservation next_view = Observation(3, kCup, 0.6f, surface);
  next_view.view = 1;
  ASSERT_TRUE(map.AddObservation(id, next_view, kIdentity));
  EXPECT_EQ(map.Find(id)->Views(), 2);
  EXPECT_EQ(map.ModelPoints(*map.Find(id)).size(), 2u) << "the stray voxel, one view, is out";
  EXPECT_EQ(map.Find(id)->model_W.size(), 3u) << "the association still sees every voxel";
  // Reassigned views (poses changed): all three keyframes one view, the stray voxel counts.
  map.AssignViews({{1, 0}, {2, 0}, {3, 0}});
  map.Rebuild([](KeyframeId) { return std::optional<Eigen::Isometry3d>(kIdentity); });
  EXPECT_EQ(map.ModelPoints(*map.Find(id)).size(), 3u);
}

}  // namespace
}  // namespace objmap
