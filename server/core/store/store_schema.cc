#include "store/store_schema.h"

#include <vector>

namespace objmap {
namespace store_internal {
namespace {

// The schema of version 1; later versions are the migrations below, so a new file and a
// migrated one have the same schema. Comments stay in sqlite_master, so `sqlite3 map.db .schema`
// documents the blob layouts (all little-endian).
const char kSchemaV1Sql[] = R"sql(
CREATE TABLE meta(
  key TEXT PRIMARY KEY NOT NULL,  -- map_version, next_object_id
  value INTEGER NOT NULL
);
CREATE TABLE keyframes(
  id INTEGER PRIMARY KEY,
  stamp_s REAL NOT NULL,
  name TEXT NOT NULL,
  T_W_C BLOB NOT NULL,       -- 16 float64, column-major 4x4, camera to world
  width INTEGER NOT NULL,    -- intrinsics, pixels
  height INTEGER NOT NULL,
  fx REAL NOT NULL,
  fy REAL NOT NULL,
  cx REAL NOT NULL,
  cy REAL NOT NULL,
  depth_png BLOB NOT NULL,   -- 16-bit PNG, millimetres (lossless)
  mask_png BLOB NOT NULL,    -- 8-bit PNG, 1 where a pixel belongs to an object segment
  color_jpeg BLOB,           -- NULL when the keyframe came without colour
  detections BLOB NOT NULL   -- per detection: box (4 float32), class (int32), score (float32)
);
CREATE TABLE observations(
  id INTEGER PRIMARY KEY,    -- insertion order
  object_id INTEGER NOT NULL,
  keyframe_id INTEGER NOT NULL REFERENCES keyframes(id),
  box_x_min REAL NOT NULL,   -- detection box, colour pixels
  box_y_min REAL NOT NULL,
  box_x_max REAL NOT NULL,
  box_y_max REAL NOT NULL,
  class_scores BLOB NOT NULL,  -- per entry: class (int32) score (float32)
  points BLOB NOT NULL,      -- segment in the camera frame: x y z (float32) per point
  colors BLOB NOT NULL       -- r g b (uint8) per point, or empty
);
CREATE INDEX observations_by_object ON observations(object_id, keyframe_id);
CREATE INDEX observations_by_keyframe ON observations(keyframe_id);
CREATE TABLE objects(        -- derived summaries, for inspection
  id INTEGER PRIMARY KEY,
  class_id INTEGER NOT NULL,
  confidence REAL NOT NULL,
  centroid_x REAL NOT NULL,  -- world frame, metres
  centroid_y REAL NOT NULL,
  centroid_z REAL NOT NULL,
  observations INTEGER NOT NULL
);
INSERT INTO meta(key, value) VALUES ('map_version', 0), ('next_object_id', 1);
)sql";

// Version 2: a restart loads the OctoMap instead of re-integrating every keyframe.
const char kSchemaV2Sql[] = R"sql(
CREATE TABLE occupancy_checkpoint(  -- at most one row: the OctoMap as of a map version
  id INTEGER PRIMARY KEY CHECK (id = 1),
  map_version INTEGER NOT NULL,
  keyframe_poses BLOB NOT NULL,  -- per keyframe in it: id (int64), T_W_C (16 float64, col-major)
  state BLOB NOT NULL            -- the OcTree with its log-odds (OccupancyMap::WriteState)
);
)sql";

// Version 3: sessions. A database from before them holds one run: its keyframes (if any) become
// session 1, whose name, pose source and times are not known.
const char kSchemaV3Sql[] = R"sql(
CREATE TABLE sessions(  -- runs of keyframes: a server start, a client's StartSession, objmap map
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  pose_source TEXT NOT NULL,  -- request | estimate; empty: not known (from before sessions)
  started_s REAL,             -- wall clock, seconds since the Unix epoch; NULL: not known
  ended_s REAL                -- NULL: open, or its process ended without closing it
);
ALTER TABLE keyframes ADD COLUMN session_id INTEGER NOT NULL DEFAULT 1;  -- sessions(id)
CREATE INDEX keyframes_by_session ON keyframes(session_id, id);
INSERT INTO sessions(id, name, pose_source, started_s, ended_s)
  SELECT 1, 'session 1', '', NULL, NULL WHERE EXISTS (SELECT 1 FROM keyframes);
)sql";

