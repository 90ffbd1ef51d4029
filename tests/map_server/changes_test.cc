// Object changes through a MapServer: a table visited in two sessions, one cup taken away and one
// moved in between. The removed cup is a tombstone (GetObject, ListChanges) and out of the
// inventory, QueryObjects, IsFree and CastRay; the moved one keeps its id; WatchMap sends the
// typed changes; a restart (also after kill -9: the store is all there is) lists the same changes.

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <map>

#include "map_server/map_server.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

using testing::SceneBox;

const int kCup = CocoClassId("cup");
using namespace testing::table_visits;  // kTable, kWall, the cups, both visits' eyes

std::string TempDatabase() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return ::testing::TempDir() + "objmap_changes_" + std::to_string(getpid()) + "_" + info->name() +
         ".db";
}

void RemoveDatabase(const std::string& path) {
  for (const char* suffix : {"", "-wal", "-shm", ".lock"}) std::remove((path + suffix).c_str());
}

class MapServerChanges : public ::testing::Test {
 protected:
  MapServerChanges() : db_path_(TempDatabase()) { RemoveDatabase(db_path_); }
  ~MapServerChanges() override { RemoveDatabase(db_path_); }

  std::unique_ptr<MapServer> OpenServer() const {
    std::string why;
    auto server = MapServer::Open(config_, db_path_, nullptr, &why);
    EXPECT_TRUE(server) << why;
    return server;
  }

  // One keyframe per eye over the table, the wall and `cups`, each cup detected.
  void MapVisit(MapServer* server, const std::vector<Eigen::Vector3d>& eyes,
                const std::vector<SceneBox>& cups) const {
    std::vector<SceneBox> boxes = {kTable, kWall};
    boxes.insert(boxes.end(), cups.begin(), cups.end());
    for (const Eigen::Vector3d& eye : eyes) {
      const Eigen::Isometry3d T_W_C = testing::LookAt(eye, kTarget);
      std::vector<Detection> detections;
      for (const SceneBox& cup : cups) {
        detections.push_back({testing::ProjectBox(cup, T_W_C, K_), kCup, 0.6f});
      }
      AddKeyframeOutcome outcome;
      const ServiceStatus status = server->AddKeyframe(
          testing::RenderFrame(boxes, K_, T_W_C, "frame"), detections, &outcome);
      ASSERT_TRUE(status.ok()) << status.message;
    }
  }

  // The present object nearest the box's centre (0: none within 5 cm).
  static ObjectId ObjectAt(const MapServer& server, const SceneBox& box) {
    const Eigen::Vector3f centre = ((box.lo + box.hi) * 0.5).cast<float>();
    for (const auto& [id, view] : server.Snapshot()->objects) {
      if ((view->centroid_W - centre).norm() < 0.05f) return id;
    }
    return 0;
  }

  static std::vector<MapObjectChange> Changes(const MapServer& server,
                                              const ChangeFilter& filter = {}) {
    std::vector<MapObjectChange> changes;
    std::uint64_t version = 0;
    const ServiceStatus status = server.ListChanges(filter, &changes, &version);
    EXPECT_TRUE(status.ok()) << status.message;
    return changes;
  }

  const MapServerConfig config_;
  CameraIntrinsics K_;
  std::string db_path_;
};

