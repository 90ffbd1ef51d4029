#include "objects/object_map.h"

#include <gtest/gtest.h>

#include <algorithm>

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

TEST(ObjectMap, AnObjectOnlySegmentedIsUnknownUntilADetectionNamesIt) {
  ObjectMap map;
  const auto points = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  const ObjectId id = map.AddObject(Observation(1, kUnknownClassId, 0.f, points), kIdentity);
  EXPECT_TRUE(IsUnclassified(map.Find(id)->observations[0]));
  EXPECT_TRUE(map.AddObservation(id, Observation(2, kUnknownClassId, 0.f, points), kIdentity));
  EXPECT_EQ(map.Find(id)->Label(), kUnknownClassId);
  EXPECT_EQ(map.Find(id)->Confidence(), 0.f);
  EXPECT_GT(map.Find(id)->model_W.size(), 0u);
  EXPECT_TRUE(map.AddObservation(id, Observation(3, kCup, 0.6f, points), kIdentity));
  EXPECT_FALSE(IsUnclassified(map.Find(id)->observations[2]));
  EXPECT_EQ(map.Find(id)->Label(), kCup);
  // Over the one observation that named it: the views that only segmented it say nothing of
  // its class.
  EXPECT_NEAR(map.Find(id)->Confidence(), 0.6f, 1e-6);
  std::map<ObjectId, std::vector<ObjectObservation>> stored = {{id, map.Find(id)->observations}};
  stored[id].pop_back();
  map.Restore(stored, id + 1, [](KeyframeId) { return kIdentity; });
  EXPECT_EQ(map.Find(id)->Label(), kUnknownClassId) << "restored from its unnamed views";
}

// Four views of one model, each naming it with `scores`.
const MapObject& ObjectSeenFourTimes(ObjectMap* map, const std::vector<Eigen::Vector3f>& points,
                                     const std::vector<std::pair<int, float>>& scores) {
  ObjectObservation observation = Observation(1, kCup, 0.f, points);
  observation.class_scores = scores;
  const ObjectId id = map->AddObject(observation, kIdentity);
  for (KeyframeId keyframe = 2; keyframe <= 4; ++keyframe) {
    observation.keyframe_id = keyframe;
    EXPECT_TRUE(map->AddObservation(id, observation, kIdentity));
  }
  return *map->Find(id);
}

