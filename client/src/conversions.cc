#include "objmap/conversions.h"

#include <cmath>
#include <cstring>

namespace objmap {
namespace {

// Quaternions shorter than this carry no rotation to normalize.
constexpr double kMinQuaternionNorm = 1e-6;

void AppendFloatLe(float value, std::string* bytes) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  for (int shift = 0; shift < 32; shift += 8) {
    bytes->push_back(static_cast<char>((bits >> shift) & 0xffu));
  }
}

float ReadFloatLe(const std::string& bytes, std::size_t offset) {
  std::uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) {
    bits |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[offset + i])) << (8 * i);
  }
  float value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

}  // namespace

bool PoseFromProto(const v1::Pose& pose, Eigen::Isometry3d* T, std::string* why) {
  const Eigen::Vector3d t = Vec3FromProto(pose.translation());
  const Eigen::Vector4d q(pose.qx(), pose.qy(), pose.qz(), pose.qw());
  if (!t.allFinite() || !q.allFinite()) {
    *why = "pose has NaN or infinite entries";
    return false;
  }
  if (q.norm() < kMinQuaternionNorm) {
    *why = "pose quaternion is zero";
    return false;
  }
  const Eigen::Quaterniond rotation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized();
  T->setIdentity();
  T->linear() = rotation.toRotationMatrix();
  T->translation() = t;
  return true;
}

bool DecodeObjectModel(const v1::Object& object, std::vector<Eigen::Vector3f>* points_W,
                       std::vector<std::array<std::uint8_t, 3>>* colors, std::string* why) {
  const std::size_t n = object.num_points() > 0 ? static_cast<std::size_t>(object.num_points()) : 0;
  if (object.num_points() < 0 || object.points_xyz().size() != 12 * n ||
      object.points_rgb().size() != 3 * n) {
    *why = "object " + std::to_string(object.id()) + ": model has " +
           std::to_string(object.num_points()) + " points but " +
           std::to_string(object.points_xyz().size()) + " xyz bytes and " +
           std::to_string(object.points_rgb().size()) + " rgb bytes";
    return false;
  }
  points_W->resize(n);
  colors->resize(n);
  const std::string& xyz = object.points_xyz();
  const std::string& rgb = object.points_rgb();
  for (std::size_t i = 0; i < n; ++i) {
    (*points_W)[i] = {ReadFloatLe(xyz, 12 * i), ReadFloatLe(xyz, 12 * i + 4),
                      ReadFloatLe(xyz, 12 * i + 8)};
    for (int c = 0; c < 3; ++c) (*colors)[i][c] = static_cast<std::uint8_t>(rgb[3 * i + c]);
  }
  return true;
}

void EncodeObjectModel(const std::vector<Eigen::Vector3f>& points_W,
                       const std::vector<std::array<std::uint8_t, 3>>& colors, v1::Object* object) {
  std::string xyz;
  std::string rgb;
  xyz.reserve(12 * points_W.size());
  rgb.reserve(3 * points_W.size());
  for (std::size_t i = 0; i < points_W.size(); ++i) {
    for (int c = 0; c < 3; ++c) AppendFloatLe(points_W[i][c], &xyz);
    const std::array<std::uint8_t, 3> color =
        i < colors.size() ? colors[i] : std::array<std::uint8_t, 3>{};
    for (int c = 0; c < 3; ++c) rgb.push_back(static_cast<char>(color[c]));
  }
  object->set_num_points(static_cast<std::int32_t>(points_W.size()));
  object->set_points_xyz(std::move(xyz));
  object->set_points_rgb(std::move(rgb));
}

}  // namespace objmap
