#include "mapper/mapper.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "mapper/keyframe_segments.h"
#include "mapper/map_export.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// The mappers of these tests run at the defaults.
const MapperConfig kDefaultConfig;

using testing::SceneBox;

const int kCup = CocoClassId("cup");
// A box on the table beside the cups that no detection names.
const SceneBox kUnnamedBox{{0.15, -0.05, 0.70}, {0.27, 0.05, 0.80}, {40, 160, 40}};

// The mapper's objects labelled `class_id`, in id order.
std::vector<const MapObject*> ObjectsLabelled(const Mapper& mapper, int class_id) {
  std::vector<const MapObject*> labelled;
  for (const auto& [id, object] : mapper.objects().objects()) {
    if (object.Label() == class_id) labelled.push_back(&object);
  }
  return labelled;
}

// A table top with two cups and a wall behind, seen from three viewpoints.
class MapperScene : public ::testing::Test {
 protected:
  MapperScene() {
    boxes_ = {
        {{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},      // table top
        {{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}},  // cup 1
        {{-0.05, 0.15, 0.70}, {0.05, 0.25, 0.82}, {30, 30, 200}},    // cup 2
        {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}},        // wall
    };
    eyes_ = {{-1.0, 0.0, 1.3}, {-1.0, 0.25, 1.3}, {-0.95, -0.25, 1.35}};
  }

  BoundingBox2D Project(const SceneBox& box, const Eigen::Isometry3d& T_W_C) const {
    return testing::ProjectBox(box, T_W_C, K_);
  }

  Eigen::Isometry3d Pose(int view) const {
    return testing::LookAt(eyes_[view], Eigen::Vector3d(0, 0, 0.7));
  }

  RgbdFrame Frame(int view) const {
    return testing::RenderFrame(boxes_, K_, Pose(view), "view-" + std::to_string(view));
  }

  // Keyframe k of an every-frame sequence: eye k / 5, moved by 2 mm per frame.
  RgbdFrame NearFrame(int keyframe) const {
    Eigen::Isometry3d pose = Pose(keyframe / 5);
    pose.translation() += Eigen::Vector3d(0.002 * (keyframe % 5), 0, 0);
    return testing::RenderFrame(boxes_, K_, pose, "near-" + std::to_string(keyframe));
  }

  std::vector<Detection> CupDetections(int view) const {
    return {{Project(boxes_[1], Pose(view)), kCup, 0.6f},
            {Project(boxes_[2], Pose(view)), kCup, 0.5f}};
  }

