// What Open does with files that are not (intact, known) objmap databases, and durability of
// acknowledged commits when the writing process is killed.

#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <random>

#include "store/keyframe_codec.h"
#include "store/keyframe_store.h"
#include "store_test_data.h"

namespace objmap {
namespace {

using testing::ExpectSameKeyframe;
using testing::MakeKeyframe;
using testing::MakeObservation;

// Turns a file of this version into one of version 4, whose observations were all points ...
constexpr char kWithoutPixelsSql[] = "ALTER TABLE observations DROP COLUMN pixels;";
// ... into one of version 3, which had no revisits either ...
constexpr char kWithoutRevisitsSql[] =
    "ALTER TABLE observations DROP COLUMN pixels; DROP TABLE revisits;";
// ... and into one of version 2, which had no sessions either.
constexpr char kWithoutSessionsSql[] =
    "ALTER TABLE observations DROP COLUMN pixels;"
    " DROP TABLE revisits; DROP TABLE sessions; DROP INDEX keyframes_by_session;"
    " ALTER TABLE keyframes DROP COLUMN session_id;";

class KeyframeStoreRecoveryTest : public testing::StoreTest {
 protected:
  // A closed store with `n` keyframes (closing checkpoints the WAL into the file).
  void CreateStore(const std::string& path, int n) {
    auto store = OpenStore(path);
    ASSERT_NE(store, nullptr);
    for (int i = 1; i <= n; ++i) {
      StoreChange change;
      change.keyframe = MakeKeyframe(i);
      change.observations = {MakeObservation(i, i, 50)};
      std::string why;
      ASSERT_TRUE(store->Commit(change, &why)) << why;
    }
  }

  // Runs SQL on the file directly, as another program would.
  void RunSql(const std::string& path, const std::string& sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    char* message = nullptr;
    EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message), SQLITE_OK)
        << (message != nullptr ? message : "");
    sqlite3_free(message);
    sqlite3_close(db);
  }

  // Open must fail with a reason that names the file and contains `expected`.
  void ExpectOpenFails(const std::string& path, const std::string& expected) {
    std::string why;
    EXPECT_EQ(KeyframeStore::Open(path, KeyframeStoreConfig{}, &why), nullptr);
    EXPECT_NE(why.find(path), std::string::npos) << why;
    EXPECT_NE(why.find(expected), std::string::npos) << why;
  }

  // `bytes` as an SQL blob literal's hex digits.
  static std::string Hex(const std::vector<std::uint8_t>& bytes) {
    const char digits[] = "0123456789ABCDEF";
    std::string hex;
    for (std::uint8_t byte : bytes) {
      hex += digits[byte >> 4];
      hex += digits[byte & 15];
    }
    return hex;
  }