// Version 4: revisits, the keyframes of a later session that repeated a stored view with
// nothing changed (RevisitThinningConfig): kept as a sighting of that view, without images.
const char kSchemaV4Sql[] = R"sql(
CREATE TABLE revisits(
  id INTEGER PRIMARY KEY,    -- in the order they came
  session_id INTEGER NOT NULL,  -- sessions(id)
  stamp_s REAL NOT NULL,     -- the camera's stamp
  name TEXT NOT NULL,
  keyframe_id INTEGER NOT NULL REFERENCES keyframes(id),  -- the stored view it repeated
  T_K_C BLOB NOT NULL,       -- 16 float64, column-major: the camera in that keyframe's frame
  explained REAL NOT NULL    -- share of its depth pixels the stored views explained
);
CREATE INDEX revisits_by_keyframe ON revisits(keyframe_id, id);
CREATE INDEX revisits_by_session ON revisits(session_id, id);
)sql";

// Version 5: an observation made from its keyframe's stored depth keeps the pixels it was made
// from instead of its points (rebuilt when loaded): runs instead of 12 bytes a point.
const char kSchemaV5Sql[] = R"sql(
ALTER TABLE observations ADD COLUMN pixels BLOB NOT NULL DEFAULT x'';
  -- empty: `points` holds the segment; else the voxel size (float32), the number of points,
  -- then per run of depth pixels the gap from the previous run's end and its length (LEB128)
)sql";

// kMigrations[v - 1] takes schema version v to v + 1.
const char* const kMigrations[] = {kSchemaV2Sql, kSchemaV3Sql, kSchemaV4Sql, kSchemaV5Sql};

const char* const kTables[] = {
    "meta", "keyframes", "observations", "objects", "occupancy_checkpoint", "sessions", "revisits"};

// Runs the migrations from schema version `from` to this build's.
bool ApplyMigrations(Connection* db, std::int64_t from, std::string* why) {
  static_assert(sizeof(kMigrations) / sizeof(kMigrations[0]) == KeyframeStore::kSchemaVersion - 1,
                "one migration per schema version");
  for (std::int64_t v = from; v < KeyframeStore::kSchemaVersion; ++v) {
    if (!db->Exec(kMigrations[v - 1], why)) return false;
  }
  return true;
}

// The whole schema of this build.
bool CreateSchema(Connection* db, std::string* why) {
  return db->Exec(kSchemaV1Sql, why) && ApplyMigrations(db, 1, why);
}

// "name type notnull pk" of each column of `table`, in order; empty when the table is missing.
bool DescribeTable(Connection* db, const std::string& table, std::string* description,
                   std::string* why) {
  auto columns = db->Prepare("SELECT name, type, \"notnull\", pk FROM pragma_table_info(?)",
                             "describe table " + table, why);
  if (!columns) return false;
  columns->Bind(1, table);
  description->clear();
  for (bool row = true;;) {
    if (!columns->Step(&row, why)) return false;
    if (!row) return true;
    *description += columns->Text(0) + " " + columns->Text(1) + " " +
                    std::to_string(columns->Int64(2)) + " " + std::to_string(columns->Int64(3)) +
                    ", ";
  }
}

// Compares the tables of `db` with those the schema creates (in a scratch in-memory database,
// so the expected columns are never written down twice).
bool CheckTables(Connection* db, std::string* why) {
  std::string ignored;
  auto expected = Connection::Open(":memory:", SQLITE_OPEN_READWRITE, 0, &ignored);
  if (!expected || !CreateSchema(expected.get(), why)) return false;
  for (const char* table : kTables) {
    std::string want, have;
    if (!DescribeTable(expected.get(), table, &want, why) ||
        !DescribeTable(db, table, &have, why)) {
      return false;
    }
    if (have.empty()) {
      *why = std::string("not an objmap database: table ") + table + " is missing";
      return false;
    }
    if (have != want) {
      *why = std::string("not an objmap database: table ") + table + " has columns (" + have +
             ") instead of (" + want + ")";
      return false;
    }
  }
  return true;
}

bool QuickCheck(Connection* db, std::string* why) {
  auto check = db->Prepare("PRAGMA quick_check", "integrity check", why);
  bool row = false;
  if (!check || !check->Step(&row, why)) return false;
  if (row && check->Text(0) == "ok") return true;
  *why = "corrupt database (integrity check: " + (row ? check->Text(0) : "no answer") + ")";
  return false;
}

