#pragma once

#include <Eigen/Geometry>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "detection/detector.h"
#include "map_server/fairness.h"
#include "map_server/request_limits.h"
#include "map_server/revisit_thinning.h"
#include "mapper/mapper.h"
#include "objects/voxel_model.h"
#include "occupancy/occupancy_map.h"
#include "odometry/rgbd_odometry.h"
#include "store/keyframe_store.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// Outcome classes of server calls; transports map them onto their own codes (gRPC, ROS).
enum class StatusCode {
  kOk,
  kInvalidArgument,     ///< the request is malformed; the message names the field
  kNotFound,            ///< an id the map does not have
  kResourceExhausted,   ///< the ingest queue is full; retry later
  kUnavailable,         ///< the server is shutting down
  kInternal,            ///< storage failed; the message says how
  kFailedPrecondition,  ///< well-formed, but the server's state refuses it (tracking lost)
};

struct ServiceStatus {
  StatusCode code = StatusCode::kOk;
  std::string message;

  [[nodiscard]] bool ok() const { return code == StatusCode::kOk; }
  static ServiceStatus Ok() { return {}; }
  static ServiceStatus Invalid(std::string message) {
    return {StatusCode::kInvalidArgument, std::move(message)};
  }
  static ServiceStatus NotFound(std::string message) {
    return {StatusCode::kNotFound, std::move(message)};
  }
};

/// Where the poses of added keyframes come from.
enum class PoseSource {
  kRequest,   ///< each AddKeyframe's own pose (a SLAM system, TF, a dataset)
  kEstimate,  ///< RGB-D odometry on the keyframes themselves; the request's pose is ignored
  /// Each AddKeyframe's own pose, in a frame of its session's own (a robot's odometry that starts
  /// at zero at each boot): the server finds where the session's frame lies in the map by
  /// relocalising its first keyframes in the saved map, then maps every keyframe of the session
  /// at that transform times its pose.
  kSessionFrame,
};

/// "request" / "estimate" / "session_frame" (config files, messages).
[[nodiscard]] const char* PoseSourceName(PoseSource source);
/// False for any other name.
[[nodiscard]] bool ParsePoseSource(const std::string& name, PoseSource* source);

