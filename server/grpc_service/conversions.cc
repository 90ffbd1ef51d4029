#include "grpc_service/conversions.h"

#include <cmath>
#include <cstring>
#include <sstream>

#include "grpc_service/handler_guard.h"
#include "types/coco_classes.h"

namespace objmap::grpc_service {
namespace {

std::string FormatNumber(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// "<field> is NaN" / "<field> is inf" for the first non-finite entry of `values`.
bool CheckFinite(const std::string& field, const char* const* names, const double* values, int n,
                 std::string* why) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(values[i])) {
      *why = field + names[i] + " is " + FormatNumber(values[i]) + ", must be finite";
      return false;
    }
  }
  return true;
}

void AppendFloatLe(float value, std::string* bytes) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  for (int shift = 0; shift < 32; shift += 8) {
    bytes->push_back(static_cast<char>((bits >> shift) & 0xffu));
  }
}

void ModelToProto(const ColoredPoints& model_W, v1::Object* object) {
  std::string xyz;
  std::string rgb;
  xyz.reserve(12 * model_W.size());
  rgb.reserve(3 * model_W.size());
  for (std::size_t i = 0; i < model_W.size(); ++i) {
    for (int c = 0; c < 3; ++c) AppendFloatLe(model_W.points[i][c], &xyz);
    // Models without colour go out grey rather than with a short rgb field.
    for (int c = 0; c < 3; ++c) {
      rgb.push_back(static_cast<char>(i < model_W.colors.size() ? model_W.colors[i][c] : 128));
    }
  }
  object->set_num_points(static_cast<std::int32_t>(model_W.size()));
  object->set_points_xyz(std::move(xyz));
  object->set_points_rgb(std::move(rgb));
}

}  // namespace

grpc::Status ToGrpcStatus(const ServiceStatus& status) {
  switch (status.code) {
    case StatusCode::kOk:
      return grpc::Status::OK;
    case StatusCode::kInvalidArgument:
      return {grpc::StatusCode::INVALID_ARGUMENT, status.message};
    case StatusCode::kNotFound:
      return {grpc::StatusCode::NOT_FOUND, status.message};
    case StatusCode::kResourceExhausted:
      return {grpc::StatusCode::RESOURCE_EXHAUSTED, status.message};
    case StatusCode::kUnavailable:
      return {grpc::StatusCode::UNAVAILABLE, status.message};
    case StatusCode::kInternal:
      return {grpc::StatusCode::INTERNAL, status.message};
    case StatusCode::kFailedPrecondition:
      return {grpc::StatusCode::FAILED_PRECONDITION, status.message};
  }
  return {grpc::StatusCode::INTERNAL, "unknown status code: " + status.message};
}

bool PoseFromProto(const v1::Pose& pose, const std::string& field, Eigen::Isometry3d* T,
                   std::string* why) {
  static const char* const kTranslation[] = {".translation.x", ".translation.y", ".translation.z"};
  static const char* const kQuaternion[] = {".qx", ".qy", ".qz", ".qw"};
  const Eigen::Vector3d t = Vec3FromProto(pose.translation());
  const double q[4] = {pose.qx(), pose.qy(), pose.qz(), pose.qw()};
  if (!CheckFinite(field, kTranslation, t.data(), 3, why) ||
      !CheckFinite(field, kQuaternion, q, 4, why)) {
    return false;
  }
  for (int i = 0; i < 3; ++i) {
    if (std::abs(t[i]) > kMaxTranslationM) {
      *why = field + kTranslation[i] + " is " + FormatNumber(t[i]) + " m; at most " +
             FormatNumber(kMaxTranslationM) +
             " m from the map origin (float map coordinates keep centimetres only that far)";
      return false;
    }
  }
  const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
  const double norm = rotation.norm();
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    *why = field + ".q* (qx, qy, qz, qw) has norm " + FormatNumber(norm) +
           (norm == 0.0 ? " (pose unset?)" : "") + "; a unit quaternion is required";
    return false;
  }
  T->setIdentity();
  T->linear() = rotation.normalized().toRotationMatrix();
  T->translation() = t;
  return true;
}

bool BoxFromProto(const v1::Box& box, const std::string& field,
                  std::pair<Eigen::Vector3d, Eigen::Vector3d>* box_W, std::string* why) {
  box_W->first = Vec3FromProto(box.min());
  box_W->second = Vec3FromProto(box.max());
  return ValidateBox(box_W->first, box_W->second, field, why);
}