// Creates the schema when the file is still empty. The emptiness is checked again inside the
// write transaction: another process may have created it meanwhile.
bool CreateIfEmpty(Connection* db, std::string* why) {
  std::int64_t version = 0, tables = 0;
  if (!db->Exec("BEGIN IMMEDIATE", why)) return false;
  const bool ok =
      db->QueryInt("PRAGMA user_version", &version, why) &&
      db->QueryInt("SELECT count(*) FROM sqlite_master", &tables, why) &&
      (version != 0 || tables != 0 ||
       (CreateSchema(db, why) &&
        db->Exec("PRAGMA application_id = " + std::to_string(kApplicationId), why) &&
        db->Exec("PRAGMA user_version = " + std::to_string(KeyframeStore::kSchemaVersion), why))) &&
      db->Exec("COMMIT", why);
  if (!ok) db->RollbackIfOpen();
  return ok;
}

// Takes an objmap database of an older schema version to this build's, in one transaction.
bool Migrate(Connection* db, std::int64_t from_version, std::string* why) {
  if (!db->Exec("BEGIN IMMEDIATE", why)) return false;
  const bool ok =
      ApplyMigrations(db, from_version, why) &&
      db->Exec("PRAGMA user_version = " + std::to_string(KeyframeStore::kSchemaVersion), why) &&
      db->Exec("COMMIT", why);
  if (!ok) {
    db->RollbackIfOpen();
    *why = "migration from schema version " + std::to_string(from_version) + " failed: " + *why;
  }
  return ok;
}

// Recognises what is in the file, creating the schema when it is empty.
bool CheckOrCreate(Connection* db, std::string* why) {
  std::int64_t version = 0, application = 0, tables = 0;
  if (!db->QueryInt("PRAGMA user_version", &version, why) ||
      !db->QueryInt("PRAGMA application_id", &application, why) ||
      !db->QueryInt("SELECT count(*) FROM sqlite_master", &tables, why)) {
    *why = "not a readable SQLite database (" + *why + ")";
    return false;
  }
  if (version == 0 && tables == 0) {
    if (!CreateIfEmpty(db, why)) return false;
    return CheckOrCreate(db, why);
  }
  if (version == 0 || application != kApplicationId) {
    *why = "not an objmap database (application_id " + std::to_string(application) +
           ", user_version " + std::to_string(version) + ")";
    return false;
  }
  if (version > KeyframeStore::kSchemaVersion) {
    *why = "schema version " + std::to_string(version) + " is newer than this build's version " +
           std::to_string(KeyframeStore::kSchemaVersion);
    return false;
  }
  if (!QuickCheck(db, why)) return false;
  if (version < KeyframeStore::kSchemaVersion && !Migrate(db, version, why)) return false;
  return CheckTables(db, why);
}

// WAL lets readers run alongside the writer; in WAL mode synchronous=NORMAL already survives
// a killed process (only power loss can take the last commits).
bool Configure(Connection* db, const KeyframeStoreConfig& config, std::string* why) {
  auto mode = db->Prepare("PRAGMA journal_mode = WAL", "set WAL journal mode", why);
  bool row = false;
  if (!mode || !mode->Step(&row, why)) return false;
  if (!row || mode->Text(0) != "wal") {
    *why = "cannot switch to WAL journal mode (journal mode " + mode->Text(0) + ")";
    return false;
  }
  // An OctoMap checkpoint is one large transaction; the WAL grows to hold it and is cut back to
  // this size once checkpointed into the database, instead of keeping its largest size.
  return db->Exec("PRAGMA synchronous = " + config.synchronous, why) &&
         db->Exec("PRAGMA foreign_keys = ON", why) &&
         db->Exec("PRAGMA journal_size_limit = 16777216", why);
}

}  // namespace

std::unique_ptr<Connection> OpenWriter(const std::string& path, const KeyframeStoreConfig& config,
                                       std::string* why) {
  auto db = Connection::Open(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                             config.busy_timeout_ms, why);
  if (!db) return nullptr;
  if (!CheckOrCreate(db.get(), why) || !Configure(db.get(), config, why)) {
    *why = path + ": " + *why;
    return nullptr;
  }
  return db;
}

std::unique_ptr<Connection> OpenReader(const std::string& path, int busy_timeout_ms,
                                       std::string* why) {
  auto db =
      Connection::Open(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX, busy_timeout_ms, why);
  if (!db || !db->Exec("PRAGMA query_only = ON", why)) return nullptr;
  return db;
}

}  // namespace store_internal
}  // namespace objmap