struct MapServerConfig {
  MapperConfig mapper;
  /// Config key server.pose_source: request (default), estimate or session_frame. With kEstimate
  /// the server tracks the camera from the keyframes (sent in time order, each overlapping the
  /// last ones), closes loops, and moves the mapped keyframes when a loop closes (as UpdatePoses
  /// would). With kSessionFrame the requests' poses are in their session's own frame (above).
  PoseSource pose_source = PoseSource::kRequest;
  OdometryConfig odometry;  ///< with kEstimate, and kSessionFrame's relocalisation
  KeyframeStoreConfig store;
  /// Keyframes of a later session that repeat a stored view with nothing changed are kept as
  /// revisits (session, time, pose) instead of being mapped and stored again (config section
  /// thinning): a patrol of an unchanged room does not grow the map.
  RevisitThinningConfig thinning;
  /// Keyframes and pose updates waiting for the mapping thread; AddKeyframe beyond this answers
  /// kResourceExhausted instead of queueing without bound.
  int max_queue = 64;
  /// Map changes remembered for WatchMap / Inventory(since): older ones are summarized.
  int change_history = 10000;
  /// Largest region (volume, cubic metres) an occupancy query may cover at the map resolution.
  double max_query_volume_m3 = 1000.0;
  /// Most voxels one occupancy query lists.
  int max_listed_voxels = 1000000;
  /// The OctoMap is checkpointed to the store after this many new keyframes, after every
  /// regeneration and at shutdown, so that a restart loads it instead of re-integrating every
  /// keyframe (about 0.35 s each). 0: never.
  int checkpoint_every_keyframes = 20;
  /// ... and only once the mapping work since the last checkpoint is at least this many times
  /// what saving that checkpoint took: a large map, slower to save, is saved less often, and
  /// saving never takes more than about 1 / (1 + this) of the mapping thread's time.
  double checkpoint_work_ratio = 10.0;
  /// Config key server.relocalisation_map_keyframes. With kEstimate and kSessionFrame: stored
  /// keyframes (the newest ones) that tracking loads at each session start to place the camera
  /// in the saved map by relocalisation (about 5 ms each, docs/benchmarks.md). 0: all of them.
  int relocalisation_map_keyframes = 0;
  /// Config key server.max_held_keyframes. With kEstimate: keyframes of a part of a session not
  /// placed in the map yet (a provisional fragment, OdometryConfig::provisional_fragments) are
  /// held in memory, detected, until a keyframe of that part is placed, then mapped at their
  /// poses; at most this many in all (the oldest go first). 0: none are held.
  int max_held_keyframes = 200;
  /// Config key server.estimate_from_first_pose. With kEstimate: the first keyframe of an empty
  /// map is mapped at the pose it carries (tracking starts there) instead of at the origin, so
  /// that the map shares the frame of a source whose poses only score the estimate (`objmap map
  /// --map DIR --poses estimate` on a dataset). Later keyframes' poses are ignored as before.
  bool estimate_from_first_pose = false;
  /// What one request may ask (config section server: max_image_pixels, ...).
  RequestLimits limits;
  /// How writes and queries share the CPU (config section server: heavy_query_threads, ...).
  FairnessConfig fairness;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// One detection that joined an object: where, in which keyframe's colour image, and as what.
struct ObjectSighting {
  KeyframeId keyframe_id = 0;
  BoundingBox2D box;  ///< colour pixels
  int class_id = -1;  ///< the observation's best class (kUnknownClassId: no detection named it)
  float score = 0.f;
};

/// An immutable view of one object, shared between snapshots while the object does not change.
/// A keyframe that observed an object: which, in which session, at which camera stamp.
struct ObjectSeen {
  KeyframeId keyframe_id = 0;
  SessionId session_id = 0;
  double stamp_s = 0.0;
};

/// A place an object stood before it moved, or where a removed object was.
struct ObjectPlaceView {
  Eigen::Vector3f centroid_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f min_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f max_W = Eigen::Vector3f::Zero();
  ObjectSeen first_seen, last_seen;  ///< its first and last sighting there
  /// The keyframe whose view completed the evidence that the place is empty (ChangeConfig).
  ObjectSeen seen_empty;
};

struct ObjectView {
  /// Its published id: a moved object keeps the id it had at its first place (Mapper::Changes).
  ObjectId id = 0;
  int class_id = -1;  ///< label
  float confidence = 0.f;
  Eigen::Vector3f centroid_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f min_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f max_W = Eigen::Vector3f::Zero();
  int observations = 0;
  std::vector<KeyframeId> keyframes;
  std::vector<std::pair<int, float>> scores;  ///< non-zero accumulated class scores, best first
  std::vector<ObjectSighting> sightings;      ///< one per observation, in keyframe order
  /// The first and the last keyframe that observed it (lowest and highest id: keyframes are
  /// numbered in the order they were mapped), with their sessions and stamps.
  ObjectSeen first_seen, last_seen;
  /// The newest keyframe that had it in view and did not see it (InventoryConfig::
  /// absent_min_visibility): seen absent, e.g. taken away since; keyframe_id 0: never.
  ObjectSeen last_seen_absent;
  bool confirmed = false;  ///< passes the inventory thresholds
  /// kPresent, kMoved (with previous_places), or kRemoved for a tombstone
  /// (MapSnapshot::tombstones: the object as it was last seen, at its last place).
  ObjectState state = ObjectState::kPresent;
  std::vector<ObjectPlaceView> previous_places;  ///< oldest first; empty unless it moved
  /// Its first place had been seen empty before it was first seen there (it was put there
  /// while the map watched): that first sighting; keyframe_id 0: not known to be added.
  ObjectSeen added;
  /// Tombstones: the keyframe whose view completed the evidence that it is gone.
  ObjectSeen removed;
  std::uint64_t changed_version = 0;             ///< map version of the last change
  std::shared_ptr<const ColoredPoints> model_W;  ///< the 5 mm model, world frame
};

/// One change of an object (added, removed, moved), with when the map learnt it.
struct MapObjectChange {
  ObjectChange change;
  ObjectSeen seen;  ///< the keyframe that completed its evidence: its session and stamp
  /// The map version at which it was first listed (after a restart: the first snapshot's).
  std::uint64_t version = 0;
  /// Moved: the previous place's sightings (first_seen .. last_seen there).
  ObjectSeen from_last_seen;
};

/// Which changes a query wants; every set field must hold.
struct ChangeFilter {
  std::optional<std::uint64_t> since_version;  ///< listed after this map version
  std::optional<double> since_stamp_s;         ///< its keyframe's camera stamp >= this
  std::optional<SessionId> since_session;      ///< its keyframe's session >= this
};

/// The map as queries see it: replaced as a whole after every change, never modified.
struct MapSnapshot {
  std::uint64_t version = 0;
  std::size_t num_keyframes = 0;
  /// The present objects, by published id (removed ones are in tombstones, not here).
  std::map<ObjectId, std::shared_ptr<const ObjectView>> objects;
  /// Removed objects, by id: out of the inventory, object queries, IsFree and CastRay; kept
  /// for the change queries and GetObject.
  std::map<ObjectId, std::shared_ptr<const ObjectView>> tombstones;
  /// The present object with this id or, failing that, its tombstone; nullptr when neither.
  [[nodiscard]] std::shared_ptr<const ObjectView> ObjectOrTombstone(ObjectId id) const;
  /// Every change of the map's objects, ordered by keyframe (ChangeList).
  std::vector<MapObjectChange> changes;
  std::vector<InventoryEntry> inventory;  ///< confirmed objects per class, most frequent first
  /// Per COCO class, the last version at which an object of it was added, changed or removed
  /// (or changed label or inventory status); what Inventory(since) filters on.
  std::vector<std::uint64_t> class_changed_version;
};

/// Object query; every set field must hold.
struct ObjectFilter {
  std::optional<int> class_id;
  /// Objects whose centroid lies in [min, max].
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> region;
  float min_confidence = 0.f;
  /// Results sorted by centroid distance to this point (otherwise by id).
  std::optional<Eigen::Vector3d> nearest_to;
  std::size_t max_results = 0;  ///< 0: all
  bool include_unconfirmed = false;
};

struct AddKeyframeOutcome {
  KeyframeId keyframe_id = 0;
  std::uint64_t map_version = 0;
  int detections_used = 0;
  std::vector<ObjectId> created;
  std::vector<ObjectId> updated;
  std::vector<ObjectId> removed;  ///< absorbed by merges
  /// The pose the keyframe was mapped at: the request's, or with PoseSource::kEstimate the
  /// tracked one.
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  /// PoseSource::kEstimate: loops this keyframe closed (every tracked keyframe then moved).
  int loops_closed = 0;
  /// PoseSource::kEstimate: the camera was placed in the map by relocalisation for this
  /// keyframe (the first of a session on a saved map, or after tracking was lost).
  /// PoseSource::kSessionFrame: this keyframe placed its session's frame in the map.
  bool relocalized = false;
  SessionId session_id = 0;  ///< the session it was mapped in
  /// PoseSource::kEstimate, with kFailedPrecondition: the camera could not be placed (tracking
  /// lost, no saved keyframe explains the frame); the keyframe is not mapped. The same with
  /// kSessionFrame while the session's frame is not placed in the map yet.
  bool untracked = false;
  /// PoseSource::kEstimate, untracked: the keyframe is held (in memory, not stored) in
  /// provisional fragment `held_fragment` with the others of its part of the session, and is
  /// mapped at its pose once one of them is placed (MapServerConfig::max_held_keyframes).
  bool held = false;
  int held_fragment = 0;
  /// PoseSource::kEstimate: the held keyframes this keyframe's placement mapped (before it), in
  /// the order they came.
  std::vector<KeyframeId> attached;
  /// The keyframe repeated the view of this stored keyframe of an earlier session with nothing
  /// changed (MapServerConfig::thinning), 0 otherwise. With keyframe_id 0 it repeated it whole
  /// and was kept as a revisit only, not mapped or stored as a keyframe; otherwise it repeated
  /// a part and was mapped and stored with the depth of the rest only (and a revisit).
  KeyframeId repeated_keyframe = 0;
  float explained_fraction = 0.f;  ///< of its depth pixels, by the stored views (thinning)
};

struct PoseUpdateOutcome {
  std::uint64_t map_version = 0;  ///< the version that holds the new poses
  bool regenerated = false;       ///< waited and done
  int keyframes_moved = 0;
  double regeneration_ms = 0.0;
  bool reassociated = false;  ///< objects regrouped (MapperConfig::reassociation)
  int objects_before = 0;
  int objects_after = 0;
};

/// One change of the map, in version order.
struct MapChange {
  /// kKeyframeRepeated: a keyframe was kept as a revisit of a stored view (thinning); the
  /// objects that view saw were seen again (their last sighting changed).
  enum class Kind { kKeyframeAdded, kPosesUpdated, kKeyframeRepeated };
  std::uint64_t version = 0;
  Kind kind = Kind::kKeyframeAdded;
  KeyframeId keyframe_id = 0;  ///< kKeyframeAdded: the new one; kKeyframeRepeated: the one repeated
  std::vector<ObjectId> added;
  std::vector<ObjectId> updated;
  std::vector<ObjectId> removed;
  /// Object changes (added, removed, moved) first listed at this version.
  std::vector<MapObjectChange> object_changes;
};

/// "keyframe_added", "poses_updated", "keyframe_repeated".
[[nodiscard]] const char* MapChangeKindName(MapChange::Kind kind);

struct ServerStatus {
  std::uint64_t map_version = 0;
  std::size_t keyframes = 0;
  std::size_t objects = 0;
  std::size_t confirmed_objects = 0;
  int queue_length = 0;
  bool regenerating = false;
  double last_regeneration_ms = 0.0;
  std::uint64_t last_regeneration_version = 0;
  std::string database;
  std::uint64_t database_bytes = 0;
  double uptime_s = 0.0;
  std::uint64_t checkpoint_version = 0;  ///< of the OctoMap checkpoint in the store (0: none)
  double last_checkpoint_ms = 0.0;       ///< writing and storing the last checkpoint
  double startup_ms = 0.0;               ///< opening the store and restoring the map
  /// Keyframes integrated into the OctoMap at start: all of them without a usable checkpoint,
  /// only those after it otherwise.
  int startup_keyframes_integrated = 0;
  /// Memory of one copy of the OctoMap (OcTree nodes), and how many copies are kept.
  std::uint64_t occupancy_bytes = 0;
  int occupancy_copies = 1;
  SessionId session_id = 0;  ///< the current session (keyframes added now join it)
  std::string session_name;
};

/// The mapping server without transport: a durable store, one mapping thread that applies
/// keyframes and pose updates in arrival order, and snapshots that queries read.
///
/// Thread-safety: every method may be called from any thread at any time. Writes (AddKeyframe,
/// UpdatePoses) are queued and applied by the mapping thread in order; they return once the
/// change is committed to the store (AddKeyframe) or the new poses are (UpdatePoses). Queries
/// read the latest snapshot and the latest published OctoMap and never wait for a keyframe or a
/// regeneration (MapperConfig::occupancy_second_copy). Heavy queries (QueryOccupancy,
/// GetOctomap) run on threads of their own at a lower priority (FairnessConfig), so that many
/// of them slow neither the writes nor the short queries.
class MapServer {
 public:
  /// Opens (or creates) the store at `db_path` and rebuilds the map from it: same keyframe and
  /// object ids, labels and inventory as before the restart. `detector` (may be null) runs on
  /// keyframes that come without detections. nullptr and a reason when the store cannot be used.
  static std::unique_ptr<MapServer> Open(const MapServerConfig& config, const std::string& db_path,
                                         std::unique_ptr<Detector> detector, std::string* why);
  /// Finishes queued work and stops the mapping thread.
  ~MapServer();
  MapServer(const MapServer&) = delete;
  MapServer& operator=(const MapServer&) = delete;

