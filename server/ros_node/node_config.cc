#include "node_config.h"

#include <ros/ros.h>

#include <vector>

#include "config/config_fields.h"
#include "ros_params.h"
#include "types/coco_classes.h"

namespace objmap::ros_node {
namespace {

// The shared typed reader plus objmap_node's one special type: lists of COCO classes.
class ParamReader : public ros_bridge::RosParamReader {
 public:
  explicit ParamReader(const ros::NodeHandle& node)
      : RosParamReader(node,
                       "objmap_node's parameters are listed in launch/objmap.launch and "
                       "server/core/config/objmap.example.yaml") {}

  using RosParamReader::operator();

  /// request, estimate or session_frame, as in the YAML file.
  void operator()(const char* key, PoseSource* source) {
    XmlRpc::XmlRpcValue raw;
    if (!Fetch(key, &raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeString ||
        !ParsePoseSource(static_cast<std::string>(raw), source)) {
      Fail(key, "expected request, estimate or session_frame, got " + ros_bridge::DescribeParam(raw));
    }
  }

  /// COCO classes, by name ("dining table") or id, as in the YAML file.
  void operator()(const char* key, std::vector<int>* class_ids) {
    XmlRpc::XmlRpcValue raw;
    if (!Fetch(key, &raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeArray) {
      Fail(key, "expected a list of COCO class names, got " + ros_bridge::DescribeParam(raw));
      return;
    }
    std::vector<int> ids;
    for (int i = 0; i < raw.size(); ++i) {
      int id = -1;
      if (raw[i].getType() == XmlRpc::XmlRpcValue::TypeString) {
        id = CocoClassId(static_cast<std::string>(raw[i]));
      } else if (raw[i].getType() == XmlRpc::XmlRpcValue::TypeInt) {
        id = static_cast<int>(raw[i]);
        if (id >= kNumCocoClasses) id = -1;
      }
      if (id < 0) {
        Fail(std::string(key) + "[" + std::to_string(i) + "]",
             ros_bridge::DescribeParam(raw[i]) + " is not a COCO class");
        return;
      }
      ids.push_back(id);
    }
    *class_ids = ids;
  }
};

void VisitNodeKeys(NodeConfig* c, ParamReader& v) {
  v.TopLevel();
  v("database", &c->database);
  v("world_frame", &c->world_frame);
  v("camera_frame", &c->camera_frame);
  v("pose_topic", &c->pose_topic);
  v("pose_source", &c->pose_source);
  v("detections_topic", &c->detections_topic);
  v("run_detector", &c->run_detector);
  v("depth_scale", &c->depth_scale);
  v("sync_max_interval_s", &c->sync_max_interval_s);
  v("sync_queue_size", &c->sync_queue_size);
  v("pose_timeout_s", &c->pose_timeout_s);
  v("input", &c->input);
  v.Section("publish");
  v("markers", &c->publish.markers);
  v("occupied_every_keyframes", &c->publish.occupied_every_keyframes);
  v("occupied_max_points", &c->publish.occupied_max_points);
  v.Section("openni2");
  v("device_uri", &c->openni2.source.device_uri);
  v("oni_path", &c->openni2.source.oni_path);
  v("width", &c->openni2.source.width);
  v("height", &c->openni2.source.height);
  v("fps", &c->openni2.source.fps);
  v("depth_to_color_registration", &c->openni2.source.depth_to_color_registration);
  v("mirror", &c->openni2.source.mirror);
  v("static_camera", &c->openni2.static_camera);
}

}  // namespace

bool PublishConfig::IsValid(std::string* why) const {
  if (occupied_every_keyframes < 0) {
    *why = "~publish/occupied_every_keyframes must be >= 0 (0: never)";
    return false;
  }
  if (occupied_max_points <= 0) {
    *why = "~publish/occupied_max_points must be positive";
    return false;
  }
  return true;
}

bool NodeConfig::IsValid(std::string* why) const {
  if (database.empty()) {
    *why = "~database must name the map's SQLite file";
    return false;
  }
  if (world_frame.empty()) {
    *why = "~world_frame must not be empty";
    return false;
  }
  if (!(depth_scale > 0.0)) {
    *why = "~depth_scale must be positive (0.001: millimetres)";
    return false;
  }
  if (!(sync_max_interval_s >= 0.0) || sync_queue_size <= 0) {
    *why = "~sync_max_interval_s must be >= 0 and ~sync_queue_size positive";
    return false;
  }
  if (!(pose_timeout_s >= 0.0)) {
    *why = "~pose_timeout_s must be >= 0";
    return false;
  }
  if (input != "topics" && input != "openni2") {
    *why = "~input '" + input + "' must be topics or openni2";
    return false;
  }
  if (pose_source != "external" && pose_source != "estimate") {
    *why = "~pose_source '" + pose_source + "' must be external or estimate";
    return false;
  }
  if (estimates_poses() && objmap.map_server.pose_source == PoseSource::kEstimate) {
    *why =
        "~pose_source estimate tracks every frame in the node; ~server/pose_source must stay "
        "request";
    return false;
  }
  if (input == "openni2" && !openni2.static_camera && !estimates_poses() && camera_frame.empty()) {
    *why =
        "~input openni2 needs ~camera_frame (the TF frame of the camera), "
        "~openni2/static_camera true or ~pose_source estimate";
    return false;
  }
  // Named as the node's parameters; the other sections' reasons name their config struct.
  std::string reason;
  if (!objmap.keyframes.IsValid(&reason)) {
    *why = "~keyframes: " + reason;
    return false;
  }
  return publish.IsValid(why) && objmap.IsValid(why);
}

bool LoadNodeConfig(const ros::NodeHandle& private_node, NodeConfig* config, std::string* why) {
  ParamReader reader(private_node);
  VisitNodeKeys(config, reader);
  // objmap's sections, walked by the same list as the YAML file's reader; it ends with
  // Finish(), which reports parameters that neither list has.
  internal::VisitObjmapConfig(&config->objmap, reader);
  if (!reader.ok()) {
    *why = reader.error();
    return false;
  }
  return config->IsValid(why);
}

}  // namespace objmap::ros_node
