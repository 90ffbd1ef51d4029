// Thinning of revisit sessions (MapServerConfig::thinning): a keyframe that repeats the view of
// stored keyframes of earlier sessions, nothing changed, is stored as a revisit of that view.
#include <algorithm>

#include "map_server/map_server_impl.h"

namespace objmap {

std::optional<MapServer::Impl::Repeated> MapServer::Impl::RepeatedView(const MapJob& job) const {
  const RevisitThinningConfig& thinning = config.thinning;
  if (!thinning.enabled || job.frame.depth.empty()) return std::nullopt;
  // Nearest first: camera distance, with a degree of axis angle weighing as much as a cm.
  std::vector<std::pair<double, KeyframeId>> nearby;
  {
    // Scanned under the lock rather than copied out of it: the scan is short.
    std::lock_guard<std::mutex> lock(known_mutex);
    for (KeyframeId id : known_keyframes) {
      const SessionId session = snapshot_builder.Seen(id).session_id;
      if (session <= 0 || session >= job.session.id) continue;
      const KeyframeRecord* record = mapper->FindKeyframe(id);
      if (record == nullptr || !IsNearbyView(record->T_W_C, job.frame.T_W_C, thinning)) continue;
      const Eigen::Quaterniond relative(record->T_W_C.linear().transpose() *
                                        job.frame.T_W_C.linear());
      const double distance_m =
          (record->T_W_C.translation() - job.frame.T_W_C.translation()).norm() +
          0.01 * Eigen::AngleAxisd(relative).angle() * 180.0 / M_PI;
      nearby.emplace_back(distance_m, id);
    }
  }
  if (nearby.empty()) return std::nullopt;
  std::sort(nearby.begin(), nearby.end());
  if (nearby.size() > static_cast<std::size_t>(thinning.max_views)) {
    nearby.resize(static_cast<std::size_t>(thinning.max_views));
  }
  std::vector<StoredView> views;
  for (const auto& [distance_m, id] : nearby) {
    const KeyframeRecord* record = mapper->FindKeyframe(id);
    views.push_back(StoredView{id, record->T_W_C, &record->intrinsics, &record->depth_mm});
  }
  ViewCoverage coverage =
      CoverageOf(job.frame.depth, job.frame.intrinsics, job.frame.T_W_C, views, thinning);
  if ((!coverage.repeated && !coverage.repeated_in_part) || coverage.best_keyframe == 0) {
    return std::nullopt;
  }
  Repeated repeated;
  repeated.whole = coverage.repeated;
  StoredRevisit& revisit = repeated.revisit;
  revisit.session_id = job.session.id;
  revisit.stamp_s = job.frame.stamp_s;
  revisit.name = job.frame.name;
  revisit.keyframe_id = coverage.best_keyframe;
  revisit.T_K_C = mapper->FindKeyframe(coverage.best_keyframe)->T_W_C.inverse() * job.frame.T_W_C;
  revisit.explained_fraction = coverage.explained_fraction;
  repeated.coverage = std::move(coverage);
  return repeated;
}

MapJob::Result MapServer::Impl::ApplyRevisit(MapJob* job, StoredRevisit revisit) {
  MapJob::Result out;
  StoreChange change;
  std::vector<StoredSession> ends;
  change.sessions = SessionsToStore(job->session, &ends);
  change.revisit = revisit;
  change.map_version = job->version;
  std::string why;
  if (!store->Commit(change, &why)) {
    out.status = {StatusCode::kInternal, job->frame.name + " repeats the view of keyframe " +
                                             std::to_string(revisit.keyframe_id) +
                                             "; its revisit was not stored: " + why};
    return out;
  }
  SessionsStored(job->session.id, ends);
  snapshot_builder.AddRevisit(revisit.keyframe_id, revisit.session_id, revisit.stamp_s);
  const SnapshotBuilder::Diff diff =
      PublishVersion(job->version, MapChange::Kind::kKeyframeRepeated, revisit.keyframe_id);
  out.keyframe.session_id = job->session.id;
  out.keyframe.map_version = job->version;
  out.keyframe.repeated_keyframe = revisit.keyframe_id;
  out.keyframe.explained_fraction = revisit.explained_fraction;
  out.keyframe.updated = diff.changed_objects;
  return out;
}

}  // namespace objmap