TEST_F(MapServerChanges, ARemovedCupIsATombstoneAndAMovedOneKeepsItsId) {
  ObjectId cup_one = 0, cup_two = 0;
  std::vector<MapObjectChange> listed;
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapVisit(server.get(), kFirstEyes, {kCupOne, kCupTwo});
    cup_one = ObjectAt(*server, kCupOne);
    cup_two = ObjectAt(*server, kCupTwo);
    ASSERT_NE(cup_one, 0);
    ASSERT_NE(cup_two, 0);
    const std::uint64_t first_visit_version = server->Snapshot()->version;
    EXPECT_TRUE(Changes(*server).empty());

    SessionSummary second;
    ASSERT_TRUE(server->StartSession("second visit", &second).ok());
    MapVisit(server.get(), kSecondEyes, {kCupTwoMoved});

    listed = Changes(*server);
    ASSERT_EQ(listed.size(), 2u);
    const MapObjectChange* removed = nullptr;
    const MapObjectChange* moved = nullptr;
    for (const MapObjectChange& change : listed) {
      if (change.change.kind == ObjectChange::Kind::kRemoved) removed = &change;
      if (change.change.kind == ObjectChange::Kind::kMoved) moved = &change;
      EXPECT_EQ(change.seen.session_id, second.session.id);
      EXPECT_GT(change.version, first_visit_version);
    }
    ASSERT_NE(removed, nullptr);
    ASSERT_NE(moved, nullptr);
    EXPECT_EQ(removed->change.id, cup_one);
    EXPECT_EQ(moved->change.id, cup_two);
    EXPECT_NEAR(moved->change.from_W.y(), 0.2f, 0.03f);
    EXPECT_NEAR(moved->change.centroid_W.y(), 0.5f, 0.03f);
    EXPECT_EQ(moved->from_last_seen.session_id, 1);

    // The moved cup is where it is now, under its id; the removed one only as a tombstone.
    const auto snapshot = server->Snapshot();
    ASSERT_EQ(snapshot->objects.count(cup_two), 1u);
    EXPECT_EQ(snapshot->objects.at(cup_two)->state, ObjectState::kMoved);
    EXPECT_NEAR(snapshot->objects.at(cup_two)->centroid_W.y(), 0.5f, 0.03f);
    ASSERT_EQ(snapshot->objects.at(cup_two)->previous_places.size(), 1u);
    EXPECT_EQ(snapshot->objects.count(cup_one), 0u);
    ASSERT_EQ(snapshot->tombstones.count(cup_one), 1u);
    std::shared_ptr<const ObjectView> tombstone;
    ASSERT_TRUE(server->GetObject(cup_one, &tombstone).ok());
    EXPECT_EQ(tombstone->state, ObjectState::kRemoved);
    EXPECT_EQ(tombstone->removed.session_id, second.session.id);
    std::vector<InventoryEntry> inventory;
    std::uint64_t version = 0;
    ASSERT_TRUE(server->Inventory(std::nullopt, &inventory, &version).ok());
    ASSERT_EQ(inventory.size(), 1u);
    EXPECT_EQ(inventory[0].objects, std::vector<ObjectId>{cup_two});

    // Where cup one stood is free for a planner, and a ray through it hits no object.
    const Eigen::Vector3d lo = kCupOne.lo + Eigen::Vector3d(0.01, 0.01, 0.02);
    const Eigen::Vector3d hi = kCupOne.hi - Eigen::Vector3d(0.01, 0.01, 0.01);
    bool free = false;
    RegionOccupancy counts;
    std::vector<ObjectId> inside;
    ASSERT_TRUE(server->IsFree(lo, hi, true, &free, &counts, &inside, &version).ok());
    EXPECT_TRUE(inside.empty());
    RayHit hit;
    ObjectId hit_object = -1;
    const Eigen::Vector3d origin(-1.0, -0.2, 0.76);
    ASSERT_TRUE(
        server->CastRay(origin, Eigen::Vector3d::UnitX(), 1.2, false, &hit, &hit_object, &version)
            .ok());
    EXPECT_NE(hit_object, cup_one);

    // Filters: nothing after the current version; everything since session 2; nothing since 3.
    ChangeFilter after_now;
    after_now.since_version = snapshot->version;
    EXPECT_TRUE(Changes(*server, after_now).empty());
    ChangeFilter since_second;
    since_second.since_session = second.session.id;
    EXPECT_EQ(Changes(*server, since_second).size(), 2u);
    ChangeFilter since_third;
    since_third.since_session = second.session.id + 1;
    EXPECT_TRUE(Changes(*server, since_third).empty());
    ChangeFilter bad;
    bad.since_stamp_s = std::nan("");
    std::vector<MapObjectChange> none;
    EXPECT_EQ(server->ListChanges(bad, &none, &version).code, StatusCode::kInvalidArgument);

    // WatchMap: every change was sent once, typed, at the version it was first listed. The cup
    // at its new place may come first as added (its place was seen empty): until a view sees its
    // old place empty, it is an arrival, not yet a move.
    std::map<ObjectChange::Kind, int> watched;
    for (const MapChange& change :
         server->ChangesSince(first_visit_version, std::chrono::milliseconds(100))) {
      for (const MapObjectChange& object_change : change.object_changes) {
        EXPECT_EQ(object_change.version, change.version);
        ++watched[object_change.change.kind];
      }
    }
    EXPECT_EQ(watched[ObjectChange::Kind::kRemoved], 1);
    EXPECT_EQ(watched[ObjectChange::Kind::kMoved], 1);
    EXPECT_LE(watched[ObjectChange::Kind::kAdded], 1);
  }
  // The store holds the keyframes and observations: a restart lists the same changes.
  auto restarted = OpenServer();
  ASSERT_TRUE(restarted);
  const std::vector<MapObjectChange> again = Changes(*restarted);
  ASSERT_EQ(again.size(), listed.size());
  for (std::size_t i = 0; i < listed.size(); ++i) {
    EXPECT_EQ(again[i].change.kind, listed[i].change.kind);
    EXPECT_EQ(again[i].change.id, listed[i].change.id);
    EXPECT_EQ(again[i].seen.keyframe_id, listed[i].seen.keyframe_id);
    EXPECT_EQ(again[i].seen.session_id, listed[i].seen.session_id);
  }
  std::shared_ptr<const ObjectView> tombstone;
  ASSERT_TRUE(restarted->GetObject(cup_one, &tombstone).ok());
  EXPECT_EQ(tombstone->state, ObjectState::kRemoved);
}

