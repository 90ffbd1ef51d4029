// KeyframeStore::LoadAll and LoadKeyframe: rows are read inside one read transaction (a
// consistent snapshot while Commit goes on), images decoded afterwards, in parallel.

#include <algorithm>
#include <cstring>
#include <map>
#include <thread>

#include "store/keyframe_codec.h"
#include "store/keyframe_store.h"
#include "store/store_impl.h"

namespace objmap {
namespace {

using store_internal::Bytes;
using store_internal::Connection;
using store_internal::Statement;

const char kSelectKeyframes[] =
    "SELECT id, stamp_s, name, T_W_C, width, height, fx, fy, cx, cy, depth_png, mask_png,"
    " color_jpeg, detections, session_id FROM keyframes";

// An observation kept as pixels, read but not yet whole: its points are rebuilt and its colours
// decoded once its keyframe's depth is decoded (DecodeAll).
struct PendingSegment {
  std::size_t observation = 0;  ///< index into StoredMap::observations
  std::size_t points = 0;
  Bytes colors_png;
};

/// A keyframe row whose images are not decoded yet.
struct RawKeyframe {
  StoredKeyframe keyframe;
  Bytes depth_png, mask_png, color_jpeg;
};

Bytes CopyBlob(const Statement& row, int column) {
  std::size_t bytes = 0;
  const std::uint8_t* data = row.Blob(column, &bytes);
  return Bytes(data, data + bytes);
}

bool ReadKeyframeRow(const Statement& row, RawKeyframe* raw, std::string* why) {
  StoredKeyframe& k = raw->keyframe;
  k.id = row.Int64(0);
  k.stamp_s = row.Double(1);
  k.name = row.Text(2);
  k.session_id = row.Int64(14);
  k.intrinsics.width = static_cast<int>(row.Int64(4));
  k.intrinsics.height = static_cast<int>(row.Int64(5));
  k.intrinsics.fx = row.Double(6);
  k.intrinsics.fy = row.Double(7);
  k.intrinsics.cx = row.Double(8);
  k.intrinsics.cy = row.Double(9);
  std::size_t pose_bytes = 0, detection_bytes = 0;
  const std::uint8_t* pose = row.Blob(3, &pose_bytes);
  const std::uint8_t* detections = row.Blob(13, &detection_bytes);
  if (!store_internal::UnpackPose(pose, pose_bytes, &k.T_W_C) ||
      !store_internal::UnpackDetections(detections, detection_bytes, &k.detections)) {
    *why = "keyframe " + std::to_string(k.id) + ": corrupt pose or detections blob (a pose must be a finite rigid transform)";
    return false;
  }
  raw->depth_png = CopyBlob(row, 10);
  raw->mask_png = CopyBlob(row, 11);
  raw->color_jpeg = CopyBlob(row, 12);
  return true;
}

bool DecodeImages(RawKeyframe* raw, std::string* why) {
  StoredKeyframe& k = raw->keyframe;
  const int width = k.intrinsics.width, height = k.intrinsics.height;
  std::string reason;
  const char* field = "depth_png";
  bool ok = store_internal::DecodeDepthPng(raw->depth_png.data(), raw->depth_png.size(), width,
                                           height, &k.depth_mm, &reason);
  if (ok) {
    field = "mask_png";
    ok = store_internal::DecodeMaskPng(raw->mask_png.data(), raw->mask_png.size(), width, height,
                                       &k.object_mask, &reason);
  }
  if (ok && !raw->color_jpeg.empty()) {
    field = "color_jpeg";
    ok = store_internal::DecodeColorJpeg(raw->color_jpeg.data(), raw->color_jpeg.size(), width,
                                         height, &k.color, &reason);
  }
  if (!ok) *why = "keyframe " + std::to_string(k.id) + ": " + field + ": " + reason;
  Bytes().swap(raw->depth_png);  // the encoded images are not needed any more
  Bytes().swap(raw->mask_png);
  Bytes().swap(raw->color_jpeg);
  return ok;
}

// The points of an observation kept as pixels, from its keyframe's decoded depth: the function
// that made them (SegmentPointsFromDepth) on the same millimetres; their number must be the one
// stored. And its colours.
bool CompleteSegment(const StoredKeyframe& keyframe, PendingSegment* pending,
                     ObjectObservation* observation, std::string* why) {
  ColoredPoints rebuilt =
      SegmentPointsFromDepth(keyframe.depth_mm, keyframe.intrinsics, observation->segment_pixels,
                             observation->segment_voxel_size_m, nullptr);
  const std::string label = "observation in keyframe " + std::to_string(keyframe.id) + ": ";
  if (rebuilt.size() != pending->points) {
    *why = label + "its pixels make " + std::to_string(rebuilt.size()) +
           " points of the keyframe's depth, " + std::to_string(pending->points) + " were stored";
    return false;
  }
  std::string reason;
  const std::size_t colors = pending->colors_png.empty() ? 0 : pending->points;
  if (!store_internal::DecodeSegmentColorsPng(pending->colors_png.data(),
                                              pending->colors_png.size(), colors,
                                              &observation->segment_C.colors, &reason)) {
    *why = label + "colours: " + reason;
    return false;
  }
  Bytes().swap(pending->colors_png);
  observation->segment_C.points = std::move(rebuilt.points);
  return true;
}

// PNG decoding dominates a restart; keyframes are independent, so they decode on all cores,
// each followed by the observations kept as its pixels.
bool DecodeAll(std::vector<RawKeyframe>* raws, std::vector<StoredObservation>* observations,
               std::vector<PendingSegment>* pending, std::string* why) {
  std::map<KeyframeId, std::size_t> index_of;
  for (std::size_t i = 0; i < raws->size(); ++i) index_of[(*raws)[i].keyframe.id] = i;
  std::vector<std::vector<PendingSegment*>> of_keyframe(raws->size());
  for (PendingSegment& segment : *pending) {
    const StoredObservation& o = (*observations)[segment.observation];
    const auto found = index_of.find(o.observation.keyframe_id);
    if (found == index_of.end()) {
      *why = "observation of object " + std::to_string(o.object_id) + ": unknown keyframe " +
             std::to_string(o.observation.keyframe_id);
      return false;
    }
    of_keyframe[found->second].push_back(&segment);
  }
  auto decode = [&](std::size_t i, std::string* error) {
    if (!DecodeImages(&(*raws)[i], error)) return;
    for (PendingSegment* segment : of_keyframe[i]) {
      if (!CompleteSegment((*raws)[i].keyframe, segment,
                           &(*observations)[segment->observation].observation, error)) {
        return;
      }
    }
  };
  const std::size_t threads = std::max<std::size_t>(
      1, std::min<std::size_t>({std::thread::hardware_concurrency(), 8, raws->size() / 4}));
  std::vector<std::string> errors(threads);
  std::vector<std::thread> workers;
  for (std::size_t t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      for (std::size_t i = t; i < raws->size() && errors[t].empty(); i += threads) {
        decode(i, &errors[t]);
      }
    });
  }
  for (std::thread& worker : workers) worker.join();
  for (const std::string& error : errors) {
    if (!error.empty()) {
      *why = error;
      return false;
    }
  }
  return true;
}

