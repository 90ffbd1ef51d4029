#include "proto_geometry.h"

namespace objmap {

v1::Vec3 Vec3ToProto(const Eigen::Vector3d& v) {
  v1::Vec3 out;
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
  return out;
}

v1::Vec3 Vec3ToProto(const Eigen::Vector3f& v) {
  return Vec3ToProto(Eigen::Vector3d(v.cast<double>()));
}

Eigen::Vector3d Vec3FromProto(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

v1::Pose PoseToProto(const Eigen::Isometry3d& T) {
  v1::Pose pose;
  *pose.mutable_translation() = Vec3ToProto(Eigen::Vector3d(T.translation()));
  const Eigen::Quaterniond q(T.rotation());
  pose.set_qx(q.x());
  pose.set_qy(q.y());
  pose.set_qz(q.z());
  pose.set_qw(q.w());
  return pose;
}

v1::Box BoxToProto(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W) {
  v1::Box box;
  *box.mutable_min() = Vec3ToProto(min_W);
  *box.mutable_max() = Vec3ToProto(max_W);
  return box;
}

}  // namespace objmap