  void MapAllViews(Mapper* mapper) const {
    for (int view = 0; view < 3; ++view) {
      KeyframeResult result;
      std::string why;
      ASSERT_TRUE(mapper->AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
      EXPECT_EQ(result.detections_used, 2) << "view " << view;
    }
  }

  // The three views, the third with its pose drifted by `drift` (15 cm sideways by default; a
  // loop closure corrects it to Pose(2)): what it sees lands beside the objects of the first two.
  void MapWithTheThirdViewDrifted(Mapper* mapper,
                                  const Eigen::Vector3d& drift = {0.0, 0.15, 0.0}) const {
    Eigen::Isometry3d drifted = Pose(2);
    drifted.pretranslate(drift);
    for (int view = 0; view < 3; ++view) {
      RgbdFrame frame = Frame(view);
      if (view == 2) frame.T_W_C = drifted;
      KeyframeResult result;
      std::string why;
      ASSERT_TRUE(mapper->AddKeyframe(frame, CupDetections(view), &result, &why)) << why;
    }
  }

  CameraIntrinsics K_;
  std::vector<SceneBox> boxes_;
  std::vector<Eigen::Vector3d> eyes_;
};

TEST_F(MapperScene, TwoCupsSeenThriceAreTwoObjects) {
  Mapper mapper{kDefaultConfig};
  MapAllViews(&mapper);
  ASSERT_EQ(mapper.objects().size(), 2u);
  for (const auto& [id, object] : mapper.objects().objects()) {
    EXPECT_EQ(object.observations.size(), 3u);
    EXPECT_EQ(object.Label(), kCup);
    EXPECT_NEAR(object.centroid_W.z(), 0.76, 0.05);
    EXPECT_NEAR(std::abs(object.centroid_W.y()), 0.2, 0.05);
  }
  const auto inventory = mapper.Inventory();
  ASSERT_EQ(inventory.size(), 1u);
  EXPECT_EQ(inventory[0].class_id, kCup);
  EXPECT_EQ(inventory[0].count, 2);
  EXPECT_NEAR(inventory[0].mean_confidence, 0.55f, 1e-4);
  EXPECT_NE(ObjectsJson(mapper).find("\"class\": \"cup\""), std::string::npos);
}

TEST_F(MapperScene, ObjectsRarelyDetectedWhereSeenAreLeftOutOfTheInventory) {
  MapperConfig config;
  Mapper mapper{config};
  for (int view = 0; view < 3; ++view) {
    std::vector<Detection> detections = CupDetections(view);
    if (view > 0) detections.pop_back();  // the second cup is detected in one view of three
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
  }
  ASSERT_EQ(mapper.objects().size(), 2u);
  for (const auto& [id, object] : mapper.objects().objects()) {
    const ObjectEvidence evidence = mapper.Evidence(object);
    EXPECT_EQ(evidence.keyframes_seeing, 3) << "both cups are in every view";
    EXPECT_EQ(evidence.views_seeing, 3) << "the three eyes lie 25 cm apart: three views";
    EXPECT_EQ(evidence.views_detecting, static_cast<int>(object.observations.size()));
  }
  const auto confirmed = mapper.ConfirmedObjects();
  ASSERT_EQ(confirmed.size(), 1u);
  EXPECT_EQ(confirmed[0]->observations.size(), 3u);
  // Detected once (0.5) and missed twice in full view (2 x 0.3) against three detections (0.6).
  for (const auto& [id, object] : mapper.objects().objects()) {
    const float expected = object.observations.size() == 3u ? 1.8f : -0.1f;
    EXPECT_NEAR(mapper.Evidence(object).evidence, expected, 0.02f);
  }

  config.inventory.miss_weight = 0.f;  // misses ignored: the paper's rule keeps both
  Mapper paper_mapper{config};
  for (int view = 0; view < 3; ++view) {
    std::vector<Detection> detections = CupDetections(view);
    if (view > 0) detections.pop_back();
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(paper_mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
  }
  EXPECT_EQ(paper_mapper.ConfirmedObjects().size(), 2u);
}

TEST_F(MapperScene, OneGoodViewIsEnoughEvidence) {
  Mapper mapper{kDefaultConfig};
  KeyframeResult result;
  std::string why;
  ASSERT_TRUE(mapper.AddKeyframe(Frame(0), CupDetections(0), &result, &why)) << why;
  ASSERT_EQ(mapper.objects().size(), 2u);
  const auto inventory = mapper.Inventory();
  ASSERT_EQ(inventory.size(), 1u);
  EXPECT_EQ(inventory[0].count, 2) << "each cup, detected once at 1.3 m, is in the inventory";

  MapperConfig strict;
  strict.inventory.min_evidence = 0.55f;  // above the second cup's single score (0.5)
  Mapper strict_mapper{strict};
  ASSERT_TRUE(strict_mapper.AddKeyframe(Frame(0), CupDetections(0), &result, &why)) << why;
  EXPECT_EQ(strict_mapper.ConfirmedObjects().size(), 1u);
}

TEST_F(MapperScene, RepeatedFramesOfOneViewCountOnceForAndAgainstAnObject) {
  // Every-frame sampling: each of the three eyes gives five keyframes (a few millimetres
  // apart). The second cup is detected in the five frames of the first eye and missed in the
  // ten others: one view for it, two against, as with one keyframe per eye.
  Mapper dense{kDefaultConfig};
  for (int keyframe = 0; keyframe < 15; ++keyframe) {
    const int view = keyframe / 5;
    const RgbdFrame frame = NearFrame(keyframe);
    std::vector<Detection> detections = CupDetections(view);
    if (view > 0) detections.pop_back();
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(dense.AddKeyframe(frame, detections, &result, &why)) << why;
  }
  ASSERT_EQ(dense.objects().size(), 2u);
  for (const auto& [id, object] : dense.objects().objects()) {
    const ObjectEvidence evidence = dense.Evidence(object);
    EXPECT_EQ(evidence.keyframes_seeing, 15);
    EXPECT_EQ(evidence.views_seeing, 3);
    const float expected = object.observations.size() == 15u ? 1.8f : -0.1f;
    EXPECT_NEAR(evidence.evidence, expected, 0.02f);
  }
  const auto confirmed = dense.ConfirmedObjects();
  ASSERT_EQ(confirmed.size(), 1u) << "the rarely detected cup stays out, as with three keyframes";
  EXPECT_EQ(confirmed[0]->observations.size(), 15u);

  // Without independent views the fifteen frames would be fifteen votes.
  MapperConfig per_keyframe;
  per_keyframe.views.translation_m = 0.f;
  per_keyframe.views.rotation_deg = 0.f;
  Mapper counted{per_keyframe};
  for (int keyframe = 0; keyframe < 15; ++keyframe) {
    const RgbdFrame frame = NearFrame(keyframe);
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(counted.AddKeyframe(frame, CupDetections(keyframe / 5), &result, &why)) << why;
  }
  for (const auto& [id, object] : counted.objects().objects()) {
    EXPECT_EQ(counted.Evidence(object).views_seeing, 15);
  }
}

TEST_F(MapperScene, OccupancyHoldsStructureNotObjects) {
  Mapper mapper{kDefaultConfig};
  MapAllViews(&mapper);
  const OccupancyMap& occupancy = mapper.occupancy();
  // The wall is visible only below ~0.9 m: higher, it is out of the field of view.
  EXPECT_EQ(occupancy.Query({1.505, 0.0, 0.8}), VoxelState::kOccupied);     // wall surface
  EXPECT_EQ(occupancy.Query({-0.3, 0.0, 1.1}), VoxelState::kFree);          // air above the table
  EXPECT_EQ(occupancy.Query({0.0, 0.0, 0.705}), VoxelState::kOccupied);     // table top
  EXPECT_NE(occupancy.Query({-0.045, -0.2, 0.78}), VoxelState::kOccupied);  // cup surface
  EXPECT_EQ(occupancy.Query({2.5, 0.0, 1.0}), VoxelState::kUnknown);        // behind the wall
}

TEST_F(MapperScene, PoseUpdateRegeneratesObjectsAndOccupancy) {
  Mapper mapper{kDefaultConfig};
  MapAllViews(&mapper);
  std::map<ObjectId, Eigen::Vector3f> before;
  for (const auto& [id, object] : mapper.objects().objects()) before[id] = object.centroid_W;

  Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
  G.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  G.translation() = Eigen::Vector3d(0.5, -0.2, 0.1);
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (int view = 0; view < 3; ++view) poses[view + 1] = G * Pose(view);
  std::string why;
  PoseUpdateReport rigid;
  ASSERT_TRUE(mapper.UpdatePoses(poses, &why, &rigid)) << why;
  EXPECT_EQ(rigid.keyframes_moved, 3);
  EXPECT_FALSE(rigid.reassociated) << "a rigid move of the whole map keeps every association";

  ASSERT_EQ(mapper.objects().size(), before.size());
  for (const auto& [id, centroid] : before) {
    const MapObject* object = mapper.objects().Find(id);
    ASSERT_NE(object, nullptr) << "object ids survive regeneration";
    const Eigen::Vector3f expected = (G.cast<float>() * centroid);
    EXPECT_LT((object->centroid_W - expected).norm(), 0.01f);
  }
  const Eigen::Vector3d wall_point = G * Eigen::Vector3d(1.505, 0.0, 0.8);
  EXPECT_EQ(mapper.occupancy().Query(wall_point), VoxelState::kOccupied);

  // The same poses sent again, with the noise of a text or quaternion round trip, move nothing;
  // a millimetre does.
  Eigen::Isometry3d resent = poses[2];
  resent.translation().x() += 1e-9;
  resent.rotate(Eigen::AngleAxisd(1e-9, Eigen::Vector3d::UnitX()));
  PoseUpdateReport report;
  ASSERT_TRUE(mapper.UpdatePoses({{1, poses[1]}, {2, resent}}, &why, &report)) << why;
  EXPECT_EQ(report.keyframes_moved, 0);
  resent.translation().x() += 1e-3;
  ASSERT_TRUE(mapper.UpdatePoses({{2, resent}}, &why, &report)) << why;
  EXPECT_EQ(report.keyframes_moved, 1);
  EXPECT_FALSE(report.reassociated) << "a millimetre is within the rigid tolerance";
}

// Odometry drifted 15 cm sideways before the third view, so its cups landed where no cup was and
// became two more objects. A loop closure that corrects only that keyframe is not rigid: the
// association is replayed with the corrected pose and the third view's cups join the first two.
TEST_F(MapperScene, NonRigidCorrectionReassociatesAndKeepsTheIdsOfTheObjectsThatStay) {
  Mapper mapper{kDefaultConfig};
  MapWithTheThirdViewDrifted(&mapper);
  ASSERT_EQ(mapper.objects().size(), 4u) << "the drifted view's cups are two more objects";
  std::vector<ObjectId> seen_twice;
  for (const auto& [id, object] : mapper.objects().objects()) {
    if (object.observations.size() == 2u) seen_twice.push_back(id);
  }
  ASSERT_EQ(seen_twice.size(), 2u);

  std::string why;
  PoseUpdateReport report;
  ASSERT_TRUE(mapper.UpdatePoses({{3, Pose(2)}}, &why, &report)) << why;
  EXPECT_TRUE(report.reassociated);
  EXPECT_EQ(report.objects_before, 4);
  EXPECT_EQ(report.objects_after, 2);
  ASSERT_EQ(mapper.objects().size(), 2u);
  for (ObjectId id : seen_twice) {
    const MapObject* object = mapper.objects().Find(id);
    ASSERT_NE(object, nullptr) << "object " << id << " keeps its id";
    EXPECT_EQ(object->observations.size(), 3u);
    EXPECT_EQ(object->Keyframes(), (std::vector<KeyframeId>{1, 2, 3}));
    EXPECT_NEAR(std::abs(object->centroid_W.y()), 0.2, 0.05);
  }
  EXPECT_GT(mapper.objects().next_id(), 4u) << "ids are never reused";

  // With re-association off the correction only moves the drifted models into place.
  MapperConfig keep;
  keep.reassociation.enabled = false;
  Mapper kept{keep};
  MapWithTheThirdViewDrifted(&kept);
  ASSERT_TRUE(kept.UpdatePoses({{3, Pose(2)}}, &why, &report)) << why;
  EXPECT_FALSE(report.reassociated);
  EXPECT_EQ(kept.objects().size(), 4u);
}

// Correcting one keyframe of three rebuilds the OctoMap only where that keyframe's rays reach;
// the map is the one a full rebuild gives.
TEST_F(MapperScene, CorrectingAFewKeyframesRebuildsOnlyWhereTheySeeWithTheSameMap) {
  MapperConfig incremental;
  MapperConfig full;
  full.regeneration.incremental_max_moved_fraction = 0.f;
  Mapper a{incremental}, b{full};
  for (Mapper* mapper : {&a, &b}) MapWithTheThirdViewDrifted(mapper, {0.0, 0.04, 0.01});
  const OccupancyCounts drifted_counts = a.occupancy().Counts();
  std::string why;
  PoseUpdateReport report_a, report_b;
  ASSERT_TRUE(a.UpdatePoses({{3, Pose(2)}}, &why, &report_a)) << why;
  ASSERT_TRUE(b.UpdatePoses({{3, Pose(2)}}, &why, &report_b)) << why;
  EXPECT_TRUE(report_a.occupancy_incremental);
  EXPECT_FALSE(report_b.occupancy_incremental);
  EXPECT_EQ(report_b.keyframes_reintegrated, 3);
  EXPECT_GE(report_a.keyframes_reintegrated, 1);
  const OccupancyCounts counts_a = a.occupancy().Counts(), counts_b = b.occupancy().Counts();
  EXPECT_EQ(counts_a.occupied, counts_b.occupied);
  EXPECT_EQ(counts_a.free, counts_b.free);
  EXPECT_NE(counts_a.occupied, drifted_counts.occupied) << "the correction changed the map";
  std::vector<Eigen::Vector3d> occupied_a = a.occupancy().OccupiedVoxelCenters();
  std::vector<Eigen::Vector3d> occupied_b = b.occupancy().OccupiedVoxelCenters();
  auto by_coordinates = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
  };
  std::sort(occupied_a.begin(), occupied_a.end(), by_coordinates);
  std::sort(occupied_b.begin(), occupied_b.end(), by_coordinates);
  EXPECT_TRUE(occupied_a == occupied_b);
}

TEST_F(MapperScene, RestoreLoadsAUsableCheckpointAndIntegratesOnlyTheLaterKeyframes) {
  Mapper live{kDefaultConfig};
  OccupancyCheckpoint after_two;
  for (int view = 0; view < 3; ++view) {
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(live.AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
    if (view == 1) after_two = live.MakeOccupancyCheckpoint();
  }
  ASSERT_EQ(after_two.keyframe_poses.size(), 2u);
  // What a restart has: the keyframe records and the observations.
  auto records = [&] {
    std::map<KeyframeId, KeyframeRecord> out;
    for (KeyframeId id = 1; id <= 3; ++id) out[id] = *live.FindKeyframe(id);
    return out;
  };
  auto observations = [&] {
    std::map<ObjectId, std::vector<ObjectObservation>> out;
    for (const auto& [id, object] : live.objects().objects()) out[id] = object.observations;
    return out;
  };
  const std::string live_state = live.occupancy().WriteState();

  Mapper from_checkpoint{kDefaultConfig};
  RestoreOutcome outcome =
      from_checkpoint.Restore(records(), observations(), live.objects().next_id(), &after_two);
  EXPECT_TRUE(outcome.from_checkpoint) << outcome.checkpoint_refused;
  EXPECT_EQ(outcome.keyframes_integrated, 1);
  // The same OctoMap, log-odds included, as the mapper that integrated all three.
  EXPECT_EQ(from_checkpoint.occupancy().WriteState(), live_state);

  Mapper without{kDefaultConfig};
  outcome = without.Restore(records(), observations(), live.objects().next_id());
  EXPECT_FALSE(outcome.from_checkpoint);
  EXPECT_EQ(outcome.keyframes_integrated, 3);
  EXPECT_EQ(without.occupancy().WriteState(), live_state);

  // A keyframe moved after the checkpoint was taken: the checkpoint is refused and the OctoMap
  // rebuilt from every keyframe.
  OccupancyCheckpoint stale = after_two;
  stale.keyframe_poses[2].translation().x() += 0.05;
  Mapper refused{kDefaultConfig};
  outcome = refused.Restore(records(), observations(), live.objects().next_id(), &stale);
  EXPECT_FALSE(outcome.from_checkpoint);
  EXPECT_EQ(outcome.checkpoint_refused, "keyframe 2 moved since the checkpoint");
  EXPECT_EQ(outcome.keyframes_integrated, 3);
  EXPECT_EQ(refused.occupancy().WriteState(), live_state);
  // A corrupt state is refused the same way.
  OccupancyCheckpoint corrupt = after_two;
  corrupt.state.back() ^= 1;
  outcome = refused.Restore(records(), observations(), live.objects().next_id(), &corrupt);
  EXPECT_FALSE(outcome.from_checkpoint);
  EXPECT_NE(outcome.checkpoint_refused.find("corrupt"), std::string::npos)
      << outcome.checkpoint_refused;
}

// The paper's failures: a keyboard flat on the desk is lost in depth noise, and a table, being
// the supporting plane, has no segment of its own.
// The keyboard's pixels are part of the table's plane; whichever is detected with the higher
// score, both become objects.
TEST_F(MapperScene, FlatKeyboardAndTableBecomeObjects) {
  const int kKeyboard = CocoClassId("keyboard");
  const int kTable = CocoClassId("dining table");
  boxes_.push_back({{-0.35, -0.2, 0.705}, {-0.2, 0.2, 0.713}, {20, 20, 20}});  // 8 mm keyboard
  for (const float table_score : {0.3f, 0.9f}) {
    SCOPED_TRACE("table score " + std::to_string(table_score));
    Mapper mapper{kDefaultConfig};
    for (int view = 0; view < 3; ++view) {
      std::vector<Detection> detections = CupDetections(view);
      detections.push_back({Project(boxes_[4], Pose(view)), kKeyboard, 0.4f});
      detections.push_back({Project(boxes_[0], Pose(view)), kTable, table_score});
      KeyframeResult result;
      std::string why;
      ASSERT_TRUE(mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
      EXPECT_EQ(result.detections_used, 4) << "view " << view;
    }
    std::map<int, std::vector<const MapObject*>> by_class;
    for (const MapObject* object : mapper.ConfirmedObjects())
      by_class[object->Label()].push_back(object);
    ASSERT_EQ(by_class[kKeyboard].size(), 1u);
    ASSERT_EQ(by_class[kTable].size(), 1u);
    ASSERT_EQ(by_class[kCup].size(), 2u);
    const MapObject& keyboard = *by_class[kKeyboard][0];
    EXPECT_NEAR(keyboard.centroid_W.x(), -0.275, 0.05);
    EXPECT_NEAR(keyboard.centroid_W.y(), 0.0, 0.05);
    EXPECT_LT(keyboard.max_W.x() - keyboard.min_W.x(), 0.25);  // the keyboard, not the table
    const MapObject& table = *by_class[kTable][0];
    EXPECT_GT(table.max_W.y() - table.min_W.y(), 1.0);  // most of the 1.6 m table top
    EXPECT_NEAR(table.centroid_W.z(), 0.705, 0.02);
    EXPECT_EQ(table.observations.size(), 3u);
  }
}

// Two mugs of one colour touching side by side are one convex segment in the oblique views. Their
// two boxes share it out, and they map as two cups of one mug's width (plus border pixels), each
// seen in all three views; without the split, the paper's rule, those views see one thing.
TEST_F(MapperScene, TouchingSameClassObjectsShareTheirSegmentAndStayTwo) {
  boxes_[1] = {{-0.05, -0.10, 0.70}, {0.05, 0.0, 0.82}, {200, 30, 30}};
  boxes_[2] = {{-0.05, 0.0, 0.70}, {0.05, 0.10, 0.82}, {200, 30, 30}};
  auto map_with = [&](float split_max_box_iou, std::vector<const MapObject*>* cups) {
    MapperConfig config;
    config.split_max_box_iou = split_max_box_iou;
    auto mapper = std::make_unique<Mapper>(config);
    for (int view = 0; view < 3; ++view) {
      KeyframeResult result;
      std::string why;
      EXPECT_TRUE(mapper->AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
    }
    *cups = ObjectsLabelled(*mapper, kCup);
    return mapper;
  };
  std::vector<const MapObject*> cups;
  const auto split = map_with(0.3f, &cups);
  ASSERT_EQ(cups.size(), 2u);
  std::vector<float> y;
  for (const MapObject* cup : cups) {
    EXPECT_EQ(cup->observations.size(), 3u);
    y.push_back(cup->centroid_W.y());
    EXPECT_LT(cup->max_W.y() - cup->min_W.y(), 0.18f) << "one mug wide, not two";
  }
  std::sort(y.begin(), y.end());
  EXPECT_NEAR(y[0], -0.05, 0.025);
  EXPECT_NEAR(y[1], 0.05, 0.025);

  const auto fused = map_with(0.f, &cups);
  std::size_t observations = 0;
  for (const MapObject* cup : cups) observations += cup->observations.size();
  EXPECT_EQ(observations, 4u) << "the two oblique views each saw one thing where the mugs are";
}

// Two touching mugs, boxed together in three views and the first alone in three more: a box
// alone takes a slice of its neighbour with it (its dilation, for unregistered colour and
// depth). The first mug's published model gives that slice to the second, whose own views all
// reached it.
TEST_F(MapperScene, ATouchingMugSeenAloneDoesNotPublishItsNeighboursSide) {
  boxes_[1] = {{-0.05, -0.10, 0.70}, {0.05, 0.0, 0.82}, {200, 30, 30}};
  boxes_[2] = {{-0.05, 0.0, 0.70}, {0.05, 0.10, 0.82}, {200, 30, 30}};
  eyes_.push_back({-0.9, -0.45, 1.3});
  eyes_.push_back({-1.05, -0.1, 1.25});
  eyes_.push_back({-0.85, 0.1, 1.4});
  // Points of each mug's published model on the other mug and on its own.
  auto points_on_neighbour = [&](bool resolve, std::array<int, 2>* on_other,
                                 std::array<int, 2>* on_own) {
    MapperConfig config;
    config.objects.resolve_shared_voxels = resolve;
    Mapper mapper{config};
    for (int view = 0; view < 6; ++view) {
      std::vector<Detection> detections = CupDetections(view);
      if (view >= 3) detections.pop_back();  // the second mug is not boxed
      KeyframeResult result;
      std::string why;
      ASSERT_TRUE(mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
    }
    std::vector<const MapObject*> cups = ObjectsLabelled(mapper, kCup);
    ASSERT_EQ(cups.size(), 2u);
    // cups[0]: the first mug (y < 0).
    if (cups[0]->centroid_W.y() > cups[1]->centroid_W.y()) std::swap(cups[0], cups[1]);
    for (int k = 0; k < 2; ++k) {
      const ColoredPoints model = mapper.objects().ModelPoints(*cups[k]);
      (*on_other)[k] = (*on_own)[k] = 0;
      for (const Eigen::Vector3f& p : model.points) {
        // On the other mug: past the contact by more than the 5 mm voxel. Its own: more than
        // a centimetre from the contact, where no voxel is in doubt.
        const float beyond_contact = k == 0 ? p.y() : -p.y();
        if (beyond_contact > 0.005f) ++(*on_other)[k];
        if (beyond_contact < -0.01f) ++(*on_own)[k];
      }
    }
  };
  std::array<int, 2> on_other{}, on_own{}, on_other_kept{}, on_own_kept{};
  points_on_neighbour(true, &on_other, &on_own);
  points_on_neighbour(false, &on_other_kept, &on_own_kept);
  EXPECT_GT(on_other_kept[0], 20) << "the scene must give the first mug a slice of the second";
  EXPECT_LT(on_other[0], on_other_kept[0] / 4) << "most of the slice is the second mug's";
  // Sides of the second mug that only the views boxing the first saw go to the first (no view
  // of the second's own says otherwise): a few per cent.
  EXPECT_GT(on_own[0], 0.85 * on_own_kept[0]) << "the first mug keeps its own surface";
  EXPECT_GT(on_own[1], 0.85 * on_own_kept[1]) << "and so does the second";
}

// The paper's first failure: two monitors side by side on a desk merged into one object. Their
// screens face the camera on one plane and touch, so no segment tells them apart; each box
// takes its own screen.
TEST_F(MapperScene, TwoMonitorsSideBySideStayTwo) {
  const int kTv = CocoClassId("tv");
  boxes_[1] = {{0.30, -0.50, 0.72}, {0.34, 0.0, 1.02}, {20, 20, 20}};
  boxes_[2] = {{0.30, 0.0, 0.72}, {0.34, 0.50, 1.02}, {20, 20, 20}};
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 3; ++view) {
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(
        Frame(view),
        {{Project(boxes_[1], Pose(view)), kTv, 0.8f}, {Project(boxes_[2], Pose(view)), kTv, 0.7f}},
        &result, &why))
        << why;
    EXPECT_EQ(result.detections_used, 2) << "view " << view;
  }
  std::vector<const MapObject*> monitors = ObjectsLabelled(mapper, kTv);
  ASSERT_EQ(monitors.size(), 2u);
  std::sort(monitors.begin(), monitors.end(), [](const MapObject* a, const MapObject* b) {
    return a->centroid_W.y() < b->centroid_W.y();
  });
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(monitors[k]->observations.size(), 3u);
    EXPECT_NEAR(monitors[k]->centroid_W.y(), k == 0 ? -0.25 : 0.25, 0.05);
    EXPECT_LT(monitors[k]->max_W.y() - monitors[k]->min_W.y(), 0.6) << "one screen wide";
  }
  EXPECT_EQ(mapper.ConfirmedObjects().size(), 2u);
}

// A fridge is larger than what one close view shows: the top half, then the bottom half (no
// point in common with the top), then all of it from farther away. One fridge, not fragments.
TEST_F(MapperScene, AFridgeSeenInPartsIsOneObject) {
  const int kFridge = CocoClassId("refrigerator");
  const SceneBox fridge{{0.9, -1.6, 0.0}, {1.5, -1.0, 1.8}, {235, 235, 235}};
  boxes_.push_back(fridge);
  boxes_.push_back({{-3.0, -3.0, -0.02}, {3.0, 3.0, 0.0}, {90, 80, 70}});  // the floor
  const Eigen::Vector3d front(0.9, -1.3, 0.0);
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> eyes_targets = {
      {{-0.2, -1.3, 1.5}, front + Eigen::Vector3d(0, 0, 1.35)},  // the top half
      {{-0.2, -1.3, 0.6}, front + Eigen::Vector3d(0, 0, 0.45)},  // the bottom half
      {{-1.4, -1.2, 1.1}, front + Eigen::Vector3d(0, 0, 0.9)},   // all of it
      {{-0.25, -1.2, 1.5}, front + Eigen::Vector3d(0, 0, 1.35)},
      {{-0.25, -1.2, 0.6}, front + Eigen::Vector3d(0, 0, 0.45)},
  };
  Mapper mapper{kDefaultConfig};
  for (std::size_t view = 0; view < eyes_targets.size(); ++view) {
    const Eigen::Isometry3d pose =
        testing::LookAt(eyes_targets[view].first, eyes_targets[view].second);
    BoundingBox2D box = Project(fridge, pose);
    box.x_min = std::max(box.x_min, 0.f);
    box.y_min = std::max(box.y_min, 0.f);
    box.x_max = std::min(box.x_max, static_cast<float>(K_.width - 1));
    box.y_max = std::min(box.y_max, static_cast<float>(K_.height - 1));
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(
        mapper.AddKeyframe(testing::RenderFrame(boxes_, K_, pose, "fridge-" + std::to_string(view)),
                           {{box, kFridge, 0.8f}}, &result, &why))
        << why;
    EXPECT_EQ(result.detections_used, 1) << "view " << view;
  }
  std::vector<const MapObject*> fridges = ObjectsLabelled(mapper, kFridge);
  ASSERT_EQ(fridges.size(), 1u);
  EXPECT_EQ(fridges[0]->observations.size(), eyes_targets.size());
  EXPECT_GT(fridges[0]->max_W.z() - fridges[0]->min_W.z(), 1.4) << "top and bottom";
  EXPECT_EQ(mapper.ConfirmedObjects().size(), 1u);
}

// Small objects were discarded in the paper. A mouse (6 x 10 x 3.5 cm) beside the cups, 1.3 to
// 1.5 m away, is a few hundred pixels: it is mapped and counted.
TEST_F(MapperScene, AMouseOnTheDeskIsMapped) {
  const int kMouse = CocoClassId("mouse");
  const SceneBox mouse{{-0.25, 0.35, 0.70}, {-0.19, 0.45, 0.735}, {60, 60, 60}};
  boxes_.push_back(mouse);
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 3; ++view) {
    std::vector<Detection> detections = CupDetections(view);
    detections.push_back({Project(mouse, Pose(view)), kMouse, 0.6f});
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
    EXPECT_EQ(result.detections_used, 3) << "view " << view;
  }
  int mice = 0;
  for (const MapObject* object : mapper.ConfirmedObjects()) {
    if (object->Label() != kMouse) continue;
    ++mice;
    EXPECT_EQ(object->observations.size(), 3u);
    EXPECT_NEAR(object->centroid_W.x(), -0.22, 0.03);
    EXPECT_NEAR(object->centroid_W.y(), 0.40, 0.03);
    EXPECT_LT(object->max_W.z(), 0.75) << "the mouse, not something standing above it";
  }
  EXPECT_EQ(mice, 1);
}

// A detector names a mouse a phone or a remote about as often as a mouse. The mouse's model is
// 4 cm thick, which no phone or remote is: it is labelled a mouse, confidently enough for the
// inventory. A phone lying flat, named a phone, stays a phone.
TEST_F(MapperScene, AMouseNamedAPhoneMoreOftenIsAMouseAndAFlatPhoneStaysAPhone) {
  const int kMouse = CocoClassId("mouse"), kPhone = CocoClassId("cell phone");
  const int kRemote = CocoClassId("remote");
  const SceneBox mouse{{-0.25, 0.35, 0.70}, {-0.19, 0.46, 0.74}, {60, 60, 60}};
  const SceneBox phone{{-0.30, -0.50, 0.70}, {-0.23, -0.35, 0.708}, {20, 20, 20}};
  boxes_.push_back(mouse);
  boxes_.push_back(phone);
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 3; ++view) {
    std::vector<Detection> detections = CupDetections(view);
    const BoundingBox2D mouse_box = Project(mouse, Pose(view));
    detections.push_back({mouse_box, kPhone, 0.4f});
    detections.push_back({mouse_box, kRemote, 0.2f});
    detections.push_back({mouse_box, kMouse, 0.3f});
    detections.push_back({Project(phone, Pose(view)), kPhone, 0.5f});
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
  }
  const MapObject* mapped_mouse = nullptr;
  const MapObject* mapped_phone = nullptr;
  for (const auto& [id, object] : mapper.objects().objects()) {
    if (object.centroid_W.y() > 0.3) mapped_mouse = &object;
    if (object.centroid_W.y() < -0.3) mapped_phone = &object;
  }
  ASSERT_NE(mapped_mouse, nullptr);
  ASSERT_NE(mapped_phone, nullptr);
  EXPECT_NEAR(mapped_mouse->accumulated_scores[kPhone], 1.2f, 1e-4) << "the scores are kept";
  EXPECT_TRUE(mapped_mouse->ruled_out_classes[kPhone]);
  EXPECT_TRUE(mapped_mouse->ruled_out_classes[kRemote]);
  EXPECT_EQ(mapped_mouse->Label(), kMouse);
  // 0.3 per view, and the phone's and remote's share goes to the mouse: 0.3 x (0.4+0.2+0.3) / 0.3.
  EXPECT_NEAR(mapped_mouse->Confidence(), 0.9f, 1e-3);
  EXPECT_FALSE(mapped_phone->ruled_out_classes[kPhone]);
  EXPECT_EQ(mapped_phone->Label(), kPhone);
  const std::vector<const MapObject*> confirmed = mapper.ConfirmedObjects();
  EXPECT_NE(std::find(confirmed.begin(), confirmed.end(), mapped_mouse), confirmed.end());
  EXPECT_NE(std::find(confirmed.begin(), confirmed.end(), mapped_phone), confirmed.end());

