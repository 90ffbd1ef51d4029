// Changes over two visits of a table: a cup taken away, moved or put down between them, and
// what the mapper makes of each (Mapper::Changes, ConfirmedObjects, Inventory, objects.json).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <set>

#include "mapper/map_export.h"
#include "mapper/mapper.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

using testing::SceneBox;

const int kCup = CocoClassId("cup");

using namespace testing::table_visits;  // kTable, kWall, the cups, both visits' eyes

// Where a third cup is put down: on the table, in view of both visits, 30 cm and more from
// anything else.
const SceneBox kCupThree{{-0.35, 0.45, 0.70}, {-0.25, 0.55, 0.82}, {30, 160, 30}};

class ObjectChangesTest : public ::testing::Test {
 protected:
  // Maps every eye of a visit over the table, the wall and the cups in `cups`; the cups in
  // `detected` (a subset of `cups`) are detected in every view.
  void MapVisit(Mapper* mapper, const std::vector<Eigen::Vector3d>& eyes,
                const std::vector<SceneBox>& cups, const std::vector<SceneBox>& detected) const {
    std::vector<SceneBox> boxes = {kTable, kWall};
    boxes.insert(boxes.end(), cups.begin(), cups.end());
    for (const Eigen::Vector3d& eye : eyes) {
      const Eigen::Isometry3d T_W_C = testing::LookAt(eye, kTarget);
      std::vector<Detection> detections;
      for (const SceneBox& cup : detected) {
        detections.push_back({testing::ProjectBox(cup, T_W_C, K_), kCup, 0.6f});
      }
      KeyframeResult result;
      std::string why;
      ASSERT_TRUE(mapper->AddKeyframe(testing::RenderFrame(boxes, K_, T_W_C, "frame"), detections,
                                      &result, &why))
          << why;
    }
  }

  // The object of the mapper nearest `box`'s centre.
  static ObjectId ObjectAt(const Mapper& mapper, const SceneBox& box) {
    const Eigen::Vector3f centre = ((box.lo + box.hi) * 0.5).cast<float>();
    ObjectId best = 0;
    float best_distance = 1e9f;
    for (const auto& [id, object] : mapper.objects().objects()) {
      const float distance = (object.centroid_W - centre).norm();
      if (distance < best_distance) {
        best = id;
        best_distance = distance;
      }
    }
    return best_distance < 0.05f ? best : 0;
  }

  static bool IsConfirmed(const Mapper& mapper, ObjectId id) {
    for (const MapObject* object : mapper.ConfirmedObjects()) {
      if (object->id == id) return true;
    }
    return false;
  }

  CameraIntrinsics K_;
  const MapperConfig config_;
};

TEST_F(ObjectChangesTest, OneVisitHasNoChanges) {
  Mapper mapper{config_};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  MapVisit(&mapper, kSecondEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const ObjectChanges changes = mapper.Changes();
  EXPECT_TRUE(changes.histories.empty());
  EXPECT_TRUE(changes.gone.empty());
  EXPECT_EQ(mapper.ConfirmedObjects().size(), 2u);
}

TEST_F(ObjectChangesTest, ACupTakenAwayIsRemovedAndLeavesTheInventory) {
  Mapper mapper{config_};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const ObjectId cup_two = ObjectAt(mapper, kCupTwo);
  ASSERT_NE(cup_two, 0);
  ASSERT_TRUE(IsConfirmed(mapper, cup_two));
  MapVisit(&mapper, kSecondEyes, {kCupOne}, {kCupOne});

  const ObjectChanges changes = mapper.Changes();
  ASSERT_EQ(changes.histories.count(cup_two), 1u);
  const ObjectHistory& history = changes.histories.at(cup_two);
  EXPECT_EQ(history.state, ObjectState::kRemoved);
  EXPECT_EQ(history.class_id, kCup);
  ASSERT_EQ(history.places.size(), 1u);
  // Two independent views of the second visit are the evidence: the fifth keyframe completes it.
  EXPECT_EQ(history.places[0].seen_empty_at, 5);
  EXPECT_EQ(changes.gone.count(cup_two), 1u);
  EXPECT_FALSE(IsConfirmed(mapper, cup_two));
  ASSERT_EQ(mapper.Inventory().size(), 1u);
  EXPECT_EQ(mapper.Inventory()[0].count, 1);

  const std::vector<ObjectChange> list = ChangeList(changes);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].kind, ObjectChange::Kind::kRemoved);
  EXPECT_EQ(list[0].id, cup_two);
  EXPECT_NEAR(list[0].centroid_W.y(), 0.2f, 0.03f);

  // objects.json lists it as removed, not among the objects.
  const nlohmann::json json = nlohmann::json::parse(ObjectsJson(mapper));
  ASSERT_EQ(json["removed"].size(), 1u);
  EXPECT_EQ(json["removed"][0]["id"], cup_two);
  for (const nlohmann::json& object : json["objects"]) EXPECT_NE(object["id"], cup_two);
}