  /// Validates the frame, maps it and commits it; returns when it is durable. `detections`
  /// absent: the configured detector runs (no detector: no objects from this keyframe).
  /// With PoseSource::kEstimate the frame's pose is ignored and tracked instead; calls are then
  /// taken one at a time (one camera, in order), and a frame that cannot be tracked is refused
  /// with kFailedPrecondition and the reason, and not mapped.
  [[nodiscard]] ServiceStatus AddKeyframe(RgbdFrame frame,
                                          std::optional<std::vector<Detection>> detections,
                                          AddKeyframeOutcome* outcome);

  /// Validates (known ids, finite rigid poses), stores the poses durably and queues the
  /// regeneration; with `wait`, returns after it has been applied.
  /// True with PoseSource::kEstimate: AddKeyframe needs no pose.
  [[nodiscard]] bool estimates_poses() const;
  /// The newest stored keyframe with its images and current pose (where a camera tracker
  /// resumes after a restart); kNotFound on an empty map.
  [[nodiscard]] ServiceStatus NewestKeyframe(RgbdFrame* frame) const;
  /// A stored keyframe with its images and current pose; kNotFound for an unknown id.
  [[nodiscard]] ServiceStatus StoredFrame(KeyframeId id, RgbdFrame* frame) const;
  /// Gives `odometry` (not yet started) the stored map's keyframes at their current poses
  /// (RgbdOdometry::AddMapKeyframe; the newest config.relocalisation_map_keyframes, the newest
  /// last), so that tracking goes on in the stored map's frame: where it stopped, or wherever
  /// the camera is placed by relocalisation. `resumed_from` names the newest. On an empty map:
  /// Ok and nothing done (the first frame starts the map). kFailedPrecondition with the reason
  /// when the keyframes cannot be read or none can be tracked from.
  [[nodiscard]] ServiceStatus StartTrackingOnStoredMap(RgbdOdometry* odometry,
                                                       std::string* resumed_from) const;
  [[nodiscard]] ServiceStatus UpdatePoses(const std::map<KeyframeId, Eigen::Isometry3d>& poses,
                                          bool wait, PoseUpdateOutcome* outcome);

