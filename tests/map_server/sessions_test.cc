// Sessions of a MapServer: one per start and per StartSession, stored with their first keyframe,
// ended by the next one or at shutdown, and listed after a restart; and, with estimated poses, a
// session that starts elsewhere in the saved map is placed there by relocalisation (real
// redkitchen frames), while a start the map cannot explain is refused, never placed wrongly.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <map>

#include "dataset/sequence_reader.h"
#include "map_server/map_server.h"
#include "test_data.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

std::string TempDatabase(const std::string& prefix) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return ::testing::TempDir() + prefix + std::to_string(getpid()) + "_" + info->name() + ".db";
}

void RemoveDatabase(const std::string& path) {
  for (const char* suffix : {"", "-wal", "-shm", ".lock"}) std::remove((path + suffix).c_str());
}

class MapServerSessions : public ::testing::Test {
 protected:
  MapServerSessions() : db_path_(TempDatabase("objmap_sessions_")) {
    RemoveDatabase(db_path_);
    // These sessions map the same views again to follow their bookkeeping: every keyframe is
    // mapped (revisits_test covers the keyframes kept as revisits instead).
    config_.thinning.enabled = false;
    boxes_ = {
        {{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},  // table top
        {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}},    // wall
    };
  }
  ~MapServerSessions() override { RemoveDatabase(db_path_); }

  std::unique_ptr<MapServer> OpenServer() const {
    std::string why;
    auto server = MapServer::Open(config_, db_path_, nullptr, &why);
    EXPECT_TRUE(server) << why;
    return server;
  }

  // Adds a keyframe seen from `eye` and returns the session it joined.
  SessionId AddView(MapServer* server, const Eigen::Vector3d& eye, const std::string& name) {
    RgbdFrame frame =
        testing::RenderFrame(boxes_, K_, testing::LookAt(eye, Eigen::Vector3d(0, 0, 0.7)), name);
    AddKeyframeOutcome outcome;
    const ServiceStatus status = server->AddKeyframe(frame, std::vector<Detection>{}, &outcome);
    EXPECT_TRUE(status.ok()) << status.message;
    return outcome.session_id;
  }

  static std::vector<SessionSummary> Sessions(const MapServer& server, SessionId* current) {
    std::vector<SessionSummary> sessions;
    const ServiceStatus status = server.ListSessions(&sessions, current);
    EXPECT_TRUE(status.ok()) << status.message;
    return sessions;
  }

  MapServerConfig config_;
  CameraIntrinsics K_;
  std::vector<testing::SceneBox> boxes_;
  std::string db_path_;
};