// A cup put down between the visits, detected by one view of the second: the first visit's
// views looked through its place, which is no miss of it (it was not there then), so the one
// detection confirms it, and a restart keeps it so (the sessions come back from the store). The
// same views in one session leave it out: within a session the world stands still, and a
// detection where its own views saw the table is wrong.
TEST_F(MapServerChanges, ACupDetectedOnceWhereAnEarlierSessionSawTheTableIsConfirmed) {
  const SceneBox cup_three{{-0.35, 0.45, 0.70}, {-0.25, 0.55, 0.82}, {30, 160, 30}};
  auto confirmed_at = [](const MapServer& server, const SceneBox& box) {
    const ObjectId id = ObjectAt(server, box);
    if (id == 0) ADD_FAILURE() << "no object at the box";
    return id != 0 && server.Snapshot()->objects.at(id)->confirmed;
  };
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapVisit(server.get(), kFirstEyes, {kCupOne, kCupTwo});
    ASSERT_TRUE(server->StartSession("second visit", nullptr).ok());
    MapVisit(server.get(), {kSecondEyes[0]}, {kCupOne, kCupTwo, cup_three});
    EXPECT_TRUE(confirmed_at(*server, cup_three));
  }
  {
    auto restarted = OpenServer();
    ASSERT_TRUE(restarted);
    EXPECT_TRUE(confirmed_at(*restarted, cup_three));
  }
  RemoveDatabase(db_path_);
  auto one_session = OpenServer();
  ASSERT_TRUE(one_session);
  MapVisit(one_session.get(), kFirstEyes, {kCupOne, kCupTwo});
  MapVisit(one_session.get(), {kSecondEyes[0]}, {kCupOne, kCupTwo, cup_three});
  EXPECT_FALSE(confirmed_at(*one_session, cup_three));
}

