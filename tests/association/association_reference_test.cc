// The Associator's answers against a brute-force reference of the paper's test (Sec. III-C):
// every test point tried against every model point, no grid, no cache, no early stop.
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <random>

#include "association/associator.h"
#include "test_scenes.h"

namespace objmap {
namespace {

const Eigen::Isometry3d kIdentity = Eigen::Isometry3d::Identity();
const int kCup = CocoClassId("cup");
const int kBook = CocoClassId("book");

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

std::vector<Eigen::Vector3f> Noisy(std::vector<Eigen::Vector3f> points, float sigma_m,
                                   std::mt19937* rng) {
  std::normal_distribution<float> noise(0.f, sigma_m);
  for (Eigen::Vector3f& p : points) p += Eigen::Vector3f(noise(*rng), noise(*rng), noise(*rng));
  return points;
}

bool WithinBruteForce(const std::vector<Eigen::Vector3f>& model_points, const Eigen::Vector3f& p,
                      float distance_m) {
  for (const Eigen::Vector3f& q : model_points) {
    const float dx = p.x() - q.x(), dy = p.y() - q.y(), dz = p.z() - q.z();
    float distance_sq = dx * dx;
    distance_sq += dy * dy;
    distance_sq += dz * dz;
    if (distance_sq <= distance_m * distance_m) return true;
  }
  return false;
}

// The fraction of the evenly spaced test points (AssociationConfig::max_test_points) of `points`
// within `distance_m` of the object's model points.
float ReferenceFraction(const MapObject& object, const std::vector<Eigen::Vector3f>& points,
                        float distance_m, int max_test_points) {
  if (points.empty()) return 0.f;
  const std::vector<Eigen::Vector3f> model_points = object.model_W.Points().points;
  const std::size_t stride = (points.size() + max_test_points - 1) / max_test_points;
  std::size_t matched = 0, tested = 0;
  for (std::size_t i = 0; i < points.size(); i += stride, ++tested) {
    if (WithinBruteForce(model_points, points[i], distance_m)) ++matched;
  }
  return static_cast<float>(matched) / static_cast<float>(tested);
}

// AssignKeyframe's rule on reference fractions: best pairs first (the match fraction less the
// centroid distance in metres), one segment per object.
std::vector<std::optional<ObjectId>> ReferenceAssignment(
    const ObjectMap& map, const std::vector<SegmentToAssociate>& segments,
    const AssociationConfig& config) {
  const Associator gate(config);  // candidates by centroid and the class gate only
  struct Pair {
    float rank;
    std::size_t segment;
    ObjectId object;
  };
  std::vector<Pair> pairs;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    for (const Eigen::Vector3f& p : segments[s].points_W) centroid += p;
    centroid /= static_cast<float>(segments[s].points_W.size());
    for (ObjectId id : gate.Candidates(map, segments[s].points_W)) {
      const MapObject& object = *map.Find(id);
      if (!gate.ClassCompatible(object, segments[s].class_id)) continue;
      const float fraction = ReferenceFraction(object, segments[s].points_W,
                                               config.match_distance_m, config.max_test_points);
      if (fraction >= config.min_match_fraction) {
        pairs.push_back({fraction - (object.centroid_W - centroid).norm(), s, id});
      }
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.rank != b.rank ? a.rank > b.rank : a.segment < b.segment;
  });
  std::vector<std::optional<ObjectId>> assignment(segments.size());
  std::vector<ObjectId> taken;
  for (const Pair& pair : pairs) {
    if (assignment[pair.segment]) continue;
    if (std::find(taken.begin(), taken.end(), pair.object) != taken.end()) continue;
    assignment[pair.segment] = pair.object;
    taken.push_back(pair.object);
  }
  return assignment;
}

// Boxes of random size and place in a 1 m cube, each drawn from two noisy views so that the
// model's points are voxel means, not the inserted points.
ObjectMap RandomMap(std::mt19937* rng, int objects,
                    std::vector<std::vector<Eigen::Vector3f>>* shapes) {
  std::uniform_real_distribution<float> place(0.f, 0.6f), size(0.04f, 0.15f);
  ObjectMap map;
  for (int i = 0; i < objects; ++i) {
    const Eigen::Vector3f lo(place(*rng), place(*rng), place(*rng));
    const Eigen::Vector3f hi = lo + Eigen::Vector3f(size(*rng), size(*rng), size(*rng));
    shapes->push_back(testing::BoxSurface(lo, hi, 0.008f));
    const int class_id = i % 3 == 0 ? kBook : kCup;
    const ObjectId id =
        map.AddObject(Observation(1, class_id, Noisy(shapes->back(), 0.004f, rng)), kIdentity);
    map.AddObservation(id, Observation(2, class_id, Noisy(shapes->back(), 0.004f, rng)), kIdentity);
  }
  return map;
}

TEST(AssociationReference, MatchFractionEqualsBruteForce) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    std::vector<std::vector<Eigen::Vector3f>> shapes;
    const ObjectMap map = RandomMap(&rng, 6, &shapes);
    for (const int max_test_points : {97, INT_MAX}) {
      AssociationConfig config;
      config.max_test_points = max_test_points;
      Associator associator(config);
      int partial = 0;
      for (const auto& shape : shapes) {
        std::uniform_real_distribution<float> shift(-0.04f, 0.04f);
        const auto segment =
            Noisy(Shifted(shape, {shift(rng), shift(rng), shift(rng)}), 0.008f, &rng);
        for (const auto& [id, object] : map.objects()) {
          for (const float distance_m : {0.02f, 0.05f}) {
            const float expected = ReferenceFraction(object, segment, distance_m, max_test_points);
            EXPECT_EQ(associator.MatchFraction(object, segment, distance_m), expected)
                << "seed " << seed << ", object " << id << ", distance " << distance_m;
            partial += expected > 0.f && expected < 1.f ? 1 : 0;
          }
        }
      }
      EXPECT_GT(partial, 0) << "the scenes must exercise partial overlaps";
    }
  }
}