  /// Ends the current session and starts a new one (`name` empty: "session N"); every keyframe
  /// added from now on joins it. A current session that has mapped nothing is replaced, id kept. A
  /// session is stored with its first keyframe (a session that maps nothing leaves no trace); its
  /// end time is stored with the next session's first keyframe or at shutdown. Each Open starts a
  /// session too. With PoseSource::kEstimate, tracking starts over on the saved map: the camera may
  /// be anywhere, and the session's first keyframe is placed by relocalisation before it is mapped.
  /// `started` (may be null) receives the new session.
  [[nodiscard]] ServiceStatus StartSession(const std::string& name, SessionSummary* started);
  /// Every stored session, ascending id, and the current one (also before its first keyframe,
  /// then with no keyframes); `current` (may be null) receives its id.
  [[nodiscard]] ServiceStatus ListSessions(std::vector<SessionSummary>* sessions,
                                           SessionId* current) const;

  /// Writes the map into folder `dir` as `objmap map` writes its output (WriteMapOutputs:
  /// map.bt, objects.json, objects/*.ply), after the writes queued before it; queries go on
  /// meanwhile. kInternal with the file's problem.
  [[nodiscard]] ServiceStatus WriteMapFolder(const std::string& dir);

  /// The current snapshot (never null).
  [[nodiscard]] std::shared_ptr<const MapSnapshot> Snapshot() const;