bool ReadKeyframes(Connection* db, std::vector<RawKeyframe>* raws, std::string* why) {
  auto rows = db->Prepare(std::string(kSelectKeyframes) + " ORDER BY id", "load keyframes", why);
  if (!rows) return false;
  for (bool has_row = true;;) {
    if (!rows->Step(&has_row, why)) return false;
    if (!has_row) return true;
    raws->emplace_back();
    if (!ReadKeyframeRow(*rows, &raws->back(), why)) return false;
  }
}

bool ReadObservations(Connection* db, std::vector<StoredObservation>* observations,
                      std::vector<PendingSegment>* pending, std::string* why) {
  auto rows = db->Prepare(
      "SELECT object_id, keyframe_id, box_x_min, box_y_min, box_x_max, box_y_max, class_scores,"
      " points, colors, pixels FROM observations ORDER BY object_id, keyframe_id, id",
      "load observations", why);
  if (!rows) return false;
  for (bool has_row = true;;) {
    if (!rows->Step(&has_row, why)) return false;
    if (!has_row) return true;
    StoredObservation& o = observations->emplace_back();
    o.object_id = rows->Int64(0);
    ObjectObservation& obs = o.observation;
    obs.keyframe_id = rows->Int64(1);
    obs.box = {static_cast<float>(rows->Double(2)), static_cast<float>(rows->Double(3)),
               static_cast<float>(rows->Double(4)), static_cast<float>(rows->Double(5))};
    std::size_t score_bytes = 0, xyz_bytes = 0, rgb_bytes = 0, pixel_bytes = 0;
    const std::uint8_t* scores = rows->Blob(6, &score_bytes);
    const std::uint8_t* xyz = rows->Blob(7, &xyz_bytes);
    const std::uint8_t* rgb = rows->Blob(8, &rgb_bytes);
    const std::uint8_t* pixels = rows->Blob(9, &pixel_bytes);
    bool ok = store_internal::UnpackClassScores(scores, score_bytes, &obs.class_scores);
    if (ok && pixel_bytes == 0) {
      ok = store_internal::UnpackColoredPoints(xyz, xyz_bytes, rgb, rgb_bytes, &obs.segment_C);
    } else if (ok) {
      PendingSegment segment;
      segment.observation = observations->size() - 1;
      ok = xyz_bytes == 0 &&
           store_internal::UnpackSegmentPixels(pixels, pixel_bytes, &obs.segment_pixels,
                                               &obs.segment_voxel_size_m, &segment.points) &&
           !obs.segment_pixels.empty();
      segment.colors_png.assign(rgb, rgb + rgb_bytes);
      pending->push_back(std::move(segment));
    }
    if (!ok) {
      *why = "observation of object " + std::to_string(o.object_id) + " in keyframe " +
             std::to_string(obs.keyframe_id) + ": corrupt blob";
      return false;
    }
  }
}

