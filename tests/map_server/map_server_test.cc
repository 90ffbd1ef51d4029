#include "map_server/map_server.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <thread>

#include "store/keyframe_store.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

using testing::SceneBox;

const int kCup = CocoClassId("cup");

// A table top with two cups and a wall behind, seen from three viewpoints; the server's store is
// a real SQLite file in a temporary directory.
class MapServerScene : public ::testing::Test {
 protected:
  MapServerScene() {
    boxes_ = {
        {{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},      // table top
        {{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}},  // cup 1
        {{-0.05, 0.15, 0.70}, {0.05, 0.25, 0.82}, {30, 30, 200}},    // cup 2
        {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}},        // wall
    };
    eyes_ = {{-1.0, 0.0, 1.3}, {-1.0, 0.25, 1.3}, {-0.95, -0.25, 1.35}};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    db_path_ = ::testing::TempDir() + "objmap_map_server_" + std::to_string(getpid()) + "_" +
               info->name() + ".db";
    RemoveDatabase();
  }
  ~MapServerScene() override { RemoveDatabase(); }

  void RemoveDatabase() const {
    for (const char* suffix : {"", "-wal", "-shm"}) std::remove((db_path_ + suffix).c_str());
  }

  std::unique_ptr<MapServer> OpenServer() const {
    std::string why;
    const MapServerConfig server_config;
    auto server = MapServer::Open(server_config, db_path_, nullptr, &why);
    EXPECT_TRUE(server) << why;
    return server;
  }

  Eigen::Isometry3d Pose(int view) const {
    return testing::LookAt(eyes_[view], Eigen::Vector3d(0, 0, 0.7));
  }
  std::vector<Detection> CupDetections(int view) const {
    return {{testing::ProjectBox(boxes_[1], Pose(view), K_), kCup, 0.6f},
            {testing::ProjectBox(boxes_[2], Pose(view), K_), kCup, 0.5f}};
  }

  void IngestAllViews(MapServer* server) const {
    for (int view = 0; view < 3; ++view) {
      RgbdFrame frame =
          testing::RenderFrame(boxes_, K_, Pose(view), "view-" + std::to_string(view));
      AddKeyframeOutcome outcome;
      const ServiceStatus status = server->AddKeyframe(frame, CupDetections(view), &outcome);
      ASSERT_TRUE(status.ok()) << status.message;
      EXPECT_EQ(outcome.keyframe_id, view + 1);
      EXPECT_EQ(outcome.detections_used, 2);
    }
  }

  std::vector<std::shared_ptr<const ObjectView>> Cups(const MapServer& server,
                                                      bool include_unconfirmed = false) const {
    ObjectFilter filter;
    filter.class_id = kCup;
    filter.include_unconfirmed = include_unconfirmed;
    std::vector<std::shared_ptr<const ObjectView>> cups;
    std::uint64_t version = 0;
    EXPECT_TRUE(server.QueryObjects(filter, &cups, &version).ok());
    return cups;
  }

  // The third view arrives with a pose drifted 15 cm sideways, so its two cups land where no cup
  // is and become two more objects.
  void IngestWithTheThirdViewDrifted(MapServer* server) const {
    Eigen::Isometry3d drifted = Pose(2);
    drifted.pretranslate(Eigen::Vector3d(0.0, 0.15, 0.0));
    for (int view = 0; view < 3; ++view) {
      RgbdFrame frame =
          testing::RenderFrame(boxes_, K_, Pose(view), "view-" + std::to_string(view));
      if (view == 2) frame.T_W_C = drifted;
      AddKeyframeOutcome outcome;
      ASSERT_TRUE(server->AddKeyframe(frame, CupDetections(view), &outcome).ok());
    }
  }