TEST_F(ObjectChangesTest, DetectorMissesAloneRemoveNothing) {
  Mapper mapper{config_};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const ObjectId cup_two = ObjectAt(mapper, kCupTwo);
  // Cup two is still there; the detector just does not find it in the second visit.
  MapVisit(&mapper, kSecondEyes, {kCupOne, kCupTwo}, {kCupOne});
  const ObjectChanges changes = mapper.Changes();
  EXPECT_EQ(changes.histories.count(cup_two), 0u);
  EXPECT_EQ(changes.gone.count(cup_two), 0u);
  EXPECT_TRUE(ChangeList(changes).empty());
}

TEST_F(ObjectChangesTest, AMovedCupKeepsItsIdAndBothPlaces) {
  Mapper mapper{config_};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const ObjectId cup_two = ObjectAt(mapper, kCupTwo);
  MapVisit(&mapper, kSecondEyes, {kCupOne, kCupTwoMoved}, {kCupOne, kCupTwoMoved});
  const ObjectId new_place = ObjectAt(mapper, kCupTwoMoved);
  ASSERT_NE(new_place, 0);
  ASSERT_NE(new_place, cup_two);  // the map keeps one object per place ...

  const ObjectChanges changes = mapper.Changes();
  EXPECT_EQ(changes.PublishedId(new_place), cup_two);  // ... published under one id
  ASSERT_EQ(changes.histories.count(cup_two), 1u);
  const ObjectHistory& history = changes.histories.at(cup_two);
  EXPECT_EQ(history.state, ObjectState::kMoved);
  ASSERT_EQ(history.places.size(), 2u);
  EXPECT_EQ(history.places[0].object, cup_two);
  EXPECT_EQ(history.places[1].object, new_place);
  EXPECT_EQ(history.added_at, 0);

  const std::vector<ObjectChange> list = ChangeList(changes);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].kind, ObjectChange::Kind::kMoved);
  EXPECT_EQ(list[0].id, cup_two);
  EXPECT_NEAR(list[0].from_W.y(), 0.2f, 0.03f);
  EXPECT_NEAR(list[0].centroid_W.y(), 0.5f, 0.03f);

  // Two cups in the inventory, under the ids a client knew.
  const std::vector<InventoryEntry> inventory = mapper.Inventory();
  ASSERT_EQ(inventory.size(), 1u);
  ASSERT_EQ(inventory[0].count, 2);
  std::vector<ObjectId> ids = inventory[0].objects;
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(ids, (std::vector<ObjectId>{ObjectAt(mapper, kCupOne), cup_two}));
  const nlohmann::json json = nlohmann::json::parse(ObjectsJson(mapper));
  bool found = false;
  for (const nlohmann::json& object : json["objects"]) {
    if (object["id"] != cup_two) continue;
    found = true;
    EXPECT_EQ(object["state"], "moved");
    ASSERT_EQ(object["previous_places"].size(), 1u);
    EXPECT_NEAR(object["centroid"][1].get<double>(), 0.5, 0.03);
  }
  EXPECT_TRUE(found);
}

