#include "node_config.h"

#include <ros/ros.h>

#include <set>
#include <type_traits>

#include "server_config_fields.h"
#include "types/coco_classes.h"

namespace objmap::ros_node {
namespace {

std::string Describe(const XmlRpc::XmlRpcValue& value) {
  XmlRpc::XmlRpcValue copy = value;
  switch (copy.getType()) {
    case XmlRpc::XmlRpcValue::TypeArray:
      return "a list";
    case XmlRpc::XmlRpcValue::TypeStruct:
      return "a mapping";
    default:
      return "'" + copy.toXml() + "'";
  }
}

template <typename T>
const char* Expected() {
  if constexpr (std::is_same_v<T, bool>) return "true or false";
  if constexpr (std::is_integral_v<T>) return "an integer";
  if constexpr (std::is_floating_point_v<T>) return "a number";
  return "a string";
}

// One parameter value as T; integers are accepted where numbers are expected.
template <typename T>
bool Convert(XmlRpc::XmlRpcValue& value, T* out) {
  const auto type = value.getType();
  if constexpr (std::is_same_v<T, bool>) {
    if (type != XmlRpc::XmlRpcValue::TypeBoolean) return false;
    *out = static_cast<bool>(value);
  } else if constexpr (std::is_integral_v<T>) {
    if (type != XmlRpc::XmlRpcValue::TypeInt) return false;
    *out = static_cast<T>(static_cast<int>(value));
  } else if constexpr (std::is_floating_point_v<T>) {
    if (type == XmlRpc::XmlRpcValue::TypeInt) {
      *out = static_cast<T>(static_cast<int>(value));
    } else if (type == XmlRpc::XmlRpcValue::TypeDouble) {
      *out = static_cast<T>(static_cast<double>(value));
    } else {
      return false;
    }
  } else {
    if (type != XmlRpc::XmlRpcValue::TypeString) return false;
    *out = static_cast<std::string>(value);
  }
  return true;
}

// Reads `~key` and `~section/key` parameters, remembering every name it knows so that the
// parameters left over can be reported as unknown. Stops at the first problem.
class ParamReader {
 public:
  explicit ParamReader(const ros::NodeHandle& node) : node_(node) {}

  void Section(const char* name) { section_ = std::string(name) + "/"; }
  void TopLevel() { section_.clear(); }

  template <typename T>
  void operator()(const char* key, T* value) {
    const std::string name = section_ + key;
    known_.insert(node_.resolveName(name));
    XmlRpc::XmlRpcValue raw;
    if (!ok() || !node_.getParam(name, raw)) return;
    if (!Convert(raw, value)) {
      error_ = "~" + name + ": expected " + Expected<T>() + ", got " + Describe(raw);
    }
  }

  /// COCO classes, by name ("dining table") or id, as in the YAML file.
  void operator()(const char* key, std::vector<int>* class_ids) {
    const std::string name = section_ + key;
    known_.insert(node_.resolveName(name));
    XmlRpc::XmlRpcValue raw;
    if (!ok() || !node_.getParam(name, raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeArray) {
      error_ = "~" + name + ": expected a list of COCO class names, got " + Describe(raw);
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
        error_ = "~" + name + "[" + std::to_string(i) + "]: " + Describe(raw[i]) +
                 " is not a COCO class";
        return;
      }
      ids.push_back(id);
    }
    *class_ids = ids;
  }

  /// After the last section: every parameter in the namespace must have been read.
  void Finish() {
    if (!ok()) return;
    std::vector<std::string> names;
    if (!ros::param::getParamNames(names)) {
      error_ = "the parameter server's names could not be listed";
      return;
    }
    const std::string prefix = node_.getNamespace() + "/";
    for (const std::string& name : names) {
      if (name.rfind(prefix, 0) != 0 || known_.count(name) != 0) continue;
      error_ = "~" + name.substr(prefix.size()) +
               ": unknown parameter (objmap_node's parameters are listed in "
               "launch/objmap.launch and server/apps/objmap.example.yaml)";
      return;
    }
  }

  [[nodiscard]] bool ok() const { return error_.empty(); }
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  const ros::NodeHandle& node_;
  std::string section_;
  std::set<std::string> known_;
  std::string error_;
};

void VisitNodeKeys(NodeConfig* c, ParamReader& v) {
  v.TopLevel();
  v("database", &c->database);
  v("world_frame", &c->world_frame);
  v("camera_frame", &c->camera_frame);
  v("pose_topic", &c->pose_topic);
  v("detections_topic", &c->detections_topic);
  v("run_detector", &c->run_detector);
  v("depth_scale", &c->depth_scale);
  v("sync_max_interval_s", &c->sync_max_interval_s);
  v("sync_queue_size", &c->sync_queue_size);
  v("pose_timeout_s", &c->pose_timeout_s);
  v("input", &c->input);
  v.Section("keyframes");
  v("min_translation_m", &c->keyframes.min_translation_m);
  v("min_rotation_deg", &c->keyframes.min_rotation_deg);
  v("every_nth_frame", &c->keyframes.every_nth_frame);
  v.Section("publish");
  v("markers", &c->publish.markers);
  v("occupied_every_keyframes", &c->publish.occupied_every_keyframes);
  v("occupied_max_points", &c->publish.occupied_max_points);
  v.Section("openni2");
  v("device_uri", &c->openni2.device_uri);
  v("oni_path", &c->openni2.oni_path);
  v("width", &c->openni2.width);
  v("height", &c->openni2.height);
  v("fps", &c->openni2.fps);
  v("depth_to_color_registration", &c->openni2.depth_to_color_registration);
  v("mirror", &c->openni2.mirror);
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
  if (input == "openni2" && !openni2.static_camera && camera_frame.empty()) {
    *why =
        "~input openni2 needs ~camera_frame (the TF frame of the camera) or "
        "~openni2/static_camera true";
    return false;
  }
  std::string reason;
  if (!keyframes.IsValid(&reason)) {
    *why = "~keyframes: " + reason;
    return false;
  }
  return publish.IsValid(why) && server.IsValid(why);
}

bool LoadNodeConfig(const ros::NodeHandle& private_node, NodeConfig* config, std::string* why) {
  ParamReader reader(private_node);
  VisitNodeKeys(config, reader);
  // The map server's sections, walked by the same list as objmap_server's YAML reader; it ends
  // with Finish(), which reports parameters that neither list has.
  internal::VisitServerConfig(&config->server, reader);
  if (!reader.ok()) {
    *why = reader.error();
    return false;
  }
  return config->IsValid(why);
}

}  // namespace objmap::ros_node