  // The store's "pose update pending" mark, read on a plain SQLite connection of its own (a
  // second store on a database in use is refused).
  bool StoredPoseUpdatePending() const {
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open_v2(db_path_.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
    sqlite3_stmt* query = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, "SELECT value FROM meta WHERE key = 'pose_update_pending'",
                                 -1, &query, nullptr),
              SQLITE_OK)
        << sqlite3_errmsg(db);
    const bool pending = sqlite3_step(query) == SQLITE_ROW && sqlite3_column_int(query, 0) != 0;
    sqlite3_finalize(query);
    sqlite3_close(db);
    return pending;
  }

  // Restarts the server on its file: the cups come back with their ids, observations and
  // centroids.
  void ExpectTheSameCupsAfterRestart(
      std::unique_ptr<MapServer>* server,
      const std::vector<std::shared_ptr<const ObjectView>>& before) const {
    server->reset();
    *server = OpenServer();
    ASSERT_TRUE(*server);
    const auto restored = Cups(**server);
    ASSERT_EQ(restored.size(), before.size());
    for (std::size_t i = 0; i < before.size(); ++i) {
      EXPECT_EQ(restored[i]->id, before[i]->id);
      EXPECT_EQ(restored[i]->observations, before[i]->observations);
      EXPECT_LT((restored[i]->centroid_W - before[i]->centroid_W).norm(), 1e-4);
    }
  }

  CameraIntrinsics K_;
  std::vector<SceneBox> boxes_;
  std::vector<Eigen::Vector3d> eyes_;
  std::string db_path_;
};

TEST_F(MapServerScene, QueriesByClassRegionAndNearest) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestAllViews(server.get());
  EXPECT_EQ(server->Status().map_version, 3u);
  EXPECT_EQ(server->Status().keyframes, 3u);

  const auto cups = Cups(*server);
  ASSERT_EQ(cups.size(), 2u);
  for (const auto& cup : cups) {
    EXPECT_NEAR(cup->centroid_W.z(), 0.76, 0.05);
    EXPECT_EQ(cup->observations, 3);
    ASSERT_TRUE(cup->model_W);
    EXPECT_GT(cup->model_W->size(), 100u);
  }

  ObjectFilter region;  // only the cup at y > 0
  region.region = {{-0.2, 0.0, 0.6}, {0.2, 0.4, 1.0}};
  std::vector<std::shared_ptr<const ObjectView>> found;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->QueryObjects(region, &found, &version).ok());
  ASSERT_EQ(found.size(), 1u);
  EXPECT_GT(found[0]->centroid_W.y(), 0.1f);
  EXPECT_EQ(version, 3u);

  ObjectFilter nearest;
  nearest.nearest_to = Eigen::Vector3d(0.0, -0.2, 0.8);
  nearest.max_results = 1;
  ASSERT_TRUE(server->QueryObjects(nearest, &found, &version).ok());
  ASSERT_EQ(found.size(), 1u);
  EXPECT_LT(found[0]->centroid_W.y(), -0.1f);

  std::shared_ptr<const ObjectView> object;
  EXPECT_TRUE(server->GetObject(found[0]->id, &object).ok());
  const ServiceStatus missing = server->GetObject(999, &object);
  EXPECT_EQ(missing.code, StatusCode::kNotFound);
  EXPECT_NE(missing.message.find("999"), std::string::npos);

  // A ray from the first camera towards a cup stops at the cup (an object, not in the OctoMap);
  // one that passes beside the cups stops at the table top (structure).
  const Eigen::Vector3d eye = eyes_[0];
  const Eigen::Vector3d cup_centre = 0.5 * (boxes_[1].lo + boxes_[1].hi);
  RayHit hit;
  ObjectId object_hit = -1;
  ASSERT_TRUE(server->CastRay(eye, cup_centre - eye, 5.0, false, &hit, &object_hit, &version).ok());
  EXPECT_TRUE(hit.hit);
  EXPECT_EQ(hit.state, VoxelState::kOccupied);
  EXPECT_EQ(object_hit, found[0]->id);  // the cup at y < 0, found by the nearest query above
  // The cup's near face is at x = -0.05; the ray meets it about 0.95 m along from the eye.
  EXPECT_NEAR(hit.voxel_center_W.x(), -0.05, 0.015);
  const Eigen::Vector3d table_point(-0.3, 0.0, 0.70);
  ASSERT_TRUE(
      server->CastRay(eye, table_point - eye, 5.0, false, &hit, &object_hit, &version).ok());
  EXPECT_TRUE(hit.hit);
  EXPECT_EQ(object_hit, 0);
  EXPECT_NEAR(hit.voxel_center_W.z(), 0.70, 0.015);

  std::vector<InventoryEntry> inventory;
  ASSERT_TRUE(server->Inventory(std::nullopt, &inventory, &version).ok());
  ASSERT_EQ(inventory.size(), 1u);
  EXPECT_EQ(inventory[0].class_id, kCup);
  EXPECT_EQ(inventory[0].count, 2);
}