// kill -9 during the second visit, at several moments: the reopened map holds exactly the
// acknowledged keyframes, both sessions, and the changes (tombstone included) that a map of those
// keyframes has: nothing acknowledged is lost, nothing is half there.
TEST_F(MapServerChanges, KillNineDuringTheSecondVisitLosesNoChange) {
  // What the map says after each keyframe: a clean run in a database of its own.
  struct Expected {
    std::vector<std::pair<ObjectChange::Kind, ObjectId>> changes;
  };
  std::vector<Expected> after;  // after[k]: after k keyframes
  const std::string reference_path = db_path_ + ".reference";
  RemoveDatabase(reference_path);
  auto list = [](const MapServer& server) {
    std::vector<std::pair<ObjectChange::Kind, ObjectId>> listed;
    for (const MapObjectChange& change : Changes(server)) {
      listed.emplace_back(change.change.kind, change.change.id);
    }
    return listed;
  };
  {
    std::string why;
    auto reference = MapServer::Open(config_, reference_path, nullptr, &why);
    ASSERT_TRUE(reference) << why;
    after.push_back({});
    for (std::size_t i = 0; i < kFirstEyes.size(); ++i) {
      MapVisit(reference.get(), {kFirstEyes[i]}, {kCupOne, kCupTwo});
      after.push_back({list(*reference)});
    }
    ASSERT_TRUE(reference->StartSession("second visit", nullptr).ok());
    for (std::size_t i = 0; i < kSecondEyes.size(); ++i) {
      MapVisit(reference.get(), {kSecondEyes[i]}, {kCupTwoMoved});
      after.push_back({list(*reference)});
    }
  }
  RemoveDatabase(reference_path);
  ASSERT_EQ(after.back().changes.size(), 2u);  // cup one removed, cup two moved

  // Killed after one, two and all three keyframes of the second visit: before any change is
  // known, while the evidence builds up, and after both changes are listed.
  bool saw_changes = false;
  for (int kill_after = 1; kill_after <= 3; ++kill_after) {
    const int trial = kill_after;
    RemoveDatabase(db_path_);
    // The child maps both visits and writes a byte for every acknowledged keyframe; the parent
    // kills it once `kill_after` of the second visit's keyframes are acknowledged.
    int acks[2];
    ASSERT_EQ(pipe(acks), 0);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      close(acks[0]);
      std::string why;
      auto server = MapServer::Open(config_, db_path_, nullptr, &why);
      if (!server) _exit(3);
      auto add = [&](const Eigen::Vector3d& eye, const std::vector<SceneBox>& cups) {
        MapVisit(server.get(), {eye}, cups);
        const char ack = 1;
        if (write(acks[1], &ack, 1) != 1) _exit(4);
      };
      for (const Eigen::Vector3d& eye : kFirstEyes) add(eye, {kCupOne, kCupTwo});
      if (!server->StartSession("second visit", nullptr).ok()) _exit(5);
      for (const Eigen::Vector3d& eye : kSecondEyes) add(eye, {kCupTwoMoved});
      for (;;) pause();  // killed here at the latest
    }
    close(acks[1]);
    const int first_visit = static_cast<int>(kFirstEyes.size());
    int acknowledged = 0;
    char ack = 0;
    while (acknowledged < first_visit + kill_after && read(acks[0], &ack, 1) == 1) ++acknowledged;
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    while (read(acks[0], &ack, 1) == 1) ++acknowledged;  // acknowledged before the kill landed
    close(acks[0]);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the child ended by itself, status " << status;

    auto reopened = OpenServer();
    ASSERT_TRUE(reopened);
    const std::size_t held = reopened->Snapshot()->num_keyframes;
    // Every acknowledged keyframe is there; one more may be, committed as the kill came.
    EXPECT_GE(held, static_cast<std::size_t>(acknowledged)) << "trial " << trial;
    EXPECT_LE(held, static_cast<std::size_t>(acknowledged) + 1) << "trial " << trial;
    ASSERT_LT(held, after.size());
    EXPECT_EQ(list(*reopened), after[held].changes)
        << "trial " << trial << ", " << held << " keyframes";
    saw_changes = saw_changes || !after[held].changes.empty();
    SessionId current = 0;
    std::vector<SessionSummary> sessions;
    ASSERT_TRUE(reopened->ListSessions(&sessions, &current).ok());
    std::size_t stored = 0;
    for (const SessionSummary& session : sessions) stored += session.keyframes > 0 ? 1 : 0;
    EXPECT_EQ(stored, held > kFirstEyes.size() ? 2u : 1u) << "trial " << trial;
  }
  EXPECT_TRUE(saw_changes) << "no kill came after a change was known";
}

}  // namespace
}  // namespace objmap