bool IntrinsicsFromProto(const v1::CameraIntrinsics& proto, CameraIntrinsics* intrinsics,
                         std::string* why) {
  intrinsics->width = proto.width();
  intrinsics->height = proto.height();
  intrinsics->fx = proto.fx();
  intrinsics->fy = proto.fy();
  intrinsics->cx = proto.cx();
  intrinsics->cy = proto.cy();
  return intrinsics->IsValid(why);  // its reasons start with "intrinsics: "
}

bool ClassIdFromName(const std::string& name, const std::string& field, int* class_id,
                     std::string* why) {
  *class_id = CocoClassId(name);
  if (*class_id < 0) {
    *why = field + " '" + Shortened(name, kMaxQuotedBytes) + "' is not a COCO class";
    return false;
  }
  return true;
}

bool DetectionFromProto(const v1::Detection& proto, const std::string& field, Detection* detection,
                        std::string* why) {
  if (!proto.class_name().empty()) {
    if (!ClassIdFromName(proto.class_name(), field + ".class_name", &detection->class_id, why)) {
      return false;
    }
  } else if (proto.class_id() < 0 || proto.class_id() >= kNumCocoClasses) {
    *why = field + ".class_id " + std::to_string(proto.class_id()) + " is not a COCO class (0.." +
           std::to_string(kNumCocoClasses - 1) + ")";
    return false;
  } else {
    detection->class_id = proto.class_id();
  }
  if (!(proto.score() >= 0.f && proto.score() <= 1.f)) {  // NaN fails too
    *why = field + ".score " + FormatNumber(proto.score()) + " must lie in [0, 1]";
    return false;
  }
  static const char* const kCorners[] = {".x_min", ".y_min", ".x_max", ".y_max"};
  const double corners[] = {proto.x_min(), proto.y_min(), proto.x_max(), proto.y_max()};
  if (!CheckFinite(field, kCorners, corners, 4, why)) return false;
  if (!(proto.x_min() < proto.x_max() && proto.y_min() < proto.y_max())) {
    *why = field + " box (" + FormatNumber(proto.x_min()) + ", " + FormatNumber(proto.y_min()) +
           ") - (" + FormatNumber(proto.x_max()) + ", " + FormatNumber(proto.y_max()) +
           ") is empty: x_min < x_max and y_min < y_max are required";
    return false;
  }
  detection->box = {proto.x_min(), proto.y_min(), proto.x_max(), proto.y_max()};
  detection->score = proto.score();
  return true;
}

namespace {

void SeenToProto(const ObjectSeen& seen, v1::Seen* proto) {
  proto->set_keyframe_id(seen.keyframe_id);
  proto->set_session_id(seen.session_id);
  proto->set_stamp(seen.stamp_s);
}

v1::ObjectState ObjectStateToProto(ObjectState state) {
  switch (state) {
    case ObjectState::kRemoved:
      return v1::REMOVED;
    case ObjectState::kMoved:
      return v1::MOVED;
    case ObjectState::kPresent:
      break;
  }
  return v1::PRESENT;
}

v1::ObjectChange::Kind ChangeKindToProto(ObjectChange::Kind kind) {
  switch (kind) {
    case ObjectChange::Kind::kRemoved:
      return v1::ObjectChange::REMOVED;
    case ObjectChange::Kind::kMoved:
      return v1::ObjectChange::MOVED;
    case ObjectChange::Kind::kAdded:
      break;
  }
  return v1::ObjectChange::ADDED;
}

}  // namespace

void ObjectChangeToProto(const MapObjectChange& entry, v1::ObjectChange* proto) {
  const ObjectChange& change = entry.change;
  proto->set_kind(ChangeKindToProto(change.kind));
  proto->set_object_id(change.id);
  proto->set_class_id(change.class_id);
  proto->set_class_name(std::string(ObjectClassName(change.class_id)));
  SeenToProto(entry.seen, proto->mutable_seen());
  proto->set_map_version(entry.version);
  *proto->mutable_position() = Vec3ToProto(change.centroid_W);
  *proto->mutable_bounds()->mutable_min() = Vec3ToProto(change.min_W);
  *proto->mutable_bounds()->mutable_max() = Vec3ToProto(change.max_W);
  if (change.kind == ObjectChange::Kind::kMoved) {
    *proto->mutable_from() = Vec3ToProto(change.from_W);
    SeenToProto(entry.from_last_seen, proto->mutable_from_last_seen());
  }
}