// A box on the table that nothing detects: an unknown object the queries return (by class
// "unknown" and by region), outside the inventory and its changes, and kept over a restart.
TEST_F(MapServerScene, AnUnnamedThingIsAnUnknownObjectThatSurvivesARestart) {
  boxes_.push_back({{0.15, -0.05, 0.70}, {0.27, 0.05, 0.80}, {40, 160, 40}});
  ObjectFilter unknown;
  unknown.class_id = kUnknownClassId;
  std::vector<std::shared_ptr<const ObjectView>> found;
  std::uint64_t version = 0;
  ObjectId unknown_id = 0;
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    IngestAllViews(server.get());
    ASSERT_TRUE(server->QueryObjects(unknown, &found, &version).ok());
    ASSERT_EQ(found.size(), 1u);
    EXPECT_TRUE(found[0]->confirmed);
    EXPECT_EQ(found[0]->observations, 3);
    EXPECT_TRUE(found[0]->scores.empty());
    unknown_id = found[0]->id;

    ObjectFilter region;
    region.region = {{0.1, -0.1, 0.6}, {0.35, 0.1, 1.0}};
    ASSERT_TRUE(server->QueryObjects(region, &found, &version).ok());
    ASSERT_EQ(found.size(), 1u);
    EXPECT_EQ(found[0]->id, unknown_id);

    std::vector<InventoryEntry> inventory;
    ASSERT_TRUE(server->Inventory(std::nullopt, &inventory, &version).ok());
    ASSERT_EQ(inventory.size(), 1u);
    EXPECT_EQ(inventory[0].class_id, kCup);
    ASSERT_TRUE(server->Inventory(std::uint64_t{0}, &inventory, &version).ok());
    for (const InventoryEntry& entry : inventory) EXPECT_NE(entry.class_id, kUnknownClassId);
  }
  auto server = OpenServer();
  ASSERT_TRUE(server);
  ASSERT_TRUE(server->QueryObjects(unknown, &found, &version).ok());
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0]->id, unknown_id);
  EXPECT_EQ(found[0]->observations, 3);

  unknown.class_id = kUnknownClassId + 1;
  const ServiceStatus bad = server->QueryObjects(unknown, &found, &version);
  EXPECT_EQ(bad.code, StatusCode::kInvalidArgument);
  EXPECT_NE(bad.message.find("nor unknown (80)"), std::string::npos) << bad.message;
}

