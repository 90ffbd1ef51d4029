#include "ros_conversions.h"

#include <sensor_msgs/image_encodings.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "types/coco_classes.h"

namespace objmap::ros_bridge {
namespace {

namespace encodings = sensor_msgs::image_encodings;

std::string SizeText(std::int64_t width, std::int64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Rows of `bytes_per_pixel` pixels: the step must hold a row and the data every step.
bool CheckBuffer(const sensor_msgs::Image& image, const std::string& field, int bytes_per_pixel,
                 std::string* why) {
  if (image.width == 0 || image.height == 0) {
    *why = field + " is empty (" + SizeText(image.width, image.height) + ")";
    return false;
  }
  const std::uint64_t row_bytes = std::uint64_t{image.width} * bytes_per_pixel;
  if (image.step < row_bytes) {
    *why = field + ".step " + std::to_string(image.step) + " is shorter than a row of " +
           std::to_string(image.width) + " " + image.encoding + " pixels (" +
           std::to_string(row_bytes) + " bytes)";
    return false;
  }
  const std::uint64_t needed = std::uint64_t{image.step} * (image.height - 1) + row_bytes;
  if (image.data.size() < needed) {
    *why = field + ".data has " + std::to_string(image.data.size()) + " bytes but " +
           SizeText(image.width, image.height) + " " + image.encoding + " with step " +
           std::to_string(image.step) + " needs " + std::to_string(needed);
    return false;
  }
  return true;
}

// The bytes of a multi-byte sample in the host's order.
template <typename T>
T ReadSample(const std::uint8_t* bytes, bool big_endian) {
  std::uint8_t ordered[sizeof(T)];
  std::memcpy(ordered, bytes, sizeof(T));
  if (big_endian) std::reverse(ordered, ordered + sizeof(T));
  T value;
  std::memcpy(&value, ordered, sizeof(T));
  return value;
}

bool QuaternionFromMsg(double x, double y, double z, double w, const std::string& field,
                       Eigen::Quaterniond* q, std::string* why) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(w)) {
    *why = field + " has a non-finite component";
    return false;
  }
  *q = Eigen::Quaterniond(w, x, y, z);
  const double norm = q->norm();
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    *why = field + " has norm " + std::to_string(norm) + "; a unit quaternion is needed";
    return false;
  }
  q->normalize();
  return true;
}

bool RigidFromParts(const Eigen::Vector3d& translation, double qx, double qy, double qz, double qw,
                    const std::string& field, const std::string& rotation_name,
                    Eigen::Isometry3d* T, std::string* why) {
  if (!translation.allFinite()) {
    *why = field + " has a non-finite translation";
    return false;
  }
  Eigen::Quaterniond q;
  if (!QuaternionFromMsg(qx, qy, qz, qw, field + "." + rotation_name, &q, why)) return false;
  T->setIdentity();
  T->linear() = q.toRotationMatrix();
  T->translation() = translation;
  return true;
}

}  // namespace

bool ColorFromMsg(const sensor_msgs::Image& image, ColorImage* color, std::string* why) {
  const std::string& encoding = image.encoding;
  int channels = 0;
  bool swap_red_blue = false;
  if (encoding == encodings::RGB8) {
    channels = 3;
  } else if (encoding == encodings::BGR8) {
    channels = 3;
    swap_red_blue = true;
  } else if (encoding == encodings::RGBA8) {
    channels = 4;
  } else if (encoding == encodings::BGRA8) {
    channels = 4;
    swap_red_blue = true;
  } else if (encoding == encodings::MONO8) {
    channels = 1;
  } else {
    *why = "color.encoding '" + encoding + "' is not rgb8, bgr8, rgba8, bgra8 or mono8";
    return false;
  }
  if (!CheckBuffer(image, "color", channels, why)) return false;
  color->width = static_cast<int>(image.width);
  color->height = static_cast<int>(image.height);
  color->rgb.resize(std::size_t{image.width} * image.height * 3);
  for (std::uint32_t v = 0; v < image.height; ++v) {
    const std::uint8_t* in = image.data.data() + std::size_t{v} * image.step;
    std::uint8_t* out = color->rgb.data() + std::size_t{v} * image.width * 3;
    for (std::uint32_t u = 0; u < image.width; ++u, in += channels, out += 3) {
      if (channels == 1) {
        out[0] = out[1] = out[2] = in[0];
      } else {
        out[0] = in[swap_red_blue ? 2 : 0];
        out[1] = in[1];
        out[2] = in[swap_red_blue ? 0 : 2];
      }
    }
  }
  return true;
}

