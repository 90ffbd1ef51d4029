// objmap_node: the object map as a ROS1 node. Parameters: launch/objmap.launch and
// server/core/config/objmap.example.yaml; topics and services: docs/ros.md.
#include <ros/ros.h>

#include "dataset/frame_stream.h"
#include "detection/centernet_detector.h"
#include "detection/model_location.h"
#include "map_node.h"
#include "map_server/map_server.h"
#include "node_config.h"

namespace {

// The node's own camera for input "openni2"; nullptr and the reason when it cannot be opened.
std::unique_ptr<objmap::FrameStream> OpenCamera(const objmap::ros_node::CameraInputConfig& input,
                                                std::string* why) {
#ifdef OBJMAP_NODE_WITH_OPENNI2
  const objmap::OpenNI2SourceConfig& config = input.source;
  if (!config.IsValid(why)) {
    *why = "~openni2: " + *why;
    return nullptr;
  }
  return objmap::OpenNI2Source::Open(config, why);
#else
  (void)input;
  *why = "~input openni2: objmap_node was built without OpenNI2 (Debian: libopenni2-dev)";
  return nullptr;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "objmap_node");
  ros::NodeHandle node;
  ros::NodeHandle private_node("~");

  objmap::ros_node::NodeConfig config;
  std::string why;
  if (!objmap::ros_node::LoadNodeConfig(private_node, &config, &why)) {
    ROS_FATAL_STREAM("objmap_node: bad parameters: " << why);
    return 2;
  }
  std::unique_ptr<objmap::Detector> detector;
  if (config.detections_topic.empty() && config.run_detector) {
    objmap::CenterNetConfig detector_config = config.objmap.detector;
    if (!objmap::FindDetectorModel(detector_config.model_path, &detector_config.model_path, &why)) {
      ROS_FATAL_STREAM("objmap_node: " << why
                                       << " (or set ~detector/model_path, or ~run_detector false)");
      return 2;
    }
    ROS_INFO_STREAM("objmap_node: detector " << detector_config.model_path);
    detector = objmap::MakeCenterNetDetector(detector_config, &why);
    if (!detector) {
      ROS_FATAL_STREAM("objmap_node: detector: " << why);
      return 2;
    }
  }
  std::unique_ptr<objmap::FrameStream> camera;
  if (config.input == "openni2") {
    camera = OpenCamera(config.openni2, &why);
    if (!camera) {
      ROS_FATAL_STREAM("objmap_node: " << why);
      return 2;
    }
  }
  std::shared_ptr<objmap::MapServer> server =
      objmap::MapServer::Open(config.objmap.map_server, config.database, std::move(detector), &why);
  if (!server) {
    ROS_FATAL_STREAM("objmap_node: map database " << config.database << ": " << why);
    return 2;
  }
  // Services on the global queue, two at a time (a regeneration waited for must not block
  // status calls); frames have their own queue and thread inside MapNode.
  ros::AsyncSpinner spinner(2);
  spinner.start();
  {
    objmap::ros_node::MapNode map_node(node, private_node, config, server, std::move(camera));
    const objmap::ServerStatus status = server->Status();
    ROS_INFO_STREAM("objmap_node: serving " << config.database << " (" << status.keyframes
                                            << " keyframes, " << status.objects
                                            << " objects) in frame " << config.world_frame);
    ros::waitForShutdown();
  }
  server->Shutdown();
  return 0;
}
