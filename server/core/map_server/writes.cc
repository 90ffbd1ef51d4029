// The writes clients call (AddKeyframe, UpdatePoses, WriteMapFolder): validated, the camera
// placed where the server places it (estimated poses, a session's own frame), queued for the
// mapping thread (map_server.cc), and answered once it has applied them.
#include "map_server/map_server.h"
#include "map_server/map_server_impl.h"

namespace objmap {

bool MapServer::estimates_poses() const { return impl_->odometry != nullptr; }

ServiceStatus MapServer::AddKeyframe(RgbdFrame frame,
                                     std::optional<std::vector<Detection>> detections,
                                     AddKeyframeOutcome* outcome) {
  std::string why;
  std::unique_lock<std::mutex> tracking;
  const bool session_frame = impl_->config.pose_source == PoseSource::kSessionFrame;
  if (impl_->odometry || session_frame) {
    tracking = std::unique_lock<std::mutex>(impl_->tracking_mutex);
  }
  const Eigen::Isometry3d given_pose = frame.T_W_C;
  if (impl_->odometry) {
    frame.T_W_C = Eigen::Isometry3d::Identity();  // ours to estimate; only the images are checked
  }
  if (!ValidateFrame(frame, &why)) return ServiceStatus::Invalid(why);
  if (impl_->shutting_down) return {StatusCode::kUnavailable, "the server is shutting down"};
  bool placed_session_frame = false;
  if (session_frame) {
    const ServiceStatus placed = impl_->PlaceInSessionFrame(&frame, &placed_session_frame);
    if (!placed.ok()) {
      *outcome = AddKeyframeOutcome{};
      outcome->untracked = placed.code == StatusCode::kFailedPrecondition;
      return placed;
    }
  }
  TrackingReport tracked;
  if (impl_->odometry) {
    if (!impl_->tracking_blocked.empty()) {
      return {StatusCode::kFailedPrecondition, impl_->tracking_blocked};
    }
    if (impl_->config.estimate_from_first_pose && impl_->odometry->num_keyframes() == 0) {
      // An empty map starts at the pose the first keyframe carries.
      if (!IsValidRigidTransform(given_pose.matrix(), &why)) {
        return ServiceStatus::Invalid("T_W_C (the map's start, server.estimate_from_first_pose): " +
                                      why);
      }
      RgbdFrame first = frame;
      first.T_W_C = given_pose;
      std::string why_not;
      if (impl_->odometry->StartFromKnownPose(first, &why_not)) {
        tracked.status = TrackingStatus::kInitialized;
        tracked.T_W_C = given_pose;
        tracked.reference_keyframe = 0;
        tracked.new_keyframe = true;
      } else {
        tracked.status = TrackingStatus::kLost;
        tracked.why = why_not;
      }
    } else {
      tracked = impl_->odometry->Track(frame);
    }
    const bool hold =
        tracked.status == TrackingStatus::kProvisional && impl_->config.max_held_keyframes > 0;
    if (tracked.status == TrackingStatus::kLost ||
        (tracked.status == TrackingStatus::kProvisional && !hold)) {
      *outcome = AddKeyframeOutcome{};
      outcome->untracked = true;
      return {StatusCode::kFailedPrecondition,
              frame.name + ": tracking lost (" + tracked.why +
                  "); the keyframe is not mapped: send one that overlaps the last ones"};
    }
    frame.T_W_C = tracked.T_W_C;
  }
  auto job = std::make_shared<MapJob>();
  if (detections) {
    job->detections = std::move(*detections);
  } else if (impl_->detector) {
    bool detected = false;
    // Unbounded: the request threads bound how many wait.
    (void)impl_->detector_thread->Run(
        [&] { detected = impl_->detector->Detect(frame, &job->detections, &why); });
    if (!detected) return ServiceStatus::Invalid("detector: " + why);
  }
  const Eigen::Isometry3d mapped_pose = frame.T_W_C;
  const std::string name = frame.name;
  job->frame = std::move(frame);
  {
    std::lock_guard<std::mutex> lock(impl_->session_mutex);
    job->session = impl_->session;
  }
  if (impl_->odometry && tracked.status == TrackingStatus::kProvisional) {
    const auto dropped = impl_->held_keyframes.Hold(
        job, tracked, *impl_->odometry, static_cast<std::size_t>(impl_->config.max_held_keyframes));
    const std::size_t held = impl_->held_keyframes.In(tracked.fragment);
    *outcome = AddKeyframeOutcome{};
    outcome->untracked = true;
    outcome->held = true;
    outcome->held_fragment = tracked.fragment;
    // The client learns which of the keyframes it sent will never be mapped.
    std::string dropped_note;
    if (!dropped.empty()) {
      dropped_note = "; beyond server.max_held_keyframes (" +
                     std::to_string(impl_->config.max_held_keyframes) + ") the oldest held " +
                     (dropped.size() == 1 ? "keyframe was" : "keyframes were") +
                     " dropped, never to be mapped:";
      for (const auto& old : dropped) dropped_note += " " + old.payload->frame.name;
    }
    return {StatusCode::kFailedPrecondition,
            name + ": not placed in the map yet (" + tracked.why + "); held in provisional part " +
                std::to_string(tracked.fragment) + " of the session (" + std::to_string(held) +
                " keyframes), in memory only: mapped at their poses once one of them is placed, "
                "lost if the server stops or a new session starts first" +
                dropped_note};
  }
  std::vector<KeyframeId> attached;
  if (impl_->odometry && tracked.attached_fragment > 0) {
    const ServiceStatus mapped = impl_->MapHeld(tracked.attached_fragment, &attached);
    if (!mapped.ok()) return mapped;
  }
  const std::shared_future<MapJob::Result> done = job->result;
  ServiceStatus queued = impl_->Enqueue(job, /*bounded=*/true);
  if (!queued.ok()) return queued;
  MapJob::Result result = done.get();
  if (!result.status.ok()) return result.status;
  *outcome = std::move(result.keyframe);
  outcome->attached = std::move(attached);
  outcome->T_W_C = mapped_pose;
  outcome->relocalized = placed_session_frame;
  if (!impl_->odometry) return result.status;
  // A revisit is no keyframe of the map: it follows the keyframe it repeated, not the odometry.
  if (outcome->keyframe_id != 0) {
    impl_->tracked_keyframes.Add(outcome->keyframe_id, tracked, *impl_->odometry);
  }
  outcome->loops_closed = tracked.loops_closed;
  outcome->relocalized = tracked.status == TrackingStatus::kRelocalized;
  if (tracked.loops_closed == 0) return result.status;
  // A loop closed: every tracked keyframe follows the odometry keyframe it was tracked against
  // (none, while every keyframe of the session so far was a revisit of a stored view).
  const std::map<KeyframeId, Eigen::Isometry3d> moved =
      impl_->tracked_keyframes.Poses(*impl_->odometry);
  if (moved.empty()) return result.status;
  PoseUpdateOutcome update;
  const ServiceStatus updated = UpdatePoses(moved, /*wait=*/false, &update);
  if (!updated.ok()) {
    return {updated.code, "keyframe " + std::to_string(outcome->keyframe_id) +
                              " is mapped, but the poses of the loop it closed are not: " +
                              updated.message};
  }
  return result.status;
}

ServiceStatus MapServer::Impl::MapHeld(int fragment, std::vector<KeyframeId>* mapped) {
  for (auto& held : held_keyframes.Take(fragment)) {
    // The fragment now lies in the map's frame: each keyframe where its odometry keyframe went.
    held.payload->frame.T_W_C = held.T_W_C(*odometry);
    const std::shared_future<MapJob::Result> done = held.payload->result;
    const ServiceStatus queued = Enqueue(held.payload, /*bounded=*/true);
    if (!queued.ok()) {
      return {queued.code, "the held keyframes of the part just placed: " + queued.message};
    }
    const MapJob::Result result = done.get();
    if (!result.status.ok()) {
      return {result.status.code, "a held keyframe of the part just placed (" +
                                      held.payload->frame.name + "): " + result.status.message};
    }
    if (result.keyframe.keyframe_id == 0) continue;  // kept as a revisit only
    tracked_keyframes.AddRelative(result.keyframe.keyframe_id, held.odometry_keyframe, held.T_K_C);
    mapped->push_back(result.keyframe.keyframe_id);
  }
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::UpdatePoses(const std::map<KeyframeId, Eigen::Isometry3d>& poses,
                                     bool wait, PoseUpdateOutcome* outcome) {
  if (poses.empty()) return ServiceStatus::Invalid("poses: empty");
  {
    std::lock_guard<std::mutex> lock(impl_->known_mutex);
    for (const auto& [id, T_W_C] : poses) {
      if (impl_->known_keyframes.count(id) == 0) {
        return ServiceStatus::NotFound("poses: unknown keyframe id " + std::to_string(id));
      }
    }
  }
  for (const auto& [id, T_W_C] : poses) {
    std::string why;
    if (!IsValidRigidTransform(T_W_C.matrix(), &why)) {
      return ServiceStatus::Invalid("poses[keyframe " + std::to_string(id) + "]: " + why);
    }
  }
  auto job = std::make_shared<MapJob>();
  job->kind = MapJob::Kind::kPoses;
  job->poses = poses;
  {
    // Durable before acknowledging (a restart regenerates with these poses), and stored and
    // queued under the queue lock, so that a shutdown cannot fall between the two: poses the
    // caller is told were refused are never stored.
    std::lock_guard<std::mutex> lock(impl_->queue_mutex);
    if (impl_->stopping) return {StatusCode::kUnavailable, "the server is shutting down"};
    StoreChange change;
    change.poses = poses;
    change.pose_update_pending = true;  // until the regeneration's commit clears it
    std::string why;
    if (!impl_->store->Commit(change, &why)) {
      return {StatusCode::kInternal, "poses not stored: " + why};
    }
    // A pose update queued behind another that has not started joins it: one regeneration
    // applies both (later poses win), so a flood of small updates costs one regeneration, not
    // one each, and the queue holds at most one waiting pose update.
    std::deque<std::shared_ptr<MapJob>>& queue = impl_->queue;
    if (!queue.empty() && queue.back()->kind == MapJob::Kind::kPoses &&
        queue.back().get() != impl_->applying) {
      for (const auto& [id, T_W_C] : poses) queue.back()->poses[id] = T_W_C;
      job = queue.back();
    } else {
      ServiceStatus queued = impl_->EnqueueLocked(job, /*bounded=*/false);
      if (!queued.ok()) return queued;
    }
  }
  const std::shared_future<MapJob::Result> done = job->result;
  *outcome = PoseUpdateOutcome{};
  outcome->map_version = job->version;
  if (!wait) return ServiceStatus::Ok();
  MapJob::Result result = done.get();
  if (result.status.ok()) *outcome = result.poses;
  return result.status;
}

ServiceStatus MapServer::WriteMapFolder(const std::string& dir) {
  if (dir.empty()) return ServiceStatus::Invalid("folder: empty");
  auto job = std::make_shared<MapJob>();
  job->kind = MapJob::Kind::kWriteFolder;
  job->folder = dir;
  const std::shared_future<MapJob::Result> done = job->result;
  ServiceStatus queued = impl_->Enqueue(job, /*bounded=*/false);
  if (!queued.ok()) return queued;
  return done.get().status;
}

}  // namespace objmap
