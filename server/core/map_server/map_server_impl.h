#pragma once
// Private to map_server: the state shared by the writer (map_server.cc) and the queries
// (queries.cc).

#include <array>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <future>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "map_server/map_server.h"
#include "map_server/snapshot_builder.h"
#include "map_server/task_threads.h"
#include "odometry/held_keyframes.h"
#include "odometry/tracked_keyframes.h"

namespace objmap {

/// A queued write: a keyframe or a pose update, applied by the mapping thread in order; or the
/// map written as files (kWriteFolder), in order with them and without a version of its own.
struct MapJob {
  enum class Kind { kKeyframe, kPoses, kWriteFolder };
  Kind kind = Kind::kKeyframe;
  std::uint64_t version = 0;  ///< the map version this job produces when it succeeds
  RgbdFrame frame;
  std::vector<Detection> detections;
  StoredSession session;  ///< the session the keyframe joins
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  std::string folder;  ///< kWriteFolder: where

  struct Result {
    ServiceStatus status;
    AddKeyframeOutcome keyframe;
    PoseUpdateOutcome poses;
  };
  std::promise<Result> done;
  /// Every caller waiting on this job (pose updates merged into one job share it).
  std::shared_future<Result> result = done.get_future().share();
};

struct MapServer::Impl {
  MapServerConfig config;
  std::unique_ptr<KeyframeStore> store;
  std::unique_ptr<Mapper> mapper;  // touched by the mapping thread only (and ReadOccupancy)
  SnapshotBuilder snapshot_builder;  // mapping thread only
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();

  std::unique_ptr<Detector> detector;
  std::unique_ptr<TaskThreads> detector_thread;  // the one thread that runs the detector
  std::unique_ptr<TaskThreads> heavy_query_threads;  // FairnessConfig

  // Queue of writes.
  mutable std::mutex queue_mutex;
  std::condition_variable queue_cv;
  std::deque<std::shared_ptr<MapJob>> queue;
  std::uint64_t planned_version = 0;  // last version handed to a job (queue_mutex)
  const MapJob* applying = nullptr;   // the job the mapping thread works on (queue_mutex)
  bool stopping = false;              // queue_mutex
  std::atomic<bool> shutting_down{false};
  std::thread worker;

  // PoseSource::kEstimate: the odometry, and the keyframes it placed (loop closures move them).
  // tracking_mutex is held through a whole AddKeyframe: one camera, in order.
  std::mutex tracking_mutex;
  std::unique_ptr<RgbdOdometry> odometry;
  TrackedKeyframes tracked_keyframes;
  std::string tracking_blocked;  // why tracking cannot resume on the stored map (empty: it can)
  // Keyframes tracked in a provisional fragment (kProvisional), detected and waiting to be
  // mapped when their fragment is placed: the job (frame, detections, session).
  HeldKeyframes<std::shared_ptr<MapJob>> held_keyframes;
  /// Maps the keyframes held in `fragment`, just placed (tracking_mutex held), in order, at the
  /// poses their odometry keyframes now have; their ids into `mapped`.
  ServiceStatus MapHeld(int fragment, std::vector<KeyframeId>* mapped);

  // PoseSource::kSessionFrame (tracking_mutex): a tracker seeded with the stored map that places
  // the current session's first keyframe, and then where the session's frame lies in the map.
  std::unique_ptr<RgbdOdometry> session_placer;
  std::optional<Eigen::Isometry3d> T_map_session;
  /// A session starts (Open, StartSession): with kEstimate a new odometry, with kSessionFrame a
  /// new placer and no placed frame; either seeded with the stored map (tracking_mutex held, or
  /// before the mapping thread runs). Nothing with kRequest.
  void BeginSessionTracking(const MapServer& server);
  /// Moves `frame`'s pose from its session's frame into the map's, placing the session's frame
  /// first when needed (`placed_now`); kFailedPrecondition with the reason when it cannot be.
  ServiceStatus PlaceInSessionFrame(RgbdFrame* frame, bool* placed_now);

  // Sessions: the current one (keyframes added now join it) and those ended whose end is not
  // stored yet (written with the next keyframe, or at shutdown). stored_sessions: ids with a
  // row in the store.
  mutable std::mutex session_mutex;
  StoredSession session;
  std::vector<StoredSession> ended_sessions;
  std::set<SessionId> stored_sessions;
  /// Opens the session after `previous_id` (session_mutex held).
  void BeginSessionLocked(SessionId previous_id, const std::string& name);
  /// Stores the end of every session ended (and, with `end_current`, of the current one) that
  /// has a row; at shutdown.
  void StoreSessionEnds(bool end_current);