  // Switched off (no thin classes), the mouse is a phone as the scores say.
  MapperConfig plain;
  plain.objects.thin_classes.clear();
  Mapper plain_mapper{plain};
  for (int view = 0; view < 3; ++view) {
    std::vector<Detection> detections = CupDetections(view);
    const BoundingBox2D mouse_box = Project(mouse, Pose(view));
    detections.push_back({mouse_box, kPhone, 0.5f});
    detections.push_back({mouse_box, kMouse, 0.3f});
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(plain_mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
  }
  EXPECT_EQ(ObjectsLabelled(plain_mapper, kPhone).size(), 1u);
  EXPECT_TRUE(ObjectsLabelled(plain_mapper, kMouse).empty());
}

TEST(PartDetections, AKeyboardBoxWellInsideALargerLaptopBoxIsTheLaptopsDeck) {
  const int kKeyboard = CocoClassId("keyboard"), kLaptop = CocoClassId("laptop");
  const MapperConfig config;
  const BoundingBox2D laptop{100, 100, 240, 210};
  const BoundingBox2D deck{115, 160, 225, 205};
  std::vector<Detection> detections = {{laptop, kLaptop, 0.6f}, {deck, kKeyboard, 0.4f}};
  EXPECT_TRUE(IsPartOfAnotherDetection(detections, 1, config));
  EXPECT_FALSE(IsPartOfAnotherDetection(detections, 0, config)) << "a laptop is no part";
  // The same box named both: two guesses at one object, which fuse as one observation.
  detections[1].box = laptop;
  EXPECT_FALSE(IsPartOfAnotherDetection(detections, 1, config));
  // An external keyboard in front of the laptop: its box reaches well below the laptop's.
  detections[1].box = {90, 180, 250, 260};
  EXPECT_FALSE(IsPartOfAnotherDetection(detections, 1, config));
  // A laptop box too weak to be used decides nothing.
  detections[1].box = deck;
  detections[0].score = config.min_detection_score / 2;
  EXPECT_FALSE(IsPartOfAnotherDetection(detections, 1, config));
  // No part classes: every keyboard is a keyboard.
  MapperConfig no_parts;
  no_parts.part_classes.clear();
  detections[0].score = 0.6f;
  EXPECT_FALSE(IsPartOfAnotherDetection(detections, 1, no_parts));
}

// Three books of one footprint stacked on the table are one convex segment in every view, and
// their boxes overlap too much to share it out by box. Cut by height above the table, each box
// takes its own layer: three books, each model within its own book's height.
TEST_F(MapperScene, StackedBooksAreCutByHeightAndStayThree) {
  const int kBook = CocoClassId("book");
  const std::array<double, 4> tops = {0.70, 0.74, 0.765, 0.785};  // table, then each book's top
  boxes_.erase(boxes_.begin() + 1, boxes_.begin() + 3);           // no cups
  for (int b = 0; b < 3; ++b) {
    boxes_.push_back({{-0.08, -0.11, tops[b]}, {0.08, 0.11, tops[b + 1]}, {90, 60, 40}});
  }
  auto map_with = [&](const std::vector<int>& stack_classes, std::vector<const MapObject*>* books) {
    MapperConfig config;
    config.stack_classes = stack_classes;
    auto mapper = std::make_unique<Mapper>(config);
    for (int view = 0; view < 3; ++view) {
      std::vector<Detection> detections;
      for (int b = 0; b < 3; ++b) {
        detections.push_back({Project(boxes_[2 + b], Pose(view)), kBook, 0.7f - 0.1f * b});
      }
      KeyframeResult result;
      std::string why;
      EXPECT_TRUE(mapper->AddKeyframe(Frame(view), detections, &result, &why)) << why;
    }
    *books = ObjectsLabelled(*mapper, kBook);
    std::sort(books->begin(), books->end(), [](const MapObject* a, const MapObject* b) {
      return a->centroid_W.z() < b->centroid_W.z();
    });
    return mapper;
  };
  std::vector<const MapObject*> books;
  const auto cut = map_with(kDefaultConfig.stack_classes, &books);
  ASSERT_EQ(books.size(), 3u);
  for (int b = 0; b < 3; ++b) {
    SCOPED_TRACE("book " + std::to_string(b));
    EXPECT_EQ(books[b]->observations.size(), 3u);
    // Within a centimetre of its own layer (points on the cut may go either way).
    EXPECT_GT(books[b]->min_W.z(), tops[b] - 0.01);
    EXPECT_LT(books[b]->max_W.z(), tops[b + 1] + 0.01);
    // Over the stack's footprint (the lower books show only their fronts to these views).
    EXPECT_GT(books[b]->min_W.x(), -0.09);
    EXPECT_LT(books[b]->max_W.x(), 0.09);
    EXPECT_NEAR(books[b]->centroid_W.y(), 0.0, 0.02);
  }

  // Without the cut, the stack's views each see one thing, or things spanning the stack.
  const auto uncut = map_with({}, &books);
  bool layered = books.size() == 3u;
  for (const MapObject* book : books) layered = layered && book->max_W.z() - book->min_W.z() < 0.05;
  EXPECT_FALSE(layered);

  MapperConfig bad;
  bad.min_stack_layer_gap_m = 0.f;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("min_stack_layer_gap_m"), std::string::npos) << why;
}

