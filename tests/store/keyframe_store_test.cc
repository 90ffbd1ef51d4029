// Round trips through the store and the all-or-nothing semantics of Commit.

#include "store/keyframe_store.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "store/keyframe_codec.h"
#include "store_test_data.h"

namespace objmap {
namespace {

using testing::ExpectSameKeyframe;
using testing::ExpectSameMap;
using testing::ExpectSameObservation;
using testing::MakeKeyframe;
using testing::MakeObservation;

class KeyframeStoreTest : public testing::StoreTest {
 protected:
  // Three keyframes (the third without colour), observations of objects 1 and 2 inserted out of
  // (object, keyframe) order, two summaries and the metadata.
  void CommitSmallMap(KeyframeStore* store) {
    std::string why;
    StoreChange first;
    first.keyframe = MakeKeyframe(1);
    first.observations = {MakeObservation(2, 1, 5), MakeObservation(1, 1, 7),
                          MakeObservation(1, 1, 3, /*colored=*/false)};
    first.map_version = 1;
    first.next_object_id = 3;
    ASSERT_TRUE(store->Commit(first, &why)) << why;
    StoreChange second;
    second.keyframe = MakeKeyframe(2);
    second.observations = {MakeObservation(1, 2, 4), MakeObservation(2, 2, 0)};
    second.object_summaries = {{1, 41, 0.75f, {0.5f, -1.f, 2.25f}, 3},
                               {2, 2, 0.5f, {0.f, 0.f, 1.f}, 2}};
    second.map_version = 2;
    ASSERT_TRUE(store->Commit(second, &why)) << why;
    StoreChange third;
    third.keyframe = MakeKeyframe(3, /*with_color=*/false);
    third.map_version = 3;
    ASSERT_TRUE(store->Commit(third, &why)) << why;
  }

  StoredMap Load(const KeyframeStore& store) {
    StoredMap map;
    std::string why;
    EXPECT_TRUE(store.LoadAll(&map, &why)) << why;
    return map;
  }
};

TEST(KeyframeStoreConfig, IsValidNamesTheBadField) {
  std::string why;
  EXPECT_TRUE(KeyframeStoreConfig{}.IsValid(&why)) << why;
  KeyframeStoreConfig config;
  config.color_jpeg_quality = 0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("color_jpeg_quality"), std::string::npos) << why;
  config = {};
  config.color_jpeg_quality = 101;
  EXPECT_FALSE(config.IsValid(&why));
  config = {};
  config.busy_timeout_ms = -1;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("busy_timeout_ms"), std::string::npos) << why;
  config = {};
  config.synchronous = "SOMETIMES";
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("synchronous"), std::string::npos) << why;
  config.synchronous = "FULL";
  EXPECT_TRUE(config.IsValid(&why)) << why;
}

TEST_F(KeyframeStoreTest, RoundTripsKeyframesObservationsSummariesAndMeta) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  EXPECT_EQ(store->path(), Path());
  StoredMap empty = Load(*store);
  EXPECT_TRUE(empty.keyframes.empty());
  EXPECT_EQ(empty.map_version, 0u);
  EXPECT_EQ(empty.next_object_id, 1);
  CommitSmallMap(store.get());
  EXPECT_EQ(store->NumKeyframes(), 3u);

  const StoredMap map = Load(*store);
  EXPECT_EQ(map.map_version, 3u);
  EXPECT_EQ(map.next_object_id, 3);
  ASSERT_EQ(map.keyframes.size(), 3u);
  for (int i = 0; i < 3; ++i) ExpectSameKeyframe(MakeKeyframe(i + 1, i < 2), map.keyframes[i], 3.0);
  EXPECT_TRUE(map.keyframes[2].color.empty());

  // Ascending (object, keyframe, insertion).
  const std::vector<StoredObservation> expected = {
      MakeObservation(1, 1, 7), MakeObservation(1, 1, 3, false), MakeObservation(1, 2, 4),
      MakeObservation(2, 1, 5), MakeObservation(2, 2, 0)};
  ASSERT_EQ(map.observations.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ExpectSameObservation(expected[i], map.observations[i]);
  }
  ASSERT_EQ(map.objects.size(), 2u);
  EXPECT_EQ(map.objects[0].id, 1);
  EXPECT_EQ(map.objects[0].class_id, 41);
  EXPECT_EQ(map.objects[0].confidence, 0.75f);
  EXPECT_EQ(map.objects[0].centroid_W, Eigen::Vector3f(0.5f, -1.f, 2.25f));
  EXPECT_EQ(map.objects[0].observations, 3);
  EXPECT_EQ(map.objects[1].id, 2);

  StoredKeyframe one;
  std::string why;
  ASSERT_TRUE(store->LoadKeyframe(2, &one, &why)) << why;
  ExpectSameKeyframe(map.keyframes[1], one, 0.0);
  EXPECT_FALSE(store->LoadKeyframe(42, &one, &why));
  EXPECT_EQ(why, "unknown keyframe id 42");
}

