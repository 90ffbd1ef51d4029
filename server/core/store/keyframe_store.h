#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "objects/object_map.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// A session: one run of keyframes (a server start, a client's StartSession, one `objmap map`).
using SessionId = std::int64_t;

/// What the store keeps of a keyframe: everything regeneration needs (pose, intrinsics, depth,
/// which pixels belong to objects) plus the colour image and the detections, for export and audit.
struct StoredKeyframe {
  KeyframeId id = 0;
  SessionId session_id = 1;  ///< the session it was mapped in (StoredSession)
  double stamp_s = 0.0;
  std::string name;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  CameraIntrinsics intrinsics;
  /// Row-major depth in millimetres (0: no depth), intrinsics.width * intrinsics.height values.
  std::vector<std::uint16_t> depth_mm;
  /// Row-major, one byte per pixel: 1 where the pixel belongs to an object segment.
  std::vector<std::uint8_t> object_mask;
  /// Empty, or intrinsics-sized RGB. Stored as JPEG (lossy): nothing is derived from it.
  ColorImage color;
  std::vector<Detection> detections;
};

/// A keyframe without its images: what ListKeyframes returns.
struct KeyframeSummary {
  KeyframeId id = 0;
  SessionId session_id = 1;
  double stamp_s = 0.0;
  std::string name;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< the current (last stored) pose
};

/// A session: one run of keyframes into the map (a server start, a client's StartSession, one
/// `objmap map` run). Times are wall-clock seconds since the Unix epoch; keyframes carry their
/// camera's own stamps instead.
struct StoredSession {
  SessionId id = 0;
  std::string name;
  /// How its keyframes got their poses: "request" or "estimate" (PoseSourceName); empty for the
  /// one session a database made before sessions existed is opened as.
  std::string pose_source;
  std::optional<double> started_s;  ///< absent: not known (a database from before sessions)
  std::optional<double> ended_s;    ///< absent: still open, or its process ended without closing it
};

/// A keyframe of a later session that repeated a stored view with nothing changed
/// (RevisitThinningConfig): not stored as a keyframe, kept as a sighting of that view.
struct StoredRevisit {
  std::int64_t id = 0;  ///< assigned by the store, in the order revisits come (0 before)
  SessionId session_id = 1;
  double stamp_s = 0.0;  ///< the camera's stamp
  std::string name;
  KeyframeId keyframe_id = 0;  ///< the stored keyframe whose view it repeated
  /// Where the camera was, in that keyframe's camera frame: it follows the keyframe's pose.
  Eigen::Isometry3d T_K_C = Eigen::Isometry3d::Identity();
  float explained_fraction = 0.f;  ///< of its depth pixels, by the stored views
};

/// A stored session with what its keyframes say of it.
struct SessionSummary {
  StoredSession session;
  std::size_t keyframes = 0;
  std::size_t revisits = 0;  ///< its keyframes kept as revisits of stored views (StoredRevisit)
  KeyframeId first_keyframe = 0, last_keyframe = 0;  ///< 0 without keyframes
  double first_stamp_s = 0.0, last_stamp_s = 0.0;    ///< camera stamps of those two
};

/// One observation of one object (see ObjectObservation), with the object that holds it.
struct StoredObservation {
  ObjectId object_id = 0;
  ObjectObservation observation;
};

/// Derived per-object facts kept for inspection with sqlite3 (the map itself is rebuilt from
/// keyframes and observations).
struct StoredObjectSummary {
  ObjectId id = 0;
  int class_id = -1;
  float confidence = 0.f;
  Eigen::Vector3f centroid_W = Eigen::Vector3f::Zero();
  int observations = 0;
};

/// One atomic change of the store: everything a mapping step did. Applied in one transaction:
/// either all of it is on disk when Commit returns true, or none of it. Applied in this order:
/// sessions, keyframe, revisit, replace_all_objects, observations, merged, removed_objects,
/// object_summaries, poses, metadata (so observations of this change follow its merges and
/// removals).
struct StoreChange {
  /// Sessions inserted or replaced (a keyframe's session is written with its first keyframe;
  /// its end replaces the row), before the keyframe.
  std::vector<StoredSession> sessions;
  std::optional<StoredKeyframe> keyframe;          ///< a new keyframe
  std::optional<StoredRevisit> revisit;            ///< a new revisit (its id is assigned)
  /// Every stored observation and object summary is deleted first: `observations` and
  /// `object_summaries` then describe all objects (a re-association regrouped them).
  bool replace_all_objects = false;
  std::vector<StoredObservation> observations;     ///< observations to insert
  /// (kept, absorbed): every observation of `absorbed` now belongs to `kept`.
  std::vector<std::pair<ObjectId, ObjectId>> merged;
  std::vector<ObjectId> removed_objects;           ///< their summaries (and observations) go
  std::vector<StoredObjectSummary> object_summaries;  ///< insert or replace
  std::map<KeyframeId, Eigen::Isometry3d> poses;   ///< new poses of existing keyframes
  /// Map metadata written with the change (absent: unchanged).
  std::optional<std::uint64_t> map_version;
  std::optional<ObjectId> next_object_id;
  /// Set with stored poses that are not yet regenerated, cleared with the regeneration: a
  /// restart that finds it set re-associates the objects with the stored poses.
  std::optional<bool> pose_update_pending;
};

