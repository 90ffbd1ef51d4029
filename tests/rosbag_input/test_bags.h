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
    const ros::Time stamp(100.0 + 0.1 * static_cast<double>(k));
    ros_bridge::FrameMessages m =
        ros_bridge::FrameToMsgs(frames[k], stamp, "map", options.camera_frame);
    m.depth.header.stamp += ros::Duration(options.depth_delay_s);
    if (options.write_tf && k < options.frames_with_tf) {
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(m.T_W_C);
      bag.write("/tf", stamp, tf);
    }
    if (!options.pose_topic.empty()) {
      geometry_msgs::PoseStamped pose;
      pose.header = m.T_W_C.header;
      pose.pose = ros_bridge::PoseToMsg(frames[k].T_W_C);
      bag.write(options.pose_topic, stamp, pose);
    }
    bag.write(options.camera_info_topic, stamp, m.camera_info);
    bag.write(options.color_topic, stamp, m.color);
    bag.write(options.depth_topic, m.depth.header.stamp, m.depth);
  }
  bag.close();
}

}  // namespace objmap::testing
