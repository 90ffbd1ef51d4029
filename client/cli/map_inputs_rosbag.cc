// The `.bag` branch of OpenMapInput; compiled into `objmap` only in builds with ROS (see
// cmake/objmap_ros.cmake).
#include "map_inputs.h"
#include "rosbag_input.h"

namespace objmap::cli {

std::unique_ptr<SequenceReader> OpenBagInput(const std::string& path,
                                             const MapInputOptions& options, std::string* why) {
  RosbagInputConfig config;
  config.color_topic = options.bag_color_topic;
  config.depth_topic = options.bag_depth_topic;
  config.camera_info_topic = options.bag_camera_info_topic;
  config.pose_topic = options.bag_pose_topic;
  if (!options.world_frame.empty()) config.world_frame = options.world_frame;
  config.camera_frame = options.camera_frame;
  // A bag without TF is mapped when the poses are estimated anyway (--poses auto or estimate).
  config.poses_optional = options.estimate_poses || options.estimate_missing_poses;
  return OpenRosbagSequence(path, config, why);
}

}  // namespace objmap::cli
