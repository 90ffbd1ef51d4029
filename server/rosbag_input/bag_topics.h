#pragma once
// The topics of an open bag and the choice of the colour, depth, camera info and pose topics
// among them (given by name, or auto-detected). Internal to objmap_rosbag_input.

#include <rosbag/bag.h>

#include <cstddef>
#include <string>
#include <vector>

#include "rosbag_input.h"

namespace objmap::rosbag_input {

/// One topic of a bag as the error messages list it.
struct BagTopic {
  std::string name;
  std::string datatype;  ///< "sensor_msgs/Image"
  std::string encoding;  ///< of the first message, for images only
  std::size_t messages = 0;
};

/// The topics chosen for the frames; pose_topic empty means /tf and /tf_static.
struct ChosenTopics {
  std::string color, depth, camera_info, pose;
  bool without_poses = false;  // no pose source in the bag (RosbagInputConfig::poses_optional)
};

/// Every topic of `bag`, sorted by name.
[[nodiscard]] std::vector<BagTopic> ListTopics(const rosbag::Bag& bag);

/// "/a (sensor_msgs/Image rgb8, 60 messages), /tf (tf2_msgs/TFMessage, 60 messages)".
[[nodiscard]] std::string DescribeTopics(const std::vector<BagTopic>& topics);

/// Resolves the configured topics against the bag (see RosbagInputConfig); false with a reason
/// that names the bag and lists its topics (or the candidates) otherwise.
[[nodiscard]] bool ChooseTopics(const std::string& bag_path, const std::vector<BagTopic>& topics,
                                const RosbagInputConfig& config, ChosenTopics* chosen,
                                std::string* why);

}  // namespace objmap::rosbag_input
