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
    tracked = impl_->odometry->Track(frame);
    if (tracked.status == TrackingStatus::kLost) {
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
  job->frame = std::move(frame);
  {
    std::lock_guard<std::mutex> lock(impl_->session_mutex);
    job->session = impl_->session;
  }
  const std::shared_future<MapJob::Result> done = job->result;
  ServiceStatus queued = impl_->Enqueue(job, /*bounded=*/true);
  if (!queued.ok()) return queued;
  MapJob::Result result = done.get();
  if (!result.status.ok()) return result.status;
  *outcome = std::move(result.keyframe);
  outcome->T_W_C = mapped_pose;
  outcome->relocalized = placed_session_frame;
  if (!impl_->odometry) return result.status;
  impl_->tracked_keyframes.Add(outcome->keyframe_id, tracked, *impl_->odometry);
  outcome->loops_closed = tracked.loops_closed;
  outcome->relocalized = tracked.status == TrackingStatus::kRelocalized;
  if (tracked.loops_closed == 0) return result.status;
  // A loop closed: every tracked keyframe follows the odometry keyframe it was tracked against.
  PoseUpdateOutcome update;
  const ServiceStatus updated =
      UpdatePoses(impl_->tracked_keyframes.Poses(*impl_->odometry), /*wait=*/false, &update);
  if (!updated.ok()) {
    return {updated.code, "keyframe " + std::to_string(outcome->keyframe_id) +
                              " is mapped, but the poses of the loop it closed are not: " +
                              updated.message};
  }
  return result.status;
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