TEST_F(KeyframeStoreTest, ReopeningFindsTheSameMap) {
  StoredMap before;
  {
    auto store = OpenStore(Path());
    ASSERT_NE(store, nullptr);
    CommitSmallMap(store.get());
    before = Load(*store);
  }
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  EXPECT_EQ(store->NumKeyframes(), 3u);
  ExpectSameMap(before, Load(*store));
}

// One writer per database: a second store on a file in use is refused and names the process
// that holds it; the file opens again once the first store is closed, or once its process died
// without closing it.
TEST_F(KeyframeStoreTest, ASecondStoreOnADatabaseInUseIsRefusedNamingItsHolder) {
  auto first = OpenStore(Path());
  ASSERT_NE(first, nullptr);
  CommitSmallMap(first.get());
  std::string why;
  EXPECT_EQ(KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why), nullptr);
  EXPECT_NE(why.find("in use by another objmap process (pid " + std::to_string(::getpid())),
            std::string::npos)
      << why;
  EXPECT_NE(why.find(Path() + ".lock"), std::string::npos) << why;
  EXPECT_NE(OpenStore(Path("other.db")), nullptr) << "other files are not locked";
  first.reset();
  auto again = OpenStore(Path());
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(again->NumKeyframes(), 3u);
  again.reset();

  // A child opens the store and is killed (SIGKILL: nothing is closed by the process).
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::string child_why;
    auto held = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &child_why);
    const char byte = held ? 'y' : 'n';
    (void)!::write(ready[1], &byte, 1);
    ::pause();
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ::close(ready[0]);
  ::close(ready[1]);
  ASSERT_EQ(byte, 'y');
  EXPECT_EQ(KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why), nullptr);
  EXPECT_NE(why.find("pid " + std::to_string(child)), std::string::npos) << why;
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  EXPECT_NE(OpenStore(Path()), nullptr) << "the lock died with its process";
}

// An image blob is checked against its keyframe's size by its header, before it is decoded: a
// damaged blob claiming a huge image costs nothing to refuse.
TEST(KeyframeCodec, AnImageBlobOfAnotherSizeIsRefusedByItsHeader) {
  ColorImage big;
  big.width = 32;
  big.height = 24;
  big.rgb.assign(32 * 24 * 3, 90);
  store_internal::Bytes jpeg;
  std::string why;
  ASSERT_TRUE(store_internal::EncodeColorJpeg(big, 90, &jpeg, &why)) << why;
  ColorImage decoded;
  EXPECT_FALSE(store_internal::DecodeColorJpeg(jpeg.data(), jpeg.size(), 8, 6, &decoded, &why));
  EXPECT_EQ(why, "image blob is 32x24, its keyframe 8x6");
  EXPECT_TRUE(store_internal::DecodeColorJpeg(jpeg.data(), jpeg.size(), 32, 24, &decoded, &why))
      << why;
  const std::vector<std::uint16_t> depth(32 * 24, 1000);
  store_internal::Bytes png;
  ASSERT_TRUE(store_internal::EncodeDepthPng(depth, 32, 24, &png, &why)) << why;
  std::vector<std::uint16_t> depth_back;
  EXPECT_FALSE(store_internal::DecodeDepthPng(png.data(), png.size(), 64, 48, &depth_back, &why));
  EXPECT_EQ(why, "image blob is 32x24, its keyframe 64x48");
}

