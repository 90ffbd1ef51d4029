// A later session over an unchanged place (MapServerConfig::thinning): its keyframes that repeat
// stored views are kept as revisits (no images, no new keyframe), so the store barely grows, and
// the objects those views saw are last seen in the later session, also after a restart. A
// keyframe that sees a change, or a place no stored view saw, is mapped as before.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "map_server/map_server.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

using testing::SceneBox;
using namespace testing::table_visits;

const int kCup = CocoClassId("cup");

std::string TempDatabase() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return ::testing::TempDir() + "objmap_revisits_" + std::to_string(getpid()) + "_" + info->name() +
         ".db";
}

void RemoveDatabase(const std::string& path) {
  for (const char* suffix : {"", "-wal", "-shm", ".lock"}) std::remove((path + suffix).c_str());
}

// The first visit's places, each a few centimetres off: the same views seen again.
std::vector<Eigen::Vector3d> NearFirstEyes() {
  std::vector<Eigen::Vector3d> eyes;
  for (const Eigen::Vector3d& eye : kFirstEyes)
    eyes.push_back(eye + Eigen::Vector3d(0.02, -0.02, 0.01));
  return eyes;
}

class MapServerRevisits : public ::testing::Test {
 protected:
  MapServerRevisits() : db_path_(TempDatabase()) { RemoveDatabase(db_path_); }
  ~MapServerRevisits() override { RemoveDatabase(db_path_); }

  std::unique_ptr<MapServer> OpenServer() const {
    std::string why;
    auto server = MapServer::Open(config_, db_path_, nullptr, &why);
    EXPECT_TRUE(server) << why;
    return server;
  }

  // One keyframe per eye over the table, the wall and `cups` (each detected); their outcomes.
  std::vector<AddKeyframeOutcome> MapVisit(MapServer* server,
                                           const std::vector<Eigen::Vector3d>& eyes,
                                           const std::vector<SceneBox>& cups) const {
    std::vector<SceneBox> boxes = {kTable, kWall};
    boxes.insert(boxes.end(), cups.begin(), cups.end());
    std::vector<AddKeyframeOutcome> outcomes;
    for (const Eigen::Vector3d& eye : eyes) {
      const Eigen::Isometry3d T_W_C = testing::LookAt(eye, kTarget);
      std::vector<Detection> detections;
      for (const SceneBox& cup : cups) {
        detections.push_back({testing::ProjectBox(cup, T_W_C, K_), kCup, 0.6f});
      }
      RgbdFrame frame = testing::RenderFrame(boxes, K_, T_W_C, "frame");
      frame.stamp_s = stamp_s_ += 1.0;
      AddKeyframeOutcome outcome;
      const ServiceStatus status = server->AddKeyframe(frame, detections, &outcome);
      EXPECT_TRUE(status.ok()) << status.message;
      outcomes.push_back(outcome);
    }
    return outcomes;
  }

  static std::vector<SessionSummary> Sessions(const MapServer& server) {
    std::vector<SessionSummary> sessions;
    SessionId current = 0;
    const ServiceStatus status = server.ListSessions(&sessions, &current);
    EXPECT_TRUE(status.ok()) << status.message;
    return sessions;
  }

  // The session each present cup was last seen in.
  static std::vector<SessionId> LastSeenSessions(const MapServer& server) {
    std::vector<SessionId> sessions;
    for (const auto& [id, view] : server.Snapshot()->objects) {
      if (view->class_id == kCup) sessions.push_back(view->last_seen.session_id);
    }
    return sessions;
  }

  MapServerConfig config_;
  CameraIntrinsics K_;
  std::string db_path_;
  mutable double stamp_s_ = 100.0;
};

TEST_F(MapServerRevisits, ASessionOverAnUnchangedPlaceIsKeptAsRevisitsThatOutliveARestart) {
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    for (const AddKeyframeOutcome& outcome :
         MapVisit(server.get(), kFirstEyes, {kCupOne, kCupTwo})) {
      EXPECT_NE(outcome.keyframe_id, 0);
      EXPECT_EQ(outcome.repeated_keyframe, 0);  // nothing before it to repeat
    }
    ASSERT_EQ(server->Snapshot()->objects.size(), 2u);
  }
  // Closed: the write-ahead log is folded into the file.
  const std::uintmax_t first_bytes = std::filesystem::file_size(db_path_);
  {
    auto server = OpenServer();  // a restart: session 2
    ASSERT_TRUE(server);
    const std::uint64_t before = server->Snapshot()->version;
    const std::vector<AddKeyframeOutcome> outcomes =
        MapVisit(server.get(), NearFirstEyes(), {kCupOne, kCupTwo});
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
      SCOPED_TRACE(i);
      EXPECT_EQ(outcomes[i].keyframe_id, 0);
      EXPECT_EQ(outcomes[i].repeated_keyframe, static_cast<KeyframeId>(i + 1));
      EXPECT_GE(outcomes[i].explained_fraction, 0.95f);
      EXPECT_EQ(outcomes[i].session_id, 2);
    }
    EXPECT_EQ(server->Status().keyframes, 3u);
    EXPECT_EQ(server->Snapshot()->objects.size(), 2u);
    EXPECT_EQ(LastSeenSessions(*server), (std::vector<SessionId>{2, 2}));
    // Each revisit is a change of the map that says which view was seen again.
    const std::vector<MapChange> changes =
        server->ChangesSince(before, std::chrono::milliseconds(0));
    ASSERT_EQ(changes.size(), 3u);
    EXPECT_EQ(changes[0].kind, MapChange::Kind::kKeyframeRepeated);
    EXPECT_EQ(changes[0].keyframe_id, 1);
  }
  // Three revisits against three keyframes with their images and observations.
  const std::uintmax_t second_bytes = std::filesystem::file_size(db_path_);
  EXPECT_LE(second_bytes, first_bytes + first_bytes / 20)
      << "first session " << first_bytes << " bytes, with the revisit session " << second_bytes;

  auto server = OpenServer();
  ASSERT_TRUE(server);
  const std::vector<SessionSummary> sessions = Sessions(*server);
  ASSERT_GE(sessions.size(), 2u);
  EXPECT_EQ(sessions[0].keyframes, 3u);
  EXPECT_EQ(sessions[0].revisits, 0u);
  EXPECT_EQ(sessions[1].session.id, 2);
  EXPECT_EQ(sessions[1].keyframes, 0u);
  EXPECT_EQ(sessions[1].revisits, 3u);
  EXPECT_EQ(LastSeenSessions(*server), (std::vector<SessionId>{2, 2}));
  for (const auto& [id, view] : server->Snapshot()->objects) {
    EXPECT_EQ(view->first_seen.session_id, 1);
    EXPECT_GT(view->last_seen.stamp_s, view->first_seen.stamp_s);
  }
}