TEST_F(MapServerSessions, EachStartAndStartSessionOpenASessionThatARestartLists) {
  const Eigen::Vector3d eye(-1.0, 0.0, 1.3), other(-1.0, 0.25, 1.3);
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    SessionId current = 0;
    std::vector<SessionSummary> sessions = Sessions(*server, &current);
    // The first start's session, not stored until it maps a keyframe.
    ASSERT_EQ(sessions.size(), 1u);
    EXPECT_EQ(current, 1);
    EXPECT_EQ(sessions[0].keyframes, 0u);
    EXPECT_EQ(sessions[0].session.name, "session 1");
    EXPECT_EQ(sessions[0].session.pose_source, "request");
    EXPECT_TRUE(sessions[0].session.started_s.has_value());
    EXPECT_EQ(server->Status().session_id, 1);

    EXPECT_EQ(AddView(server.get(), eye, "a"), 1);
    EXPECT_EQ(AddView(server.get(), other, "b"), 1);
    SessionSummary started;
    ASSERT_TRUE(server->StartSession("afternoon", &started).ok());
    EXPECT_EQ(started.session.id, 2);
    EXPECT_EQ(started.session.name, "afternoon");
    EXPECT_EQ(server->Status().session_name, "afternoon");
    // A session that maps nothing leaves no trace: session 3 replaces it.
    // "afternoon" mapped nothing: the next session takes its place and its id.
    ASSERT_TRUE(server->StartSession("", &started).ok());
    EXPECT_EQ(started.session.id, 2);
    EXPECT_EQ(started.session.name, "session 2");
    EXPECT_EQ(AddView(server.get(), eye, "c"), 2);
    ASSERT_TRUE(server->StartSession("evening", &started).ok());
    EXPECT_EQ(started.session.id, 3);
    EXPECT_EQ(AddView(server.get(), other, "d"), 3);

    // Bad names are refused with the reason, and the session stays.
    EXPECT_EQ(server->StartSession("two\nlines", nullptr).code, StatusCode::kInvalidArgument);
    EXPECT_EQ(server->StartSession(std::string(300, 'x'), nullptr).code,
              StatusCode::kInvalidArgument);
    EXPECT_EQ(server->Status().session_id, 3);
  }
  auto server = OpenServer();
  ASSERT_TRUE(server);
  SessionId current = 0;
  const std::vector<SessionSummary> sessions = Sessions(*server, &current);
  ASSERT_EQ(sessions.size(), 4u);  // 1, 2 and 3 stored, 4 the restart's
  EXPECT_EQ(current, 4);
  EXPECT_EQ(sessions[0].session.id, 1);
  EXPECT_EQ(sessions[0].keyframes, 2u);
  EXPECT_EQ(sessions[0].first_keyframe, 1);
  EXPECT_EQ(sessions[0].last_keyframe, 2);
  // Session 1 ended when "afternoon" started; its end was stored with session 2's first keyframe.
  ASSERT_TRUE(sessions[0].session.ended_s.has_value());
  EXPECT_GE(*sessions[0].session.ended_s, *sessions[0].session.started_s);
  EXPECT_EQ(sessions[1].session.id, 2);
  EXPECT_EQ(sessions[1].session.name, "session 2");
  EXPECT_EQ(sessions[1].keyframes, 1u);
  EXPECT_EQ(sessions[1].first_keyframe, 3);
  EXPECT_TRUE(sessions[1].session.ended_s.has_value());
  EXPECT_EQ(sessions[2].session.id, 3);
  EXPECT_EQ(sessions[2].session.name, "evening");
  EXPECT_EQ(sessions[2].keyframes, 1u);
  EXPECT_EQ(sessions[2].first_keyframe, 4);
  EXPECT_TRUE(sessions[2].session.ended_s.has_value());  // at shutdown
  EXPECT_EQ(sessions[3].session.id, 4);
  EXPECT_EQ(sessions[3].keyframes, 0u);
  std::vector<KeyframeSummary> keyframes;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->ListKeyframes(0, 0, &keyframes, &version).ok());
  ASSERT_EQ(keyframes.size(), 4u);
  EXPECT_EQ(keyframes[0].session_id, 1);
  EXPECT_EQ(keyframes[1].session_id, 1);
  EXPECT_EQ(keyframes[2].session_id, 2);
  EXPECT_EQ(keyframes[3].session_id, 3);
}