bool ReadObjects(Connection* db, std::vector<StoredObjectSummary>* objects, std::string* why) {
  auto rows = db->Prepare(
      "SELECT id, class_id, confidence, centroid_x, centroid_y, centroid_z, observations"
      " FROM objects ORDER BY id",
      "load objects", why);
  if (!rows) return false;
  for (bool has_row = true;;) {
    if (!rows->Step(&has_row, why)) return false;
    if (!has_row) return true;
    StoredObjectSummary& s = objects->emplace_back();
    s.id = rows->Int64(0);
    s.class_id = static_cast<int>(rows->Int64(1));
    s.confidence = static_cast<float>(rows->Double(2));
    s.centroid_W = Eigen::Vector3d(rows->Double(3), rows->Double(4), rows->Double(5)).cast<float>();
    s.observations = static_cast<int>(rows->Int64(6));
  }
}

bool ReadMeta(Connection* db, StoredMap* map, std::string* why) {
  std::int64_t version = 0, next_id = 1, pending = 0;
  // A missing row reads 0 (files written before a key existed).
  if (!db->QueryInt("SELECT value FROM meta WHERE key = 'map_version'", &version, why) ||
      !db->QueryInt("SELECT value FROM meta WHERE key = 'next_object_id'", &next_id, why) ||
      !db->QueryInt("SELECT value FROM meta WHERE key = 'pose_update_pending'", &pending, why)) {
    return false;
  }
  map->map_version = static_cast<std::uint64_t>(version);
  map->next_object_id = next_id;
  map->pose_update_pending = pending != 0;
  return true;
}

}  // namespace

bool KeyframeStore::LoadAll(StoredMap* map, std::string* why) const {
  auto reader = impl_->readers->Acquire(why);
  if (!reader) return false;
  Connection* db = reader.get();
  *map = StoredMap{};
  std::vector<RawKeyframe> raws;
  std::vector<PendingSegment> pending;
  std::string reason;
  // The lease rolls the read transaction back when it returns the connection.
  if (!db->Exec("BEGIN", &reason) || !ReadMeta(db, map, &reason) ||
      !ReadKeyframes(db, &raws, &reason) ||
      !ReadObservations(db, &map->observations, &pending, &reason) ||
      !ReadObjects(db, &map->objects, &reason) || !db->Exec("COMMIT", &reason) ||
      !DecodeAll(&raws, &map->observations, &pending, &reason)) {
    *why = impl_->path + ": " + reason;
    *map = StoredMap{};
    return false;
  }
  map->keyframes.reserve(raws.size());
  for (RawKeyframe& raw : raws) map->keyframes.push_back(std::move(raw.keyframe));
  return true;
}