// A later session's path a little farther back and higher: each keyframe repeats the stored
// views in part and is mapped and stored with the depth of the rest only.
TEST_F(MapServerRevisits, AViewThatRepeatsStoredViewsInPartIsStoredWithItsNewPartOnly) {
  std::vector<KeyframeId> partial;
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapVisit(server.get(), kFirstEyes, {kCupOne, kCupTwo});
    ASSERT_TRUE(server->StartSession("from farther back", nullptr).ok());
    std::vector<Eigen::Vector3d> eyes;
    for (const Eigen::Vector3d& eye : kFirstEyes) {
      eyes.push_back(kTarget + 1.2 * (eye - kTarget) + Eigen::Vector3d(0, 0, 0.1));
    }
    for (const AddKeyframeOutcome& outcome : MapVisit(server.get(), eyes, {kCupOne, kCupTwo})) {
      EXPECT_NE(outcome.keyframe_id, 0);
      EXPECT_NE(outcome.repeated_keyframe, 0);
      EXPECT_LT(outcome.explained_fraction, config_.thinning.min_explained_fraction);
      partial.push_back(outcome.keyframe_id);
    }
    EXPECT_EQ(server->Status().keyframes, 6u);
    EXPECT_EQ(LastSeenSessions(*server), (std::vector<SessionId>{2, 2}));
    std::vector<MapObjectChange> changes;
    std::uint64_t version = 0;
    ASSERT_TRUE(server->ListChanges(ChangeFilter{}, &changes, &version).ok());
    EXPECT_TRUE(changes.empty());  // nothing changed
  }
  std::string why;
  auto store = KeyframeStore::Open(db_path_, KeyframeStoreConfig{}, &why);
  ASSERT_TRUE(store) << why;
  auto with_depth = [](const StoredKeyframe& keyframe) {
    return std::count_if(keyframe.depth_mm.begin(), keyframe.depth_mm.end(),
                         [](std::uint16_t z) { return z > 0; });
  };
  StoredKeyframe first;
  ASSERT_TRUE(store->LoadKeyframe(1, &first, &why)) << why;
  for (KeyframeId id : partial) {
    StoredKeyframe keyframe;
    ASSERT_TRUE(store->LoadKeyframe(id, &keyframe, &why)) << why;
    EXPECT_LT(with_depth(keyframe), with_depth(first) / 2) << "keyframe " << id;
    EXPECT_GT(with_depth(keyframe), 0) << "keyframe " << id;
  }
  std::vector<StoredRevisit> revisits;
  ASSERT_TRUE(store->ListRevisits(0, &revisits, &why)) << why;
  EXPECT_EQ(revisits.size(), partial.size());
}

TEST_F(MapServerRevisits, KeyframesThatSeeAChangeAreMappedAndTheChangeFound) {
  auto server = OpenServer();
  ASSERT_TRUE(server);
  MapVisit(server.get(), kFirstEyes, {kCupOne, kCupTwo});
  ASSERT_TRUE(server->StartSession("", nullptr).ok());
  // Cup one taken away: every view of it sees the table where it stood.
  for (const AddKeyframeOutcome& outcome : MapVisit(server.get(), NearFirstEyes(), {kCupTwo})) {
    EXPECT_NE(outcome.keyframe_id, 0);
    EXPECT_EQ(outcome.repeated_keyframe, 0);
  }
  EXPECT_EQ(server->Status().keyframes, 6u);
  std::vector<MapObjectChange> changes;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->ListChanges(ChangeFilter{}, &changes, &version).ok());
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].change.kind, ObjectChange::Kind::kRemoved);
}

TEST_F(MapServerRevisits, TheSameSessionAndThinningOffMapEveryKeyframe) {
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapVisit(server.get(), kFirstEyes, {kCupOne, kCupTwo});
    // Within one session the client chose its keyframes: none is compared.
    for (const AddKeyframeOutcome& outcome :
         MapVisit(server.get(), NearFirstEyes(), {kCupOne, kCupTwo})) {
      EXPECT_EQ(outcome.repeated_keyframe, 0);
    }
    EXPECT_EQ(server->Status().keyframes, 6u);
  }
  config_.thinning.enabled = false;
  auto server = OpenServer();
  ASSERT_TRUE(server);
  for (const AddKeyframeOutcome& outcome :
       MapVisit(server.get(), NearFirstEyes(), {kCupOne, kCupTwo})) {
    EXPECT_EQ(outcome.repeated_keyframe, 0);
  }
  EXPECT_EQ(server->Status().keyframes, 9u);
}

}  // namespace
}  // namespace objmap