TEST_F(ObjectChangesTest, LookAlikesAreNoGuessedMoveWhenAmbiguityIsChecked) {
  // Two blue cups of one make; both go, one blue cup appears elsewhere: which of them it is, if
  // either, nothing tells. Two removals and an addition, no move.
  SceneBox blue_one = kCupOne;
  blue_one.rgb = kCupTwo.rgb;
  MapperConfig undecided;
  undecided.changes.move_ambiguity_overlap_margin = 0.1f;
  Mapper mapper{undecided};
  MapVisit(&mapper, kFirstEyes, {blue_one, kCupTwo}, {blue_one, kCupTwo});
  MapVisit(&mapper, kSecondEyes, {kCupTwoMoved}, {kCupTwoMoved});
  std::map<ObjectChange::Kind, int> kinds;
  for (const ObjectChange& change : ChangeList(mapper.Changes())) ++kinds[change.kind];
  EXPECT_EQ(kinds[ObjectChange::Kind::kRemoved], 2);
  EXPECT_EQ(kinds[ObjectChange::Kind::kAdded], 1);
  EXPECT_EQ(kinds[ObjectChange::Kind::kMoved], 0);

  // With the ambiguity check off (the default), the best fit is taken: one move, one removal.
  Mapper guesser{config_};
  MapVisit(&guesser, kFirstEyes, {blue_one, kCupTwo}, {blue_one, kCupTwo});
  MapVisit(&guesser, kSecondEyes, {kCupTwoMoved}, {kCupTwoMoved});
  kinds.clear();
  for (const ObjectChange& change : ChangeList(guesser.Changes())) ++kinds[change.kind];
  EXPECT_EQ(kinds[ObjectChange::Kind::kMoved], 1);
  EXPECT_EQ(kinds[ObjectChange::Kind::kRemoved], 1);
}

TEST_F(ObjectChangesTest, ACupPutWhereTheTableWasSeenEmptyIsAdded) {
  Mapper mapper{config_};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  MapVisit(&mapper, kSecondEyes, {kCupOne, kCupTwo, kCupThree}, {kCupOne, kCupTwo, kCupThree});
  const ObjectId cup_three = ObjectAt(mapper, kCupThree);
  ASSERT_NE(cup_three, 0);
  const ObjectChanges changes = mapper.Changes();
  ASSERT_EQ(changes.histories.size(), 1u);
  ASSERT_EQ(changes.histories.count(cup_three), 1u);
  EXPECT_EQ(changes.histories.at(cup_three).state, ObjectState::kPresent);
  EXPECT_EQ(changes.histories.at(cup_three).added_at, 4);
  const std::vector<ObjectChange> list = ChangeList(changes);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].kind, ObjectChange::Kind::kAdded);
  EXPECT_TRUE(IsConfirmed(mapper, cup_three));
}

TEST_F(ObjectChangesTest, ACupSeenStandingBeforeItsFirstDetectionIsStillAdded) {
  // The first view of the second visit sees cup three on the table and does not detect it (too
  // far, too small for the detector yet); the next two do. The first visit's empty table still
  // says it was put there. (Unnamed segments would make that view an observation of the cup.)
  MapperConfig named_only;
  named_only.unknown_objects.enabled = false;
  Mapper mapper{named_only};
  mapper.SetSession(1);
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const std::vector<SceneBox> cups = {kCupOne, kCupTwo, kCupThree};
  mapper.SetSession(2);
  MapVisit(&mapper, {kSecondEyes[0]}, cups, {kCupOne, kCupTwo});
  MapVisit(&mapper, {kSecondEyes[1], kSecondEyes[2]}, cups, cups);
  const ObjectId cup_three = ObjectAt(mapper, kCupThree);
  ASSERT_NE(cup_three, 0);
  const ObjectChanges changes = mapper.Changes();
  ASSERT_EQ(changes.histories.count(cup_three), 1u);
  EXPECT_EQ(changes.histories.at(cup_three).added_at, 5);
  const std::vector<ObjectChange> list = ChangeList(changes);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].kind, ObjectChange::Kind::kAdded);
}

