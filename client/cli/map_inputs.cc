#include "map_inputs.h"

namespace objmap::cli {
namespace {

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

const char kMapInputUsage[] =
    "inputs:\n"
    "  FOLDER                    7-Scenes folder (frame-NNNNNN.*) or TUM RGB-D folder\n"
    "  FILE.bag                  ROS1 bag (builds with ROS): colour, depth and camera info\n"
    "                            images paired by stamp, poses from /tf + /tf_static at each\n"
    "                            colour stamp; topics left unset are auto-detected\n"
    "  --bag-color-topic T       sensor_msgs/Image colour topic (rgb8, bgr8, rgba8, bgra8)\n"
    "  --bag-depth-topic T       sensor_msgs/Image depth topic (16UC1 mm, 32FC1 m)\n"
    "  --bag-camera-info-topic T sensor_msgs/CameraInfo topic\n"
    "  --bag-pose-topic T        geometry_msgs/PoseStamped T_W_C topic instead of TF\n"
    "  --world-frame F           TF frame of the map (default: map)\n"
    "  --camera-frame F          TF frame of the camera (default: the colour header's frame_id)\n";

std::set<std::string> MapInputFlags() {
  return {"--bag-color-topic", "--bag-depth-topic", "--bag-camera-info-topic",
          "--bag-pose-topic",  "--world-frame",     "--camera-frame"};
}

MapInputOptions MapInputOptionsFrom(const Arguments& args) {
  MapInputOptions options;
  options.bag_color_topic = args.Get("--bag-color-topic", "");
  options.bag_depth_topic = args.Get("--bag-depth-topic", "");
  options.bag_camera_info_topic = args.Get("--bag-camera-info-topic", "");
  options.bag_pose_topic = args.Get("--bag-pose-topic", "");
  options.world_frame = args.Get("--world-frame", "");
  options.camera_frame = args.Get("--camera-frame", "");
  return options;
}

std::unique_ptr<SequenceReader> OpenMapInput(const std::string& path,
                                             const MapInputOptions& options, std::string* why) {
  if (EndsWith(path, ".bag")) {
#ifdef OBJMAP_CLI_WITH_ROSBAG
    return OpenBagInput(path, options, why);
#else
    (void)options;
    *why = path +
           ": ROS bags need objmap built with ROS (this one was built without it: "
           "configure with -DOBJMAP_WITH_ROS=ON where ROS1 is installed)";
    return nullptr;
#endif
  }
  return OpenSequence(path, why);
}

}  // namespace objmap::cli