  /// Objects matching the filter, from one snapshot (its version in `version`).
  [[nodiscard]] ServiceStatus QueryObjects(const ObjectFilter& filter,
                                           std::vector<std::shared_ptr<const ObjectView>>* objects,
                                           std::uint64_t* version) const;
  /// A present object, or a removed one (its tombstone, state kRemoved).
  [[nodiscard]] ServiceStatus GetObject(ObjectId id,
                                        std::shared_ptr<const ObjectView>* object) const;
  /// The object changes (added, removed, moved) that match the filter, ordered by keyframe, from
  /// one snapshot (its version in `version`).
  [[nodiscard]] ServiceStatus ListChanges(const ChangeFilter& filter,
                                          std::vector<MapObjectChange>* changes,
                                          std::uint64_t* version) const;

  /// The inventory; with `since_version`, only classes with an object added, changed or
  /// removed after it (a class whose last object went away comes with count 0).
  [[nodiscard]] ServiceStatus Inventory(std::optional<std::uint64_t> since_version,
                                        std::vector<InventoryEntry>* entries,
                                        std::uint64_t* version) const;

  /// Occupancy of a box (validated: finite, min <= max, volume limit).
  [[nodiscard]] ServiceStatus QueryOccupancy(const Eigen::Vector3d& min_W,
                                             const Eigen::Vector3d& max_W, double resolution_m,
                                             bool list_voxels, std::size_t max_voxels,
                                             RegionOccupancy* region, std::uint64_t* version) const;
  /// True when the box holds no occupied voxel, no point of an object model and (unless
  /// `unknown_is_free`) no unknown voxel. Objects are not in the OctoMap (their rays stop short
  /// of them), so their 5 mm models are what keeps a box around a cup or a table top from being
  /// free. `objects_inside` (may be null) receives the ids of those objects, ascending.
  [[nodiscard]] ServiceStatus IsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                     bool unknown_is_free, bool* free, RegionOccupancy* counts,
                                     std::vector<ObjectId>* objects_inside,
                                     std::uint64_t* version) const;
  /// The first occupied voxel (or unknown one, with `unknown_stops`) on the ray, or the first
  /// point of an object model, whichever comes first; `object_hit` is that object's id (0 when
  /// the structure or nothing was hit).
  [[nodiscard]] ServiceStatus CastRay(const Eigen::Vector3d& origin_W,
                                      const Eigen::Vector3d& direction_W, double max_range_m,
                                      bool unknown_stops, RayHit* hit, ObjectId* object_hit,
                                      std::uint64_t* version) const;
  /// The colour image stored with keyframe `id` (JPEG-decoded; empty when it came without one);
  /// kNotFound for an id the map does not hold.
  [[nodiscard]] ServiceStatus KeyframeColor(KeyframeId id, ColorImage* color) const;
  /// The OctoMap (or the part in the box) as standard .bt bytes.
  [[nodiscard]] ServiceStatus OctomapBytes(
      const std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& region, std::string* bytes,
      std::size_t* leaf_count, std::uint64_t* version) const;

