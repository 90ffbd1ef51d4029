#pragma once
// Writes small bags for the rosbag input tests, with the rosbag C++ API and the same
// conversions objmap_dataset_player uses.

#include <geometry_msgs/PoseStamped.h>
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <string>
#include <vector>

#include "ros_conversions.h"
#include "types/frame.h"

namespace objmap::testing {

/// How a test bag departs from the player's layout.
struct TestBagOptions {
  std::string color_topic = "/rgb/image";
  std::string depth_topic = "/depth/image";
  std::string camera_info_topic = "/rgb/camera_info";
  std::string camera_frame = "camera";
  double depth_delay_s = 0.0;  ///< depth stamps after the colour ones
  bool write_tf = true;
  std::size_t frames_with_tf = 1000000;  ///< TF only for the first frames
  std::string pose_topic;                ///< also write the poses as PoseStamped here
};

/// Frame k stamped 100 + 0.1 k s; TF map -> camera_frame at the same stamps.
inline void WriteTestBag(const std::string& path, const std::vector<RgbdFrame>& frames,
                         const TestBagOptions& options = {}) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const RgbdFrame& frame = frames[k];
    const ros::Time stamp(100.0 + 0.1 * static_cast<double>(k));
    sensor_msgs::Image color = ros_bridge::ColorToMsg(frame.color);
    sensor_msgs::Image depth = ros_bridge::DepthToMsgMillimetres(frame.depth);
    sensor_msgs::CameraInfo info = ros_bridge::IntrinsicsToMsg(frame.intrinsics);
    color.header.stamp = info.header.stamp = stamp;
    depth.header.stamp = stamp + ros::Duration(options.depth_delay_s);
    color.header.frame_id = depth.header.frame_id = info.header.frame_id = options.camera_frame;
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = stamp;
    transform.header.frame_id = "map";
    transform.child_frame_id = options.camera_frame;
    transform.transform = ros_bridge::TransformToMsg(frame.T_W_C);
    if (options.write_tf && k < options.frames_with_tf) {
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(transform);
      bag.write("/tf", stamp, tf);
    }
    if (!options.pose_topic.empty()) {
      geometry_msgs::PoseStamped pose;
      pose.header = transform.header;
      pose.pose = ros_bridge::PoseToMsg(frame.T_W_C);
      bag.write(options.pose_topic, stamp, pose);
    }
    bag.write(options.camera_info_topic, stamp, info);
    bag.write(options.color_topic, stamp, color);
    bag.write(options.depth_topic, depth.header.stamp, depth);
  }
  bag.close();
}

}  // namespace objmap::testing
