#include "association/associator.h"

#include <gtest/gtest.h>

#include "test_scenes.h"

namespace objmap {
namespace {

const Eigen::Isometry3d kIdentity = Eigen::Isometry3d::Identity();
const int kTv = CocoClassId("tv");
const int kCup = CocoClassId("cup");

ObjectObservation Observation(KeyframeId keyframe, int class_id,
                              const std::vector<Eigen::Vector3f>& points) {
  ObjectObservation observation;
  observation.keyframe_id = keyframe;
  observation.class_scores = {{class_id, 0.8f}};
  observation.segment_C.points = points;
  return observation;
}

std::vector<Eigen::Vector3f> Shifted(std::vector<Eigen::Vector3f> points,
                                     const Eigen::Vector3f& d) {
  for (Eigen::Vector3f& p : points) p += d;
  return points;
}

TEST(Associator, FiftyPercentWithinTwoCentimetres) {
  ObjectMap map;
  const auto cup = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  const ObjectId id = map.AddObject(Observation(1, kCup, cup), kIdentity);
  Associator associator{AssociationConfig{}};
  EXPECT_FLOAT_EQ(associator.MatchFraction(*map.Find(id), cup), 1.f);
  EXPECT_FLOAT_EQ(associator.MatchFraction(*map.Find(id), Shifted(cup, {0.015f, 0, 0})), 1.f);
  // Shifted by 3 cm along x: only the faces that still overlap (y/z walls) match.
  const float shifted_3cm = associator.MatchFraction(*map.Find(id), Shifted(cup, {0.03f, 0, 0}));
  EXPECT_GT(shifted_3cm, 0.3f);
  EXPECT_LT(shifted_3cm, 1.f);
  EXPECT_FLOAT_EQ(associator.MatchFraction(*map.Find(id), Shifted(cup, {0.5f, 0, 0})), 0.f);

  auto joins = associator.AssignKeyframe(map, {{Shifted(cup, {0.01f, 0, 0}), kCup}});
  ASSERT_EQ(joins.size(), 1u);
  EXPECT_EQ(joins[0], id);
  joins = associator.AssignKeyframe(map, {{Shifted(cup, {0.2f, 0, 0}), kCup}});
  EXPECT_FALSE(joins[0].has_value());
}

TEST(Associator, CandidatesByCentroidDistance) {
  ObjectMap map;
  const auto cup = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  const ObjectId near = map.AddObject(Observation(1, kCup, cup), kIdentity);
  map.AddObject(Observation(1, kCup, Shifted(cup, {3.f, 0, 0})), kIdentity);
  Associator associator{AssociationConfig{}};
  EXPECT_EQ(associator.Candidates(map, Shifted(cup, {0.1f, 0, 0})), std::vector<ObjectId>{near});
}

TEST(Associator, OneObjectTakesOneSegmentPerKeyframe) {
  // One wide object built from an earlier view covers two monitors; a later keyframe sees both
  // monitors separately: they must not both join it.
  ObjectMap map;
  const auto left = testing::BoxSurface({0, 0, 0}, {0.5f, 0.02f, 0.3f}, 0.005f);
  const auto right = Shifted(left, {0.52f, 0, 0});
  std::vector<Eigen::Vector3f> both = left;
  both.insert(both.end(), right.begin(), right.end());
  const ObjectId merged = map.AddObject(Observation(1, kTv, both), kIdentity);
  Associator associator{AssociationConfig{}};
  const auto joins = associator.AssignKeyframe(map, {{left, kTv}, {right, kTv}});
  ASSERT_EQ(joins.size(), 2u);
  EXPECT_EQ(static_cast<int>(joins[0].has_value()) + static_cast<int>(joins[1].has_value()), 1);
  EXPECT_TRUE(joins[0] == merged || joins[1] == merged);
}

// Two books in a stack, each 1.5 cm thick: every point of either lies within 2 cm of the other,
// so a segment of one matches both in full. The nearer centroid decides, whichever order the
// segments come in and whichever object is older.
TEST(Associator, StackedThinObjectsGoToTheNearerCentroid) {
  const int kBook = CocoClassId("book");
  const auto lower = testing::BoxSurface({0, 0, 0}, {0.24f, 0.17f, 0.015f}, 0.005f);
  const auto upper = Shifted(lower, {0, 0, 0.015f});
  for (const bool upper_first : {false, true}) {
    ObjectMap map;
    const ObjectId lower_id =
        map.AddObject(Observation(1, kBook, upper_first ? upper : lower), kIdentity);
    const ObjectId upper_id =
        map.AddObject(Observation(1, kBook, upper_first ? lower : upper), kIdentity);
    const ObjectId lower_object = upper_first ? upper_id : lower_id;
    const ObjectId upper_object = upper_first ? lower_id : upper_id;
    Associator associator{AssociationConfig{}};
    ASSERT_FLOAT_EQ(associator.MatchFraction(*map.Find(lower_object), upper), 1.f);
    ASSERT_FLOAT_EQ(associator.MatchFraction(*map.Find(upper_object), lower), 1.f);
    for (const bool upper_segment_first : {false, true}) {
      std::vector<SegmentToAssociate> segments = {{lower, kBook}, {upper, kBook}};
      if (upper_segment_first) std::swap(segments[0], segments[1]);
      const auto joins = associator.AssignKeyframe(map, segments);
      ASSERT_EQ(joins.size(), 2u);
      EXPECT_EQ(joins[upper_segment_first ? 1 : 0], lower_object);
      EXPECT_EQ(joins[upper_segment_first ? 0 : 1], upper_object);
      // Alone, too: the upper book's segment goes to the upper book.
      EXPECT_EQ(associator.AssignKeyframe(map, {{upper, kBook}})[0], upper_object);
    }
  }
}

TEST(Associator, FindsDuplicatesOfTheSameLabelOnly) {
  ObjectMap map;
  const auto table = testing::BoxSurface({0, 0, 0}, {1.0f, 0.6f, 0.02f}, 0.01f);
  const auto part = testing::BoxSurface({0, 0, 0}, {0.4f, 0.6f, 0.02f}, 0.01f);
  const int kTable = CocoClassId("dining table");
  const ObjectId whole = map.AddObject(Observation(1, kTable, table), kIdentity);
  const ObjectId piece = map.AddObject(Observation(2, kTable, part), kIdentity);
  const ObjectId cup_on_it = map.AddObject(Observation(2, kCup, part), kIdentity);
  Associator associator{AssociationConfig{}};
  const auto duplicates = associator.FindDuplicates(map, {piece, cup_on_it});
  ASSERT_EQ(duplicates.size(), 1u);
  EXPECT_EQ(duplicates[0], std::make_pair(whole, piece));
}

TEST(Associator, ClassesMustAgreeUnlessGatingIsOff) {
  // A book lying on a table: all its points are within 2 cm of the table's model.
  ObjectMap map;
  const int kTable = CocoClassId("dining table");
  const int kBook = CocoClassId("book");
  const auto table = testing::BoxSurface({0, 0, 0}, {1.0f, 0.6f, 0.02f}, 0.01f);
  const auto book = testing::BoxSurface({0.2f, 0.2f, 0.0f}, {0.4f, 0.35f, 0.02f}, 0.01f);
  const ObjectId table_id = map.AddObject(Observation(1, kTable, table), kIdentity);
  Associator gated{AssociationConfig{}};
  EXPECT_FALSE(gated.AssignKeyframe(map, {{book, kBook}})[0].has_value());
  EXPECT_EQ(gated.AssignKeyframe(map, {{book, kTable}})[0], table_id);
  AssociationConfig paper;
  paper.min_class_share = 0.f;
  Associator geometric{paper};
  EXPECT_EQ(geometric.AssignKeyframe(map, {{book, kBook}})[0], table_id);
}

}  // namespace
}  // namespace objmap
