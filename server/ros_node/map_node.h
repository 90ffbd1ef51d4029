#pragma once
// objmap_node's ROS side: takes synchronised colour + depth + camera info (and optionally
// detections) from topics and camera poses from TF or a pose topic, selects keyframes and feeds
// them to the same MapServer as objmap_server; answers the map services and publishes markers,
// occupied cells and map changes.

#include <memory>

#include "node_config.h"

namespace ros {
class NodeHandle;
}

namespace objmap {
class FrameStream;
class MapServer;
}  // namespace objmap

namespace objmap::ros_node {

/// Thread-safety: constructed and destroyed on one thread. Frames are handled in arrival order
/// on a callback queue of their own (one thread), so a keyframe being mapped never delays a
/// service answer; services run on the global queue (spin it with an AsyncSpinner).
class MapNode {
 public:
  /// Subscribes, advertises and starts the thread that publishes map changes. `node` resolves
  /// the input topics (remap them: rgb/image, depth/image, rgb/camera_info), `private_node` the
  /// services and published topics (~query_objects, ~objects, ...). With `camera` (input
  /// "openni2"), frames are read from it on a thread of their own instead of the topics.
  MapNode(const ros::NodeHandle& node, const ros::NodeHandle& private_node,
          const NodeConfig& config, std::shared_ptr<MapServer> server,
          std::unique_ptr<FrameStream> camera = nullptr);
  /// Stops taking frames and publishing; the MapServer is left to its owner.
  ~MapNode();
  MapNode(const MapNode&) = delete;
  MapNode& operator=(const MapNode&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap::ros_node