// An object seen in two sessions says when it was first and last seen, and once taken away,
// when it was seen absent: the keyframes, their sessions and stamps, also after a restart.
TEST_F(MapServerSessions, AnObjectSaysInWhichSessionsItWasFirstAndLastSeen) {
  const testing::SceneBox cup = {{-0.05, -0.05, 0.70}, {0.05, 0.05, 0.82}, {200, 30, 30}};
  boxes_.push_back(cup);
  auto add_cup_view = [&](MapServer* server, double y, double stamp_s, bool cup_there = true) {
    const Eigen::Isometry3d T_W_C =
        testing::LookAt({-1.0, y, 1.3}, Eigen::Vector3d(0, 0, 0.7));
    std::vector<testing::SceneBox> scene = boxes_;
    if (!cup_there) scene.pop_back();
    RgbdFrame frame = testing::RenderFrame(scene, K_, T_W_C, "view");
    frame.stamp_s = stamp_s;
    std::vector<Detection> detections;
    if (cup_there) {
      detections.push_back({testing::ProjectBox(cup, T_W_C, K_), CocoClassId("cup"), 0.8f});
    }
    AddKeyframeOutcome outcome;
    const ServiceStatus status = server->AddKeyframe(frame, detections, &outcome);
    EXPECT_TRUE(status.ok()) << status.message;
  };
  auto the_cup = [](const MapServer& server) {
    ObjectFilter filter;
    filter.class_id = CocoClassId("cup");
    filter.include_unconfirmed = true;
    std::vector<std::shared_ptr<const ObjectView>> objects;
    std::uint64_t version = 0;
    EXPECT_TRUE(server.QueryObjects(filter, &objects, &version).ok());
    EXPECT_EQ(objects.size(), 1u);
    return objects.empty() ? std::make_shared<const ObjectView>() : objects[0];
  };
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    add_cup_view(server.get(), 0.0, 10.0);
    add_cup_view(server.get(), 0.1, 11.0);
    const auto cup_view = the_cup(*server);
    EXPECT_EQ(cup_view->first_seen.keyframe_id, 1);
    EXPECT_EQ(cup_view->first_seen.session_id, 1);
    EXPECT_EQ(cup_view->first_seen.stamp_s, 10.0);
    EXPECT_EQ(cup_view->last_seen.keyframe_id, 2);
    EXPECT_EQ(cup_view->last_seen.stamp_s, 11.0);
    ASSERT_TRUE(server->StartSession("next day", nullptr).ok());
    add_cup_view(server.get(), -0.1, 90000.0);
    const auto seen_again = the_cup(*server);
    EXPECT_EQ(seen_again->first_seen.session_id, 1);
    EXPECT_EQ(seen_again->last_seen.keyframe_id, 3);
    EXPECT_EQ(seen_again->last_seen.session_id, 2);
    EXPECT_EQ(seen_again->last_seen.stamp_s, 90000.0);
    EXPECT_EQ(seen_again->last_seen_absent.keyframe_id, 0) << "every view so far saw it";
    // The cup taken away: the next view, which has its place in sight, sees it absent.
    add_cup_view(server.get(), 0.05, 90010.0, /*cup_there=*/false);
    const auto taken = the_cup(*server);
    EXPECT_EQ(taken->last_seen.keyframe_id, 3);
    EXPECT_EQ(taken->last_seen_absent.keyframe_id, 4);
    EXPECT_EQ(taken->last_seen_absent.session_id, 2);
    EXPECT_EQ(taken->last_seen_absent.stamp_s, 90010.0);
  }
  auto server = OpenServer();
  ASSERT_TRUE(server);
  const auto restored = the_cup(*server);
  EXPECT_EQ(restored->first_seen.keyframe_id, 1);
  EXPECT_EQ(restored->first_seen.session_id, 1);
  EXPECT_EQ(restored->first_seen.stamp_s, 10.0);
  EXPECT_EQ(restored->last_seen.keyframe_id, 3);
  EXPECT_EQ(restored->last_seen.session_id, 2);
  EXPECT_EQ(restored->last_seen.stamp_s, 90000.0);
  EXPECT_EQ(restored->last_seen_absent.keyframe_id, 4);
  EXPECT_EQ(restored->last_seen_absent.session_id, 2);

  InventoryConfig bad;
  bad.absent_min_visibility = 0.f;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("absent_min_visibility"), std::string::npos) << why;
}

// Estimated poses on real frames: a map of one part of redkitchen, then sessions that start
// elsewhere.
class Relocalisation : public ::testing::Test {
 protected:
  Relocalisation() : db_path_(TempDatabase("objmap_relocalisation_")) {
    RemoveDatabase(db_path_);
    config_.pose_source = PoseSource::kEstimate;
  }
  ~Relocalisation() override { RemoveDatabase(db_path_); }

  bool OpenSequenceOrSkip() {
    const std::string folder = testing::SharedDataPath("redkitchen");
    if (!testing::Exists(folder)) return false;
    std::string why;
    reader_ = OpenSequence(folder, &why);
    EXPECT_NE(reader_, nullptr) << why;
    return reader_ != nullptr;
  }

  std::unique_ptr<MapServer> OpenServer() const {
    std::string why;
    auto server = MapServer::Open(config_, db_path_, nullptr, &why);
    EXPECT_TRUE(server) << why;
    return server;
  }

  // Frame `index` without its pose, as a camera without tracking sends it.
  RgbdFrame Frame(std::size_t index) const {
    RgbdFrame frame;
    std::string why;
    EXPECT_TRUE(reader_->ReadFrame(index, &frame, &why)) << why;
    frame.T_W_C = Eigen::Isometry3d::Identity();
    return frame;
  }
  // The sequence's pose of frame `index` in the map's world, whose origin is the first mapped
  // frame's camera.
  Eigen::Isometry3d TruthInMap(std::size_t index) const {
    RgbdFrame first, frame;
    std::string why;
    EXPECT_TRUE(reader_->ReadFrame(first_mapped_, &first, &why)) << why;
    EXPECT_TRUE(reader_->ReadFrame(index, &frame, &why)) << why;
    return first.T_W_C.inverse() * frame.T_W_C;
  }

