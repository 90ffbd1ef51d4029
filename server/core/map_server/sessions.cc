// Sessions (runs of keyframes into one map) and where tracking starts in a session: the stored
// map's keyframes, so that the camera is placed in the saved map wherever it starts.

#include <algorithm>
#include <chrono>

#include "map_server/map_server.h"
#include "map_server/map_server_impl.h"
#include "objects/observation_segment.h"

namespace objmap {
namespace {

double WallClockSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A session name is shown in tables and stored: printable, one line, not too long.
bool ValidSessionName(const std::string& name, std::string* why) {
  constexpr std::size_t kMaxBytes = 200;
  if (name.size() > kMaxBytes) {
    *why = "name: " + std::to_string(name.size()) + " bytes, at most " +
           std::to_string(kMaxBytes);
    return false;
  }
  for (const char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      *why = "name: control characters are not allowed";
      return false;
    }
  }
  return true;
}

}  // namespace

void MapServer::Impl::BeginSessionLocked(SessionId previous_id, const std::string& name) {
  session = StoredSession{};
  session.id = previous_id + 1;
  session.name = name.empty() ? "session " + std::to_string(session.id) : name;
  session.pose_source = PoseSourceName(config.pose_source);
  session.started_s = WallClockSeconds();
}

void MapServer::Impl::StoreSessionEnds(bool end_current) {
  StoreChange change;
  {
    std::lock_guard<std::mutex> lock(session_mutex);
    for (const StoredSession& ended : ended_sessions) {
      if (stored_sessions.count(ended.id) > 0) change.sessions.push_back(ended);
    }
    if (end_current && stored_sessions.count(session.id) > 0) {
      StoredSession ended = session;
      ended.ended_s = WallClockSeconds();
      change.sessions.push_back(ended);
    }
  }
  std::string why;
  // Losing an end time loses no keyframe: the session then reads as ended by its process.
  if (!change.sessions.empty()) (void)store->Commit(change, &why);
}

ServiceStatus MapServer::StartSession(const std::string& name, SessionSummary* started) {
  std::string why;
  if (!ValidSessionName(name, &why)) return ServiceStatus::Invalid(why);
  if (impl_->shutting_down) return {StatusCode::kUnavailable, "the server is shutting down"};
  // With estimated poses or poses in a session's frame, no keyframe is being placed while
  // tracking starts over.
  const bool session_frame = impl_->config.pose_source == PoseSource::kSessionFrame;
  std::unique_lock<std::mutex> tracking;
  if (impl_->odometry || session_frame) {
    tracking = std::unique_lock<std::mutex>(impl_->tracking_mutex);
  }
  StoredSession begun;
  {
    std::lock_guard<std::mutex> lock(impl_->session_mutex);
    StoredSession ended = impl_->session;
    if (impl_->stored_sessions.count(ended.id) > 0) {
      ended.ended_s = WallClockSeconds();
      impl_->ended_sessions.push_back(ended);
      impl_->BeginSessionLocked(ended.id, name);
    } else {
      // Nothing was mapped in the current session: the new one takes its place and id (a
      // client that names its run right after a start leaves no empty session behind).
      impl_->BeginSessionLocked(ended.id - 1, name);
    }
    begun = impl_->session;
  }
  impl_->BeginSessionTracking(*this);
  if (started != nullptr) {
    *started = SessionSummary{};
    started->session = begun;
  }
  return ServiceStatus::Ok();
}

void MapServer::Impl::BeginSessionTracking(const MapServer& server) {
  RgbdOdometry* tracker = nullptr;
  if (config.pose_source == PoseSource::kEstimate) {
    odometry = std::make_unique<RgbdOdometry>(config.odometry);
    tracked_keyframes = TrackedKeyframes{};
    // Held keyframes lie on the old odometry's keyframes: a new session cannot place them.
    held_keyframes.Clear();
    tracker = odometry.get();
  } else if (config.pose_source == PoseSource::kSessionFrame) {
    T_map_session.reset();
    session_placer = std::make_unique<RgbdOdometry>(config.odometry);
    tracker = session_placer.get();
  } else {
    return;
  }
  std::string resumed_from;
  tracking_blocked = server.StartTrackingOnStoredMap(tracker, &resumed_from).message;
}