TEST_F(MapServerScene, ARayStoppedByTheStructureOnACupsSurfaceNamesTheCup) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestAllViews(server.get());
  // A fourth keyframe in which nothing was detected: its cup surfaces go into the OctoMap as
  // structure. Its depth puts the cups' faces 7 mm nearer (sensor noise), so the ray meets a
  // structure voxel (centre x = -0.055) before it passes the cups' model points (x = -0.05).
  std::vector<SceneBox> nearer = boxes_;
  for (int cup : {1, 2}) nearer[cup].lo.x() -= 0.007;
  RgbdFrame frame = testing::RenderFrame(nearer, K_, Pose(0), "undetected");
  AddKeyframeOutcome outcome;
  ASSERT_TRUE(server->AddKeyframe(frame, {}, &outcome).ok());

  const auto cups = Cups(*server);
  ASSERT_EQ(cups.size(), 2u);
  for (const auto& cup : cups) {
    const Eigen::Vector3d centre = cup->centroid_W.cast<double>();
    RayHit hit;
    ObjectId object_hit = -1;
    std::uint64_t version = 0;
    ASSERT_TRUE(
        server->CastRay(eyes_[0], centre - eyes_[0], 5.0, false, &hit, &object_hit, &version).ok());
    EXPECT_TRUE(hit.hit);
    EXPECT_EQ(object_hit, cup->id) << "hit at " << hit.voxel_center_W.transpose();
  }
  // The table top beside the cups is still structure only.
  RayHit hit;
  ObjectId object_hit = -1;
  std::uint64_t version = 0;
  const Eigen::Vector3d table_point(-0.3, 0.0, 0.70);
  ASSERT_TRUE(
      server->CastRay(eyes_[0], table_point - eyes_[0], 5.0, false, &hit, &object_hit, &version)
          .ok());
  EXPECT_TRUE(hit.hit);
  EXPECT_EQ(object_hit, 0);
}

TEST_F(MapServerScene, BadRequestsNameTheFieldAndChangeNothing) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestAllViews(server.get());

  RgbdFrame frame = testing::RenderFrame(boxes_, K_, Pose(0), "bad");
  frame.depth.depth_m.resize(10);
  AddKeyframeOutcome outcome;
  ServiceStatus status = server->AddKeyframe(frame, CupDetections(0), &outcome);
  EXPECT_EQ(status.code, StatusCode::kInvalidArgument);

  ObjectFilter inverted;
  inverted.region = {{1.0, 0.0, 0.0}, {0.0, 1.0, 1.0}};
  std::vector<std::shared_ptr<const ObjectView>> found;
  std::uint64_t version = 0;
  status = server->QueryObjects(inverted, &found, &version);
  EXPECT_EQ(status.code, StatusCode::kInvalidArgument);
  EXPECT_NE(status.message.find("region.min.x"), std::string::npos) << status.message;

  PoseUpdateOutcome pose_outcome;
  status = server->UpdatePoses({{42, Eigen::Isometry3d::Identity()}}, true, &pose_outcome);
  EXPECT_EQ(status.code, StatusCode::kNotFound);
  EXPECT_NE(status.message.find("42"), std::string::npos);
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  status = server->UpdatePoses({{1, nan_pose}}, true, &pose_outcome);
  EXPECT_EQ(status.code, StatusCode::kInvalidArgument);

  EXPECT_EQ(server->Status().map_version, 3u);
  EXPECT_EQ(Cups(*server).size(), 2u);
}

