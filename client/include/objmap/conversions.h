#pragma once
// Conversions between Eigen and objmap.proto messages (the plain geometry ones are in
// proto_geometry.h, shared with the server).

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "objmap.pb.h"
#include "proto_geometry.h"  // Vec3ToProto, PoseToProto, BoxToProto, Vec3FromProto

namespace objmap {

/// The transform of a Pose; the quaternion is normalized. False with a reason when an entry is
/// not finite or the quaternion is (nearly) zero.
[[nodiscard]] bool PoseFromProto(const v1::Pose& pose, Eigen::Isometry3d* T, std::string* why);

/// The point model of an Object (sent with include_model): world-frame points and their colours.
/// False with a reason naming the object when the byte counts do not match num_points.
[[nodiscard]] bool DecodeObjectModel(const v1::Object& object,
                                     std::vector<Eigen::Vector3f>* points_W,
                                     std::vector<std::array<std::uint8_t, 3>>* colors,
                                     std::string* why);

/// The inverse of DecodeObjectModel: fills num_points, points_xyz (float32 little-endian triples)
/// and points_rgb of `object`.
void EncodeObjectModel(const std::vector<Eigen::Vector3f>& points_W,
                       const std::vector<std::array<std::uint8_t, 3>>& colors, v1::Object* object);

}  // namespace objmap
