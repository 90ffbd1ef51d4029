#pragma once
// Conversions between ROS messages and the core's types, shared by objmap_node, the rosbag input
// and the dataset player. Every *FromMsg function validates what the core cannot check on its
// own (encodings, buffer sizes, quaternion norms, class names) and names the bad field the way
// the message spells it ("depth.encoding", "T_W_C.orientation").

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/TransformStamped.h>
#include <objmap_msgs/Detection.h>
#include <objmap_msgs/InventoryEntry.h>
#include <objmap_msgs/MapChange.h>
#include <objmap_msgs/Object.h>
#include <objmap_msgs/ObjectChange.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "map_server/map_server.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap::ros_bridge {

/// Quaternions whose norm differs from 1 by more than this are refused rather than normalized
/// (an unset orientation has norm 0): the same rule as the gRPC API.
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// A colour image: rgb8, bgr8, rgba8, bgra8 or mono8, any row step that holds the row.
[[nodiscard]] bool ColorFromMsg(const sensor_msgs::Image& image, ColorImage* color,
                                std::string* why);

/// A depth image: 16UC1 / mono16 in `depth_scale_m` metres per unit (0.001: millimetres), or
/// 32FC1 in metres. Zero, NaN and negative values become 0 (no depth).
[[nodiscard]] bool DepthFromMsg(const sensor_msgs::Image& image, double depth_scale_m,
                                DepthImage* depth, std::string* why);

/// Pinhole intrinsics from K (fx = K[0], fy = K[4], cx = K[2], cy = K[5]) and the image size.
[[nodiscard]] bool IntrinsicsFromMsg(const sensor_msgs::CameraInfo& info,
                                     CameraIntrinsics* intrinsics, std::string* why);

/// A whole frame: the images converted, the intrinsics from `info`, the pose, then ValidateFrame
/// (image sizes against the intrinsics and each other). Reasons name the message.
[[nodiscard]] bool FrameFromMsgs(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                                 const sensor_msgs::CameraInfo& info,
                                 const Eigen::Isometry3d& T_W_C, double depth_scale_m,
                                 RgbdFrame* frame, std::string* why);

/// Rigid transforms; the *FromMsg ones check finiteness and the quaternion norm.
[[nodiscard]] bool PoseFromMsg(const geometry_msgs::Pose& pose, const std::string& field,
                               Eigen::Isometry3d* T, std::string* why);
[[nodiscard]] bool TransformFromMsg(const geometry_msgs::Transform& transform,
                                    const std::string& field, Eigen::Isometry3d* T,
                                    std::string* why);
[[nodiscard]] geometry_msgs::Pose PoseToMsg(const Eigen::Isometry3d& T);
[[nodiscard]] geometry_msgs::Transform TransformToMsg(const Eigen::Isometry3d& T);

/// Points in metres.
[[nodiscard]] geometry_msgs::Point PointToMsg(const Eigen::Vector3d& point);
[[nodiscard]] Eigen::Vector3d PointFromMsg(const geometry_msgs::Point& point);

/// A detection by class name (the name wins) or id; `field` is its path ("detections[3]").
[[nodiscard]] bool DetectionFromMsg(const objmap_msgs::Detection& msg, const std::string& field,
                                    Detection* detection, std::string* why);
[[nodiscard]] objmap_msgs::Detection DetectionToMsg(const objmap::Detection& detection);

/// Encoders for players and recorders: rgb8 colour, 16UC1 depth in millimetres (depth rounded
/// to the nearest millimetre; 0 stays 0), CameraInfo with K, P and plumb_bob without distortion.
[[nodiscard]] sensor_msgs::Image ColorToMsg(const ColorImage& color);
[[nodiscard]] sensor_msgs::Image DepthToMsgMillimetres(const DepthImage& depth);
[[nodiscard]] sensor_msgs::CameraInfo IntrinsicsToMsg(const CameraIntrinsics& intrinsics);

/// One frame as a camera driver publishes it, every message stamped `stamp`: the images and
/// camera info in `camera_frame`, and T_W_C as the transform world_frame -> camera_frame.
struct FrameMessages {
  sensor_msgs::Image color;  ///< rgb8
  sensor_msgs::Image depth;  ///< 16UC1, millimetres
  sensor_msgs::CameraInfo camera_info;
  geometry_msgs::TransformStamped T_W_C;
};
[[nodiscard]] FrameMessages FrameToMsgs(const RgbdFrame& frame, const ros::Time& stamp,
                                        const std::string& world_frame,
                                        const std::string& camera_frame);

/// A coloured point set as PointCloud2 (x y z float32 and rgb packed in a float32, as PCL
/// writes it), unorganized (height 1).
[[nodiscard]] sensor_msgs::PointCloud2 PointsToMsg(const ColoredPoints& points);

/// Map answers as messages; the point model only with `include_model`.
void ObjectToMsg(const ObjectView& view, bool include_model, objmap_msgs::Object* object);
void InventoryEntryToMsg(const InventoryEntry& entry, objmap_msgs::InventoryEntry* msg);
void MapChangeToMsg(const MapChange& change, objmap_msgs::MapChange* msg);
void ObjectChangeToMsg(const MapObjectChange& change, objmap_msgs::ObjectChange* msg);

}  // namespace objmap::ros_bridge