TEST_F(MapServerScene, RestartRestoresTheSameMap) {
  std::vector<std::shared_ptr<const ObjectView>> before;
  std::string octomap_before;
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    EXPECT_EQ(server->Status().checkpoint_version, 0u);
    IngestAllViews(server.get());
    before = Cups(*server);
    std::size_t leaves = 0;
    std::uint64_t version = 0;
    ASSERT_TRUE(server->OctomapBytes(std::nullopt, &octomap_before, &leaves, &version).ok());
  }
  auto server = OpenServer();
  ASSERT_TRUE(server);
  EXPECT_EQ(server->Status().keyframes, 3u);
  EXPECT_EQ(server->Status().map_version, 3u);
  // The shutdown saved the OctoMap; the restart loaded it instead of integrating the keyframes.
  EXPECT_EQ(server->Status().checkpoint_version, 3u);
  EXPECT_EQ(server->Status().startup_keyframes_integrated, 0);
  std::string octomap_after;
  std::size_t leaves = 0;
  std::uint64_t octomap_version = 0;
  ASSERT_TRUE(server->OctomapBytes(std::nullopt, &octomap_after, &leaves, &octomap_version).ok());
  EXPECT_EQ(octomap_after, octomap_before);
  const auto after = Cups(*server);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i]->id, before[i]->id);
    EXPECT_EQ(after[i]->class_id, before[i]->class_id);
    EXPECT_FLOAT_EQ(after[i]->confidence, before[i]->confidence);
    EXPECT_LT((after[i]->centroid_W - before[i]->centroid_W).norm(), 1e-4);
    // Observations are stored as their pixels and rebuilt from the stored depth: the models
    // are the same, bit for bit.
    ASSERT_TRUE(after[i]->model_W && before[i]->model_W);
    EXPECT_EQ(after[i]->model_W->points, before[i]->model_W->points);
    EXPECT_EQ(after[i]->model_W->colors, before[i]->model_W->colors);
  }
  // The restart's session sees the first view again, unchanged: a revisit of keyframe 1, no
  // new keyframe (MapServerConfig::thinning).
  RgbdFrame frame = testing::RenderFrame(boxes_, K_, Pose(0), "again");
  AddKeyframeOutcome outcome;
  ASSERT_TRUE(server->AddKeyframe(frame, CupDetections(0), &outcome).ok());
  EXPECT_EQ(outcome.keyframe_id, 0);
  EXPECT_EQ(outcome.repeated_keyframe, 1);
  EXPECT_EQ(outcome.map_version, 4u);
  EXPECT_EQ(server->Status().keyframes, 3u);
  // A keyframe with something new in view (a box put down) is mapped: new keyframes continue
  // the ids.
  boxes_.push_back({{0.15, -0.05, 0.70}, {0.27, 0.05, 0.80}, {40, 160, 40}});
  frame = testing::RenderFrame(boxes_, K_, Pose(0), "changed");
  ASSERT_TRUE(server->AddKeyframe(frame, CupDetections(0), &outcome).ok());
  EXPECT_EQ(outcome.keyframe_id, 4);
  EXPECT_EQ(outcome.repeated_keyframe, 0);
  EXPECT_EQ(outcome.map_version, 5u);
  EXPECT_EQ(outcome.created.size(), 1u);  // the box, segmented and never named: unknown
}

TEST_F(MapServerScene, WithoutCheckpointsARestartIntegratesEveryKeyframeToTheSameOctomap) {
  MapServerConfig config;
  config.checkpoint_every_keyframes = 0;
  std::string why, octomap_before, octomap_after;
  std::size_t leaves = 0;
  std::uint64_t version = 0;
  {
    auto server = MapServer::Open(config, db_path_, nullptr, &why);
    ASSERT_TRUE(server) << why;
    IngestAllViews(server.get());
    ASSERT_TRUE(server->OctomapBytes(std::nullopt, &octomap_before, &leaves, &version).ok());
  }
  auto server = MapServer::Open(config, db_path_, nullptr, &why);
  ASSERT_TRUE(server) << why;
  EXPECT_EQ(server->Status().checkpoint_version, 0u);
  EXPECT_EQ(server->Status().startup_keyframes_integrated, 3);
  ASSERT_TRUE(server->OctomapBytes(std::nullopt, &octomap_after, &leaves, &version).ok());
  EXPECT_EQ(octomap_after, octomap_before);
  config.checkpoint_every_keyframes = -1;
  EXPECT_FALSE(MapServer::Open(config, db_path_, nullptr, &why));
  EXPECT_NE(why.find("checkpoint_every_keyframes"), std::string::npos) << why;
}