bool KeyframeStore::LoadKeyframe(KeyframeId id, StoredKeyframe* keyframe, std::string* why) const {
  auto reader = impl_->readers->Acquire(why);
  if (!reader) return false;
  auto row = reader.get()->Prepare(std::string(kSelectKeyframes) + " WHERE id = ?",
                                   "load keyframe " + std::to_string(id), why);
  bool has_row = false;
  if (!row || !row->Bind(1, std::int64_t{id}).Step(&has_row, why)) return false;
  if (!has_row) {
    *why = "unknown keyframe id " + std::to_string(id);
    return false;
  }
  RawKeyframe raw;
  if (!ReadKeyframeRow(*row, &raw, why) || !DecodeImages(&raw, why)) return false;
  *keyframe = std::move(raw.keyframe);
  return true;
}

bool KeyframeStore::ListKeyframes(KeyframeId first_id, std::size_t max_count,
                                  std::vector<KeyframeSummary>* keyframes, std::string* why) const {
  keyframes->clear();
  auto reader = impl_->readers->Acquire(why);
  if (!reader) return false;
  // LIMIT -1 is SQLite's "no limit".
  auto rows = reader.get()->Prepare(
      "SELECT id, stamp_s, name, T_W_C, session_id FROM keyframes WHERE id >= ? ORDER BY id"
      " LIMIT ?",
      "list keyframes", why);
  if (!rows) return false;
  rows->Bind(1, std::int64_t{first_id});
  rows->Bind(2, max_count == 0 ? std::int64_t{-1} : static_cast<std::int64_t>(max_count));
  for (bool has_row = true;;) {
    if (!rows->Step(&has_row, why)) return false;
    if (!has_row) return true;
    KeyframeSummary& summary = keyframes->emplace_back();
    summary.id = rows->Int64(0);
    summary.stamp_s = rows->Double(1);
    summary.name = rows->Text(2);
    summary.session_id = rows->Int64(4);
    std::size_t pose_bytes = 0;
    const std::uint8_t* pose = rows->Blob(3, &pose_bytes);
    if (!store_internal::UnpackPose(pose, pose_bytes, &summary.T_W_C)) {
      *why = impl_->path + ": keyframe " + std::to_string(summary.id) + ": corrupt pose blob (not a finite rigid transform)";
      return false;
    }
  }
}

bool KeyframeStore::ListSessions(std::vector<SessionSummary>* sessions, std::string* why) const {
  sessions->clear();
  auto reader = impl_->readers->Acquire(why);
  if (!reader) return false;
  // One statement, so one consistent read; each session's keyframe range comes from the
  // (session_id, id) index.
  auto rows = reader.get()->Prepare(
      "SELECT s.id, s.name, s.pose_source, s.started_s, s.ended_s,"
      " (SELECT count(*) FROM keyframes WHERE session_id = s.id),"
      " (SELECT count(*) FROM revisits WHERE session_id = s.id),"
      " (SELECT min(id) FROM keyframes WHERE session_id = s.id),"
      " (SELECT max(id) FROM keyframes WHERE session_id = s.id),"
      " (SELECT stamp_s FROM keyframes WHERE id ="
      "   (SELECT min(id) FROM keyframes WHERE session_id = s.id)),"
      " (SELECT stamp_s FROM keyframes WHERE id ="
      "   (SELECT max(id) FROM keyframes WHERE session_id = s.id))"
      " FROM sessions s ORDER BY s.id",
      "list sessions", why);
  if (!rows) return false;
  for (bool has_row = true;;) {
    if (!rows->Step(&has_row, why)) return false;
    if (!has_row) return true;
    SessionSummary& summary = sessions->emplace_back();
    StoredSession& session = summary.session;
    session.id = rows->Int64(0);
    session.name = rows->Text(1);
    session.pose_source = rows->Text(2);
    if (!rows->IsNull(3)) session.started_s = rows->Double(3);
    if (!rows->IsNull(4)) session.ended_s = rows->Double(4);
    summary.keyframes = static_cast<std::size_t>(rows->Int64(5));
    summary.revisits = static_cast<std::size_t>(rows->Int64(6));
    if (summary.keyframes > 0) {
      summary.first_keyframe = rows->Int64(7);
      summary.last_keyframe = rows->Int64(8);
      summary.first_stamp_s = rows->Double(9);
      summary.last_stamp_s = rows->Double(10);
    }
  }
}

