#pragma once
// Conversions between objmap.proto messages and the core's types. Every From* function validates
// what the core cannot check on its own (quaternion norms, class names, encodings) and names the
// bad field the way the request spells it ("T_W_C.qw", "detections[3].class_name").
//
// The names live in objmap::grpc_service so that they never collide with the client library's
// conversions (namespace objmap), which a process may link next to these.

#include <grpcpp/support/status.h>

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "map_server/map_server.h"
#include "objmap.pb.h"
#include "proto_geometry.h"  // Vec3ToProto, Vec3FromProto, PoseToProto
#include "types/detection.h"
#include "types/frame.h"

namespace objmap::grpc_service {

/// Quaternions whose norm differs from 1 by more than this are rejected rather than normalized:
/// such a pose is a client bug (an unset pose has norm 0), not rounding.
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// The gRPC status of a core status (kInvalidArgument -> INVALID_ARGUMENT, ...).
[[nodiscard]] grpc::Status ToGrpcStatus(const ServiceStatus& status);

/// The rigid transform of `pose`: finite entries, quaternion norm within the tolerance of 1
/// (then normalized). Otherwise false with a reason naming `field` ("T_W_C.qw is NaN").
[[nodiscard]] bool PoseFromProto(const v1::Pose& pose, const std::string& field,
                                 Eigen::Isometry3d* T, std::string* why);

/// [min, max] of a box message, validated with ValidateBox under `field`.
[[nodiscard]] bool BoxFromProto(const v1::Box& box, const std::string& field,
                                std::pair<Eigen::Vector3d, Eigen::Vector3d>* box_W,
                                std::string* why);

/// Intrinsics, checked with CameraIntrinsics::IsValid (its reasons name "intrinsics").
[[nodiscard]] bool IntrinsicsFromProto(const v1::CameraIntrinsics& proto,
                                       CameraIntrinsics* intrinsics, std::string* why);

/// A COCO class by name (the name wins) or id; `field` is the detection's path ("detections[3]").
[[nodiscard]] bool DetectionFromProto(const v1::Detection& proto, const std::string& field,
                                      Detection* detection, std::string* why);

/// The class id of a COCO name; false with "<field> '<name>' is not a COCO class" otherwise.
[[nodiscard]] bool ClassIdFromName(const std::string& name, const std::string& field, int* class_id,
                                   std::string* why);

/// An object view as a message; the point model only with `include_model`.
void ObjectToProto(const ObjectView& view, bool include_model, v1::Object* object);

void InventoryEntryToProto(const InventoryEntry& entry, v1::InventoryEntry* proto);

void MapChangeToProto(const MapChange& change, v1::MapChange* proto);
void ObjectChangeToProto(const MapObjectChange& change, v1::ObjectChange* proto);
void SessionToProto(const SessionSummary& summary, bool current, v1::Session* proto);

[[nodiscard]] v1::VoxelState VoxelStateToProto(VoxelState state);

}  // namespace objmap::grpc_service