  // Overwrites `bytes` bytes at `offset` with pseudo-random garbage.
  void WriteGarbage(const std::string& path, std::size_t offset, std::size_t bytes) {
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    ASSERT_TRUE(file.good());
    std::mt19937 random(7);
    std::string garbage(bytes, '\0');
    for (char& c : garbage) c = static_cast<char>(random());
    file.seekp(static_cast<std::streamoff>(offset));
    file.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
};

// A pose damaged on disk (NaN, or not a rotation) is reported with its keyframe, never loaded.
TEST_F(KeyframeStoreRecoveryTest, ADamagedPoseIsReportedNotLoaded) {
  const std::string path = Path();
  CreateStore(path, 3);
  // Identity, column-major little-endian doubles, with NaN as the x translation (entry 12).
  std::string hex;
  for (int i = 0; i < 16; ++i) {
    hex += i == 12 ? "000000000000F87F" : (i % 5 == 0 ? "000000000000F03F" : "0000000000000000");
  }
  RunSql(path, "UPDATE keyframes SET T_W_C = X'" + hex + "' WHERE id = 2");
  auto store = OpenStore(path);
  ASSERT_NE(store, nullptr);
  StoredMap map;
  std::string why;
  EXPECT_FALSE(store->LoadAll(&map, &why));
  EXPECT_NE(why.find("keyframe 2: corrupt pose"), std::string::npos) << why;
}

// A version 4 file keeps its observations' points; new observations made from their keyframe's
// depth are kept as pixels beside them.
TEST_F(KeyframeStoreRecoveryTest, MigratesASchemaVersion4FileAndKeepsItsObservationsPoints) {
  CreateStore(Path(), 2);
  RunSql(Path(), std::string(kWithoutPixelsSql) + " PRAGMA user_version = 4;");
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  StoreChange change;
  change.keyframe = MakeKeyframe(3);
  change.observations = {testing::MakeObservationOfPixels(3, *change.keyframe, 2, 20, 2, 9)};
  std::string why;
  ASSERT_TRUE(store->Commit(change, &why)) << why;
  StoredMap map;
  ASSERT_TRUE(store->LoadAll(&map, &why)) << why;
  ASSERT_EQ(map.observations.size(), 3u);
  testing::ExpectSameObservation(MakeObservation(1, 1, 50), map.observations[0]);
  testing::ExpectSameObservation(MakeObservation(2, 2, 50), map.observations[1]);
  testing::ExpectSameObservation(change.observations[0], map.observations[2]);
}

// Observations kept as pixels whose blob is damaged, or whose pixels no longer make the number
// of points stored with them, are reported with their keyframe, never loaded.
TEST_F(KeyframeStoreRecoveryTest, ObservationPixelsThatDoNotMakeItsPointsAreReported) {
  const StoredKeyframe keyframe = MakeKeyframe(1);
  const StoredObservation observation = testing::MakeObservationOfPixels(4, keyframe, 4, 30, 4, 20);
  {
    auto store = OpenStore(Path());
    ASSERT_NE(store, nullptr);
    StoreChange change;
    change.keyframe = keyframe;
    change.observations = {observation};
    std::string why;
    ASSERT_TRUE(store->Commit(change, &why)) << why;
  }
  // The same pixels, one point more than they make.
  const ObjectObservation& o = observation.observation;
  const auto blob = store_internal::PackSegmentPixels(o.segment_pixels, o.segment_voxel_size_m,
                                                      o.segment_C.size() + 1);
  RunSql(Path(), "UPDATE observations SET pixels = X'" + Hex(blob) + "' WHERE object_id = 4");
  {
    auto store = OpenStore(Path());
    ASSERT_NE(store, nullptr);
    StoredMap map;
    std::string why;
    EXPECT_FALSE(store->LoadAll(&map, &why));
    EXPECT_NE(why.find("observation in keyframe 1: its pixels make " +
                       std::to_string(o.segment_C.size()) + " points of the keyframe's depth, " +
                       std::to_string(o.segment_C.size() + 1) + " were stored"),
              std::string::npos)
        << why;
  }
  // Colours that are not the PNG of as many colours as points.
  const auto pixels = store_internal::PackSegmentPixels(o.segment_pixels, o.segment_voxel_size_m,
                                                        o.segment_C.size());
  RunSql(Path(), "UPDATE observations SET pixels = X'" + Hex(pixels) +
                     "', colors = X'0102030405' WHERE object_id = 4");
  {
    auto store = OpenStore(Path());
    ASSERT_NE(store, nullptr);
    StoredMap map;
    std::string why;
    EXPECT_FALSE(store->LoadAll(&map, &why));
    EXPECT_NE(why.find("observation in keyframe 1: colours: image blob is not a PNG image"),
              std::string::npos)
        << why;
  }
  RunSql(Path(), "UPDATE observations SET pixels = X'0000A03B05' WHERE object_id = 4");
  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  StoredMap map;
  std::string why;
  EXPECT_FALSE(store->LoadAll(&map, &why));
  EXPECT_NE(why.find("observation of object 4 in keyframe 1: corrupt blob"), std::string::npos)
      << why;
}

TEST_F(KeyframeStoreRecoveryTest, RejectsATextFile) {
  std::ofstream(Path("notes.db")) << "These are not the keyframes you are looking for.\n";
  ExpectOpenFails(Path("notes.db"), "not a readable SQLite database");
}

TEST_F(KeyframeStoreRecoveryTest, RejectsADatabaseWithOverwrittenHeader) {
  CreateStore(Path(), 3);
  WriteGarbage(Path(), 0, 4096);
  ExpectOpenFails(Path(), "not a readable SQLite database");
}

TEST_F(KeyframeStoreRecoveryTest, RejectsADatabaseWithCorruptPages) {
  CreateStore(Path(), 20);
  const auto size = std::filesystem::file_size(Path());
  ASSERT_GT(size, 16 * 4096u);
  // Keep the header and schema page, destroy the table pages.
  WriteGarbage(Path(), 4096, size - 2 * 4096);
  ExpectOpenFails(Path(), "corrupt database");
}

TEST_F(KeyframeStoreRecoveryTest, RejectsANewerSchemaVersion) {
  CreateStore(Path(), 1);
  RunSql(Path(), "PRAGMA user_version = " + std::to_string(KeyframeStore::kSchemaVersion + 1));
  ExpectOpenFails(Path(), "is newer than this build's version");
}

TEST_F(KeyframeStoreRecoveryTest, MigratesASchemaVersion1FileAndKeepsItsKeyframes) {
  CreateStore(Path(), 3);
  // What a version 1 file looks like: no checkpoint table, no sessions.
  RunSql(Path(), std::string(kWithoutSessionsSql) +
                     " DROP TABLE occupancy_checkpoint; PRAGMA user_version = 1;");
  std::string why;
  auto store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  EXPECT_EQ(store->NumKeyframes(), 3u);
  std::optional<StoredCheckpoint> checkpoint;
  ASSERT_TRUE(store->LoadCheckpoint(&checkpoint, &why)) << why;
  EXPECT_FALSE(checkpoint.has_value());
  StoredCheckpoint saved;
  saved.map_version = 3;
  saved.keyframe_poses[1] = MakeKeyframe(1).T_W_C;
  saved.occupancy_state = "state";
  EXPECT_TRUE(store->SaveCheckpoint(saved, &why)) << why;
  store.reset();
  // Reopened, it is a file of this version like a new one.
  store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  ASSERT_TRUE(store->LoadCheckpoint(&checkpoint, &why)) << why;
  ASSERT_TRUE(checkpoint.has_value());
  EXPECT_EQ(checkpoint->map_version, 3u);
}

// A version 2 file (before sessions) opens with its keyframes in session 1, whose name, pose
// source and times are not known; new keyframes go on in sessions of their own.
TEST_F(KeyframeStoreRecoveryTest, MigratesASchemaVersion2FileIntoOneSession) {
  CreateStore(Path(), 3);
  RunSql(Path(), std::string(kWithoutSessionsSql) + " PRAGMA user_version = 2;");
  std::string why;
  auto store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  std::vector<SessionSummary> sessions;
  ASSERT_TRUE(store->ListSessions(&sessions, &why)) << why;
  ASSERT_EQ(sessions.size(), 1u);
  EXPECT_EQ(sessions[0].session.id, 1);
  EXPECT_EQ(sessions[0].keyframes, 3u);
  EXPECT_EQ(sessions[0].first_keyframe, 1);
  EXPECT_EQ(sessions[0].last_keyframe, 3);
  EXPECT_EQ(sessions[0].first_stamp_s, MakeKeyframe(1).stamp_s);
  EXPECT_EQ(sessions[0].last_stamp_s, MakeKeyframe(3).stamp_s);
  EXPECT_FALSE(sessions[0].session.started_s.has_value());
  EXPECT_TRUE(sessions[0].session.pose_source.empty());
  StoredMap map;
  ASSERT_TRUE(store->LoadAll(&map, &why)) << why;
  ASSERT_EQ(map.keyframes.size(), 3u);
  for (const StoredKeyframe& keyframe : map.keyframes) EXPECT_EQ(keyframe.session_id, 1);

  StoreChange next;
  next.sessions.push_back({2, "second visit", "estimate", 1.8e9, std::nullopt});
  next.keyframe = MakeKeyframe(4);
  next.keyframe->session_id = 2;
  ASSERT_TRUE(store->Commit(next, &why)) << why;
  store.reset();
  store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  ASSERT_TRUE(store->ListSessions(&sessions, &why)) << why;
  ASSERT_EQ(sessions.size(), 2u);
  EXPECT_EQ(sessions[1].session.name, "second visit");
  EXPECT_EQ(sessions[1].session.pose_source, "estimate");
  EXPECT_EQ(sessions[1].session.started_s, 1.8e9);
  EXPECT_FALSE(sessions[1].session.ended_s.has_value());
  EXPECT_EQ(sessions[1].keyframes, 1u);
  EXPECT_EQ(sessions[1].first_keyframe, 4);
  std::vector<KeyframeSummary> listed;
  ASSERT_TRUE(store->ListKeyframes(0, 0, &listed, &why)) << why;
  ASSERT_EQ(listed.size(), 4u);
  EXPECT_EQ(listed[2].session_id, 1);
  EXPECT_EQ(listed[3].session_id, 2);
}

// An empty version 2 file has no session to migrate.
TEST_F(KeyframeStoreRecoveryTest, MigratesAnEmptySchemaVersion2FileWithoutSessions) {
  CreateStore(Path(), 0);
  RunSql(Path(), std::string(kWithoutSessionsSql) + " PRAGMA user_version = 2;");
  std::string why;
  auto store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  std::vector<SessionSummary> sessions;
  ASSERT_TRUE(store->ListSessions(&sessions, &why)) << why;
  EXPECT_TRUE(sessions.empty());
}

// A version 3 file (before revisits) keeps its sessions and takes revisits, which a reopen
// lists; a revisit of a keyframe the file does not hold is refused with nothing committed.
TEST_F(KeyframeStoreRecoveryTest, MigratesASchemaVersion3FileAndStoresRevisits) {
  CreateStore(Path(), 2);
  RunSql(Path(), std::string(kWithoutRevisitsSql) + " PRAGMA user_version = 3;");
  std::string why;
  auto store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  StoreChange change;
  change.sessions.push_back({2, "patrol", "estimate", 1.8e9, std::nullopt});
  StoredRevisit revisit;
  revisit.session_id = 2;
  revisit.stamp_s = 42.5;
  revisit.name = "frame 9";
  revisit.keyframe_id = 2;
  revisit.T_K_C.translation() = Eigen::Vector3d(0.01, -0.02, 0.03);
  revisit.explained_fraction = 0.97f;
  change.revisit = revisit;
  ASSERT_TRUE(store->Commit(change, &why)) << why;
  StoreChange unknown;
  unknown.revisit = revisit;
  unknown.revisit->keyframe_id = 99;
  EXPECT_FALSE(store->Commit(unknown, &why));
  EXPECT_NE(why.find("unknown keyframe id 99"), std::string::npos) << why;
  StoreChange not_finite;
  not_finite.revisit = revisit;
  not_finite.revisit->stamp_s = std::nan("");
  EXPECT_FALSE(store->Commit(not_finite, &why));
  store.reset();

  store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  std::vector<StoredRevisit> revisits;
  ASSERT_TRUE(store->ListRevisits(0, &revisits, &why)) << why;
  ASSERT_EQ(revisits.size(), 1u);
  EXPECT_EQ(revisits[0].id, 1);
  EXPECT_EQ(revisits[0].session_id, 2);
  EXPECT_EQ(revisits[0].stamp_s, 42.5);
  EXPECT_EQ(revisits[0].name, "frame 9");
  EXPECT_EQ(revisits[0].keyframe_id, 2);
  EXPECT_TRUE(revisits[0].T_K_C.isApprox(revisit.T_K_C));
  EXPECT_FLOAT_EQ(revisits[0].explained_fraction, 0.97f);
  ASSERT_TRUE(store->ListRevisits(2, &revisits, &why)) << why;
  EXPECT_TRUE(revisits.empty());
  std::vector<SessionSummary> sessions;
  ASSERT_TRUE(store->ListSessions(&sessions, &why)) << why;
  ASSERT_EQ(sessions.size(), 2u);
  EXPECT_EQ(sessions[0].keyframes, 2u);
  EXPECT_EQ(sessions[0].revisits, 0u);
  EXPECT_EQ(sessions[1].keyframes, 0u);
  EXPECT_EQ(sessions[1].revisits, 1u);
}

TEST_F(KeyframeStoreRecoveryTest, CheckpointRoundTripsAndACorruptOneIsReported) {
  CreateStore(Path(), 2);
  std::string why;
  auto store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  StoredCheckpoint saved;
  saved.map_version = 7;
  saved.keyframe_poses[1] = MakeKeyframe(1).T_W_C;
  saved.keyframe_poses[2] = MakeKeyframe(2).T_W_C;
  saved.occupancy_state = std::string("objmap\0occupancy", 16);
  ASSERT_TRUE(store->SaveCheckpoint(saved, &why)) << why;
  saved.map_version = 8;  // a newer checkpoint replaces the older
  ASSERT_TRUE(store->SaveCheckpoint(saved, &why)) << why;
  std::optional<StoredCheckpoint> loaded;
  ASSERT_TRUE(store->LoadCheckpoint(&loaded, &why)) << why;
  ASSERT_TRUE(loaded.has_value());
  EXPECT_EQ(loaded->map_version, 8u);
  EXPECT_EQ(loaded->occupancy_state, saved.occupancy_state);
  ASSERT_EQ(loaded->keyframe_poses.size(), 2u);
  EXPECT_TRUE(loaded->keyframe_poses[2].matrix() == saved.keyframe_poses[2].matrix());
  store.reset();
  RunSql(Path(), "UPDATE occupancy_checkpoint SET keyframe_poses = x'0102030405';");
  store = KeyframeStore::Open(Path(), KeyframeStoreConfig{}, &why);
  ASSERT_NE(store, nullptr) << why;
  EXPECT_FALSE(store->LoadCheckpoint(&loaded, &why));
  EXPECT_NE(why.find("checkpoint"), std::string::npos) << why;
  EXPECT_NE(why.find(Path()), std::string::npos) << why;
}

TEST_F(KeyframeStoreRecoveryTest, RejectsDatabasesOfOtherApplications) {
  RunSql(Path("versioned.db"), "CREATE TABLE songs(title TEXT); PRAGMA user_version = 1;");
  ExpectOpenFails(Path("versioned.db"), "not an objmap database");
  RunSql(Path("plain.db"), "CREATE TABLE keyframes(id INTEGER PRIMARY KEY);");
  ExpectOpenFails(Path("plain.db"), "not an objmap database");
  // Even with objmap's application id and version, the tables must be the expected ones.
  CreateStore(Path(), 1);
  RunSql(Path(), "DROP TABLE objects;");
  ExpectOpenFails(Path(), "table objects is missing");
  CreateStore(Path("altered.db"), 1);
  RunSql(Path("altered.db"), "ALTER TABLE observations ADD COLUMN note TEXT;");
  ExpectOpenFails(Path("altered.db"), "table observations has columns");
}

TEST_F(KeyframeStoreRecoveryTest, RejectsPathsThatAreNotFilesAndBadConfigs) {
  ExpectOpenFails(dir_.string(), "cannot open");
  std::string why;
  EXPECT_EQ(KeyframeStore::Open(":memory:", KeyframeStoreConfig{}, &why), nullptr);
  KeyframeStoreConfig config;
  config.synchronous = "EVENTUALLY";
  EXPECT_EQ(KeyframeStore::Open(Path(), config, &why), nullptr);
  EXPECT_NE(why.find("synchronous"), std::string::npos) << why;
  EXPECT_FALSE(std::filesystem::exists(Path()));
}

// Child process: commits keyframes 1..kTotal, writing the number acknowledged so far to `fd`
// after each Commit returned true; then waits to be killed. Exits 2 or 3 on failure.
[[noreturn]] void CommitUntilKilled(const std::string& path, int fd, int total) {
  std::string why;
  auto store = KeyframeStore::Open(path, KeyframeStoreConfig{}, &why);
  if (!store) _exit(2);
  for (int i = 1; i <= total; ++i) {
    StoreChange change;
    change.keyframe = MakeKeyframe(i);
    change.observations = {MakeObservation(i % 5 + 1, i, 30)};
    change.map_version = i;
    if (!store->Commit(change, &why)) _exit(3);
    const std::int32_t acknowledged = i;
    if (write(fd, &acknowledged, sizeof(acknowledged)) != sizeof(acknowledged)) _exit(3);
  }
  for (;;) pause();
}

TEST_F(KeyframeStoreRecoveryTest, AcknowledgedCommitsSurviveAKilledWriter) {
  constexpr int kTotal = 3000, kKillAfter = 100;
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(fds[0]);
    CommitUntilKilled(Path(), fds[1], kTotal);
  }
  close(fds[1]);
  std::int32_t acknowledged = 0, count = 0;
  while (acknowledged < kKillAfter && read(fds[0], &count, sizeof(count)) == sizeof(count)) {
    acknowledged = count;
  }
  kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exited with " << WEXITSTATUS(status);
  // Whatever the child acknowledged before it died is still in the pipe.
  while (read(fds[0], &count, sizeof(count)) == sizeof(count)) acknowledged = count;
  close(fds[0]);
  ASSERT_GE(acknowledged, kKillAfter);
  EXPECT_LT(acknowledged, kTotal) << "the child finished before it was killed";

  auto store = OpenStore(Path());
  ASSERT_NE(store, nullptr);
  StoredMap map;
  std::string why;
  ASSERT_TRUE(store->LoadAll(&map, &why)) << why;
  // Every acknowledged commit is there; at most the one in flight may have landed too.
  ASSERT_GE(map.keyframes.size(), static_cast<std::size_t>(acknowledged));
  ASSERT_LE(map.keyframes.size(), static_cast<std::size_t>(acknowledged) + 1);
  EXPECT_EQ(map.map_version, map.keyframes.size());
  EXPECT_EQ(map.observations.size(), map.keyframes.size());
  for (std::size_t i = 0; i < map.keyframes.size(); ++i) {
    ExpectSameKeyframe(MakeKeyframe(static_cast<KeyframeId>(i + 1)), map.keyframes[i], 3.0);
  }
}

}  // namespace
}  // namespace objmap