// A box bounds what it shows: a segment spanning a small part of its box is a fragment (a handle,
// the floor between a fridge's feet, whatever a spurious box landed on) and starts no object.
TEST_F(MapperScene, ASegmentSpanningLittleOfItsBoxIsNotAnObservation) {
  auto used_with = [&](float min_fill) {
    MapperConfig config;
    config.min_segment_box_fill = min_fill;
    Mapper mapper(config);
    // A box around the first cup reaching far above it and a cup's width to either side: the
    // cup's segment is its only object segment, spanning a tenth of the box or less.
    BoundingBox2D tall = Project(boxes_[1], Pose(0));
    const float width = tall.Width();
    tall.y_min = std::max(0.f, tall.y_min - 5.f * tall.Height());
    tall.x_min -= width;
    tall.x_max += width;
    KeyframeResult result;
    std::string why;
    EXPECT_TRUE(mapper.AddKeyframe(Frame(0), {{tall, CocoClassId("bottle"), 0.6f}}, &result, &why))
        << why;
    return result.detections_used;
  };
  EXPECT_EQ(used_with(0.f), 1) << "without the test the cup's segment becomes a bottle";
  EXPECT_EQ(used_with(kDefaultConfig.min_segment_box_fill), 0);
  // The cups' own boxes are filled: both are used (MapAllViews checks it in every view).
  Mapper mapper{kDefaultConfig};
  MapAllViews(&mapper);
  MapperConfig bad;
  bad.min_segment_box_fill = 1.5f;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("min_segment_box_fill"), std::string::npos) << why;
}