  void MapFrames(MapServer* server, std::size_t first, std::size_t last, std::size_t step) {
    first_mapped_ = first;
    for (std::size_t index = first; index <= last; index += step) {
      AddKeyframeOutcome outcome;
      const ServiceStatus status =
          server->AddKeyframe(Frame(index), std::vector<Detection>{}, &outcome);
      ASSERT_TRUE(status.ok()) << "frame " << index << ": " << status.message;
    }
  }

  MapServerConfig config_;
  std::string db_path_;
  std::unique_ptr<SequenceReader> reader_;
  std::size_t first_mapped_ = 0;
};

// A restart that drives the first session's frames again (a patrol): its keyframes repeat the
// stored views and are kept as revisits, and the loops they close to the saved map (with no
// keyframe of the session mapped yet to move) are no error.
TEST_F(Relocalisation, ASessionDrivingTheSameRouteAgainIsKeptAsRevisits) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "SKIPPED: ../shared/data/redkitchen is absent";
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapFrames(server.get(), 0, 150, 6);
  }
  auto server = OpenServer();
  ASSERT_TRUE(server);
  const std::size_t keyframes_before = server->Status().keyframes;
  int revisits = 0, loops = 0, sent = 0;
  for (std::size_t index = 0; index <= 150; index += 6, ++sent) {
    AddKeyframeOutcome outcome;
    const ServiceStatus status =
        server->AddKeyframe(Frame(index), std::vector<Detection>{}, &outcome);
    ASSERT_TRUE(status.ok()) << "frame " << index << ": " << status.message;
    revisits += outcome.keyframe_id == 0;
    loops += outcome.loops_closed;
  }
  EXPECT_GE(revisits, sent / 2) << revisits << " of " << sent << " kept as revisits";
  EXPECT_EQ(server->Status().keyframes,
            keyframes_before + static_cast<std::size_t>(sent - revisits));
  std::cout << revisits << " of " << sent << " keyframes kept as revisits, " << loops
            << " loops closed" << std::endl;
}

TEST_F(Relocalisation, ASessionStartingElsewhereInTheMapIsPlacedAndMapsEveryKeyframe) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "SKIPPED: ../shared/data/redkitchen is absent";
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapFrames(server.get(), 250, 350, 5);
  }
  // A restart, and the camera starts 85 cm and 20 degrees from where the last session stopped
  // (frame 550; the nearest mapped view is frame 302, 24 cm and 12 degrees away).
  auto server = OpenServer();
  ASSERT_TRUE(server);
  const std::size_t keyframes_before = server->Status().keyframes;
  for (std::size_t index = 550; index <= 570; index += 5) {
    AddKeyframeOutcome outcome;
    const ServiceStatus status =
        server->AddKeyframe(Frame(index), std::vector<Detection>{}, &outcome);
    ASSERT_TRUE(status.ok()) << "frame " << index << ": " << status.message;
    EXPECT_EQ(outcome.session_id, 2);
    if (index == 550) {
      EXPECT_TRUE(outcome.relocalized);
    }
    const Eigen::Isometry3d error = TruthInMap(index).inverse() * outcome.T_W_C;
    EXPECT_LT(error.translation().norm(), 0.05) << "frame " << index;
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle(), 3.0 * M_PI / 180.0) << "frame " << index;
  }
  EXPECT_EQ(server->Status().keyframes, keyframes_before + 5);
}