  /// Centres of the occupied voxels at the map resolution, at most `max_count` of them (a
  /// larger map is thinned evenly, every k-th voxel): what a visualisation publishes.
  [[nodiscard]] ServiceStatus OccupiedCenters(std::size_t max_count,
                                              std::vector<Eigen::Vector3d>* centers,
                                              std::uint64_t* version) const;

  /// Stored keyframes with id >= `first_id`, ascending, at most `max_count` (0: all), with their
  /// current poses: what a pose-graph back end needs to resume after a restart. `version` is the
  /// map version before the read; every keyframe of that version is listed (later ones may be).
  [[nodiscard]] ServiceStatus ListKeyframes(KeyframeId first_id, std::size_t max_count,
                                            std::vector<KeyframeSummary>* keyframes,
                                            std::uint64_t* version) const;

  [[nodiscard]] ServerStatus Status() const;
  /// The limits on one request this server was opened with.
  [[nodiscard]] const RequestLimits& limits() const;
  /// The OctoMap's voxel size, metres.
  [[nodiscard]] double occupancy_resolution_m() const;

  /// Changes with version > `since_version`, oldest first. Waits up to `timeout` when there are
  /// none yet; returns empty on timeout or shutdown. When `since_version` is older than the
  /// remembered history (config.change_history, or a restart), one change at the current version
  /// lists every current object as updated instead.
  [[nodiscard]] std::vector<MapChange> ChangesSince(std::uint64_t since_version,
                                                    std::chrono::milliseconds timeout) const;

  /// Stops accepting writes (kUnavailable), wakes every waiter, finishes queued work.
  void Shutdown();
  [[nodiscard]] bool shutting_down() const;

 private:
  MapServer();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The objects of `snapshot` with at least one model point inside [min_W, max_W], ascending id:
/// what keeps a box from being free besides the OctoMap (objects are not in it).
[[nodiscard]] std::vector<ObjectId> ObjectsInBox(const MapSnapshot& snapshot,
                                                 const Eigen::Vector3d& min_W,
                                                 const Eigen::Vector3d& max_W);

/// Evenly thins `points` to at most `max_count` (every k-th), keeping their order.
void ThinEvenly(std::size_t max_count, std::vector<Eigen::Vector3d>* points);

/// Checks a box: finite coordinates and min <= max on every axis; `field` names it in the reason.
[[nodiscard]] bool ValidateBox(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                               const std::string& field, std::string* why);

/// Checks the box of an occupancy query (QueryOccupancy, IsFree): ValidateBox's checks and a
/// volume of at most `max_volume_m3` (MapServerConfig::max_query_volume_m3).
[[nodiscard]] ServiceStatus CheckQueryBox(const Eigen::Vector3d& min_W,
                                          const Eigen::Vector3d& max_W, const std::string& field,
                                          double max_volume_m3);

/// IsFree's answer from the box's occupancy counts and the objects with a model point in it.
[[nodiscard]] bool BoxIsFree(const RegionOccupancy& counts,
                             const std::vector<ObjectId>& objects_inside, bool unknown_is_free);

}  // namespace objmap