// A screen hung on a wall is within depth noise of it. When the segmentation does not take the
// wall for a supporting plane (cupboards break it up in a real kitchen), no segment of its own
// fills the screen's box, and the screen is the part of the wall its box covers.
TEST_F(MapperScene, AFlatObjectOnASurfaceThatIsNoPlaneIsThePartItsBoxCovers) {
  const int kTv = CocoClassId("tv");
  const SceneBox screen{{1.5, -0.4, 0.65}, {1.5, 0.4, 0.95}, {0, 0, 0}};  // on the wall's face
  auto map_screen = [&](const std::vector<int>& flat_classes) {
    MapperConfig config;
    config.segmenter.min_plane_area_m2 = 100.f;  // no supporting planes at all
    config.flat_classes = flat_classes;
    auto mapper = std::make_unique<Mapper>(config);
    for (int view = 0; view < 3; ++view) {
      KeyframeResult result;
      std::string why;
      EXPECT_TRUE(mapper->AddKeyframe(Frame(view), {{Project(screen, Pose(view)), kTv, 0.7f}},
                                      &result, &why))
          << why;
    }
    return mapper;
  };
  const auto with = map_screen(kDefaultConfig.flat_classes);
  ASSERT_EQ(with->objects().size(), 1u);
  const MapObject& tv = with->objects().objects().begin()->second;
  EXPECT_EQ(tv.observations.size(), 3u);
  EXPECT_NEAR(tv.centroid_W.x(), 1.5, 0.03);
  EXPECT_NEAR(tv.centroid_W.z(), 0.8, 0.03);
  // The box shrunk by flat_box_shrink_fraction per side: most of the screen, none of the rest.
  EXPECT_GT(tv.max_W.y() - tv.min_W.y(), 0.5);
  EXPECT_LT(tv.max_W.y() - tv.min_W.y(), 0.82);
  const auto without = map_screen({});
  EXPECT_EQ(without->objects().size(), 0u) << "the wall is no object's segment";
}