bool DepthFromMsg(const sensor_msgs::Image& image, double depth_scale_m, DepthImage* depth,
                  std::string* why) {
  const std::string& encoding = image.encoding;
  const bool millimetre_units = encoding == encodings::TYPE_16UC1 || encoding == encodings::MONO16;
  if (!millimetre_units && encoding != encodings::TYPE_32FC1) {
    *why = "depth.encoding '" + encoding + "' is not 16UC1, mono16 or 32FC1";
    return false;
  }
  if (millimetre_units && (!std::isfinite(depth_scale_m) || depth_scale_m <= 0.0)) {
    *why = "depth scale " + std::to_string(depth_scale_m) + " must be positive";
    return false;
  }
  if (!CheckBuffer(image, "depth", millimetre_units ? 2 : 4, why)) return false;
  depth->width = static_cast<int>(image.width);
  depth->height = static_cast<int>(image.height);
  depth->depth_m.resize(std::size_t{image.width} * image.height);
  const bool big_endian = image.is_bigendian != 0;
  for (std::uint32_t v = 0; v < image.height; ++v) {
    const std::uint8_t* in = image.data.data() + std::size_t{v} * image.step;
    float* out = depth->depth_m.data() + std::size_t{v} * image.width;
    for (std::uint32_t u = 0; u < image.width; ++u) {
      float metres = 0.f;
      if (millimetre_units) {
        metres =
            static_cast<float>(ReadSample<std::uint16_t>(in + 2 * u, big_endian) * depth_scale_m);
      } else {
        metres = ReadSample<float>(in + 4 * u, big_endian);
      }
      out[u] = std::isfinite(metres) && metres > 0.f ? metres : 0.f;
    }
  }
  return true;
}

bool IntrinsicsFromMsg(const sensor_msgs::CameraInfo& info, CameraIntrinsics* intrinsics,
                       std::string* why) {
  intrinsics->width = static_cast<int>(info.width);
  intrinsics->height = static_cast<int>(info.height);
  intrinsics->fx = info.K[0];
  intrinsics->fy = info.K[4];
  intrinsics->cx = info.K[2];
  intrinsics->cy = info.K[5];
  std::string reason;
  if (!intrinsics->IsValid(&reason)) {
    *why = "camera_info: " + reason;
    return false;
  }
  return true;
}

bool FrameFromMsgs(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                   const sensor_msgs::CameraInfo& info, const Eigen::Isometry3d& T_W_C,
                   double depth_scale_m, RgbdFrame* frame, std::string* why) {
  if (!ColorFromMsg(color, &frame->color, why) ||
      !DepthFromMsg(depth, depth_scale_m, &frame->depth, why) ||
      !IntrinsicsFromMsg(info, &frame->intrinsics, why)) {
    return false;
  }
  if (frame->color.width != frame->depth.width || frame->color.height != frame->depth.height) {
    *why = "color is " + SizeText(frame->color.width, frame->color.height) + " but depth is " +
           SizeText(frame->depth.width, frame->depth.height) +
           "; objmap needs them the same size (register depth to colour, or resize colour)";
    return false;
  }
  frame->T_W_C = T_W_C;
  frame->stamp_s = color.header.stamp.toSec();
  return ValidateFrame(*frame, why);
}

bool PoseFromMsg(const geometry_msgs::Pose& pose, const std::string& field, Eigen::Isometry3d* T,
                 std::string* why) {
  return RigidFromParts(Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z),
                        pose.orientation.x, pose.orientation.y, pose.orientation.z,
                        pose.orientation.w, field, "orientation", T, why);
}

bool TransformFromMsg(const geometry_msgs::Transform& transform, const std::string& field,
                      Eigen::Isometry3d* T, std::string* why) {
  return RigidFromParts(
      Eigen::Vector3d(transform.translation.x, transform.translation.y, transform.translation.z),
      transform.rotation.x, transform.rotation.y, transform.rotation.z, transform.rotation.w, field,
      "rotation", T, why);
}