bool KeyframeStore::ListRevisits(std::int64_t first_id, std::vector<StoredRevisit>* revisits,
                                 std::string* why) const {
  revisits->clear();
  auto reader = impl_->readers->Acquire(why);
  if (!reader) return false;
  auto rows = reader.get()->Prepare(
      "SELECT id, session_id, stamp_s, name, keyframe_id, T_K_C, explained FROM revisits"
      " WHERE id >= ? ORDER BY id",
      "list revisits", why);
  if (!rows) return false;
  rows->Bind(1, first_id);
  for (bool has_row = true;;) {
    if (!rows->Step(&has_row, why)) return false;
    if (!has_row) return true;
    StoredRevisit& revisit = revisits->emplace_back();
    revisit.id = rows->Int64(0);
    revisit.session_id = rows->Int64(1);
    revisit.stamp_s = rows->Double(2);
    revisit.name = rows->Text(3);
    revisit.keyframe_id = rows->Int64(4);
    std::size_t pose_bytes = 0;
    const std::uint8_t* pose = rows->Blob(5, &pose_bytes);
    if (!store_internal::UnpackPose(pose, pose_bytes, &revisit.T_K_C)) {
      *why = impl_->path + ": revisit " + std::to_string(revisit.id) + ": T_K_C blob of " +
             std::to_string(pose_bytes) + " bytes is not a pose";
      return false;
    }
    revisit.explained_fraction = static_cast<float>(rows->Double(6));
  }
}

bool KeyframeStore::LoadCheckpoint(std::optional<StoredCheckpoint>* checkpoint,
                                   std::string* why) const {
  checkpoint->reset();
  auto reader = impl_->readers->Acquire(why);
  if (!reader) return false;
  auto row = reader.get()->Prepare(
      "SELECT map_version, keyframe_poses, state FROM occupancy_checkpoint WHERE id = 1",
      "load checkpoint", why);
  bool has_row = false;
  if (!row || !row->Step(&has_row, why)) return false;
  if (!has_row) return true;
  StoredCheckpoint loaded;
  loaded.map_version = static_cast<std::uint64_t>(row->Int64(0));
  std::size_t poses_bytes = 0, state_bytes = 0;
  const std::uint8_t* poses = row->Blob(1, &poses_bytes);
  const std::uint8_t* state = row->Blob(2, &state_bytes);
  constexpr std::size_t kEntryBytes = 8 + 16 * 8;
  if (poses_bytes % kEntryBytes != 0) {
    *why = impl_->path + ": checkpoint: keyframe_poses blob of " + std::to_string(poses_bytes) +
           " bytes is not a whole number of entries";
    return false;
  }
  for (std::size_t offset = 0; offset < poses_bytes; offset += kEntryBytes) {
    std::int64_t id = 0;
    std::memcpy(&id, poses + offset, sizeof(id));
    Eigen::Isometry3d T_W_C;
    if (!store_internal::UnpackPose(poses + offset + 8, kEntryBytes - 8, &T_W_C)) {
      *why = impl_->path + ": checkpoint: corrupt pose of keyframe " + std::to_string(id);
      return false;
    }
    loaded.keyframe_poses[id] = T_W_C;
  }
  loaded.occupancy_state.assign(reinterpret_cast<const char*>(state), state_bytes);
  *checkpoint = std::move(loaded);
  return true;
}

}  // namespace objmap