// A table detection's box (down to the floor, legs included) holds more planes than the top:
// a chair's back standing in front of the table, the pieces of a top that a divider standing on
// it cuts in two, and the top of a nearer table. The table is its whole top: the up-facing
// pieces on one plane that meet, reaching highest in its box.
TEST_F(MapperScene, ATableIsItsWholeTopNotAChairBackOrANearerTable) {
  const int kTable = CocoClassId("dining table");
  boxes_[3] = {{3.0, -2.0, 0.0}, {3.1, 2.0, 2.5}, {220, 220, 220}};  // the wall, farther back
  boxes_.push_back({{-0.05, -0.05, 0.70}, {0.05, 0.05, 0.80}, {90, 90, 90}});  // post on the top
  boxes_.push_back({{-0.58, -0.8, 0.70}, {0.58, -0.7, 0.80}, {90, 90, 90}});   // rail on the top
  // The divider: a post and a rail cut the top's plane into pieces less than 20 cm apart.
  boxes_.push_back({{-0.05, -0.7, 0.70}, {0.05, 0.8, 0.72}, {90, 90, 90}});
  const SceneBox chair_back{{-0.74, -0.25, 0.45}, {-0.72, 0.25, 0.95}, {40, 120, 40}};
  const SceneBox back_table{{1.3, -0.8, 0.60}, {2.0, 0.8, 0.70}, {150, 100, 60}};
  boxes_.push_back(chair_back);
  boxes_.push_back(back_table);
  // Detection boxes hold the legs down to the floor, clipped to the image.
  auto table_box = [&](const SceneBox& top, int view) {
    SceneBox with_legs = top;
    with_legs.lo.z() = 0.0;
    BoundingBox2D box = Project(with_legs, Pose(view));
    box.x_min = std::max(box.x_min, 0.f);
    box.y_min = std::max(box.y_min, 0.f);
    box.x_max = std::min(box.x_max, static_cast<float>(K_.width - 1));
    box.y_max = std::min(box.y_max, static_cast<float>(K_.height - 1));
    return box;
  };
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 3; ++view) {
    const BoundingBox2D front = table_box(boxes_[0], view);
    const BoundingBox2D back = table_box(back_table, view);
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), {{front, kTable, 0.8f}, {back, kTable, 0.7f}},
                                   &result, &why))
        << why;
    EXPECT_EQ(result.detections_used, 2) << "view " << view;
  }
  std::vector<const MapObject*> tables = ObjectsLabelled(mapper, kTable);
  ASSERT_EQ(tables.size(), 2u);
  std::sort(tables.begin(), tables.end(), [](const MapObject* a, const MapObject* b) {
    return a->centroid_W.x() < b->centroid_W.x();
  });
  for (const MapObject* table : tables) {
    EXPECT_EQ(table->observations.size(), 3u);
    EXPECT_NEAR(table->centroid_W.z(), 0.70, 0.02) << "a top, not the chair's back";
    EXPECT_LT(table->max_W.z() - table->min_W.z(), 0.06);
  }
  // The front table: both sides of the divider, and none of the back table.
  EXPECT_GT(tables[0]->max_W.y() - tables[0]->min_W.y(), 1.2);
  EXPECT_LT(tables[0]->max_W.x(), -0.4 + 1.1);
  EXPECT_GT(tables[0]->min_W.x(), -0.65);
  // The back table: its own top, not the nearer one its box also holds.
  EXPECT_GT(tables[1]->min_W.x(), 1.25);
  EXPECT_NEAR(tables[1]->centroid_W.x(), 1.65, 0.15);
}