TEST_F(MapServerScene, AKeyframeTheStoreRefusesLeavesNoTraceAndItsIdIsReused) {
  MapServerConfig config;
  config.store.busy_timeout_ms = 50;
  std::string why;
  auto server = MapServer::Open(config, db_path_, nullptr, &why);
  ASSERT_TRUE(server) << why;
  RgbdFrame first = testing::RenderFrame(boxes_, K_, Pose(0), "view-0");
  AddKeyframeOutcome outcome;
  ASSERT_TRUE(server->AddKeyframe(first, CupDetections(0), &outcome).ok());
  const auto cups_before = Cups(*server);
  std::string octomap_before;
  std::size_t leaves = 0;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->OctomapBytes(std::nullopt, &octomap_before, &leaves, &version).ok());

  // Another program holds the database's write lock: the commit of the next keyframe fails.
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(db_path_.c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), SQLITE_OK);
  RgbdFrame second = testing::RenderFrame(boxes_, K_, Pose(1), "view-1");
  const ServiceStatus refused = server->AddKeyframe(second, CupDetections(1), &outcome);
  EXPECT_EQ(refused.code, StatusCode::kInternal);
  EXPECT_NE(refused.message.find("keyframe 2 was mapped but not stored"), std::string::npos)
      << refused.message;
  sqlite3_exec(other, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(other);

  // The map is what the store holds: one keyframe, the same cups and OctoMap as before.
  EXPECT_EQ(server->Status().keyframes, 1u);
  std::string octomap_after;
  ASSERT_TRUE(server->OctomapBytes(std::nullopt, &octomap_after, &leaves, &version).ok());
  EXPECT_EQ(octomap_after, octomap_before);
  const auto cups_after = Cups(*server);
  ASSERT_EQ(cups_after.size(), cups_before.size());
  for (std::size_t i = 0; i < cups_after.size(); ++i) {
    EXPECT_EQ(cups_after[i]->observations, cups_before[i]->observations);
  }
  // Sent again, the keyframe gets the id the refused one had.
  ASSERT_TRUE(server->AddKeyframe(second, CupDetections(1), &outcome).ok());
  EXPECT_EQ(outcome.keyframe_id, 2);
  EXPECT_EQ(server->Status().keyframes, 2u);
  for (const auto& cup : Cups(*server)) EXPECT_EQ(cup->observations, 2);
}

TEST_F(MapServerScene, PoseUpdateMovesObjectsAndOccupancy) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestAllViews(server.get());
  const auto before = Cups(*server);
  bool free = false;
  RegionOccupancy counts;
  std::uint64_t version = 0;
  const Eigen::Vector3d air_min(-0.5, -0.1, 1.0), air_max(-0.4, 0.0, 1.1);
  ASSERT_TRUE(server->IsFree(air_min, air_max, false, &free, &counts, nullptr, &version).ok());
  EXPECT_TRUE(free) << counts.occupied << " occupied, " << counts.unknown << " unknown";
  const Eigen::Vector3d table_min(-0.3, -0.05, 0.68), table_max(-0.2, 0.05, 0.72);
  ASSERT_TRUE(server->IsFree(table_min, table_max, false, &free, &counts, nullptr, &version).ok());
  EXPECT_FALSE(free);
  // Cups are objects, not OctoMap voxels: a box around one is not free even for a planner that
  // takes unknown space as free, and the answer names the cup.
  std::vector<ObjectId> objects_inside;
  ASSERT_TRUE(server
                  ->IsFree(boxes_[1].lo - Eigen::Vector3d::Constant(0.01),
                           boxes_[1].hi + Eigen::Vector3d::Constant(0.01), true, &free, &counts,
                           &objects_inside, &version)
                  .ok());
  EXPECT_FALSE(free);
  ASSERT_EQ(objects_inside.size(), 1u);
  EXPECT_LT(before[0]->centroid_W.y() * before[1]->centroid_W.y(), 0.f);  // one cup each side
  const ObjectId cup_at_negative_y =
      before[0]->centroid_W.y() < 0.f ? before[0]->id : before[1]->id;
  EXPECT_EQ(objects_inside[0], cup_at_negative_y);
  ASSERT_TRUE(
      server->IsFree(air_min, air_max, true, &free, &counts, &objects_inside, &version).ok());
  EXPECT_TRUE(free);
  EXPECT_TRUE(objects_inside.empty());

  Eigen::Isometry3d G = Eigen::Isometry3d::Identity();  // a rigid correction of every pose
  G.translate(Eigen::Vector3d(0.5, -0.3, 0.1));
  G.rotate(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (int view = 0; view < 3; ++view) poses[view + 1] = G * Pose(view);

  // Queries keep answering while the regeneration runs.
  std::atomic<bool> done{false};
  std::atomic<int> answered_while_regenerating{0};
  std::thread reader([&] {
    while (!done) {
      std::vector<std::shared_ptr<const ObjectView>> found;
      std::uint64_t v = 0;
      bool f = false;
      RegionOccupancy c;
      const bool regenerating = server->Status().regenerating;
      if (server->QueryObjects(ObjectFilter{}, &found, &v).ok() &&
          server->IsFree(air_min, air_max, false, &f, &c, nullptr, &v).ok() && regenerating) {
        ++answered_while_regenerating;
      }
    }
  });
  PoseUpdateOutcome outcome;
  const ServiceStatus status = server->UpdatePoses(poses, true, &outcome);
  done = true;
  reader.join();
  ASSERT_TRUE(status.ok()) << status.message;
  EXPECT_TRUE(outcome.regenerated);
  EXPECT_EQ(outcome.keyframes_moved, 3);
  EXPECT_EQ(outcome.map_version, 4u);
  EXPECT_GT(answered_while_regenerating.load(), 0);

  const auto after = Cups(*server);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i]->id, before[i]->id);
    const Eigen::Vector3f expected = (G * before[i]->centroid_W.cast<double>()).cast<float>();
    EXPECT_LT((after[i]->centroid_W - expected).norm(), 0.01f);
  }
  // The table top moved with the poses.
  const Eigen::Vector3d moved_table = G * Eigen::Vector3d(-0.25, 0.0, 0.70);
  ASSERT_TRUE(server
                  ->IsFree(moved_table - Eigen::Vector3d::Constant(0.03),
                           moved_table + Eigen::Vector3d::Constant(0.03), false, &free, &counts,
                           nullptr, &version)
                  .ok());
  EXPECT_GT(counts.occupied, 0u);

  // A restart regenerates with the stored poses.
  ExpectTheSameCupsAfterRestart(&server, after);
}

