#pragma once
// Eigen <-> the geometry messages of objmap.proto, shared by the server's transport and the client.
// Reading a Pose back stays with each side: the server rejects non-unit quaternions, the client
// normalizes what it reads.

#include <Eigen/Geometry>

#include "objmap.pb.h"

namespace objmap {

[[nodiscard]] v1::Vec3 Vec3ToProto(const Eigen::Vector3d& v);
[[nodiscard]] v1::Vec3 Vec3ToProto(const Eigen::Vector3f& v);
[[nodiscard]] Eigen::Vector3d Vec3FromProto(const v1::Vec3& v);

/// T as translation + unit quaternion (x, y, z, w).
[[nodiscard]] v1::Pose PoseToProto(const Eigen::Isometry3d& T);

/// An axis-aligned box [min_W, max_W].
[[nodiscard]] v1::Box BoxToProto(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W);

}  // namespace objmap