TEST_F(ObjectChangesTest, ViewsThatSawThePlaceEmptyBeforeACupCameAreNoMissesOfIt) {
  // Three views of the first visit looked through where cup three now stands; one view of the
  // second detects it. The empty views are no misses of the detector (the cup was not there), so
  // the one detection confirms it, as it would a cup the map had never seen the place of.
  Mapper mapper{config_};
  mapper.SetSession(1);
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const std::vector<SceneBox> cups = {kCupOne, kCupTwo, kCupThree};
  mapper.SetSession(2);
  MapVisit(&mapper, {kSecondEyes[0]}, cups, cups);
  const ObjectId cup_three = ObjectAt(mapper, kCupThree);
  ASSERT_NE(cup_three, 0);
  EXPECT_TRUE(IsConfirmed(mapper, cup_three));
  const std::vector<ObjectChange> list = ChangeList(mapper.Changes());
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].kind, ObjectChange::Kind::kAdded);
  EXPECT_EQ(list[0].id, cup_three);
}

TEST_F(ObjectChangesTest, ViewsOfTheSessionThatLookedThroughAOnceDetectedCupAreMisses) {
  // The same views in one session: the views before the detection looked through where the one
  // view of the cup put it. Within a session the world stands still, so that detection is wrong
  // (a drifted pose, a phantom) and the cup stays out of the inventory.
  Mapper mapper{config_};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  const std::vector<SceneBox> cups = {kCupOne, kCupTwo, kCupThree};
  MapVisit(&mapper, {kSecondEyes[0]}, cups, cups);
  const ObjectId cup_three = ObjectAt(mapper, kCupThree);
  ASSERT_NE(cup_three, 0);
  EXPECT_FALSE(IsConfirmed(mapper, cup_three));
}

TEST_F(ObjectChangesTest, AThingDetectedOnceAndSeenUndetectedSinceIsNoRemoval) {
  // A grey box on the table is called a cup by one view and seen, not detected, by the other two:
  // a false detection, never in the inventory. When the box is taken away, nothing the
  // inventory held went: no removal is reported.
  const SceneBox grey_box{{-0.35, 0.45, 0.70}, {-0.25, 0.55, 0.82}, {128, 128, 128}};
  Mapper mapper{config_};
  MapVisit(&mapper, {kFirstEyes[0]}, {kCupOne, grey_box}, {kCupOne, grey_box});
  MapVisit(&mapper, {kFirstEyes[1], kFirstEyes[2]}, {kCupOne, grey_box}, {kCupOne});
  const ObjectId box = ObjectAt(mapper, grey_box);
  ASSERT_NE(box, 0);
  EXPECT_FALSE(IsConfirmed(mapper, box));
  MapVisit(&mapper, kSecondEyes, {kCupOne}, {kCupOne});
  const ObjectChanges changes = mapper.Changes();
  EXPECT_EQ(changes.histories.count(box), 0u);
  EXPECT_TRUE(ChangeList(changes).empty());
}

TEST_F(ObjectChangesTest, ARestartFindsTheSameChanges) {
  Mapper live{config_};
  live.SetSession(1);
  MapVisit(&live, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  live.SetSession(2);
  MapVisit(&live, kSecondEyes, {kCupTwoMoved, kCupThree}, {kCupTwoMoved, kCupThree});
  std::map<KeyframeId, KeyframeRecord> records;
  for (KeyframeId id = 1; id <= 6; ++id) records[id] = *live.FindKeyframe(id);
  std::map<ObjectId, std::vector<ObjectObservation>> observations;
  for (const auto& [id, object] : live.objects().objects()) observations[id] = object.observations;
  Mapper restarted{config_};
  restarted.Restore(records, observations, live.objects().next_id());

  const std::vector<ObjectChange> before = ChangeList(live.Changes());
  const std::vector<ObjectChange> after = ChangeList(restarted.Changes());
  // Cup one removed, cup two moved, cup three added (green: not the red cup one, moved).
  ASSERT_EQ(before.size(), 3u);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i) {
    EXPECT_EQ(after[i].kind, before[i].kind);
    EXPECT_EQ(after[i].id, before[i].id);
    EXPECT_EQ(after[i].keyframe_id, before[i].keyframe_id);
  }
}