// A box on the table that no detector names, seen from three viewpoints: an unknown object of
// the map (queries see it), not in the inventory; a later detection of it names it.
TEST_F(MapperScene, AnUndetectedThingOnTheTableIsAnUnknownObjectUntilADetectionNamesIt) {
  const SceneBox thing = kUnnamedBox;
  boxes_.push_back(thing);
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 3; ++view) {
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
    EXPECT_EQ(result.detections_used, 2) << "view " << view;
    EXPECT_EQ(result.unclassified_segments, 1) << "view " << view << ": the box alone";
  }
  const auto unknown = ObjectsLabelled(mapper, kUnknownClassId);
  ASSERT_EQ(unknown.size(), 1u);
  const MapObject& object = *unknown[0];
  EXPECT_EQ(object.observations.size(), 3u);
  EXPECT_EQ(object.Confidence(), 0.f);
  EXPECT_NEAR(object.centroid_W.x(), 0.21, 0.04);
  EXPECT_NEAR(object.centroid_W.y(), 0.0, 0.03);
  EXPECT_NEAR(object.centroid_W.z(), 0.75, 0.04);
  EXPECT_GT(object.min_W.z(), 0.68) << "the box, not the table under it";
  EXPECT_EQ(ObjectsLabelled(mapper, kCup).size(), 2u);

  const auto confirmed = mapper.ConfirmedObjects();
  EXPECT_EQ(std::count(confirmed.begin(), confirmed.end(), &object), 1)
      << "segmented in three views: it is there";
  const auto inventory = mapper.Inventory();
  ASSERT_EQ(inventory.size(), 1u) << "unknown objects are out of the inventory by default";
  EXPECT_EQ(inventory[0].class_id, kCup);
  EXPECT_NE(ObjectsJson(mapper).find("\"class\": \"unknown\""), std::string::npos);
  const auto counted = InventoryOf(confirmed, /*count_unknown=*/true);
  ASSERT_EQ(counted.size(), 2u);
  EXPECT_EQ(counted[1].class_id, kUnknownClassId);

  // Named from the first viewpoint again: the same object, now a toaster.
  const int kToaster = CocoClassId("toaster");
  std::vector<Detection> detections = CupDetections(0);
  detections.push_back({Project(thing, Pose(0)), kToaster, 0.7f});
  KeyframeResult result;
  std::string why;
  ASSERT_TRUE(mapper.AddKeyframe(Frame(0), detections, &result, &why)) << why;
  EXPECT_EQ(result.unclassified_segments, 0);
  EXPECT_TRUE(ObjectsLabelled(mapper, kUnknownClassId).empty());
  const auto toasters = ObjectsLabelled(mapper, kToaster);
  ASSERT_EQ(toasters.size(), 1u);
  EXPECT_EQ(toasters[0]->id, object.id) << "the detection named the unknown object";
  EXPECT_EQ(toasters[0]->observations.size(), 4u);
  EXPECT_NEAR(toasters[0]->Confidence(), 0.7f, 1e-5) << "over the one view that named it";
}