TEST(AssociationReference, AssignmentEqualsReference) {
  int joins = 0, new_objects = 0;
  for (const unsigned seed : {4u, 5u, 6u, 7u}) {
    std::mt19937 rng(seed);
    std::vector<std::vector<Eigen::Vector3f>> shapes;
    const ObjectMap map = RandomMap(&rng, 8, &shapes);
    AssociationConfig config;
    Associator associator(config);
    std::vector<SegmentToAssociate> segments;
    std::uniform_real_distribution<float> shift(-0.05f, 0.05f);
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      const int class_id = i % 3 == 0 ? kBook : kCup;
      segments.push_back(
          {Noisy(Shifted(shapes[i], {shift(rng), shift(rng), shift(rng)}), 0.01f, &rng), class_id});
    }
    const auto expected = ReferenceAssignment(map, segments, config);
    EXPECT_EQ(associator.AssignKeyframe(map, segments), expected) << "seed " << seed;
    for (const auto& target : expected) (target ? joins : new_objects) += 1;
  }
  EXPECT_GT(joins, 0);
  EXPECT_GT(new_objects, 0);
}

// The count may stop once 50 % is out of reach; it must not stop one point too early or late.
TEST(AssociationReference, ExactlyHalfJoinsAndOneFewerDoesNot) {
  ObjectMap map;
  const auto cup = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  const ObjectId id = map.AddObject(Observation(1, kCup, cup), kIdentity);
  const std::vector<Eigen::Vector3f> on_model = map.Find(id)->model_W.Points().points;
  const std::size_t half = 200;
  AssociationConfig config;
  Associator associator(config);
  for (const bool matches_first : {true, false}) {
    for (const std::size_t matching : {half, half - 1}) {
      std::vector<Eigen::Vector3f> near(on_model.begin(), on_model.begin() + matching);
      // 3 cm off the cup's top: a candidate by centroid distance, but no point within 2 cm.
      std::vector<Eigen::Vector3f> off(2 * half - matching, Eigen::Vector3f(0.04f, 0.04f, 0.13f));
      std::vector<Eigen::Vector3f> segment = matches_first ? near : off;
      const auto& rest = matches_first ? off : near;
      segment.insert(segment.end(), rest.begin(), rest.end());
      ASSERT_EQ(associator.Candidates(map, segment), std::vector<ObjectId>{id});
      const auto joins = associator.AssignKeyframe(map, {{segment, kCup}});
      EXPECT_EQ(joins[0].has_value(), matching == half)
          << matching << " of " << segment.size() << (matches_first ? ", matches first" : "");
      EXPECT_EQ(associator.MatchFraction(*map.Find(id), segment),
                ReferenceFraction(*map.Find(id), segment, 0.02f, config.max_test_points));
    }
  }
}