// The third view arrives with a pose drifted 15 cm sideways, so its cups are two more objects; a
// loop closure corrects that one keyframe. The correction is not rigid: the server re-associates,
// stores the new grouping in place of the old one, and a restart gives the same objects.
TEST_F(MapServerScene, NonRigidCorrectionReassociatesAndTheStoreKeepsTheNewGrouping) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestWithTheThirdViewDrifted(server.get());
  ASSERT_EQ(Cups(*server, true).size(), 4u);
  // The drifted copies stand where the first two views saw the table and no cup: the evidence
  // keeps them out; the real cups, detected in both views that saw them, are in.
  const auto before = Cups(*server);
  EXPECT_EQ(before.size(), 2u);
  for (const auto& cup : before) EXPECT_EQ(cup->observations, 2) << "not a drifted copy";

  PoseUpdateOutcome outcome;
  const ServiceStatus status = server->UpdatePoses({{3, Pose(2)}}, true, &outcome);
  ASSERT_TRUE(status.ok()) << status.message;
  EXPECT_TRUE(outcome.reassociated);
  EXPECT_EQ(outcome.objects_before, 4);
  EXPECT_EQ(outcome.objects_after, 2);
  EXPECT_EQ(Cups(*server, true).size(), 2u);
  const auto after = Cups(*server);
  ASSERT_EQ(after.size(), 2u);
  for (const auto& cup : after) {
    EXPECT_EQ(cup->observations, 3);
    EXPECT_NEAR(std::abs(cup->centroid_W.y()), 0.2, 0.05);
  }
  EXPECT_FALSE(StoredPoseUpdatePending()) << "the regeneration's commit clears the flag";
  ExpectTheSameCupsAfterRestart(&server, after);
}