// A session that starts off the map (frame 640; the map holds frames 250..350) and walks back
// into it: its first keyframes are held in a provisional fragment (refused with the reason, not
// yet stored), and the keyframe that places the session maps them all at their poses, before
// itself. Every keyframe sent ends in the map near the sequence's pose.
TEST_F(Relocalisation, KeyframesBeforeASessionIsPlacedAreHeldThenMapped) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "SKIPPED: ../shared/data/redkitchen is absent";
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapFrames(server.get(), 250, 350, 5);
  }
  auto server = OpenServer();
  ASSERT_TRUE(server);
  const std::size_t keyframes_before = server->Status().keyframes;
  std::map<KeyframeId, std::size_t> frame_of;  // every keyframe mapped, by id
  std::size_t sent = 0, held = 0, placed_at = 0;
  for (std::size_t index = 640; index >= 540; index -= 10) {
    ++sent;
    AddKeyframeOutcome outcome;
    const ServiceStatus status =
        server->AddKeyframe(Frame(index), std::vector<Detection>{}, &outcome);
    if (!status.ok()) {
      ASSERT_EQ(placed_at, 0u) << "frame " << index
                               << " refused after the session was placed: " << status.message;
      ASSERT_EQ(status.code, StatusCode::kFailedPrecondition) << status.message;
      EXPECT_TRUE(outcome.untracked && outcome.held) << status.message;
      EXPECT_EQ(outcome.held_fragment, 1);
      EXPECT_NE(status.message.find("held"), std::string::npos) << status.message;
      EXPECT_EQ(server->Status().keyframes, keyframes_before);  // not stored while held
      ++held;
      continue;
    }
    if (placed_at == 0) {
      placed_at = index;
      EXPECT_TRUE(outcome.relocalized);
      ASSERT_EQ(outcome.attached.size(), held) << "frame " << index;
      // Held in order from frame 640 on, every 10th.
      for (std::size_t i = 0; i < held; ++i) frame_of[outcome.attached[i]] = 640 - 10 * i;
    } else {
      EXPECT_TRUE(outcome.attached.empty());
    }
    frame_of[outcome.keyframe_id] = index;
  }
  ASSERT_GT(held, 0u) << "frame 640 was placed at once: the test needs a start off the map";
  ASSERT_GT(placed_at, 0u) << "the session was never placed";
  EXPECT_EQ(server->Status().keyframes, keyframes_before + sent);
  EXPECT_EQ(frame_of.size(), sent);
  for (const auto& [id, index] : frame_of) {
    RgbdFrame stored;
    ASSERT_TRUE(server->StoredFrame(id, &stored).ok()) << "keyframe " << id;
    const Eigen::Isometry3d error = TruthInMap(index).inverse() * stored.T_W_C;
    EXPECT_LT(error.translation().norm(), 0.05) << "frame " << index;
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle(), 3.0 * M_PI / 180.0) << "frame " << index;
  }
}

// At most server.max_held_keyframes are held: beyond it the oldest go, and the refusal that
// dropped one names it; the placement maps those still held.
TEST_F(Relocalisation, HeldKeyframesBeyondTheLimitAreNamedWhenDropped) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "SKIPPED: ../shared/data/redkitchen is absent";
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    MapFrames(server.get(), 250, 350, 5);
  }
  config_.max_held_keyframes = 2;
  auto server = OpenServer();
  ASSERT_TRUE(server);
  std::vector<std::string> held_names;
  std::size_t named_dropped = 0;
  for (std::size_t index = 640; index >= 540; index -= 10) {
    AddKeyframeOutcome outcome;
    const RgbdFrame frame = Frame(index);
    const ServiceStatus status = server->AddKeyframe(frame, std::vector<Detection>{}, &outcome);
    if (status.ok()) {
      // Only the last two held are mapped with it.
      EXPECT_EQ(outcome.attached.size(), std::min<std::size_t>(held_names.size(), 2));
      break;
    }
    ASSERT_TRUE(outcome.held) << status.message;
    if (held_names.size() >= 2) {
      const std::string& dropped = held_names[held_names.size() - 2];
      EXPECT_NE(status.message.find("max_held_keyframes (2) the oldest held keyframe was "
                                    "dropped, never to be mapped: " +
                                    dropped),
                std::string::npos)
          << status.message;
      ++named_dropped;
    } else {
      EXPECT_EQ(status.message.find("dropped"), std::string::npos) << status.message;
    }
    held_names.push_back(frame.name);
  }
  ASSERT_GE(held_names.size(), 3u) << "the session was placed too soon to drop any";
  EXPECT_EQ(named_dropped, held_names.size() - 2);
}

// Starts the map cannot explain (views of other parts of the kitchen than the map's) are refused
// with the reason and map nothing; a start that is placed is placed right.
TEST_F(Relocalisation, AStartTheMapCannotExplainIsRefusedNeverPlacedWrongly) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "SKIPPED: ../shared/data/redkitchen is absent";
  auto server = OpenServer();
  ASSERT_TRUE(server);
  MapFrames(server.get(), 0, 100, 5);
  int refused = 0;
  for (const std::size_t index : {700u, 800u, 850u, 900u, 950u, 30u}) {
    ASSERT_TRUE(server->StartSession("start at " + std::to_string(index), nullptr).ok());
    const std::size_t keyframes_before = server->Status().keyframes;
    AddKeyframeOutcome outcome;
    const ServiceStatus status =
        server->AddKeyframe(Frame(index), std::vector<Detection>{}, &outcome);
    if (status.ok()) {
      const Eigen::Isometry3d error = TruthInMap(index).inverse() * outcome.T_W_C;
      EXPECT_LT(error.translation().norm(), 0.05) << "frame " << index << " placed wrongly";
      EXPECT_TRUE(outcome.relocalized) << "frame " << index;
    } else {
      ++refused;
      EXPECT_EQ(status.code, StatusCode::kFailedPrecondition) << status.message;
      EXPECT_EQ(server->Status().keyframes, keyframes_before);
    }
  }
  // Frame 30 lies inside the mapped stretch: it must be placed; 850 is 1.07 m and 72 degrees
  // from every mapped view.
  EXPECT_GE(refused, 1);
  EXPECT_LE(refused, 5);
}