// The database holds the camera's images: it and its WAL are readable by the owner only.
// An observation's pixels round-trip; a blob whose runs overlap, are empty or run past 2^32
// pixels (a gap that would wrap the sum around) is refused.
TEST(KeyframeCodec, SegmentPixelsRoundTripAndBadRunsAreRefused) {
  const PixelRuns runs = {{5, 3}, {100, 640}, {70000, 1}};
  const auto blob = store_internal::PackSegmentPixels(runs, 0.005f, 321);
  PixelRuns back;
  float voxel = 0.f;
  std::size_t points = 0;
  ASSERT_TRUE(
      store_internal::UnpackSegmentPixels(blob.data(), blob.size(), &back, &voxel, &points));
  EXPECT_EQ(back, runs);
  EXPECT_EQ(voxel, 0.005f);
  EXPECT_EQ(points, 321u);
  std::vector<std::uint8_t> bad(blob.begin(), blob.begin() + 5);  // voxel size, count 321 ...
  bad.insert(bad.end(), {0x05, 0x00});                            // ... a run of length 0
  EXPECT_FALSE(store_internal::UnpackSegmentPixels(bad.data(), bad.size(), &back, &voxel, &points));
  bad.resize(5);
  // A gap of 2^64 - 1 after a run ending at pixel 1 would wrap around to a run at pixel 0.
  bad.insert(bad.end(), {0x00, 0x01});
  for (int i = 0; i < 9; ++i) bad.push_back(0xff);
  bad.insert(bad.end(), {0x01, 0x01});
  EXPECT_FALSE(store_internal::UnpackSegmentPixels(bad.data(), bad.size(), &back, &voxel, &points));
  std::vector<std::uint8_t> cut(blob.begin(), blob.end() - 1);  // the last length cut off
  EXPECT_FALSE(store_internal::UnpackSegmentPixels(cut.data(), cut.size(), &back, &voxel, &points));
}

TEST_F(KeyframeStoreTest, DatabaseFilesAreCreatedOwnerOnly) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  CommitSmallMap(store.get());
  for (const std::string& file : {Path(), Path() + "-wal", Path() + ".lock"}) {
    struct stat info {};
    ASSERT_EQ(::stat(file.c_str(), &info), 0) << file;
    EXPECT_EQ(info.st_mode & 0777, 0600u) << file;
  }
}

TEST_F(KeyframeStoreTest, MergesMoveObservationsAndRemovalsDeleteThem) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  CommitSmallMap(store.get());
  StoreChange change;
  change.keyframe = MakeKeyframe(4);
  change.observations = {MakeObservation(5, 4, 2), MakeObservation(2, 4, 6)};
  change.merged = {{1, 2}};  // object 2's observations, the new one included, go to object 1
  change.removed_objects = {5};
  change.object_summaries = {{1, 41, 0.9f, {1.f, 2.f, 3.f}, 6}};
  std::string why;
  ASSERT_TRUE(store->Commit(change, &why)) << why;

  const StoredMap map = Load(*store);
  // Within a keyframe, insertion order: object 2's observation in keyframe 1 came first.
  std::vector<StoredObservation> expected = {
      MakeObservation(2, 1, 5), MakeObservation(1, 1, 7), MakeObservation(1, 1, 3, false),
      MakeObservation(1, 2, 4), MakeObservation(2, 2, 0), MakeObservation(2, 4, 6)};
  for (StoredObservation& o : expected) o.object_id = 1;
  ASSERT_EQ(map.observations.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ExpectSameObservation(expected[i], map.observations[i]);
  }
  ASSERT_EQ(map.objects.size(), 1u);
  EXPECT_EQ(map.objects[0].id, 1);
  EXPECT_EQ(map.objects[0].observations, 6);
  EXPECT_EQ(map.keyframes.size(), 4u);
}

