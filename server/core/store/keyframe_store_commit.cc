// KeyframeStore::Commit: validation and encoding outside the write lock, then one transaction.

#include <cmath>
#include <initializer_list>
#include <optional>
#include <utility>

#include "store/keyframe_codec.h"
#include "store/keyframe_store.h"
#include "store/store_impl.h"

namespace objmap {
namespace {

using store_internal::Bytes;
using store_internal::Connection;

struct EncodedKeyframe {
  Bytes pose, depth_png, mask_png, color_jpeg, detections;
};

bool IsFinite(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

// Sizes are checked here, before anything is written, so the reason can name the field.
bool CheckKeyframe(const StoredKeyframe& keyframe, std::string* why) {
  const std::string prefix = "keyframe " + std::to_string(keyframe.id) + ": ";
  const CameraIntrinsics& k = keyframe.intrinsics;
  if (!k.IsValid(why)) {
    *why = prefix + "intrinsics: " + *why;
    return false;
  }
  const std::size_t pixels = static_cast<std::size_t>(k.width) * k.height;
  const std::string size = std::to_string(k.width) + "x" + std::to_string(k.height);
  if (keyframe.depth_mm.size() != pixels) {
    *why = prefix + "depth_mm has " + std::to_string(keyframe.depth_mm.size()) +
           " values, intrinsics are " + size;
  } else if (keyframe.object_mask.size() != pixels) {
    *why = prefix + "object_mask has " + std::to_string(keyframe.object_mask.size()) +
           " values, intrinsics are " + size;
  } else if (!keyframe.color.empty() &&
             (keyframe.color.width != k.width || keyframe.color.height != k.height ||
              keyframe.color.rgb.size() != 3 * pixels)) {
    *why = prefix + "color is " + std::to_string(keyframe.color.width) + "x" +
           std::to_string(keyframe.color.height) + " with " +
           std::to_string(keyframe.color.rgb.size()) + " bytes, intrinsics are " + size;
  } else if (!IsFinite(keyframe.T_W_C)) {
    *why = prefix + "T_W_C is not finite";
  } else {
    return true;
  }
  return false;
}

bool EncodeKeyframe(const StoredKeyframe& keyframe, int jpeg_quality, EncodedKeyframe* encoded,
                    std::string* why) {
  if (!CheckKeyframe(keyframe, why)) return false;
  const int width = keyframe.intrinsics.width, height = keyframe.intrinsics.height;
  const std::string prefix = "keyframe " + std::to_string(keyframe.id) + ": ";
  std::string reason;
  if (!store_internal::EncodeDepthPng(keyframe.depth_mm, width, height, &encoded->depth_png,
                                      &reason) ||
      !store_internal::EncodeMaskPng(keyframe.object_mask, width, height, &encoded->mask_png,
                                     &reason) ||
      (!keyframe.color.empty() &&
       !store_internal::EncodeColorJpeg(keyframe.color, jpeg_quality, &encoded->color_jpeg,
                                        &reason))) {
    *why = prefix + reason;
    return false;
  }
  encoded->pose = store_internal::PackPose(keyframe.T_W_C);
  encoded->detections = store_internal::PackDetections(keyframe.detections);
  return true;
}

bool CheckChange(const StoreChange& change, std::string* why) {
  if (change.keyframe && change.keyframe->session_id <= 0) {
    *why = "keyframe " + std::to_string(change.keyframe->id) + ": session id " +
           std::to_string(change.keyframe->session_id) + " is not positive";
    return false;
  }
  for (const StoredSession& session : change.sessions) {
    if (session.id <= 0) {
      *why = "session id " + std::to_string(session.id) + " is not positive";
      return false;
    }
    if ((session.started_s && !std::isfinite(*session.started_s)) ||
        (session.ended_s && !std::isfinite(*session.ended_s))) {
      *why = "session " + std::to_string(session.id) + ": its times must be finite";
      return false;
    }
  }
  for (const StoredObservation& o : change.observations) {
    const ColoredPoints& segment = o.observation.segment_C;
    if (!segment.colors.empty() && segment.colors.size() != segment.points.size()) {
      *why = "observation of object " + std::to_string(o.object_id) + " in keyframe " +
             std::to_string(o.observation.keyframe_id) + ": segment_C has " +
             std::to_string(segment.points.size()) + " points but " +
             std::to_string(segment.colors.size()) + " colors";
      return false;
    }
  }
  if (change.revisit &&
      (change.revisit->session_id <= 0 || !std::isfinite(change.revisit->stamp_s) ||
       !IsFinite(change.revisit->T_K_C) || !std::isfinite(change.revisit->explained_fraction))) {
    *why = "revisit of keyframe " + std::to_string(change.revisit->keyframe_id) +
           ": its session id must be positive, its stamp, pose and explained share finite";
    return false;
  }
  for (const auto& [id, T_W_C] : change.poses) {
    if (!IsFinite(T_W_C)) {
      *why = "pose of keyframe " + std::to_string(id) + " is not finite";
      return false;
    }
  }
  return true;
}

bool InsertKeyframe(Connection* db, const StoredKeyframe& k, const EncodedKeyframe& e,
                    std::string* why) {
  auto insert = db->Prepare(
      "INSERT INTO keyframes(id, stamp_s, name, T_W_C, width, height, fx, fy, cx, cy, depth_png,"
      " mask_png, color_jpeg, detections, session_id)"
      " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
      "insert keyframe " + std::to_string(k.id), why);
  if (!insert) return false;
  insert->Bind(1, std::int64_t{k.id}).Bind(2, k.stamp_s).Bind(3, k.name);
  insert->BindBlob(4, e.pose.data(), e.pose.size());
  insert->Bind(5, std::int64_t{k.intrinsics.width}).Bind(6, std::int64_t{k.intrinsics.height});
  insert->Bind(7, k.intrinsics.fx).Bind(8, k.intrinsics.fy);
  insert->Bind(9, k.intrinsics.cx).Bind(10, k.intrinsics.cy);
  insert->BindBlob(11, e.depth_png.data(), e.depth_png.size());
  insert->BindBlob(12, e.mask_png.data(), e.mask_png.size());
  if (k.color.empty()) {
    insert->BindNull(13);
  } else {
    insert->BindBlob(13, e.color_jpeg.data(), e.color_jpeg.size());
  }
  insert->BindBlob(14, e.detections.data(), e.detections.size());
  insert->Bind(15, std::int64_t{k.session_id});
  if (insert->Run(why)) return true;
  if (insert->error_code() == SQLITE_CONSTRAINT_PRIMARYKEY) {
    *why = "keyframe id " + std::to_string(k.id) + " already exists";
  }
  return false;
}

bool PutSession(Connection* db, const StoredSession& session, std::string* why) {
  auto put = db->Prepare(
      "INSERT OR REPLACE INTO sessions(id, name, pose_source, started_s, ended_s)"
      " VALUES (?, ?, ?, ?, ?)",
      "store session " + std::to_string(session.id), why);
  if (!put) return false;
  put->Bind(1, std::int64_t{session.id}).Bind(2, session.name).Bind(3, session.pose_source);
  if (session.started_s) {
    put->Bind(4, *session.started_s);
  } else {
    put->BindNull(4);
  }
  if (session.ended_s) {
    put->Bind(5, *session.ended_s);
  } else {
    put->BindNull(5);
  }
  return put->Run(why);
}

// A keyframe's session is stored with it when it is not stored yet: under its id alone when
// the change did not describe it (a caller that knows nothing of sessions maps into session 1).
bool EnsureKeyframeSession(Connection* db, const StoredKeyframe& k, std::string* why) {
  auto ensure = db->Prepare(
      "INSERT OR IGNORE INTO sessions(id, name, pose_source, started_s, ended_s)"
      " VALUES (?, ?, '', NULL, NULL)",
      "store the session of keyframe " + std::to_string(k.id), why);
  return ensure && ensure->Bind(1, std::int64_t{k.session_id})
                       .Bind(2, "session " + std::to_string(k.session_id))
                       .Run(why);
}

bool InsertRevisit(Connection* db, const StoredRevisit& r, std::string* why) {
  const Bytes pose = store_internal::PackPose(r.T_K_C);
  auto insert = db->Prepare(
      "INSERT INTO revisits(session_id, stamp_s, name, keyframe_id, T_K_C, explained)"
      " VALUES (?, ?, ?, ?, ?, ?)",
      "insert the revisit of keyframe " + std::to_string(r.keyframe_id), why);
  if (!insert) return false;
  insert->Bind(1, std::int64_t{r.session_id}).Bind(2, r.stamp_s).Bind(3, r.name);
  insert->Bind(4, std::int64_t{r.keyframe_id}).BindBlob(5, pose.data(), pose.size());
  insert->Bind(6, static_cast<double>(r.explained_fraction));
  if (insert->Run(why)) return true;
  if (insert->error_code() == SQLITE_CONSTRAINT_FOREIGNKEY) {
    *why = "revisit of unknown keyframe id " + std::to_string(r.keyframe_id);
  }
  return false;
}

// An observation whose points its pixels rebuild (ObjectObservation::segment_pixels).
bool IsKeptAsPixels(const ObjectObservation& observation) {
  return !observation.segment_pixels.empty() && observation.segment_voxel_size_m > 0.f &&
         std::isfinite(observation.segment_voxel_size_m) && !observation.segment_C.empty();
}

bool InsertObservation(Connection* db, const StoredObservation& o, std::string* why) {
  const ObjectObservation& obs = o.observation;
  auto insert = db->Prepare(
      "INSERT INTO observations(object_id, keyframe_id, box_x_min, box_y_min, box_x_max,"
      " box_y_max, class_scores, points, colors, pixels) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
      "insert observation of object " + std::to_string(o.object_id), why);
  if (!insert) return false;
  const Bytes scores = store_internal::PackClassScores(obs.class_scores);
  // Points made from the keyframe's stored depth are rebuilt from it (LoadAll): their pixels
  // are kept instead. Their colours stay (the stored colour image is lossy), as a PNG.
  const bool as_pixels = IsKeptAsPixels(obs);
  const Bytes points = as_pixels ? Bytes{} : store_internal::PackPoints(obs.segment_C);
  const Bytes pixels = as_pixels
                           ? store_internal::PackSegmentPixels(
                                 obs.segment_pixels, obs.segment_voxel_size_m, obs.segment_C.size())
                           : Bytes{};
  Bytes colors;
  if (!as_pixels) {
    colors = store_internal::PackColors(obs.segment_C);
  } else if (!store_internal::EncodeSegmentColorsPng(obs.segment_C.colors, &colors, why)) {
    *why = "observation of object " + std::to_string(o.object_id) + ": " + *why;
    return false;
  }
  insert->Bind(1, std::int64_t{o.object_id}).Bind(2, std::int64_t{obs.keyframe_id});
  insert->Bind(3, double{obs.box.x_min}).Bind(4, double{obs.box.y_min});
  insert->Bind(5, double{obs.box.x_max}).Bind(6, double{obs.box.y_max});
  insert->BindBlob(7, scores.data(), scores.size());
  insert->BindBlob(8, points.data(), points.size());
  insert->BindBlob(9, colors.data(), colors.size());
  insert->BindBlob(10, pixels.data(), pixels.size());
  if (insert->Run(why)) return true;
  if (insert->error_code() == SQLITE_CONSTRAINT_FOREIGNKEY) {
    *why = "observation of object " + std::to_string(o.object_id) + ": unknown keyframe id " +
           std::to_string(obs.keyframe_id);
  }
  return false;
}

// Runs `sql` with `ids` bound in order; *changed (optional) gets the number of changed rows.
bool RunWithIds(Connection* db, const char* sql, const std::string& label,
                std::initializer_list<std::int64_t> ids, std::string* why, int* changed = nullptr) {
  auto statement = db->Prepare(sql, label, why);
  if (!statement) return false;
  int index = 1;
  for (const std::int64_t id : ids) statement->Bind(index++, id);
  if (!statement->Run(why)) return false;
  if (changed != nullptr) *changed = db->changes();
  return true;
}

bool ApplyObjectChanges(Connection* db, const StoreChange& change, std::string* why) {
  if (change.replace_all_objects &&
      !(db->Exec("DELETE FROM observations", why) && db->Exec("DELETE FROM objects", why))) {
    return false;
  }
  for (const StoredObservation& o : change.observations) {
    if (!InsertObservation(db, o, why)) return false;
  }
  for (const auto& [kept, absorbed] : change.merged) {
    const std::string label =
        "merge object " + std::to_string(absorbed) + " into " + std::to_string(kept);
    if (!RunWithIds(db, "UPDATE observations SET object_id = ? WHERE object_id = ?", label,
                    {kept, absorbed}, why) ||
        !RunWithIds(db, "DELETE FROM objects WHERE id = ?", label, {absorbed}, why)) {
      return false;
    }
  }
  for (const ObjectId id : change.removed_objects) {
    const std::string label = "remove object " + std::to_string(id);
    if (!RunWithIds(db, "DELETE FROM observations WHERE object_id = ?", label, {id}, why) ||
        !RunWithIds(db, "DELETE FROM objects WHERE id = ?", label, {id}, why)) {
      return false;
    }
  }
  for (const StoredObjectSummary& s : change.object_summaries) {
    auto upsert = db->Prepare(
        "INSERT OR REPLACE INTO objects(id, class_id, confidence, centroid_x, centroid_y,"
        " centroid_z, observations) VALUES (?, ?, ?, ?, ?, ?, ?)",
        "store summary of object " + std::to_string(s.id), why);
    if (!upsert) return false;
    upsert->Bind(1, std::int64_t{s.id}).Bind(2, std::int64_t{s.class_id});
    upsert->Bind(3, double{s.confidence}).Bind(4, double{s.centroid_W.x()});
    upsert->Bind(5, double{s.centroid_W.y()}).Bind(6, double{s.centroid_W.z()});
    if (!upsert->Bind(7, std::int64_t{s.observations}).Run(why)) return false;
  }
  return true;
}

bool SetMeta(Connection* db, const std::string& key, std::int64_t value, std::string* why) {
  auto statement =
      db->Prepare("INSERT OR REPLACE INTO meta(key, value) VALUES (?, ?)", "store " + key, why);
  return statement && statement->Bind(1, key).Bind(2, value).Run(why);
}

bool ApplyPosesAndMeta(Connection* db, const StoreChange& change, std::string* why) {
  for (const auto& [id, T_W_C] : change.poses) {
    auto update = db->Prepare("UPDATE keyframes SET T_W_C = ? WHERE id = ?",
                              "update pose of keyframe " + std::to_string(id), why);
    const Bytes pose = store_internal::PackPose(T_W_C);
    if (!update || !update->BindBlob(1, pose.data(), pose.size()).Bind(2, id).Run(why)) {
      return false;
    }
    if (db->changes() == 0) {
      *why = "pose for unknown keyframe id " + std::to_string(id);
      return false;
    }
  }
  return (!change.map_version ||
          SetMeta(db, "map_version", static_cast<std::int64_t>(*change.map_version), why)) &&
         (!change.next_object_id || SetMeta(db, "next_object_id", *change.next_object_id, why)) &&
         (!change.pose_update_pending ||
          SetMeta(db, "pose_update_pending", *change.pose_update_pending ? 1 : 0, why));
}

}  // namespace

// Encoding (the slow part) runs before the write lock is taken; the order inside the
// transaction is the one StoreChange documents.
bool KeyframeStore::Commit(const StoreChange& change, std::string* why) {
  EncodedKeyframe encoded;
  if ((change.keyframe &&
       !EncodeKeyframe(*change.keyframe, impl_->config.color_jpeg_quality, &encoded, why)) ||
      !CheckChange(change, why)) {
    return false;
  }
  std::lock_guard<std::mutex> lock(impl_->write_mutex);
  Connection* db = impl_->writer.get();
  std::string reason;
  auto put_sessions = [&] {
    for (const StoredSession& session : change.sessions) {
      if (!PutSession(db, session, &reason)) return false;
    }
    return true;
  };
  const bool ok = db->Exec("BEGIN IMMEDIATE", &reason) && put_sessions() &&
                  (!change.keyframe || (EnsureKeyframeSession(db, *change.keyframe, &reason) &&
                                        InsertKeyframe(db, *change.keyframe, encoded, &reason))) &&
                  (!change.revisit || InsertRevisit(db, *change.revisit, &reason)) &&
                  ApplyObjectChanges(db, change, &reason) &&
                  ApplyPosesAndMeta(db, change, &reason) && db->Exec("COMMIT", &reason);
  if (!ok) {
    db->RollbackIfOpen();
    *why = "nothing committed: " + reason;
  }
  return ok;
}

bool KeyframeStore::SaveCheckpoint(const StoredCheckpoint& checkpoint, std::string* why) {
  Bytes poses;
  poses.reserve(checkpoint.keyframe_poses.size() * (8 + 16 * 8));
  for (const auto& [id, T_W_C] : checkpoint.keyframe_poses) {
    const std::int64_t packed_id = id;
    const auto* id_bytes = reinterpret_cast<const std::uint8_t*>(&packed_id);
    poses.insert(poses.end(), id_bytes, id_bytes + sizeof(packed_id));
    const Bytes pose = store_internal::PackPose(T_W_C);
    poses.insert(poses.end(), pose.begin(), pose.end());
  }
  std::lock_guard<std::mutex> lock(impl_->write_mutex);
  Connection* db = impl_->writer.get();
  std::string reason;
  auto insert = db->Prepare(
      "INSERT OR REPLACE INTO occupancy_checkpoint(id, map_version, keyframe_poses, state)"
      " VALUES (1, ?, ?, ?)",
      "save checkpoint", &reason);
  bool done = false;
  const bool ok =
      insert &&
      insert->Bind(1, static_cast<std::int64_t>(checkpoint.map_version))
          .BindBlob(2, poses.data(), poses.size())
          .BindBlob(3, checkpoint.occupancy_state.data(), checkpoint.occupancy_state.size())
          .Step(&done, &reason);
  if (!ok) *why = "checkpoint not saved: " + reason;
  return ok;
}

}  // namespace objmap
