#pragma once
// The index built when a bag is opened: which colour, depth and camera info messages make each
// frame, and each frame's pose (or why it has none). Internal to objmap_rosbag_input.

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/message_instance.h>
#include <sensor_msgs/CameraInfo.h>

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "bag_topics.h"
#include "rosbag_input.h"

namespace objmap::rosbag_input {

/// One frame: handles to its images (read on demand through the bag they point into), its
/// camera info and its pose at the colour stamp.
struct IndexedFrame {
  rosbag::MessageInstance color;
  rosbag::MessageInstance depth;
  ros::Time stamp;              ///< the colour image's header stamp
  std::size_t camera_info = 0;  ///< into BagIndex::camera_infos
  std::optional<Eigen::Isometry3d> T_W_C;
  std::string pose_problem;  ///< why T_W_C is empty: the transform missing and tf2's reason
};

struct BagIndex {
  std::vector<IndexedFrame> frames;  ///< in colour stamp order
  std::vector<sensor_msgs::CameraInfo> camera_infos;
  std::string summary;  ///< topics, frame counts, colour images left out
  bool without_poses = false;  ///< the bag has no pose source (ChosenTopics::without_poses)
};

/// Pairs every colour image with the nearest depth image (within config.max_pair_interval_s)
/// and the nearest camera info, loads the pose messages into one transform buffer covering
/// the whole bag and looks each frame's pose up at its colour stamp. False with a reason when
/// a topic is empty or no colour image pairs with a depth image.
[[nodiscard]] bool IndexBag(const rosbag::Bag& bag, const ChosenTopics& topics,
                            const RosbagInputConfig& config, BagIndex* index, std::string* why);

/// "1305031102.175304000": a stamp as the messages name it.
[[nodiscard]] std::string StampText(const ros::Time& stamp);

}  // namespace objmap::rosbag_input