TEST_F(KeyframeStoreTest, PoseUpdatesAreExact) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  CommitSmallMap(store.get());
  StoreChange change;
  const Eigen::Isometry3d T_W_C1 = MakeKeyframe(17).T_W_C, T_W_C3 = MakeKeyframe(29).T_W_C;
  change.poses = {{1, T_W_C1}, {3, T_W_C3}};
  change.map_version = 7;
  std::string why;
  ASSERT_TRUE(store->Commit(change, &why)) << why;
  const StoredMap map = Load(*store);
  EXPECT_EQ(map.keyframes[0].T_W_C.matrix(), T_W_C1.matrix());
  EXPECT_EQ(map.keyframes[1].T_W_C.matrix(), MakeKeyframe(2).T_W_C.matrix());
  EXPECT_EQ(map.keyframes[2].T_W_C.matrix(), T_W_C3.matrix());
  EXPECT_EQ(map.map_version, 7u);
  EXPECT_EQ(map.next_object_id, 3);  // absent in the change: unchanged
}

TEST_F(KeyframeStoreTest, FailedCommitsLeaveTheDatabaseUnchanged) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  CommitSmallMap(store.get());
  const StoredMap before = Load(*store);
  // Each change does real work before the statement that fails.
  auto change_with = [](auto edit) {
    StoreChange change;
    change.keyframe = MakeKeyframe(9);
    change.observations = {MakeObservation(1, 9, 3)};
    change.merged = {{1, 2}};
    change.removed_objects = {1};
    change.poses = {{2, MakeKeyframe(5).T_W_C}};
    change.map_version = 99;
    change.next_object_id = 50;
    edit(&change);
    return change;
  };
  const std::vector<std::pair<StoreChange, std::string>> failing = {
      {change_with([](StoreChange* c) { c->poses[404] = Eigen::Isometry3d::Identity(); }),
       "unknown keyframe id 404"},
      {change_with([](StoreChange* c) { c->keyframe = MakeKeyframe(2); }),
       "keyframe id 2 already exists"},
      {change_with([](StoreChange* c) { c->observations.push_back(MakeObservation(3, 77, 1)); }),
       "unknown keyframe id 77"},
      {change_with([](StoreChange* c) { c->keyframe->depth_mm.pop_back(); }), "depth_mm"},
      {change_with([](StoreChange* c) { c->keyframe->object_mask.clear(); }), "object_mask"},
      {change_with([](StoreChange* c) { c->keyframe->color.width = 10; }), "color"},
      {change_with(
           [](StoreChange* c) { c->observations[0].observation.segment_C.colors.pop_back(); }),
       "colors"},
      {change_with([](StoreChange* c) { c->sessions.push_back({0, "zero", "request", 1.0, {}}); }),
       "session id 0 is not positive"},
      {change_with([](StoreChange* c) {
         c->sessions.push_back({5, "never", "request", std::nan(""), {}});
       }),
       "session 5: its times must be finite"},
      {change_with([](StoreChange* c) { c->keyframe->session_id = -3; }),
       "session id -3 is not positive"},
      // The session is written first; the keyframe that fails takes it back out.
      {change_with([](StoreChange* c) {
         c->sessions.push_back({7, "rolled back", "request", 1.0, {}});
         c->keyframe = MakeKeyframe(2);
       }),
       "keyframe id 2 already exists"},
  };
  for (const auto& [change, expected_reason] : failing) {
    std::string why;
    EXPECT_FALSE(store->Commit(change, &why));
    EXPECT_NE(why.find(expected_reason), std::string::npos) << why;
  }
  ExpectSameMap(before, Load(*store));
  std::vector<SessionSummary> sessions;
  std::string listed;
  ASSERT_TRUE(store->ListSessions(&sessions, &listed)) << listed;
  ASSERT_EQ(sessions.size(), 1u);  // session 1, made for the keyframes that named it
  EXPECT_EQ(sessions[0].session.id, 1);
  // The store still takes changes afterwards.
  std::string why;
  EXPECT_TRUE(store->Commit(change_with([](StoreChange*) {}), &why)) << why;
  EXPECT_EQ(store->NumKeyframes(), 4u);
}