geometry_msgs::Pose PoseToMsg(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose pose;
  const Eigen::Quaterniond q(T.rotation());
  pose.position.x = T.translation().x();
  pose.position.y = T.translation().y();
  pose.position.z = T.translation().z();
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

geometry_msgs::Transform TransformToMsg(const Eigen::Isometry3d& T) {
  const geometry_msgs::Pose pose = PoseToMsg(T);
  geometry_msgs::Transform transform;
  transform.translation.x = pose.position.x;
  transform.translation.y = pose.position.y;
  transform.translation.z = pose.position.z;
  transform.rotation = pose.orientation;
  return transform;
}

bool DetectionFromMsg(const objmap_msgs::Detection& msg, const std::string& field,
                      Detection* detection, std::string* why) {
  if (!msg.class_name.empty()) {
    detection->class_id = CocoClassId(msg.class_name);
    if (detection->class_id < 0) {
      *why = field + ".class_name '" + msg.class_name + "' is not a COCO class";
      return false;
    }
  } else if (msg.class_id < 0 || msg.class_id >= kNumCocoClasses) {
    *why = field + ".class_id " + std::to_string(msg.class_id) + " is not a COCO class (0.." +
           std::to_string(kNumCocoClasses - 1) + ")";
    return false;
  } else {
    detection->class_id = msg.class_id;
  }
  const float values[] = {msg.x_min, msg.y_min, msg.x_max, msg.y_max, msg.score};
  if (!std::all_of(std::begin(values), std::end(values),
                   [](float v) { return std::isfinite(v); })) {
    *why = field + " has a non-finite box or score";
    return false;
  }
  if (msg.x_max < msg.x_min || msg.y_max < msg.y_min) {
    *why = field + " box has max < min";
    return false;
  }
  detection->box = {msg.x_min, msg.y_min, msg.x_max, msg.y_max};
  detection->score = msg.score;
  return true;
}

objmap_msgs::Detection DetectionToMsg(const Detection& detection) {
  objmap_msgs::Detection msg;
  msg.x_min = detection.box.x_min;
  msg.y_min = detection.box.y_min;
  msg.x_max = detection.box.x_max;
  msg.y_max = detection.box.y_max;
  msg.class_id = detection.class_id;
  msg.class_name = std::string(CocoClassName(detection.class_id));
  msg.score = detection.score;
  return msg;
}

sensor_msgs::Image ColorToMsg(const ColorImage& color) {
  sensor_msgs::Image image;
  image.width = static_cast<std::uint32_t>(color.width);
  image.height = static_cast<std::uint32_t>(color.height);
  image.encoding = encodings::RGB8;
  image.step = image.width * 3;
  image.data = color.rgb;
  return image;
}

sensor_msgs::Image DepthToMsgMillimetres(const DepthImage& depth) {
  sensor_msgs::Image image;
  image.width = static_cast<std::uint32_t>(depth.width);
  image.height = static_cast<std::uint32_t>(depth.height);
  image.encoding = encodings::TYPE_16UC1;
  image.is_bigendian = 0;
  image.step = image.width * 2;
  image.data.resize(depth.depth_m.size() * 2);
  for (std::size_t i = 0; i < depth.depth_m.size(); ++i) {
    const float metres = depth.depth_m[i];
    const float millimetres = std::isfinite(metres) && metres > 0.f ? metres * 1000.f + 0.5f : 0.f;
    const auto units = static_cast<std::uint16_t>(std::min(millimetres, 65535.f));
    image.data[2 * i] = static_cast<std::uint8_t>(units & 0xff);  // little endian
    image.data[2 * i + 1] = static_cast<std::uint8_t>(units >> 8);
  }
  return image;
}

sensor_msgs::CameraInfo IntrinsicsToMsg(const CameraIntrinsics& intrinsics) {
  sensor_msgs::CameraInfo info;
  info.width = static_cast<std::uint32_t>(intrinsics.width);
  info.height = static_cast<std::uint32_t>(intrinsics.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {intrinsics.fx, 0.0, intrinsics.cx, 0.0, intrinsics.fy, intrinsics.cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {intrinsics.fx, 0.0, intrinsics.cx, 0.0, 0.0, intrinsics.fy,
            intrinsics.cy, 0.0, 0.0,           0.0, 1.0, 0.0};
  return info;
}

FrameMessages FrameToMsgs(const RgbdFrame& frame, const ros::Time& stamp,
                          const std::string& world_frame, const std::string& camera_frame) {
  FrameMessages m;
  m.color = ColorToMsg(frame.color);
  m.depth = DepthToMsgMillimetres(frame.depth);
  m.camera_info = IntrinsicsToMsg(frame.intrinsics);
  for (std_msgs::Header* header : {&m.color.header, &m.depth.header, &m.camera_info.header}) {
    header->stamp = stamp;
    header->frame_id = camera_frame;
  }
  m.T_W_C.header.stamp = stamp;
  m.T_W_C.header.frame_id = world_frame;
  m.T_W_C.child_frame_id = camera_frame;
  m.T_W_C.transform = TransformToMsg(frame.T_W_C);
  return m;
}

sensor_msgs::PointCloud2 PointsToMsg(const ColoredPoints& points) {
  sensor_msgs::PointCloud2 cloud;
  cloud.height = 1;
  cloud.width = static_cast<std::uint32_t>(points.size());
  const char* names[] = {"x", "y", "z", "rgb"};
  for (std::uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::PointField field;
    field.name = names[i];
    field.offset = 4 * i;
    field.datatype = sensor_msgs::PointField::FLOAT32;
    field.count = 1;
    cloud.fields.push_back(field);
  }
  cloud.is_bigendian = false;
  cloud.point_step = 16;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = true;
  cloud.data.resize(std::size_t{cloud.row_step});
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::uint8_t* out = cloud.data.data() + i * cloud.point_step;
    std::memcpy(out, points.points[i].data(), 12);
    // PCL's packed rgb: 0x00RRGGBB in the bytes of a float.
    std::uint32_t rgb = 0xffffff;
    if (i < points.colors.size()) {
      const auto& c = points.colors[i];
      rgb = (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | c[2];
    }
    std::memcpy(out + 12, &rgb, 4);
  }
  return cloud;
}

geometry_msgs::Point PointToMsg(const Eigen::Vector3d& point) {
  geometry_msgs::Point msg;
  msg.x = point.x();
  msg.y = point.y();
  msg.z = point.z();
  return msg;
}

Eigen::Vector3d PointFromMsg(const geometry_msgs::Point& point) {
  return {point.x, point.y, point.z};
}

void ObjectToMsg(const ObjectView& view, bool include_model, objmap_msgs::Object* object) {
  object->id = view.id;
  object->class_id = view.class_id;
  object->class_name = std::string(ObjectClassName(view.class_id));
  object->confidence = view.confidence;
  object->centroid = PointToMsg(view.centroid_W.cast<double>());
  object->bounds_min = PointToMsg(view.min_W.cast<double>());
  object->bounds_max = PointToMsg(view.max_W.cast<double>());
  object->observations = view.observations;
  object->keyframes.assign(view.keyframes.begin(), view.keyframes.end());
  object->scores.clear();
  for (const auto& [class_id, score] : view.scores) {
    objmap_msgs::ClassScore class_score;
    class_score.class_id = class_id;
    class_score.class_name = std::string(CocoClassName(class_id));
    class_score.score = score;
    object->scores.push_back(class_score);
  }
  object->confirmed = view.confirmed;
  object->changed_version = view.changed_version;
  object->model = sensor_msgs::PointCloud2();
  if (include_model && view.model_W) object->model = PointsToMsg(*view.model_W);
}

void InventoryEntryToMsg(const InventoryEntry& entry, objmap_msgs::InventoryEntry* msg) {
  msg->class_id = entry.class_id;
  msg->class_name = std::string(ObjectClassName(entry.class_id));
  msg->count = entry.count;
  msg->mean_confidence = entry.mean_confidence;
  msg->object_ids.assign(entry.objects.begin(), entry.objects.end());
}

void MapChangeToMsg(const MapChange& change, objmap_msgs::MapChange* msg) {
  msg->map_version = change.version;
  switch (change.kind) {
    case MapChange::Kind::kKeyframeAdded:
      msg->kind = objmap_msgs::MapChange::KEYFRAME_ADDED;
      break;
    case MapChange::Kind::kPosesUpdated:
      msg->kind = objmap_msgs::MapChange::POSES_UPDATED;
      break;
    case MapChange::Kind::kKeyframeRepeated:
      msg->kind = objmap_msgs::MapChange::KEYFRAME_REPEATED;
      break;
  }
  msg->keyframe_id = change.keyframe_id;
  msg->added_objects.assign(change.added.begin(), change.added.end());
  msg->updated_objects.assign(change.updated.begin(), change.updated.end());
  msg->removed_objects.assign(change.removed.begin(), change.removed.end());
  for (const MapObjectChange& object_change : change.object_changes) {
    ObjectChangeToMsg(object_change, &msg->object_changes.emplace_back());
  }
}

void ObjectChangeToMsg(const MapObjectChange& entry, objmap_msgs::ObjectChange* msg) {
  const ObjectChange& change = entry.change;
  switch (change.kind) {
    case ObjectChange::Kind::kAdded:
      msg->kind = objmap_msgs::ObjectChange::ADDED;
      break;
    case ObjectChange::Kind::kRemoved:
      msg->kind = objmap_msgs::ObjectChange::REMOVED;
      break;
    case ObjectChange::Kind::kMoved:
      msg->kind = objmap_msgs::ObjectChange::MOVED;
      break;
  }
  msg->object_id = change.id;
  msg->class_id = change.class_id;
  msg->class_name = std::string(ObjectClassName(change.class_id));
  msg->keyframe_id = entry.seen.keyframe_id;
  msg->session_id = entry.seen.session_id;
  msg->stamp = entry.seen.stamp_s;
  msg->map_version = entry.version;
  auto point = [](const Eigen::Vector3f& v) {
    geometry_msgs::Point p;
    p.x = v.x();
    p.y = v.y();
    p.z = v.z();
    return p;
  };
  msg->position = point(change.centroid_W);
  msg->bounds_min = point(change.min_W);
  msg->bounds_max = point(change.max_W);
  if (change.kind == ObjectChange::Kind::kMoved) msg->from = point(change.from_W);
}

}  // namespace objmap::ros_bridge
