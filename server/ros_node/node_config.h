#pragma once
// objmap_node's parameters: every ROS parameter it reads is translated into a config struct
// here, in one place, and validated before the node starts.

#include <string>

#include "config/objmap_config.h"
// The config struct only: the OpenNI2 library is linked where it was found (main.cc).
#include "openni2/openni2_source.h"

namespace ros {
class NodeHandle;
}

namespace objmap::ros_node {

/// What the node publishes besides answering services.
struct PublishConfig {
  /// Object markers (boxes coloured by class, labels) on ~objects after every map change.
  bool markers = true;
  /// Occupied voxel centres on ~occupied_cells every this many keyframes (and after every
  /// regeneration); 0: never.
  int occupied_every_keyframes = 5;
  /// Most points one ~occupied_cells cloud carries (a large map is thinned evenly).
  int occupied_max_points = 2000000;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// objmap_node's own OpenNI2 camera (input "openni2"), section `openni2`.
struct CameraInputConfig {
  /// Device or recording and how its streams are set up (device_uri, oni_path, width, height,
  /// fps, depth_to_color_registration, mirror).
  OpenNI2SourceConfig source;
  /// The camera does not move: every frame has the identity pose in world_frame and no TF is
  /// looked up (keyframes then come only from keyframes/every_nth_frame). Otherwise the pose
  /// is TF world_frame <- camera_frame at the time a frame is read.
  bool static_camera = false;
};

/// Everything objmap_node reads at start. Parameters live in the node's private namespace:
/// the keys below at the top level, and the sections of objmap's configuration file (server,
/// store, mapper, segmenter, ..., keyframes, detector: server/core/config/objmap.example.yaml,
/// the file objmap map and objmap_server read) as `~section/key`, so that
/// `rosparam load objmap.example.yaml ~` configures all three alike.
struct NodeConfig {
  /// objmap's configuration: the map server's sections, keyframe selection, the detector.
  ObjmapConfig objmap;
  /// SQLite file of the map; opened (and the map restored) at start, created when absent.
  std::string database = "objmap.db";
  /// Frame of the map: poses T_W_C are the transform from the camera's frame into this one.
  std::string world_frame = "map";
  /// Camera frame for the TF lookup; empty: the colour image's header.frame_id.
  std::string camera_frame;
  /// geometry_msgs/PoseStamped topic with T_W_C instead of TF; empty: TF.
  std::string pose_topic;
  /// Where camera poses come from: "external" (TF, or ~pose_topic) or "estimate": the node
  /// tracks every frame itself (RGB-D odometry with loop closure, settings of section
  /// `odometry`... defaults), publishes world_frame -> camera frame on TF and the keyframes'
  /// poses as nav_msgs/Path on ~trajectory, and moves the mapped keyframes when a loop closes.
  std::string pose_source = "external";
  [[nodiscard]] bool estimates_poses() const { return pose_source == "estimate"; }
  /// objmap_msgs/DetectionArray topic from the robot's own detector, paired with the images by
  /// stamp; empty: the node runs its detector (or none, see run_detector).
  std::string detections_topic;
  /// Without a detections topic: run the CenterNet detector of section `detector` (true) or map
  /// structure only, without objects (false).
  bool run_detector = true;
  /// Metres per unit of 16UC1 depth images (0.001: millimetres, as OpenNI2 drivers publish).
  double depth_scale = 0.001;
  /// Colour, depth, camera info (and detections) are paired by stamp: 0 pairs equal stamps only
  /// (exact time: a frame is handled as soon as its last message arrives; players and drivers
  /// that stamp both images alike), > 0 pairs stamps at most this far apart, in seconds
  /// (approximate time, for cameras whose colour and depth stamps differ; a set is handled once
  /// the next messages show no better match). The subscribers keep sync_queue_size messages.
  double sync_max_interval_s = 0.02;
  int sync_queue_size = 10;
  /// How long a frame waits for its camera pose (TF or pose topic) before it is rejected.
  double pose_timeout_s = 0.5;
  /// Section `publish`.
  PublishConfig publish;
  /// Where frames come from: "topics" (a camera driver's topics, the default) or "openni2" (the
  /// node reads an OpenNI2 device or .oni recording itself, section `openni2`).
  std::string input = "topics";
  CameraInputConfig openni2;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Reads the node's parameters over `config` (defaults for those not set) from `private_node`'s
/// namespace. False with a reason naming the parameter ("~mapper/min_detection_score: expected
/// a number, got 'high'") for values of the wrong type and for parameters the node does not know
/// (a misspelt key is an error, not a silent default); then IsValid.
[[nodiscard]] bool LoadNodeConfig(const ros::NodeHandle& private_node, NodeConfig* config,
                                  std::string* why);

}  // namespace objmap::ros_node