// A session is written with its first keyframe and ended by replacing its row; keyframes and
// the session listing say which keyframes each holds.
TEST_F(KeyframeStoreTest, SessionsAreStoredWithTheirKeyframesAndEndedByReplacingTheirRow) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  std::string why;
  const StoredSession first{1, "morning", "request", 1000.0, std::nullopt};
  StoreChange change;
  change.sessions = {first};
  change.keyframe = MakeKeyframe(1);
  ASSERT_TRUE(store->Commit(change, &why)) << why;
  change = StoreChange{};
  change.keyframe = MakeKeyframe(2);
  ASSERT_TRUE(store->Commit(change, &why)) << why;
  StoredSession ended = first;
  ended.ended_s = 1500.0;
  const StoredSession second{2, "evening", "estimate", 2000.0, std::nullopt};
  change = StoreChange{};
  change.sessions = {ended, second};
  change.keyframe = MakeKeyframe(3);
  change.keyframe->session_id = 2;
  ASSERT_TRUE(store->Commit(change, &why)) << why;

  std::vector<SessionSummary> sessions;
  ASSERT_TRUE(store->ListSessions(&sessions, &why)) << why;
  ASSERT_EQ(sessions.size(), 2u);
  EXPECT_EQ(sessions[0].session.name, "morning");
  EXPECT_EQ(sessions[0].session.started_s, 1000.0);
  EXPECT_EQ(sessions[0].session.ended_s, 1500.0);
  EXPECT_EQ(sessions[0].keyframes, 2u);
  EXPECT_EQ(sessions[0].first_keyframe, 1);
  EXPECT_EQ(sessions[0].last_keyframe, 2);
  EXPECT_EQ(sessions[1].session.name, "evening");
  EXPECT_EQ(sessions[1].session.pose_source, "estimate");
  EXPECT_FALSE(sessions[1].session.ended_s.has_value());
  EXPECT_EQ(sessions[1].keyframes, 1u);
  EXPECT_EQ(sessions[1].first_keyframe, 3);
  StoredKeyframe loaded;
  ASSERT_TRUE(store->LoadKeyframe(3, &loaded, &why)) << why;
  EXPECT_EQ(loaded.session_id, 2);
}

TEST_F(KeyframeStoreTest, BytesOfCountsTheStoredBlobs) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  CommitSmallMap(store.get());
  const KeyframeStore::KeyframeBytes one = store->BytesOf(1);
  EXPECT_GT(one.depth, 0u);
  EXPECT_GT(one.mask, 0u);
  EXPECT_GT(one.color, 0u);
  // Keyframe 1: 7 + 3 + 5 points (xyz float32), 7 + 5 colours (rgb), 3 x 2 class scores.
  EXPECT_EQ(one.observations, 15u * 12 + 12 * 3 + 3 * 2 * 8);
  // Plus the pose (16 doubles) and two detections (24 bytes each).
  EXPECT_EQ(one.total, one.depth + one.mask + one.color + one.observations + 128 + 48);
  EXPECT_EQ(store->BytesOf(3).color, 0u);
  EXPECT_EQ(store->BytesOf(3).observations, 0u);
  EXPECT_EQ(store->BytesOf(12345).total, 0u);
  EXPECT_GE(store->FileBytes(), one.total + store->BytesOf(2).total + store->BytesOf(3).total);
}