TEST_F(ObjectChangesTest, ChangesCanBeSwitchedOff) {
  MapperConfig config;
  config.changes.enabled = false;
  Mapper mapper{config};
  MapVisit(&mapper, kFirstEyes, {kCupOne, kCupTwo}, {kCupOne, kCupTwo});
  MapVisit(&mapper, kSecondEyes, {kCupOne}, {kCupOne});
  EXPECT_TRUE(mapper.Changes().histories.empty());
  std::string why;
  config.changes.min_empty_views = 0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("min_empty_views"), std::string::npos) << why;
}

// Objects and what each keyframe saw of them, given to DetectChanges directly: keyframes 1..N,
// each an independent view, all of session 1 unless told otherwise; every view has the whole
// object in view over 5000 pixels.
class GivenScene {
 public:
  explicit GivenScene(KeyframeId keyframes) {
    for (KeyframeId keyframe = 1; keyframe <= keyframes; ++keyframe) {
      view_of_keyframe_[keyframe] = static_cast<int>(keyframe);
      session_of_keyframe_[keyframe] = 1;
    }
  }

  // An object of `label`, detected with `score` in keyframes [from, to]: 40 points of `colour`
  // along x, `spacing` apart from `x0`.
  ObjectId AddObject(int label, float score, float x0, float spacing,
                     const std::array<std::uint8_t, 3>& colour, KeyframeId from, KeyframeId to) {
    std::vector<KeyframeId> keyframes;
    for (KeyframeId keyframe = from; keyframe <= to; ++keyframe) keyframes.push_back(keyframe);
    return AddObjectSeenIn(label, score, x0, spacing, colour, keyframes);
  }
  // The same, detected in `keyframes` (ascending).
  ObjectId AddObjectSeenIn(int label, float score, float x0, float spacing,
                           const std::array<std::uint8_t, 3>& colour,
                           const std::vector<KeyframeId>& keyframes) {
    ObjectId id = 0;
    for (const KeyframeId keyframe : keyframes) {
      ObjectObservation observation;
      observation.keyframe_id = keyframe;
      observation.class_scores = {{label, score}};
      for (int i = 0; i < 40; ++i) {
        observation.segment_C.points.emplace_back(x0 + spacing * static_cast<float>(i), 0.f, 1.f);
        observation.segment_C.colors.push_back(colour);
      }
      observation.view = static_cast<std::int64_t>(keyframe);
      if (id == 0) {
        id = objects_.AddObject(observation, Eigen::Isometry3d::Identity());
      } else {
        EXPECT_TRUE(objects_.AddObservation(id, observation, Eigen::Isometry3d::Identity()));
      }
    }
    return id;
  }

  // What `keyframe` saw through of object `id`.
  void See(ObjectId id, KeyframeId keyframe, float empty_fraction) {
    seen_[id][keyframe] = {1.f, 5000.f, empty_fraction};
  }
  // The keyframes from `first` on are of `session`.
  void StartSession(KeyframeId first, std::int64_t session) {
    for (auto it = session_of_keyframe_.lower_bound(first); it != session_of_keyframe_.end();
         ++it) {
      it->second = session;
    }
  }

  [[nodiscard]] ObjectChanges Changes(const ChangeConfig& config) const {
    ChangeInputs inputs;
    inputs.objects = &objects_;
    inputs.view_of_keyframe = &view_of_keyframe_;
    inputs.session_of = [this](KeyframeId keyframe) { return session_of_keyframe_.at(keyframe); };
    inputs.visibility_of =
        [this](const MapObject& object) -> const std::map<KeyframeId, ObjectVisibility>& {
      return seen_.at(object.id);
    };
    inputs.confirmed_through = [](const MapObject&, KeyframeId) { return true; };
    return DetectChanges(inputs, config);
  }

 private:
  ObjectMap objects_;
  std::map<KeyframeId, int> view_of_keyframe_;
  std::map<KeyframeId, std::int64_t> session_of_keyframe_;
  std::map<ObjectId, std::map<KeyframeId, ObjectVisibility>> seen_;
};