TEST(ObjectMap, AModelThickerThanAPhoneTakesTheBestClassItsShapeAllows) {
  const int phone = CocoClassId("cell phone"), remote = CocoClassId("remote");
  const int mouse = CocoClassId("mouse");
  const auto mouse_points = testing::BoxSurface({0, 0, 0}, {0.06f, 0.11f, 0.04f}, 0.005f);
  const auto phone_points = testing::BoxSurface({0, 0, 0}, {0.07f, 0.14f, 0.008f}, 0.004f);

  ObjectMap map;
  // Phone 2.0, remote 0.4, mouse 0.8 over four views: a 4 cm model is no phone or remote, and
  // the mouse had 40 % of the phone's score. Its confidence counts the phone and remote share
  // too: (0.8 / 4) x 3.2 / 0.8.
  const MapObject& thick =
      ObjectSeenFourTimes(&map, mouse_points, {{phone, 0.5f}, {remote, 0.1f}, {mouse, 0.2f}});
  EXPECT_TRUE(thick.ruled_out_classes[phone]);
  EXPECT_TRUE(thick.ruled_out_classes[remote]);
  EXPECT_EQ(thick.Label(), mouse);
  EXPECT_NEAR(thick.Confidence(), 0.8f, 1e-5);

  // A class named in passing (10 % of the phone's score) is no name: unknown.
  const MapObject& named_in_passing =
      ObjectSeenFourTimes(&map, mouse_points, {{phone, 0.5f}, {mouse, 0.05f}});
  EXPECT_EQ(named_in_passing.Label(), kUnknownClassId);
  EXPECT_EQ(named_in_passing.Confidence(), 0.f);

  // A thick model whose best class stands keeps the paper's confidence: 0.3 x 4 / 4.
  const MapObject& mouse_first =
      ObjectSeenFourTimes(&map, mouse_points, {{mouse, 0.3f}, {phone, 0.2f}});
  EXPECT_EQ(mouse_first.Label(), mouse);
  EXPECT_NEAR(mouse_first.Confidence(), 0.3f, 1e-5);

  // A flat model stays a phone, with the paper's confidence.
  const MapObject& flat = ObjectSeenFourTimes(&map, phone_points, {{phone, 0.5f}, {mouse, 0.2f}});
  EXPECT_FALSE(flat.ruled_out_classes[phone]);
  EXPECT_EQ(flat.Label(), phone);
  EXPECT_NEAR(flat.Confidence(), 0.5f, 1e-5);

  // No thin classes: the thick model is what its detections said most.
  ObjectMapConfig no_thin_classes;
  no_thin_classes.thin_classes.clear();
  ObjectMap plain_map(no_thin_classes);
  const MapObject& plain =
      ObjectSeenFourTimes(&plain_map, mouse_points, {{phone, 0.5f}, {mouse, 0.2f}});
  EXPECT_FALSE(plain.ruled_out_classes.any());
  EXPECT_EQ(plain.Label(), phone);
  EXPECT_NEAR(plain.Confidence(), 0.5f, 1e-5);
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

// Points along x from `x0` to `x1` (metres, exclusive) one voxel (5 mm) apart, 1 m ahead.
std::vector<Eigen::Vector3f> Strip(float x0, float x1) {
  std::vector<Eigen::Vector3f> points;
  for (float x = x0 + 0.0025f; x < x1; x += 0.005f) points.emplace_back(x, 0.0025f, 1.0025f);
  return points;
}

int CountIn(const ColoredPoints& model, float x0, float x1) {
  return static_cast<int>(
      std::count_if(model.points.begin(), model.points.end(),
                    [&](const Eigen::Vector3f& p) { return p.x() >= x0 && p.x() < x1; }));
}

// Two mugs side by side: a's surface x in [0, 4 cm), b's [6, 10 cm). Two of a's four views
// boxed a alone and took the near 2 cm of b with it; b's three views reached all of b.
struct TouchingMugs {
  ObjectMap map;
  ObjectId a = 0, b = 0;

  explicit TouchingMugs(const ObjectMapConfig& config, int b_class = kCup) : map(config) {
    for (int view = 0; view < 4; ++view) {
      std::vector<Eigen::Vector3f> points = Strip(0.f, 0.04f);
      if (view < 2) {
        const std::vector<Eigen::Vector3f> slice = Strip(0.06f, 0.08f);
        points.insert(points.end(), slice.begin(), slice.end());
      }
      ObjectObservation observation = Observation(view + 1, kCup, 0.8f, points);
      observation.view = view;
      if (view == 0) {
        a = map.AddObject(observation, kIdentity);
      } else {
        EXPECT_TRUE(map.AddObservation(a, observation, kIdentity));
      }
    }
    for (int view = 0; view < 3; ++view) {
      ObjectObservation observation = Observation(view + 1, b_class, 0.8f, Strip(0.06f, 0.10f));
      observation.view = view;
      if (view == 0) {
        b = map.AddObject(observation, kIdentity);
      } else {
        EXPECT_TRUE(map.AddObservation(b, observation, kIdentity));
      }
    }
  }
  [[nodiscard]] ColoredPoints Model(ObjectId id) const { return map.ModelPoints(*map.Find(id)); }
};

TEST(ObjectMap, AVoxelTwoMugsShareIsPublishedWithTheMugMostOfWhoseViewsReachedIt) {
  const TouchingMugs mugs{ObjectMapConfig{}};
  const ColoredPoints a = mugs.Model(mugs.a), b = mugs.Model(mugs.b);
  EXPECT_EQ(CountIn(a, 0.f, 0.04f), 8) << "a keeps its own surface";
  EXPECT_EQ(CountIn(a, 0.06f, 0.10f), 0) << "the slice of b (2 of a's 4 views) is b's (3 of 3)";
  EXPECT_EQ(CountIn(b, 0.06f, 0.10f), 8) << "b keeps all of itself";
  EXPECT_EQ(mugs.map.Find(mugs.a)->model_W.size(), 12u) << "the association still sees it all";
}

TEST(ObjectMap, SharedVoxelsStayWithBothWhenOffOrWhenTheClassesDiffer) {
  ObjectMapConfig off;
  off.resolve_shared_voxels = false;
  const TouchingMugs mugs{off};
  EXPECT_EQ(CountIn(mugs.Model(mugs.a), 0.06f, 0.10f), 4);
  // A bowl beside the mug is another kind of thing: what the mug's views saw of it is no
  // business of the bowl's model.
  const TouchingMugs mug_and_bowl{ObjectMapConfig{}, kBowl};
  EXPECT_EQ(CountIn(mug_and_bowl.Model(mug_and_bowl.a), 0.06f, 0.10f), 4);
}

TEST(ObjectMap, AOneViewObjectDoesNotTakeVoxelsFromAWellSeenOne) {
  TouchingMugs mugs{ObjectMapConfig{}};
  // A one-off detection over a's surface: one view reached it, against four of a's.
  ObjectObservation stray = Observation(9, kCup, 0.5f, Strip(0.f, 0.02f));
  stray.view = 9;
  const ObjectId stray_id = mugs.map.AddObject(stray, kIdentity);
  EXPECT_EQ(CountIn(mugs.Model(mugs.a), 0.f, 0.04f), 8);
  EXPECT_EQ(CountIn(mugs.Model(stray_id), 0.f, 0.04f), 0) << "its voxels are a's";
}

TEST(ObjectMap, ThePublishedModelKeyChangesWithATouchingObjectOfItsClassOnly) {
  TouchingMugs mugs{ObjectMapConfig{}};
  const auto key = mugs.map.ModelKey(*mugs.map.Find(mugs.a));
  EXPECT_EQ(key.size(), 2u) << "a and b";
  ObjectObservation far_away = Observation(5, kCup, 0.8f, {{2.f, 0.f, 1.f}});
  mugs.map.AddObject(far_away, kIdentity);
  EXPECT_EQ(mugs.map.ModelKey(*mugs.map.Find(mugs.a)), key) << "a mug 2 m away changes nothing";
  ObjectObservation more_of_b = Observation(4, kCup, 0.8f, Strip(0.06f, 0.10f));
  more_of_b.view = 3;
  ASSERT_TRUE(mugs.map.AddObservation(mugs.b, more_of_b, kIdentity));
  EXPECT_NE(mugs.map.ModelKey(*mugs.map.Find(mugs.a)), key);
}

}  // namespace
}  // namespace objmap