void ObjectToProto(const ObjectView& view, bool include_model, v1::Object* object) {
  object->set_id(view.id);
  object->set_class_id(view.class_id);
  object->set_class_name(std::string(ObjectClassName(view.class_id)));
  object->set_confidence(view.confidence);
  *object->mutable_centroid() = Vec3ToProto(view.centroid_W);
  *object->mutable_bounds()->mutable_min() = Vec3ToProto(view.min_W);
  *object->mutable_bounds()->mutable_max() = Vec3ToProto(view.max_W);
  object->set_observations(view.observations);
  object->mutable_keyframes()->Add(view.keyframes.begin(), view.keyframes.end());
  for (const auto& [class_id, score] : view.scores) {
    v1::ClassScore* class_score = object->add_scores();
    class_score->set_class_id(class_id);
    class_score->set_class_name(std::string(CocoClassName(class_id)));
    class_score->set_score(score);
  }
  object->set_confirmed(view.confirmed);
  object->set_changed_version(view.changed_version);
  if (view.first_seen.keyframe_id != 0) {
    SeenToProto(view.first_seen, object->mutable_first_seen());
    SeenToProto(view.last_seen, object->mutable_last_seen());
    if (view.last_seen_absent.keyframe_id != 0) {
      SeenToProto(view.last_seen_absent, object->mutable_last_seen_absent());
    }
  }
  object->set_state(ObjectStateToProto(view.state));
  for (const ObjectPlaceView& place : view.previous_places) {
    v1::Place* proto = object->add_previous_places();
    *proto->mutable_centroid() = Vec3ToProto(place.centroid_W);
    *proto->mutable_bounds()->mutable_min() = Vec3ToProto(place.min_W);
    *proto->mutable_bounds()->mutable_max() = Vec3ToProto(place.max_W);
    SeenToProto(place.first_seen, proto->mutable_first_seen());
    SeenToProto(place.last_seen, proto->mutable_last_seen());
    if (place.seen_empty.keyframe_id != 0)
      SeenToProto(place.seen_empty, proto->mutable_seen_empty());
  }
  if (view.added.keyframe_id != 0) SeenToProto(view.added, object->mutable_added());
  if (view.removed.keyframe_id != 0) SeenToProto(view.removed, object->mutable_removed());
  if (include_model && view.model_W) ModelToProto(*view.model_W, object);
}

void InventoryEntryToProto(const InventoryEntry& entry, v1::InventoryEntry* proto) {
  proto->set_class_id(entry.class_id);
  proto->set_class_name(std::string(ObjectClassName(entry.class_id)));
  proto->set_count(entry.count);
  proto->set_mean_confidence(entry.mean_confidence);
  proto->mutable_object_ids()->Add(entry.objects.begin(), entry.objects.end());
}

void SessionToProto(const SessionSummary& summary, bool current, v1::Session* proto) {
  const StoredSession& session = summary.session;
  proto->set_id(session.id);
  proto->set_name(session.name);
  proto->set_pose_source(session.pose_source);
  proto->set_has_started(session.started_s.has_value());
  proto->set_started_s(session.started_s.value_or(0.0));
  proto->set_has_ended(session.ended_s.has_value());
  proto->set_ended_s(session.ended_s.value_or(0.0));
  proto->set_keyframes(static_cast<std::int64_t>(summary.keyframes));
  proto->set_revisits(static_cast<std::int64_t>(summary.revisits));
  proto->set_first_keyframe_id(summary.first_keyframe);
  proto->set_last_keyframe_id(summary.last_keyframe);
  proto->set_first_stamp(summary.first_stamp_s);
  proto->set_last_stamp(summary.last_stamp_s);
  proto->set_current(current);
}

void MapChangeToProto(const MapChange& change, v1::MapChange* proto) {
  proto->set_map_version(change.version);
  switch (change.kind) {
    case MapChange::Kind::kKeyframeAdded:
      proto->set_kind(v1::MapChange::KEYFRAME_ADDED);
      break;
    case MapChange::Kind::kPosesUpdated:
      proto->set_kind(v1::MapChange::POSES_UPDATED);
      break;
    case MapChange::Kind::kKeyframeRepeated:
      proto->set_kind(v1::MapChange::KEYFRAME_REPEATED);
      break;
  }
  proto->set_keyframe_id(change.keyframe_id);
  proto->mutable_added_objects()->Add(change.added.begin(), change.added.end());
  proto->mutable_updated_objects()->Add(change.updated.begin(), change.updated.end());
  proto->mutable_removed_objects()->Add(change.removed.begin(), change.removed.end());
  for (const MapObjectChange& object_change : change.object_changes) {
    ObjectChangeToProto(object_change, proto->add_object_changes());
  }
}

v1::VoxelState VoxelStateToProto(VoxelState state) {
  switch (state) {
    case VoxelState::kFree:
      return v1::FREE;
    case VoxelState::kOccupied:
      return v1::OCCUPIED;
    case VoxelState::kUnknown:
      break;
  }
  return v1::UNKNOWN;
}

}  // namespace objmap::grpc_service