// An observation made from its keyframe's stored depth is kept as its pixels (a few bytes a
// row) and its colours, and loads with the points it had, bit for bit, also after a reopen and
// beside observations kept as points.
TEST_F(KeyframeStoreTest, ObservationsMadeFromTheStoredDepthAreKeptAsTheirPixels) {
  const StoredKeyframe keyframe = MakeKeyframe(1, /*with_color=*/true, 64, 48);
  const StoredKeyframe colorless = MakeKeyframe(2, /*with_color=*/false, 64, 48);
  const std::vector<StoredObservation> expected = {
      testing::MakeObservationOfPixels(1, keyframe, 8, 40, 4, 30),
      testing::MakeObservationOfPixels(1, colorless, 0, 64, 10, 12, 0.02f),
      MakeObservation(2, 1, 5)};
  ASSERT_GT(expected[0].observation.segment_C.size(), 500u);
  ASSERT_EQ(expected[0].observation.segment_C.colors.size(),
            expected[0].observation.segment_C.size());
  ASSERT_TRUE(expected[1].observation.segment_C.colors.empty());
  ASSERT_FALSE(expected[1].observation.segment_C.empty());
  {
    auto store = OpenStore(Path());
    ASSERT_NE(store, nullptr);
    std::string why;
    StoreChange first;
    first.keyframe = keyframe;
    first.observations = {expected[0], expected[2]};
    ASSERT_TRUE(store->Commit(first, &why)) << why;
    StoreChange second;
    second.keyframe = colorless;
    second.observations = {expected[1]};
    ASSERT_TRUE(store->Commit(second, &why)) << why;
    // The pixels instead of 12 bytes a point: the colours (3 a point) and about 2 runs a row.
    const std::size_t points = expected[0].observation.segment_C.size();
    EXPECT_LT(store->BytesOf(1).observations, 3 * points + 200 + 5 * 12 + 5 * 3 + 2 * 2 * 8);
    EXPECT_LT(store->BytesOf(2).observations, 100u);
    const StoredMap map = Load(*store);
    ASSERT_EQ(map.observations.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) ExpectSameObservation(expected[i], map.observations[i]);
  }
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  const StoredMap reopened = Load(*store);
  ASSERT_EQ(reopened.observations.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) ExpectSameObservation(expected[i], reopened.observations[i]);
}

TEST_F(KeyframeStoreTest, ReadersRunAlongsideCommits) {
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  constexpr int kKeyframes = 40;
  std::atomic<bool> done{false};
  std::atomic<int> failures{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 3; ++r) {
    readers.emplace_back([&] {
      std::size_t seen = 0;
      while (!done) {
        const std::size_t n = store->NumKeyframes();
        StoredKeyframe k;
        std::string why;
        if (n < seen || (n > 0 && !store->LoadKeyframe(static_cast<KeyframeId>(n), &k, &why))) {
          ++failures;
        }
        seen = n;
      }
    });
  }
  for (int i = 1; i <= kKeyframes; ++i) {
    StoreChange change;
    change.keyframe = MakeKeyframe(i);
    change.observations = {MakeObservation(i, i, 20)};
    std::string why;
    ASSERT_TRUE(store->Commit(change, &why)) << why;
  }
  done = true;
  for (std::thread& reader : readers) reader.join();
  EXPECT_EQ(failures, 0);
  const StoredMap map = Load(*store);
  ASSERT_EQ(map.keyframes.size(), static_cast<std::size_t>(kKeyframes));
  for (int i = 0; i < kKeyframes; ++i)
    ExpectSameKeyframe(MakeKeyframe(i + 1), map.keyframes[i], 3.0);
}

}  // namespace
}  // namespace objmap