// A cached search structure must follow the model: new observations, a merge, a rebuild that
// moves the points without changing how many there are, and a model that became empty.
TEST(AssociationReference, CacheFollowsModelChanges) {
  ObjectMap map;
  // Points at voxel centres, so that a move by whole voxels keeps the number of voxels.
  const auto cup = Shifted(testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f),
                           Eigen::Vector3f::Constant(0.0025f));
  const auto upper = Shifted(cup, {0.f, 0.f, 0.06f});
  const ObjectId id = map.AddObject(Observation(1, kCup, cup), kIdentity);
  Associator associator{AssociationConfig{}};
  const auto check = [&](const char* step) {
    const MapObject& object = *map.Find(id);
    const float expected = ReferenceFraction(object, upper, 0.02f, 1000);
    EXPECT_EQ(associator.MatchFraction(object, upper), expected) << step;
    return expected;
  };
  const float before = check("first view");

  map.AddObservation(id, Observation(2, kCup, upper), kIdentity);
  const float grown = check("after a second view");
  EXPECT_GT(grown, before);

  const ObjectId other =
      map.AddObject(Observation(3, kCup, Shifted(upper, {0.f, 0.f, 0.2f})), kIdentity);
  EXPECT_EQ(associator.MatchFraction(*map.Find(other), upper),
            ReferenceFraction(*map.Find(other), upper, 0.02f, 1000));
  ASSERT_TRUE(map.Merge(id, other));
  check("after a merge");

  // Every keyframe moved 25 cm: same number of voxels, other places.
  Eigen::Isometry3d moved = kIdentity;
  moved.translation() = Eigen::Vector3d(0.25, 0.0, 0.0);
  const std::size_t size_before = map.Find(id)->model_W.size();
  map.Rebuild([&](KeyframeId) { return std::optional<Eigen::Isometry3d>(moved); });
  ASSERT_EQ(map.Find(id)->model_W.size(), size_before);
  EXPECT_EQ(check("after a rebuild that moved the model"), 0.f);

  map.Rebuild([](KeyframeId) { return std::optional<Eigen::Isometry3d>(); });
  ASSERT_TRUE(map.Find(id)->model_W.empty());
  EXPECT_EQ(check("after the model became empty"), 0.f);
  EXPECT_EQ(associator.MatchFraction(*map.Find(id), {}), 0.f);
  EXPECT_FALSE(associator.AssignKeyframe(map, {{upper, kCup}})[0].has_value());
}

TEST(AssociationReference, EmptySegmentsJoinNothing) {
  ObjectMap map;
  const auto cup = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  map.AddObject(Observation(1, kCup, cup), kIdentity);
  Associator associator{AssociationConfig{}};
  const auto joins = associator.AssignKeyframe(map, {{{}, kCup}, {cup, kCup}});
  ASSERT_EQ(joins.size(), 2u);
  EXPECT_FALSE(joins[0].has_value());
  EXPECT_TRUE(joins[1].has_value());
}

// Two views of one cup, the second shifted further and further: they are duplicates exactly
// while the reference says >= 50 % of the smaller lies within 5 cm of the larger.
TEST(AssociationReference, DuplicatesFollowTheReferenceFraction) {
  const auto cup = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.1f}, 0.005f);
  const auto part = testing::BoxSurface({0, 0, 0}, {0.08f, 0.08f, 0.05f}, 0.005f);
  int duplicates = 0, apart = 0;
  for (float shift_m = 0.f; shift_m <= 0.12f; shift_m += 0.0025f) {
    ObjectMap map;
    const ObjectId whole = map.AddObject(Observation(1, kCup, cup), kIdentity);
    const ObjectId view =
        map.AddObject(Observation(2, kCup, Shifted(part, {shift_m, 0, 0})), kIdentity);
    const MapObject& small = *map.Find(view);
    const AssociationConfig config;
    const bool expected = ReferenceFraction(*map.Find(whole), small.model_W.Points().points,
                                            config.duplicate_distance_m,
                                            config.max_test_points) >= config.min_match_fraction;
    Associator associator(config);
    const auto found = associator.FindDuplicates(map, {view});
    if (expected) {
      EXPECT_EQ(found, (std::vector<std::pair<ObjectId, ObjectId>>{{whole, view}}))
          << "shift " << shift_m;
    } else {
      EXPECT_TRUE(found.empty()) << "shift " << shift_m;
    }
    (expected ? duplicates : apart) += 1;
  }
  EXPECT_GT(duplicates, 0);
  EXPECT_GT(apart, 0);
}

}  // namespace
}  // namespace objmap