/// The OctoMap as of a map version, with the poses its keyframes were integrated with, so that a
/// restart loads it instead of re-integrating them (when those poses still hold).
struct StoredCheckpoint {
  std::uint64_t map_version = 0;
  std::map<KeyframeId, Eigen::Isometry3d> keyframe_poses;
  std::string occupancy_state;  ///< OccupancyMap::WriteState()
};

/// Everything the store holds, in id order: what a restart rebuilds the map from.
struct StoredMap {
  std::vector<StoredKeyframe> keyframes;      ///< ascending id
  std::vector<StoredObservation> observations;  ///< ascending (object id, keyframe id, insertion)
  std::vector<StoredObjectSummary> objects;   ///< ascending id
  std::uint64_t map_version = 0;
  ObjectId next_object_id = 1;
  bool pose_update_pending = false;  ///< see StoreChange::pose_update_pending
};

struct KeyframeStoreConfig {
  /// JPEG quality of stored colour images (1..100).
  int color_jpeg_quality = 90;
  /// SQLite busy timeout, milliseconds (another process holding the file).
  int busy_timeout_ms = 5000;
  /// "FULL": a committed change survives power loss; "NORMAL": survives a killed process (WAL).
  std::string synchronous = "NORMAL";

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// SQLite file (WAL journal, schema version in PRAGMA user_version) holding keyframes,
/// detections, observations (segments) and object summaries. Depth is stored as 16-bit PNG
/// (lossless), the object mask as 8-bit PNG, colour as JPEG.
/// Thread-safety: all methods may be called from any thread. Commit calls serialize on an
/// internal mutex (one write connection); const methods each borrow a read connection of their
/// own and run concurrently with each other and with Commit, seeing the last committed state.
class KeyframeStore {
 public:
  ~KeyframeStore();
  KeyframeStore(const KeyframeStore&) = delete;
  KeyframeStore& operator=(const KeyframeStore&) = delete;

  /// Opens (creating when absent, readable by its owner only: it holds the camera's images) the
  /// database at `path`. Returns nullptr and a reason naming the file when it cannot be opened,
  /// is not an objmap database, is corrupt (integrity check), has a schema version this build
  /// does not know, or is open in another store: one writer per database, held by an exclusive
  /// lock on `path`.lock for the life of the store (the system releases it when the process
  /// ends, however it ends). The reason then names the process that holds it.
  static std::unique_ptr<KeyframeStore> Open(const std::string& path,
                                             const KeyframeStoreConfig& config, std::string* why);

  /// Applies the change in one transaction. False (and nothing applied) with a reason otherwise,
  /// e.g. a keyframe id that already exists or a pose for an unknown keyframe.
  [[nodiscard]] bool Commit(const StoreChange& change, std::string* why);

  /// Loads everything (restart, regeneration from disk).
  [[nodiscard]] bool LoadAll(StoredMap* map, std::string* why) const;

  /// Replaces the checkpoint (one transaction). False with a reason, the old one kept, otherwise.
  [[nodiscard]] bool SaveCheckpoint(const StoredCheckpoint& checkpoint, std::string* why);
  /// The checkpoint, or nullopt when there is none; false with a reason when it is corrupt.
  [[nodiscard]] bool LoadCheckpoint(std::optional<StoredCheckpoint>* checkpoint,
                                    std::string* why) const;
  /// Loads one keyframe; false with "unknown keyframe id N" when absent.
  [[nodiscard]] bool LoadKeyframe(KeyframeId id, StoredKeyframe* keyframe, std::string* why) const;

  /// Keyframes with id >= `first_id`, ascending, at most `max_count` of them (0: all), with their
  /// current poses; no image is read. False with a reason when the store cannot be read.
  [[nodiscard]] bool ListKeyframes(KeyframeId first_id, std::size_t max_count,
                                   std::vector<KeyframeSummary>* keyframes, std::string* why) const;

  /// Revisits with id >= `first_id`, ascending. False with a reason when the store cannot be
  /// read.
  [[nodiscard]] bool ListRevisits(std::int64_t first_id, std::vector<StoredRevisit>* revisits,
                                  std::string* why) const;

  /// Every stored session, ascending id, with its keyframe count and range. False with a
  /// reason when the store cannot be read.
  [[nodiscard]] bool ListSessions(std::vector<SessionSummary>* sessions, std::string* why) const;

  [[nodiscard]] std::size_t NumKeyframes() const;
  /// Bytes of the database file plus its WAL.
  [[nodiscard]] std::uint64_t FileBytes() const;
  /// Total stored bytes per table column group for one keyframe: depth, mask, colour,
  /// observations (benchmarks: bytes stored per keyframe). `total` adds the pose and detection
  /// blobs. All zero for an unknown id.
  struct KeyframeBytes {
    std::uint64_t depth = 0, mask = 0, color = 0, observations = 0, total = 0;
  };
  [[nodiscard]] KeyframeBytes BytesOf(KeyframeId id) const;

  [[nodiscard]] const std::string& path() const;
  /// 2 added the occupancy checkpoint, 3 the sessions (a database without them opens with its
  /// keyframes in session 1), 4 the revisits, 5 observations kept as their pixels; older files
  /// are migrated when opened.
  static constexpr int kSchemaVersion = 5;

 private:
  KeyframeStore();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap
