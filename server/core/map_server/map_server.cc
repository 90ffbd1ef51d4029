#include "map_server/map_server.h"

#include <pthread.h>

#include <algorithm>
#include <cmath>

#include "map_server/map_server_impl.h"
#include "map_server/store_records.h"
#include "mapper/map_export.h"

namespace objmap {
namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Observations this keyframe added, with the object that holds each now (after merges).
std::vector<StoredObservation> NewObservations(const ObjectMap& objects,
                                               const std::set<ObjectId>& touched,
                                               KeyframeId keyframe_id) {
  std::vector<StoredObservation> rows;
  for (ObjectId id : touched) {
    const MapObject* object = objects.Find(id);
    if (object == nullptr) continue;
    for (const ObjectObservation& observation : object->observations) {
      if (observation.keyframe_id == keyframe_id) rows.push_back({id, observation});
    }
  }
  return rows;
}

StoredObjectSummary Summarize(const MapObject& object) {
  StoredObjectSummary summary;
  summary.id = object.id;
  summary.class_id = object.Label();
  summary.confidence = object.Confidence();
  summary.centroid_W = object.centroid_W;
  summary.observations = static_cast<int>(object.observations.size());
  return summary;
}

// Every object with all its observations, replacing what the store holds (a re-association).
StoreChange AllObjectsChange(const Mapper& mapper) {
  StoreChange change;
  change.replace_all_objects = true;
  for (const auto& [id, object] : mapper.objects().objects()) {
    for (const ObjectObservation& observation : object.observations) {
      change.observations.push_back({id, observation});
    }
    change.object_summaries.push_back(Summarize(object));
  }
  change.next_object_id = mapper.objects().next_id();
  return change;
}

}  // namespace

const char* PoseSourceName(PoseSource source) {
  switch (source) {
    case PoseSource::kEstimate:
      return "estimate";
    case PoseSource::kSessionFrame:
      return "session_frame";
    default:
      return "request";
  }
}

bool ParsePoseSource(const std::string& name, PoseSource* source) {
  if (name == "request") {
    *source = PoseSource::kRequest;
  } else if (name == "estimate") {
    *source = PoseSource::kEstimate;
  } else if (name == "session_frame") {
    *source = PoseSource::kSessionFrame;
  } else {
    return false;
  }
  return true;
}

const char* MapChangeKindName(MapChange::Kind kind) {
  switch (kind) {
    case MapChange::Kind::kKeyframeAdded:
      return "keyframe_added";
    case MapChange::Kind::kPosesUpdated:
      return "poses_updated";
    case MapChange::Kind::kKeyframeRepeated:
      return "keyframe_repeated";
  }
  return "unknown";
}

bool MapServerConfig::IsValid(std::string* why) const {
  if (!mapper.IsValid(why) || !store.IsValid(why) || !thinning.IsValid(why) ||
      !limits.IsValid(why) || !fairness.IsValid(why)) {
    return false;
  }
  if (max_queue < 1 || change_history < 1 || max_listed_voxels < 1) {
    *why = "MapServerConfig: max_queue, change_history and max_listed_voxels must be >= 1";
    return false;
  }
  if (checkpoint_every_keyframes < 0) {
    *why = "MapServerConfig.checkpoint_every_keyframes must be >= 0 (0: never)";
    return false;
  }
  if (!(checkpoint_work_ratio >= 0.0) || !std::isfinite(checkpoint_work_ratio)) {
    *why = "MapServerConfig.checkpoint_work_ratio must be finite and >= 0";
    return false;
  }
  if (max_held_keyframes < 0) {
    *why = "MapServerConfig.max_held_keyframes must be >= 0 (0: none held)";
    return false;
  }
  if (relocalisation_map_keyframes < 0) {
    *why = "MapServerConfig.relocalisation_map_keyframes must be >= 0 (0: all)";
    return false;
  }
  if (!(max_query_volume_m3 > 0.0)) {
    *why = "MapServerConfig.max_query_volume_m3 must be positive";
    return false;
  }
  if (pose_source != PoseSource::kRequest && !odometry.IsValid(why)) return false;
  return true;
}

MapServer::MapServer() : impl_(std::make_unique<Impl>()) {}

const RequestLimits& MapServer::limits() const { return impl_->config.limits; }

double MapServer::occupancy_resolution_m() const {
  return impl_->config.mapper.occupancy.resolution_m;
}

MapServer::~MapServer() {
  Shutdown();
  if (impl_->worker.joinable()) impl_->worker.join();
  impl_->StoreSessionEnds(/*end_current=*/true);
}

std::unique_ptr<MapServer> MapServer::Open(const MapServerConfig& config,
                                           const std::string& db_path,
                                           std::unique_ptr<Detector> detector, std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  const auto start = Clock::now();
  std::unique_ptr<MapServer> server(new MapServer());
  Impl& impl = *server->impl_;
  impl.config = config;
  impl.store = KeyframeStore::Open(db_path, config.store, why);
  if (!impl.store) return nullptr;
  impl.mapper = std::make_unique<Mapper>(config.mapper);
  std::uint64_t version = 0;
  if (!impl.RestoreFromStore(&version, why)) {
    *why = "cannot load " + db_path + ": " + *why;
    return nullptr;
  }
  impl.startup_keyframes_integrated = impl.keyframes_since_checkpoint;
  std::vector<SessionSummary> sessions;
  if (!impl.store->ListSessions(&sessions, why)) {
    *why = "cannot load " + db_path + ": " + *why;
    return nullptr;
  }
  {
    std::lock_guard<std::mutex> lock(impl.session_mutex);
    for (const SessionSummary& stored : sessions) impl.stored_sessions.insert(stored.session.id);
    impl.BeginSessionLocked(sessions.empty() ? 0 : sessions.back().session.id, "");
  }
  impl.planned_version = version;
  impl.history_start = version;
  impl.snapshot = impl.snapshot_builder.Build(*impl.mapper, version, nullptr);
  impl.detector = std::move(detector);
  // One thread of the server's own runs the detector (detectors are not thread-safe), at the
  // priority of the mapping thread: detection is part of the writes.
  if (impl.detector) {
    TaskThreads::Options detection;
    detection.name = "objmap-detect";
    impl.detector_thread = std::make_unique<TaskThreads>(detection);
  }
  TaskThreads::Options heavy;
  heavy.threads = config.fairness.heavy_query_threads;
  heavy.nice = config.fairness.heavy_query_nice;
  heavy.max_waiting = config.fairness.max_waiting_heavy_queries;
  heavy.name = "objmap-heavy";
  impl.heavy_query_threads = std::make_unique<TaskThreads>(heavy);
  impl.BeginSessionTracking(*server);
  // What this start had to integrate, the next one loads.
  impl.MaybeCheckpoint(/*force=*/true);
  impl.startup_ms = MillisecondsSince(start);
  impl.worker = std::thread([&impl] {
    pthread_setname_np(pthread_self(), "objmap-mapping");
    impl.Run();
  });
  return server;
}

bool MapServer::Impl::RestoreFromStore(std::uint64_t* version, std::string* why) {
  StoredMap stored;
  if (!store->LoadAll(&stored, why)) return false;
  // A checkpoint that cannot be read only costs time: every keyframe is integrated.
  std::optional<StoredCheckpoint> checkpoint;
  std::string checkpoint_error;
  if (!store->LoadCheckpoint(&checkpoint, &checkpoint_error)) checkpoint.reset();
  if (checkpoint) checkpoint_version = checkpoint->map_version;
  *version = stored.map_version;
  const bool pose_update_pending = stored.pose_update_pending;
  for (const StoredKeyframe& keyframe : stored.keyframes) {
    snapshot_builder.AddKeyframe(keyframe.id, keyframe.session_id, keyframe.stamp_s);
  }
  std::vector<StoredRevisit> revisits;
  if (!store->ListRevisits(0, &revisits, why)) return false;
  for (const StoredRevisit& revisit : revisits) {
    snapshot_builder.AddRevisit(revisit.keyframe_id, revisit.session_id, revisit.stamp_s);
  }
  std::set<KeyframeId> keyframe_ids;
  const RestoreOutcome restored =
      RestoreMapper(std::move(stored), std::move(checkpoint), mapper.get(), &keyframe_ids);
  keyframes_since_checkpoint = restored.keyframes_integrated;
  // Poses were stored but their regeneration never committed (the process died in between):
  // the objects still have the grouping made with the old poses. Re-associate them with the
  // stored poses, as the regeneration would have (a rigid update regroups nothing).
  if (pose_update_pending) {
    mapper->ReassociateObjects();
    StoreChange change = AllObjectsChange(*mapper);
    change.pose_update_pending = false;
    if (!store->Commit(change, why)) {
      *why = "re-associating after an interrupted pose update: " + *why;
      return false;
    }
  }
  std::lock_guard<std::mutex> lock(known_mutex);
  known_keyframes.swap(keyframe_ids);
  return true;
}

std::shared_ptr<const MapSnapshot> MapServer::Impl::Current() const {
  std::lock_guard<std::mutex> lock(snapshot_mutex);
  return snapshot;
}

std::shared_ptr<const MapSnapshot> MapServer::Snapshot() const { return impl_->Current(); }

ServiceStatus MapServer::Impl::Enqueue(std::shared_ptr<MapJob> job, bool bounded) {
  std::lock_guard<std::mutex> lock(queue_mutex);
  return EnqueueLocked(std::move(job), bounded);
}

ServiceStatus MapServer::Impl::EnqueueLocked(std::shared_ptr<MapJob> job, bool bounded) {
  if (stopping) return {StatusCode::kUnavailable, "the server is shutting down"};
  if (bounded && static_cast<int>(queue.size()) >= config.max_queue) {
    return {StatusCode::kResourceExhausted,
            "ingest queue full (" + std::to_string(queue.size()) + " waiting); retry later"};
  }
  // Writing the folder changes nothing in the map: it takes no version.
  if (job->kind != MapJob::Kind::kWriteFolder) job->version = ++planned_version;
  queue.push_back(std::move(job));
  queue_cv.notify_one();
  return ServiceStatus::Ok();
}

void MapServer::Impl::Run() {
  for (;;) {
    std::shared_ptr<MapJob> job;
    {
      std::unique_lock<std::mutex> lock(queue_mutex);
      queue_cv.wait(lock, [this] { return stopping || !queue.empty(); });
      if (queue.empty()) break;  // stopping, and everything queued is done
      job = queue.front();
      applying = job.get();  // from now on no pose update merges into it
    }
    MapJob::Result result;
    switch (job->kind) {
      case MapJob::Kind::kKeyframe:
        result = ApplyKeyframe(job.get());
        break;
      case MapJob::Kind::kPoses:
        result = ApplyPoses(job.get());
        break;
      case MapJob::Kind::kWriteFolder: {
        std::string why;
        const KeyframeWhenLookup when = [this](KeyframeId id) {
          const ObjectSeen seen = snapshot_builder.Seen(id);
          return KeyframeWhen{seen.session_id, seen.stamp_s};
        };
        result.status = WriteMapOutputs(*mapper, job->folder, &why, when)
                            ? ServiceStatus::Ok()
                            : ServiceStatus{StatusCode::kInternal, why};
        break;
      }
    }
    {
      // Popped only now, so Status() counts the job being applied as queued.
      std::lock_guard<std::mutex> lock(queue_mutex);
      queue.pop_front();
      applying = nullptr;
    }
    job->done.set_value(std::move(result));
    MaybeCheckpoint(/*force=*/false);  // after the answer: the caller does not wait for it
  }
  MaybeCheckpoint(/*force=*/true);
}

void MapServer::Impl::MaybeCheckpoint(bool force) {
  const int every = config.checkpoint_every_keyframes;
  if (every == 0 || (keyframes_since_checkpoint == 0 && !checkpoint_due)) return;
  const bool enough_work =
      keyframes_since_checkpoint >= every &&
      mapping_ms_since_checkpoint >= config.checkpoint_work_ratio * last_checkpoint_ms;
  if (!force && !checkpoint_due && !enough_work) return;
  const auto start = Clock::now();
  StoredCheckpoint checkpoint;
  checkpoint.map_version = Current()->version;
  OccupancyCheckpoint occupancy = mapper->MakeOccupancyCheckpoint();
  checkpoint.occupancy_state = std::move(occupancy.state);
  checkpoint.keyframe_poses = std::move(occupancy.keyframe_poses);
  std::string why;
  if (!store->SaveCheckpoint(checkpoint, &why)) return;  // tried again after the next keyframe
  keyframes_since_checkpoint = 0;
  mapping_ms_since_checkpoint = 0.0;
  checkpoint_due = false;
  checkpoint_version = checkpoint.map_version;
  last_checkpoint_ms = MillisecondsSince(start);
}

void MapServer::Impl::Publish(std::shared_ptr<const MapSnapshot> next, MapChange change) {
  {
    std::lock_guard<std::mutex> lock(snapshot_mutex);
    snapshot = std::move(next);
  }
  std::lock_guard<std::mutex> lock(changes_mutex);
  changes.push_back(std::move(change));
  while (static_cast<int>(changes.size()) > config.change_history) {
    history_start = changes.front().version;
    changes.pop_front();
  }
  changes_cv.notify_all();
}

SnapshotBuilder::Diff MapServer::Impl::PublishVersion(std::uint64_t version, MapChange::Kind kind,
                                                      KeyframeId keyframe_id) {
  SnapshotBuilder::Diff diff;
  auto next = snapshot_builder.Build(*mapper, version, &diff);
  Publish(std::move(next), MapChange{version, kind, keyframe_id, diff.added, diff.updated,
                                     diff.removed, diff.object_changes});
  return diff;
}

MapJob::Result MapServer::Impl::ApplyKeyframe(MapJob* job) {
  const auto start = Clock::now();
  const std::optional<Repeated> repeated = RepeatedView(*job);
  if (repeated && repeated->whole) return ApplyRevisit(job, repeated->revisit);
  // Repeated in part: only the part new to the map is mapped and stored.
  if (repeated) {
    std::vector<BoundingBox2D> boxes;
    for (const Detection& detection : job->detections) boxes.push_back(detection.box);
    KeepUnexplained(repeated->coverage, boxes, config.thinning, &job->frame.depth);
  }
  MapJob::Result out;
  KeyframeResult result;
  std::string why;
  mapper->SetSession(job->session.id);
  if (!mapper->AddKeyframe(job->frame, job->detections, &result, &why)) {
    out.status = ServiceStatus::Invalid(why);
    return out;
  }
  std::set<ObjectId> touched(result.created.begin(), result.created.end());
  touched.insert(result.updated.begin(), result.updated.end());
  std::vector<ObjectId> removed;
  for (const auto& [kept, absorbed] : result.merged) {
    touched.erase(absorbed);
    touched.insert(kept);
    removed.push_back(absorbed);
  }
  StoreChange change;
  change.keyframe = MakeStoredKeyframe(job->frame, job->detections, result.keyframe_id,
                                       *mapper->FindKeyframe(result.keyframe_id));
  change.keyframe->session_id = job->session.id;
  if (repeated) change.revisit = repeated->revisit;
  std::vector<StoredSession> ends;
  change.sessions = SessionsToStore(job->session, &ends);
  change.observations = NewObservations(mapper->objects(), touched, result.keyframe_id);
  change.merged = result.merged;
  for (ObjectId id : touched) {
    if (const MapObject* object = mapper->objects().Find(id)) {
      change.object_summaries.push_back(Summarize(*object));
    }
  }
  change.map_version = job->version;
  change.next_object_id = mapper->objects().next_id();
  if (!store->Commit(change, &why)) {
    out.status = {StatusCode::kInternal, "keyframe " + std::to_string(result.keyframe_id) +
                                             " was mapped but not stored: " + why};
    // The mapper now holds a keyframe the store lacks. Rebuilt from the store, the map is again
    // what a restart would give, and the keyframe's id is handed out again.
    std::uint64_t stored_version = 0;
    std::string reload_error;
    if (!RestoreFromStore(&stored_version, &reload_error)) {
      out.status.message += "; reloading the map from the store failed too: " + reload_error;
    }
    return out;
  }
  {
    std::lock_guard<std::mutex> lock(known_mutex);
    known_keyframes.insert(result.keyframe_id);
  }
  SessionsStored(job->session.id, ends);
  out.keyframe.session_id = job->session.id;
  snapshot_builder.AddKeyframe(result.keyframe_id, job->session.id, job->frame.stamp_s);
  if (repeated) {
    const StoredRevisit& revisit = repeated->revisit;
    snapshot_builder.AddRevisit(revisit.keyframe_id, revisit.session_id, revisit.stamp_s);
    out.keyframe.repeated_keyframe = revisit.keyframe_id;
    out.keyframe.explained_fraction = revisit.explained_fraction;
  }
  PublishVersion(job->version, MapChange::Kind::kKeyframeAdded, result.keyframe_id);

  ++keyframes_since_checkpoint;
  mapping_ms_since_checkpoint += MillisecondsSince(start);
  out.keyframe.keyframe_id = result.keyframe_id;
  out.keyframe.map_version = job->version;
  out.keyframe.detections_used = result.detections_used;
  out.keyframe.created = result.created;
  out.keyframe.updated = result.updated;
  out.keyframe.removed = removed;
  return out;
}

MapJob::Result MapServer::Impl::ApplyPoses(MapJob* job) {
  MapJob::Result out;
  const auto start = Clock::now();
  regenerating = true;
  std::string why;
  PoseUpdateReport report;
  const bool ok = mapper->UpdatePoses(job->poses, &why, &report);
  regenerating = false;
  if (!ok) {  // validated before queueing; only a bug gets here
    out.status = {StatusCode::kInternal, "regeneration failed: " + why};
    return out;
  }
  const double elapsed_ms = MillisecondsSince(start);
  SnapshotBuilder::Diff diff;
  auto next = snapshot_builder.Build(*mapper, job->version, &diff);
  // Objects regrouped: the store's observations are replaced by the new grouping; otherwise the
  // object summaries follow the moved models.
  StoreChange change = report.reassociated ? AllObjectsChange(*mapper) : StoreChange{};
  if (!report.reassociated) {
    for (ObjectId id : diff.changed_objects) {
      if (const MapObject* object = mapper->objects().Find(id)) {
        change.object_summaries.push_back(Summarize(*object));
      }
    }
  }
  change.map_version = job->version;
  {
    // Another queued pose update keeps the flag set: its poses are stored, not yet regenerated.
    // (This job is still at the front of the queue: Run() pops it after applying it.)
    std::lock_guard<std::mutex> lock(queue_mutex);
    const bool more_poses =
        std::any_of(queue.begin(), queue.end(), [job](const std::shared_ptr<MapJob>& queued) {
          return queued.get() != job && queued->kind == MapJob::Kind::kPoses;
        });
    if (!more_poses) change.pose_update_pending = false;
  }
  if (!store->Commit(change, &why)) {
    out.status = {StatusCode::kInternal, "regenerated map not recorded: " + why};
  }
  last_regeneration_ms = elapsed_ms;
  last_regeneration_version = job->version;
  if (report.keyframes_moved > 0) checkpoint_due = true;
  Publish(std::move(next), MapChange{job->version, MapChange::Kind::kPosesUpdated, 0, diff.added,
                                     diff.updated, diff.removed, diff.object_changes});
  out.poses.map_version = job->version;
  out.poses.regenerated = true;
  out.poses.keyframes_moved = report.keyframes_moved;
  out.poses.reassociated = report.reassociated;
  out.poses.objects_before = report.objects_before;
  out.poses.objects_after = report.objects_after;
  out.poses.regeneration_ms = elapsed_ms;
  return out;
}

ServiceStatus MapServer::Impl::LoadKnownKeyframe(KeyframeId id, StoredKeyframe* stored) const {
  {
    std::lock_guard<std::mutex> lock(known_mutex);
    if (known_keyframes.count(id) == 0) {
      return ServiceStatus::NotFound("keyframe " + std::to_string(id) + " is not in the map");
    }
  }
  std::string why;
  if (!store->LoadKeyframe(id, stored, &why)) return {StatusCode::kInternal, why};
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::KeyframeColor(KeyframeId id, ColorImage* color) const {
  StoredKeyframe stored;
  const ServiceStatus loaded = impl_->LoadKnownKeyframe(id, &stored);
  if (!loaded.ok()) return loaded;
  *color = std::move(stored.color);
  return ServiceStatus::Ok();
}

ServerStatus MapServer::Status() const {
  const auto snapshot = impl_->Current();
  ServerStatus status;
  status.map_version = snapshot->version;
  status.keyframes = snapshot->num_keyframes;
  status.objects = snapshot->objects.size();
  for (const InventoryEntry& entry : snapshot->inventory) status.confirmed_objects += entry.count;
  {
    std::lock_guard<std::mutex> lock(impl_->queue_mutex);
    status.queue_length = static_cast<int>(impl_->queue.size());
  }
  status.regenerating = impl_->regenerating;
  status.last_regeneration_ms = impl_->last_regeneration_ms;
  status.last_regeneration_version = impl_->last_regeneration_version;
  status.database = impl_->store->path();
  status.database_bytes = impl_->store->FileBytes();
  status.uptime_s = std::chrono::duration<double>(Clock::now() - impl_->started).count();
  status.checkpoint_version = impl_->checkpoint_version;
  status.last_checkpoint_ms = impl_->last_checkpoint_ms;
  status.startup_ms = impl_->startup_ms;
  status.startup_keyframes_integrated = impl_->startup_keyframes_integrated;
  impl_->mapper->ReadOccupancy(
      [&](const OccupancyMap& map) { status.occupancy_bytes = map.MemoryBytes(); });
  status.occupancy_copies = impl_->config.mapper.occupancy_second_copy ? 2 : 1;
  {
    std::lock_guard<std::mutex> lock(impl_->session_mutex);
    status.session_id = impl_->session.id;
    status.session_name = impl_->session.name;
  }
  return status;
}

std::vector<MapChange> MapServer::ChangesSince(std::uint64_t since_version,
                                               std::chrono::milliseconds timeout) const {
  std::unique_lock<std::mutex> lock(impl_->changes_mutex);
  // A version older than the remembered history (after a restart, say) is answered at once
  // with the summary below, not after the next change.
  auto newer = [&] {
    return impl_->shutting_down || since_version < impl_->history_start ||
           (!impl_->changes.empty() && impl_->changes.back().version > since_version);
  };
  if (!impl_->changes_cv.wait_for(lock, timeout, newer) || impl_->shutting_down) return {};
  const auto& changes = impl_->changes;
  if (since_version < impl_->history_start) {
    // Older than the history: summarize as every current object updated at the newest version.
    const auto snapshot = impl_->Current();
    MapChange summary;
    summary.version = snapshot->version;
    summary.kind = MapChange::Kind::kPosesUpdated;
    for (const auto& [id, view] : snapshot->objects) summary.updated.push_back(id);
    return {summary};
  }
  std::vector<MapChange> result;
  for (const MapChange& change : changes) {
    if (change.version > since_version) result.push_back(change);
  }
  return result;
}

void MapServer::Shutdown() {
  impl_->shutting_down = true;
  {
    std::lock_guard<std::mutex> lock(impl_->queue_mutex);
    impl_->stopping = true;
  }
  impl_->queue_cv.notify_all();
  {
    std::lock_guard<std::mutex> lock(impl_->changes_mutex);
    impl_->changes_cv.notify_all();
  }
}

bool MapServer::shutting_down() const { return impl_->shutting_down; }

}  // namespace objmap