// DetectChanges on its own, with what each keyframe saw of a keyboard given: the first keyframes
// detected it there, the later ones (independent views) saw through 40 % of it. Its model took
// in a rim of the desk, which stays when the keyboard goes: less than min_empty_fraction (0.5),
// but far above the 3 % its own views saw through.
class DetectChangesOfAKeyboard : public ::testing::Test {
 protected:
  // Keyframes 1..`observing` detect the keyboard, the rest up to 5 see through 40 % of it; the
  // keyframes from `second_session` on are of a second session.
  std::vector<ObjectChange> Changes(KeyframeId observing, const ChangeConfig& config,
                                    KeyframeId second_session) {
    GivenScene scene(5);
    id_ = scene.AddObject(CocoClassId("keyboard"), 0.7f, 0.f, 0.01f, {40, 40, 40}, 1, observing);
    for (KeyframeId keyframe = 1; keyframe <= 5; ++keyframe) {
      scene.See(id_, keyframe, keyframe <= observing ? 0.03f : 0.4f);
    }
    scene.StartSession(second_session, 2);
    return ChangeList(scene.Changes(config));
  }

  ObjectId id_ = 0;
};

TEST_F(DetectChangesOfAKeyboard, IsRemovedWhenANewSessionSeesThroughWellAboveWhatItsViewsSaw) {
  const std::vector<ObjectChange> changes = Changes(3, ChangeConfig{}, 4);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ObjectChange::Kind::kRemoved);
  EXPECT_EQ(changes[0].id, id_);
  EXPECT_EQ(changes[0].keyframe_id, 5);  // the second view that saw through it

  ChangeConfig absolute_only;
  absolute_only.min_empty_fraction_over_present = 0.f;
  EXPECT_TRUE(Changes(3, absolute_only, 4).empty());
}

TEST_F(DetectChangesOfAKeyboard, StaysWhileTheSessionThatDetectedItSeesLessThanMinEmptyFraction) {
  // The same views in the session that detected it: 40 % is short of min_empty_fraction.
  EXPECT_TRUE(Changes(3, ChangeConfig{}, 6).empty());
  ChangeConfig lower;
  lower.min_empty_fraction = 0.35f;
  const std::vector<ObjectChange> changes = Changes(3, lower, 6);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ObjectChange::Kind::kRemoved);
}

TEST_F(DetectChangesOfAKeyboard, StaysWithTooFewViewsOfItThereToCompareWith) {
  // Two views saw it there: no baseline, min_empty_fraction decides, and 40 % is not empty.
  EXPECT_TRUE(Changes(2, ChangeConfig{}, 3).empty());
}

// A chair is seen through between its legs and the bars of its back while it stands there: the
// views that detected it saw through 45-55 % of it. Later views that see through 60 % of it, in
// the session that detected it or in a later one, saw it there, not an empty place.
TEST_F(DetectChangesOfAKeyboard, AThingItsOwnViewsSawThroughHalfOfNeedsMoreToBeGone) {
  GivenScene scene(7);
  const ObjectId id = scene.AddObject(CocoClassId("chair"), 0.7f, 0.f, 0.01f, {90, 60, 30}, 1, 3);
  for (KeyframeId keyframe = 1; keyframe <= 7; ++keyframe) {
    scene.See(id, keyframe, keyframe <= 3 ? 0.45f + 0.05f * (keyframe - 1) / 2.f : 0.6f);
  }
  scene.StartSession(6, 2);
  EXPECT_TRUE(ChangeList(scene.Changes(ChangeConfig{})).empty());
  // Without the baseline, 60 % is empty.
  ChangeConfig absolute_only;
  absolute_only.min_empty_fraction_over_present = 0.f;
  EXPECT_EQ(ChangeList(scene.Changes(absolute_only)).size(), 1u);
}