// The process dies after UpdatePoses stored the corrected poses and before the regeneration
// committed (simulated: the store gets exactly what UpdatePoses commits, and no server runs).
// The restart finds the pose update pending and re-associates with the stored poses.
// Pose updates that queue behind one another share one regeneration (and one map version): a
// flood of small updates costs a regeneration or two, not one each, and the last poses win.
TEST_F(MapServerScene, QueuedPoseUpdatesShareOneRegeneration) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestWithTheThirdViewDrifted(server.get());
  const std::uint64_t before = server->Status().map_version;
  PoseUpdateOutcome outcome;
  for (int i = 0; i < 20; ++i) {
    Eigen::Isometry3d shifted = Pose(2);
    shifted.pretranslate(Eigen::Vector3d(0.0, 0.01 * i, 0.0));
    ASSERT_TRUE(server->UpdatePoses({{3, shifted}}, /*wait=*/false, &outcome).ok());
  }
  ASSERT_TRUE(server->UpdatePoses({{3, Pose(2)}}, /*wait=*/true, &outcome).ok());
  const std::uint64_t after = server->Status().map_version;
  EXPECT_GE(after - before, 1u);
  EXPECT_LE(after - before, 4u) << "21 updates, " << after - before << " regenerations";
  EXPECT_EQ(outcome.map_version, after);
  std::vector<KeyframeSummary> keyframes;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->ListKeyframes(3, 1, &keyframes, &version).ok());
  ASSERT_EQ(keyframes.size(), 1u);
  EXPECT_TRUE(keyframes[0].T_W_C.isApprox(Pose(2), 1e-9)) << "the last update wins";
  EXPECT_EQ(Cups(*server, true).size(), 2u) << "the corrected view's cups joined the others";
}

TEST_F(MapServerScene, ARestartFinishesAnInterruptedPoseUpdate) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  IngestWithTheThirdViewDrifted(server.get());
  ASSERT_EQ(Cups(*server, true).size(), 4u);
  server.reset();
  {
    std::string why;
    auto store = KeyframeStore::Open(db_path_, KeyframeStoreConfig{}, &why);
    ASSERT_TRUE(store) << why;
    StoreChange change;
    change.poses = {{3, Pose(2)}};
    change.pose_update_pending = true;
    ASSERT_TRUE(store->Commit(change, &why)) << why;
  }
  server = OpenServer();
  ASSERT_TRUE(server);
  EXPECT_EQ(Cups(*server, true).size(), 2u) << "the drifted view's cups joined the others";
  const auto after = Cups(*server);
  ASSERT_EQ(after.size(), 2u);
  for (const auto& cup : after) EXPECT_EQ(cup->observations, 3);
  EXPECT_FALSE(StoredPoseUpdatePending()) << "the new grouping is stored and the flag cleared";
  ExpectTheSameCupsAfterRestart(&server, after);
}

TEST_F(MapServerScene, ChangesAndInventorySinceAVersion) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  EXPECT_TRUE(server->ChangesSince(0, std::chrono::milliseconds(10)).empty());
  IngestAllViews(server.get());
  const auto changes = server->ChangesSince(0, std::chrono::milliseconds(10));
  ASSERT_EQ(changes.size(), 3u);
  EXPECT_EQ(changes[0].version, 1u);
  EXPECT_EQ(changes[0].added.size(), 2u);
  EXPECT_EQ(changes[2].keyframe_id, 3);
  EXPECT_EQ(server->ChangesSince(2, std::chrono::milliseconds(10)).size(), 1u);

  std::vector<InventoryEntry> entries;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->Inventory(std::uint64_t{3}, &entries, &version).ok());
  EXPECT_TRUE(entries.empty());
  ASSERT_TRUE(server->Inventory(std::uint64_t{0}, &entries, &version).ok());
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].class_id, kCup);
  EXPECT_EQ(server->Inventory(std::uint64_t{99}, &entries, &version).code,
            StatusCode::kInvalidArgument);

  // After a restart the history starts at the restored version: a watcher from before it gets
  // the summary (every object, at the current version) at once, without waiting for a change.
  server.reset();
  server = OpenServer();
  ASSERT_TRUE(server);
  const auto start = std::chrono::steady_clock::now();
  const auto summary = server->ChangesSince(1, std::chrono::seconds(5));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
  ASSERT_EQ(summary.size(), 1u);
  EXPECT_EQ(summary[0].version, 3u);
  EXPECT_EQ(summary[0].updated.size(), 2u);
  EXPECT_TRUE(server->ChangesSince(3, std::chrono::milliseconds(10)).empty());
}

}  // namespace
}  // namespace objmap
