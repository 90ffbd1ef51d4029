#pragma once
// Conversions between Eigen and the geometry messages of objmap.proto.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "objmap.pb.h"

namespace objmap {

/// T as translation + unit quaternion (x, y, z, w).
[[nodiscard]] v1::Pose PoseToProto(const Eigen::Isometry3d& T);

/// The transform of a Pose; the quaternion is normalized. False with a reason when an entry is
/// not finite or the quaternion is (nearly) zero.
[[nodiscard]] bool PoseFromProto(const v1::Pose& pose, Eigen::Isometry3d* T, std::string* why);

[[nodiscard]] v1::Vec3 Vec3ToProto(const Eigen::Vector3d& v);
[[nodiscard]] Eigen::Vector3d Vec3FromProto(const v1::Vec3& v);

/// An axis-aligned box [min_W, max_W].
[[nodiscard]] v1::Box BoxToProto(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W);

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