// Two mugs of one make arrive while one goes: one where earlier views saw nothing but the
// floor (a place they could judge and never saw empty: flat, or there all along), one where
// earlier views saw the table empty. Only a move explains the first; the second is put there
// either way, and is reported added.
TEST(DetectChangesPairing, TheArrivalOnlyAMoveExplainsIsTheMove) {
  const int cup = CocoClassId("cup");
  GivenScene scene(6);
  const ObjectId gone = scene.AddObject(cup, 0.8f, 0.f, 0.002f, {200, 200, 210}, 1, 3);
  const ObjectId on_the_floor = scene.AddObject(cup, 0.8f, 1.f, 0.002f, {200, 200, 210}, 4, 6);
  const ObjectId on_the_table = scene.AddObject(cup, 0.8f, 2.f, 0.002f, {200, 200, 210}, 4, 6);
  // What each keyframe saw of each place.
  for (KeyframeId keyframe = 1; keyframe <= 6; ++keyframe) {
    const bool first_visit = keyframe <= 3;
    scene.See(gone, keyframe, first_visit ? 0.f : 0.9f);
    scene.See(on_the_floor, keyframe, 0.f);
    scene.See(on_the_table, keyframe, first_visit ? 0.9f : 0.f);
  }
  const ObjectChanges changes = scene.Changes(ChangeConfig{});
  EXPECT_EQ(changes.PublishedId(on_the_floor), gone);
  ASSERT_EQ(changes.histories.count(gone), 1u);
  EXPECT_EQ(changes.histories.at(gone).state, ObjectState::kMoved);
  ASSERT_EQ(changes.histories.count(on_the_table), 1u);
  EXPECT_EQ(changes.histories.at(on_the_table).added_at, 4);
  EXPECT_EQ(changes.histories.at(on_the_table).state, ObjectState::kPresent);
}

// A book put down in the second session where, in the first, a bottle beside that place was
// once boxed as a book: that one detection joins the new book's object. The book taken away
// from elsewhere in between is still the one that moved there.
TEST(DetectChangesPairing, ADetectionOfOneViewInAnEarlierSessionDoesNotMakeTheArrivalOlder) {
  const int book = CocoClassId("book");
  GivenScene scene(6);
  scene.StartSession(4, 2);
  const ObjectId gone = scene.AddObject(book, 0.8f, 0.f, 0.005f, {150, 40, 40}, 1, 3);
  const ObjectId arrival =
      scene.AddObjectSeenIn(book, 0.8f, 2.f, 0.005f, {150, 40, 40}, {2, 4, 5, 6});
  for (KeyframeId keyframe = 1; keyframe <= 6; ++keyframe) {
    const bool first_visit = keyframe <= 3;
    scene.See(gone, keyframe, first_visit ? 0.f : 0.9f);
    scene.See(arrival, keyframe, first_visit && keyframe != 2 ? 0.9f : 0.f);
  }
  const ObjectChanges changes = scene.Changes(ChangeConfig{});
  EXPECT_EQ(changes.PublishedId(arrival), gone);
  ASSERT_EQ(changes.histories.count(gone), 1u);
  EXPECT_EQ(changes.histories.at(gone).state, ObjectState::kMoved);
  ASSERT_EQ(changes.histories.at(gone).places.size(), 2u);
  EXPECT_EQ(changes.histories.at(gone).places[1].first_seen, 4);
}

// A chair whose model took in the table edge it stood at (bounds three times its width) moves
// to a place where it stands alone: one chair, one colour, moved. A cup and a thing of its label
// and colour five times its size are not one object.
TEST(DetectChangesPairing, SizeRulesOutOnlyTheAbsurdPairs) {
  auto changes_of = [](int label, float gone_spacing, float arrival_spacing) {
    GivenScene scene(6);
    const ObjectId gone = scene.AddObject(label, 0.8f, 0.f, gone_spacing, {90, 60, 30}, 1, 3);
    const ObjectId arrival = scene.AddObject(label, 0.8f, 3.f, arrival_spacing, {90, 60, 30}, 4, 6);
    for (KeyframeId keyframe = 1; keyframe <= 6; ++keyframe) {
      const bool first_visit = keyframe <= 3;
      scene.See(gone, keyframe, first_visit ? 0.f : 0.9f);
      scene.See(arrival, keyframe, first_visit ? 0.9f : 0.f);
    }
    return std::make_pair(gone, scene.Changes(ChangeConfig{}));
  };
  const auto [chair, chair_changes] = changes_of(CocoClassId("chair"), 0.03f, 0.01f);
  ASSERT_EQ(chair_changes.histories.count(chair), 1u);
  EXPECT_EQ(chair_changes.histories.at(chair).state, ObjectState::kMoved);
  EXPECT_EQ(chair_changes.histories.at(chair).places.size(), 2u);
  const auto [cup, cup_changes] = changes_of(CocoClassId("cup"), 0.002f, 0.011f);
  ASSERT_EQ(cup_changes.histories.count(cup), 1u);
  EXPECT_EQ(cup_changes.histories.at(cup).state, ObjectState::kRemoved);
  EXPECT_EQ(cup_changes.histories.size(), 2u);  // and the big thing added
}

