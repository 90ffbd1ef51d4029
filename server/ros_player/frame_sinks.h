#pragma once
// Where objmap_dataset_player sends each frame: live topics (optionally in step with
// objmap_node) or a bag file. Both get the same messages, built by ros_bridge::FrameToMsgs.

#include <geometry_msgs/TransformStamped.h>
#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>
#include <string>

#include "player_config.h"
#include "ros_conversions.h"
#include "types/frame.h"

namespace objmap::ros_player {

using ros_bridge::FrameMessages;

/// Receives the frames in order. Thread-safety: one thread.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  /// False with a reason when the frame cannot be sent (write error, node gone).
  [[nodiscard]] virtual bool Send(const FrameMessages& messages, std::string* why) = 0;
  /// Flushes what was sent; false with a reason on failure.
  [[nodiscard]] virtual bool Finish(std::string* why) = 0;
};

/// Writes /rgb/image, /depth/image, /rgb/camera_info and /tf into `config.write_bag`, each at
/// its stamp as bag time. Needs no rosmaster. Returns nullptr and a reason when the file
/// cannot be created.
[[nodiscard]] std::unique_ptr<FrameSink> MakeBagSink(const PlayerConfig& config, std::string* why);

/// Publishes rgb/image, depth/image, rgb/camera_info (relative to `node`) and /tf at
/// config.rate_hz; with config.wait_for_node, first waits for the node's service and
/// subscriptions, and before each frame until the node has handled the previous one.
[[nodiscard]] std::unique_ptr<FrameSink> MakeTopicSink(ros::NodeHandle& node,
                                                       const PlayerConfig& config,
                                                       std::string* why);

}  // namespace objmap::ros_player