// Poses in each session's own frame (a robot's odometry that starts at zero at each boot): the
// first session's frame is the map's; a later session, whose frame lies 1.2 m and 35 degrees
// away, is placed by relocalising its first keyframe, and every keyframe lands where it is.
TEST_F(Relocalisation, PosesInASessionsOwnFrameArePlacedInTheMap) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "SKIPPED: ../shared/data/redkitchen is absent";
  config_.pose_source = PoseSource::kSessionFrame;
  auto truth = [&](std::size_t index) {
    RgbdFrame frame;
    std::string why;
    EXPECT_TRUE(reader_->ReadFrame(index, &frame, &why)) << why;
    // As a client sends it: a quaternion (7-Scenes' matrices are rigid to about 1e-3 only).
    Eigen::Isometry3d T_W_C = frame.T_W_C;
    T_W_C.linear() = Eigen::Quaterniond(frame.T_W_C.rotation()).normalized().toRotationMatrix();
    return T_W_C;
  };
  auto add = [&](MapServer* server, std::size_t index, const Eigen::Isometry3d& T_session_map,
                 AddKeyframeOutcome* outcome) {
    RgbdFrame frame = Frame(index);
    frame.T_W_C = T_session_map * truth(index);
    return server->AddKeyframe(frame, std::vector<Detection>{}, outcome);
  };
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    for (std::size_t index = 250; index <= 350; index += 5) {
      AddKeyframeOutcome outcome;
      const ServiceStatus status = add(server.get(), index, Eigen::Isometry3d::Identity(), &outcome);
      ASSERT_TRUE(status.ok()) << "frame " << index << ": " << status.message;
      EXPECT_TRUE(outcome.T_W_C.isApprox(truth(index), 1e-9)) << "frame " << index;
    }
  }
  Eigen::Isometry3d T_session_map = Eigen::Isometry3d::Identity();
  T_session_map.linear() = Eigen::AngleAxisd(35.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix();
  T_session_map.translation() = Eigen::Vector3d(1.0, -0.5, 0.4);
  auto server = OpenServer();
  ASSERT_TRUE(server);
  ASSERT_EQ(server->Status().session_id, 2);
  // A start the map cannot explain: refused until a keyframe places the session (the stream
  // skips it), nothing mapped.
  const std::size_t keyframes_before = server->Status().keyframes;
  AddKeyframeOutcome outcome;
  ServiceStatus status = add(server.get(), 850, T_session_map, &outcome);
  ASSERT_EQ(status.code, StatusCode::kFailedPrecondition) << status.message;
  EXPECT_TRUE(outcome.untracked);
  EXPECT_NE(status.message.find("not placed in the map yet"), std::string::npos) << status.message;
  EXPECT_EQ(server->Status().keyframes, keyframes_before);
  for (std::size_t index = 550; index <= 600; index += 10) {
    status = add(server.get(), index, T_session_map, &outcome);
    ASSERT_TRUE(status.ok()) << "frame " << index << ": " << status.message;
    EXPECT_EQ(outcome.relocalized, index == 550) << "frame " << index;
    const Eigen::Isometry3d error = truth(index).inverse() * outcome.T_W_C;
    EXPECT_LT(error.translation().norm(), 0.05) << "frame " << index;
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle(), 3.0 * M_PI / 180.0) << "frame " << index;
  }
  EXPECT_EQ(server->Status().keyframes, keyframes_before + 6);
  // A new session has a frame of its own again, placed anew (here the map's own).
  ASSERT_TRUE(server->StartSession("third", nullptr).ok());
  status = add(server.get(), 575, Eigen::Isometry3d::Identity(), &outcome);
  ASSERT_TRUE(status.ok()) << status.message;
  EXPECT_TRUE(outcome.relocalized);
  EXPECT_LT((truth(575).inverse() * outcome.T_W_C).translation().norm(), 0.05);
}

}  // namespace
}  // namespace objmap