// A pile of two books, modelled as the whole pile and the top book alone. Between two sessions
// the top book goes; the book below is still detected, and its detections join the pile's
// object, which the second session then looks through a third of (where the top book was).
class DetectChangesOfAPile : public ::testing::Test {
 protected:
  // Session 1: keyframes 1-4 detect both; session 2: keyframes 5-8 detect the pile's object and
  // see through `pile_empty` of it and `top_empty` of the top book's model.
  ObjectChanges Changes(float pile_empty, float top_empty, bool with_top = true) {
    GivenScene scene(8);
    const int book = CocoClassId("book");
    pile_ = scene.AddObject(book, 0.7f, 0.f, 0.006f, {120, 40, 40}, 1, 8);
    top_ = with_top ? scene.AddObject(book, 0.7f, 0.02f, 0.005f, {120, 40, 40}, 1, 4) : 0;
    for (KeyframeId keyframe = 1; keyframe <= 8; ++keyframe) {
      const bool first_visit = keyframe <= 4;
      scene.See(pile_, keyframe, first_visit ? 0.02f : pile_empty);
      if (with_top) scene.See(top_, keyframe, first_visit ? 0.f : top_empty);
    }
    scene.StartSession(5, 2);
    return scene.Changes(ChangeConfig{});
  }

  ObjectId pile_ = 0, top_ = 0;
};

TEST_F(DetectChangesOfAPile, TheTopTakenAwayIsRemovedWhileTheRestIsStillDetected) {
  const ObjectChanges changes = Changes(0.35f, 0.08f);
  ASSERT_EQ(changes.histories.count(top_), 1u);
  const ObjectHistory& history = changes.histories.at(top_);
  EXPECT_EQ(history.state, ObjectState::kRemoved);
  ASSERT_EQ(history.places.size(), 1u);
  EXPECT_EQ(history.places[0].seen_empty_at, 6);  // the second view of session 2
  EXPECT_EQ(history.places[0].last_seen, 4);
  EXPECT_EQ(changes.gone, std::set<ObjectId>{top_});
  EXPECT_EQ(changes.histories.count(pile_), 0u);
}

TEST_F(DetectChangesOfAPile, APileSeenAsBeforeHasNoChange) {
  const ObjectChanges changes = Changes(0.03f, 0.f);
  EXPECT_TRUE(changes.histories.empty());
  EXPECT_TRUE(changes.gone.empty());
}

TEST_F(DetectChangesOfAPile, OneObjectStillDetectedIsNoRemovalWhateverASessionSeesThrough) {
  // Nothing else stood there: the session sees the thing from another side, or its model took
  // in its surroundings; which part went, if any, is not known.
  const ObjectChanges changes = Changes(0.35f, 0.f, /*with_top=*/false);
  EXPECT_TRUE(changes.histories.empty());
  EXPECT_TRUE(changes.gone.empty());
}

TEST_F(DetectChangesOfAPile, TheTopsOwnModelSeenEmptyIsTheOnlyChange) {
  const ObjectChanges changes = Changes(0.35f, 0.9f);
  EXPECT_EQ(changes.gone, std::set<ObjectId>{top_});
  ASSERT_EQ(changes.histories.size(), 1u);
  EXPECT_EQ(changes.histories.at(top_).state, ObjectState::kRemoved);
  EXPECT_EQ(changes.histories.at(top_).places[0].seen_empty_at, 6);
}

}  // namespace
}  // namespace objmap