ServiceStatus MapServer::Impl::PlaceInSessionFrame(RgbdFrame* frame, bool* placed_now) {
  *placed_now = false;
  if (T_map_session) {
    frame->T_W_C = *T_map_session * frame->T_W_C;
    return ServiceStatus::Ok();
  }
  bool map_empty = false;
  {
    std::lock_guard<std::mutex> lock(known_mutex);
    map_empty = known_keyframes.empty();
  }
  // The first session of a map defines the map's frame.
  if (map_empty) {
    T_map_session = Eigen::Isometry3d::Identity();
    return ServiceStatus::Ok();
  }
  if (!tracking_blocked.empty()) return {StatusCode::kFailedPrecondition, tracking_blocked};
  const TrackingReport report = session_placer->Track(*frame);
  // Tracked in a provisional fragment of its own is not placed either: the session's frame is
  // known once a keyframe is placed in the map's.
  if (report.status == TrackingStatus::kLost || report.fragment != 0) {
    return {StatusCode::kFailedPrecondition,
            frame->name + ": its session's frame is not placed in the map yet (" + report.why +
                "); the session's keyframes are mapped once one of them is placed"};
  }
  T_map_session = report.T_W_C * frame->T_W_C.inverse();
  frame->T_W_C = report.T_W_C;
  *placed_now = true;
  session_placer.reset();  // its keyframes' features are not needed until the next session
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::ListSessions(std::vector<SessionSummary>* sessions,
                                      SessionId* current) const {
  StoredSession now;
  {
    std::lock_guard<std::mutex> lock(impl_->session_mutex);
    now = impl_->session;
  }
  std::string why;
  if (!impl_->store->ListSessions(sessions, &why)) return {StatusCode::kInternal, why};
  const bool stored = std::any_of(sessions->begin(), sessions->end(), [&](const SessionSummary& s) {
    return s.session.id == now.id;
  });
  if (!stored) {
    SessionSummary& summary = sessions->emplace_back();
    summary.session = now;
  }
  if (current != nullptr) *current = now.id;
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::NewestKeyframe(RgbdFrame* frame) const {
  KeyframeId newest = 0;
  {
    std::lock_guard<std::mutex> lock(impl_->known_mutex);
    if (impl_->known_keyframes.empty()) return ServiceStatus::NotFound("the map has no keyframe");
    newest = *impl_->known_keyframes.rbegin();
  }
  return StoredFrame(newest, frame);
}

ServiceStatus MapServer::StoredFrame(KeyframeId id, RgbdFrame* frame) const {
  StoredKeyframe stored;
  const ServiceStatus loaded = impl_->LoadKnownKeyframe(id, &stored);
  if (!loaded.ok()) return loaded;
  *frame = RgbdFrame();
  frame->stamp_s = stored.stamp_s;
  frame->name = "stored keyframe " + std::to_string(id);
  frame->intrinsics = stored.intrinsics;
  frame->T_W_C = stored.T_W_C;
  frame->color = std::move(stored.color);
  frame->depth.width = stored.intrinsics.width;
  frame->depth.height = stored.intrinsics.height;
  frame->depth.depth_m.reserve(stored.depth_mm.size());
  for (const std::uint16_t mm : stored.depth_mm)
    frame->depth.depth_m.push_back(DepthSampleMetres(mm));
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::StartTrackingOnStoredMap(RgbdOdometry* odometry,
                                                  std::string* resumed_from) const {
  std::vector<KeyframeId> ids;
  {
    std::lock_guard<std::mutex> lock(impl_->known_mutex);
    ids.assign(impl_->known_keyframes.begin(), impl_->known_keyframes.end());
  }
  if (ids.empty()) return ServiceStatus::Ok();
  const auto limit = static_cast<std::size_t>(impl_->config.relocalisation_map_keyframes);
  if (limit > 0 && ids.size() > limit) {
    ids.erase(ids.begin(), ids.end() - static_cast<std::ptrdiff_t>(limit));
  }
  std::string newest, last_failure;
  for (const KeyframeId id : ids) {
    RgbdFrame frame;
    const ServiceStatus loaded = StoredFrame(id, &frame);
    if (!loaded.ok()) {
      return {StatusCode::kFailedPrecondition,
              "tracking cannot resume on the stored map: " + loaded.message};
    }
    // A keyframe without colour or texture is left out: the others place the camera.
    std::string why;
    if (odometry->AddMapKeyframe(frame, &why)) {
      newest = frame.name;
    } else {
      last_failure = frame.name + ": " + why;
    }
  }
  if (newest.empty()) {
    return {StatusCode::kFailedPrecondition,
            "tracking cannot resume on the stored map (no stored keyframe can be tracked from; " +
                last_failure + ")"};
  }
  *resumed_from = newest;
  return ServiceStatus::Ok();
}

std::vector<StoredSession> MapServer::Impl::SessionsToStore(const StoredSession& session,
                                                            std::vector<StoredSession>* ends) {
  // The session is stored with its first keyframe (or revisit), and the ends of the sessions
  // before it that are stored.
  std::vector<StoredSession> sessions;
  std::lock_guard<std::mutex> lock(session_mutex);
  if (stored_sessions.count(session.id) == 0) sessions.push_back(session);
  for (const StoredSession& ended : ended_sessions) {
    if (stored_sessions.count(ended.id) > 0) ends->push_back(ended);
  }
  sessions.insert(sessions.end(), ends->begin(), ends->end());
  return sessions;
}

void MapServer::Impl::SessionsStored(SessionId session_id, const std::vector<StoredSession>& ends) {
  std::lock_guard<std::mutex> lock(session_mutex);
  stored_sessions.insert(session_id);
  for (const StoredSession& stored_end : ends) {
    ended_sessions.erase(
        std::remove_if(ended_sessions.begin(), ended_sessions.end(),
                       [&](const StoredSession& s) { return s.id == stored_end.id; }),
        ended_sessions.end());
  }
}

}  // namespace objmap