  // Keyframe ids committed to the store: UpdatePoses validates against them on any thread.
  mutable std::mutex known_mutex;
  std::set<KeyframeId> known_keyframes;
  /// A keyframe of the map as stored (images, current pose); kNotFound for an id the map does
  /// not hold, kInternal when the store cannot read it.
  ServiceStatus LoadKnownKeyframe(KeyframeId id, StoredKeyframe* stored) const;

  // The published snapshot.
  mutable std::mutex snapshot_mutex;
  std::shared_ptr<const MapSnapshot> snapshot;

  // Recent changes for ChangesSince.
  mutable std::mutex changes_mutex;
  mutable std::condition_variable changes_cv;
  std::deque<MapChange> changes;
  std::uint64_t history_start = 0;  // changes after this version are all remembered

  // OctoMap checkpoints (mapping thread, and Open before it starts).
  int keyframes_since_checkpoint = 0;
  double mapping_ms_since_checkpoint = 0.0;  // mapping thread time spent on keyframes since
  bool checkpoint_due = false;  // after a regeneration
  std::atomic<std::uint64_t> checkpoint_version{0};
  std::atomic<double> last_checkpoint_ms{0.0};
  double startup_ms = 0.0;
  int startup_keyframes_integrated = 0;

  std::atomic<bool> regenerating{false};
  std::atomic<double> last_regeneration_ms{0.0};
  std::atomic<std::uint64_t> last_regeneration_version{0};

  void Run();
  /// Rebuilds the mapper (and the known keyframe ids) from the store, the OctoMap from its
  /// checkpoint when usable; `version` receives the stored map version. Mapping thread only
  /// (or Open, before it starts).
  bool RestoreFromStore(std::uint64_t* version, std::string* why);
  /// Saves the OctoMap checkpoint when it is due (`force`: whenever keyframes were added or the
  /// map regenerated since the last one). A failure only costs the next start its speed.
  void MaybeCheckpoint(bool force);
  MapJob::Result ApplyKeyframe(MapJob* job);
  /// What `job`'s keyframe repeats of stored keyframes of earlier sessions, nothing changed
  /// (MapServerConfig::thinning): the whole view (kept as a revisit only) or a part (mapped
  /// with the rest of its depth only, and a revisit); nullopt when it is to be mapped whole.
  struct Repeated {
    StoredRevisit revisit;
    bool whole = false;
    ViewCoverage coverage;
  };
  [[nodiscard]] std::optional<Repeated> RepeatedView(const MapJob& job) const;
  /// Stores the revisit instead of the keyframe; the objects its view saw were last seen now.
  MapJob::Result ApplyRevisit(MapJob* job, StoredRevisit revisit);
  /// The sessions a write of `session` stores with it: its own when it is not stored yet, and
  /// the ends of stored sessions (into `ends` too) ...
  std::vector<StoredSession> SessionsToStore(const StoredSession& session,
                                             std::vector<StoredSession>* ends);
  /// ... and, once committed, what is stored of them now.
  void SessionsStored(SessionId session_id, const std::vector<StoredSession>& ends);
  MapJob::Result ApplyPoses(MapJob* job);
  void Publish(std::shared_ptr<const MapSnapshot> next, MapChange change);
  /// Builds the snapshot of `version` and publishes it with a change of `kind` for
  /// `keyframe_id`, listing the objects the build found changed; returns what it found.
  SnapshotBuilder::Diff PublishVersion(std::uint64_t version, MapChange::Kind kind,
                                       KeyframeId keyframe_id);
  ServiceStatus Enqueue(std::shared_ptr<MapJob> job, bool bounded);
  /// Enqueue with queue_mutex already held by the caller.
  ServiceStatus EnqueueLocked(std::shared_ptr<MapJob> job, bool bounded);
  [[nodiscard]] std::shared_ptr<const MapSnapshot> Current() const;
  /// Runs `query` on a heavy-query thread (FairnessConfig); kResourceExhausted when too many
  /// wait already.
  ServiceStatus RunHeavy(const std::function<ServiceStatus()>& query) const;
  /// QueryOccupancy on the calling thread (IsFree's small boxes are not heavy queries).
  ServiceStatus ReadRegion(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                           double resolution_m, bool list_voxels, std::size_t max_voxels,
                           RegionOccupancy* region, std::uint64_t* version) const;
};

}  // namespace objmap