// A loop closure that re-associates replays the unknown observations too: the drifted view's
// copy of the unnamed box joins it again, and the object keeps its id.
TEST_F(MapperScene, ANonRigidCorrectionReassociatesAnUnknownObjectLikeTheNamedOnes) {
  boxes_.push_back(kUnnamedBox);
  Mapper mapper{kDefaultConfig};
  MapWithTheThirdViewDrifted(&mapper);
  auto unknown = ObjectsLabelled(mapper, kUnknownClassId);
  ASSERT_EQ(unknown.size(), 2u) << "the drifted view's box lands beside the first";
  const ObjectId first_id = unknown[0]->id;
  EXPECT_EQ(unknown[0]->observations.size(), 2u);

  std::string why;
  PoseUpdateReport report;
  ASSERT_TRUE(mapper.UpdatePoses({{3, Pose(2)}}, &why, &report)) << why;
  EXPECT_TRUE(report.reassociated);
  unknown = ObjectsLabelled(mapper, kUnknownClassId);
  ASSERT_EQ(unknown.size(), 1u);
  EXPECT_EQ(unknown[0]->id, first_id);
  EXPECT_EQ(unknown[0]->observations.size(), 3u);
  EXPECT_EQ(ObjectsLabelled(mapper, kCup).size(), 2u);
  const auto confirmed = mapper.ConfirmedObjects();
  EXPECT_EQ(std::count(confirmed.begin(), confirmed.end(), unknown[0]), 1);
}

TEST_F(MapperScene, AnUnknownObjectNeedsSeveralViewsAndCanBeSwitchedOff) {
  boxes_.push_back(kUnnamedBox);
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 2; ++view) {
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
  }
  ASSERT_EQ(ObjectsLabelled(mapper, kUnknownClassId).size(), 1u);
  for (const MapObject* object : mapper.ConfirmedObjects()) {
    EXPECT_NE(object->Label(), kUnknownClassId) << "two views are not yet persistence";
  }

  MapperConfig off;
  off.unknown_objects.enabled = false;
  Mapper paper_mapper{off};
  for (int view = 0; view < 3; ++view) {
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(paper_mapper.AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
    EXPECT_EQ(result.unclassified_segments, 0);
  }
  EXPECT_EQ(paper_mapper.objects().size(), 2u);
}

// What rests on no supporting plane, is cut by the image border, or is part of a named object
// does not become an unknown object; neither does a named object's segment in a view where the
// detector missed it.
TEST_F(MapperScene, OnlyFreeStandingUnnamedThingsBecomeUnknownObjects) {
  boxes_.push_back({{0.15, -0.05, 0.90}, {0.27, 0.05, 1.00}, {40, 160, 40}});  // floating
  Mapper mapper{kDefaultConfig};
  for (int view = 0; view < 3; ++view) {
    std::vector<Detection> detections = CupDetections(view);
    if (view == 2) detections.pop_back();  // the second cup missed in the last view
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), detections, &result, &why)) << why;
    EXPECT_EQ(result.unclassified_segments, view == 2 ? 1 : 0) << "view " << view;
  }
  EXPECT_TRUE(ObjectsLabelled(mapper, kUnknownClassId).empty());
  const auto cups = ObjectsLabelled(mapper, kCup);
  ASSERT_EQ(cups.size(), 2u);
  EXPECT_EQ(cups[0]->observations.size() + cups[1]->observations.size(), 5u)
      << "the missed cup's segment is not an observation of it";
}

// On a floor, undetected: a stool (a seat plate on four legs) and a step made of two blocks side
// by side. The stool's legs hold up its seat: parts of furniture, no unknown objects. The step's
// blocks meet at a concave edge, two segments: one thing, one unknown object.
TEST(UnknownObjects, LegsUnderASurfaceAreNoObjectsAndTouchingPartsAreOne) {
  const std::vector<SceneBox> boxes = {
      {{-3.0, -3.0, -0.1}, {3.0, 3.0, 0.0}, {120, 120, 120}},   // floor
      {{2.0, -3.0, 0.0}, {2.1, 3.0, 2.5}, {220, 220, 220}},     // wall
      {{0.3, -0.6, 0.45}, {0.7, -0.2, 0.48}, {160, 110, 60}},   // stool seat
      {{0.32, -0.58, 0.0}, {0.35, -0.55, 0.45}, {90, 60, 30}},  // its legs
      {{0.65, -0.58, 0.0}, {0.68, -0.55, 0.45}, {90, 60, 30}},
      {{0.32, -0.25, 0.0}, {0.35, -0.22, 0.45}, {90, 60, 30}},
      {{0.65, -0.25, 0.0}, {0.68, -0.22, 0.45}, {90, 60, 30}},
      {{0.4, 0.3, 0.0}, {0.7, 0.5, 0.1}, {200, 60, 60}},    // step: low block
      {{0.55, 0.5, 0.0}, {0.7, 0.7, 0.25}, {60, 60, 200}},  // ... and the high one
  };
  const CameraIntrinsics K;
  const std::vector<Eigen::Vector3d> eyes = {
      {-1.2, 0.0, 1.3}, {-1.1, 0.4, 1.3}, {-1.1, -0.4, 1.35}};
  Mapper mapper{kDefaultConfig};
  for (std::size_t view = 0; view < eyes.size(); ++view) {
    const Eigen::Isometry3d T_W_C = testing::LookAt(eyes[view], Eigen::Vector3d(0.5, 0.0, 0.2));
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(
        testing::RenderFrame(boxes, K, T_W_C, "floor-" + std::to_string(view)), {}, &result, &why))
        << why;
    EXPECT_EQ(result.unclassified_segments, 1) << "view " << view << ": the step alone";
  }
  const auto unknown = ObjectsLabelled(mapper, kUnknownClassId);
  ASSERT_EQ(unknown.size(), 1u);
  EXPECT_EQ(unknown[0]->observations.size(), 3u);
  EXPECT_GT(unknown[0]->min_W.y(), 0.25) << "the step, not the stool";
  EXPECT_LT(unknown[0]->min_W.y(), 0.35) << "both blocks";
  EXPECT_GT(unknown[0]->max_W.y(), 0.65) << "both blocks";
}

TEST_F(MapperScene, BadInputIsRejectedAndChangesNothing) {
  Mapper mapper{kDefaultConfig};
  std::string why;
  KeyframeResult result;
  RgbdFrame frame = Frame(0);
  frame.T_W_C.matrix()(0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(mapper.AddKeyframe(frame, CupDetections(0), &result, &why));
  EXPECT_NE(why.find("view-0"), std::string::npos) << why;
  EXPECT_NE(why.find("NaN"), std::string::npos) << why;

  frame = Frame(0);
  frame.depth.width = 320;
  EXPECT_FALSE(mapper.AddKeyframe(frame, CupDetections(0), &result, &why));
  EXPECT_NE(why.find("depth image is 320x480"), std::string::npos) << why;
  EXPECT_EQ(mapper.num_keyframes(), 0u);
  EXPECT_EQ(mapper.objects().size(), 0u);

  EXPECT_FALSE(mapper.UpdatePoses({{42, Eigen::Isometry3d::Identity()}}, &why));
  EXPECT_NE(why.find("unknown keyframe id 42"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
