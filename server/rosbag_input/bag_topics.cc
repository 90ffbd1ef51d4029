#include "bag_topics.h"

#include <geometry_msgs/PoseStamped.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <algorithm>
#include <map>

namespace objmap::rosbag_input {
namespace {

namespace encodings = sensor_msgs::image_encodings;

const std::string kImageType = "sensor_msgs/Image";
const std::string kCameraInfoType = "sensor_msgs/CameraInfo";
const std::string kPoseType = "geometry_msgs/PoseStamped";

// Tie-breakers when several topics qualify, most usual first: openni/openni2 launch files,
// realsense2_camera, TUM RGB-D bags, objmap_dataset_player.
const std::vector<std::string> kCommonColorTopics = {
    "/camera/rgb/image_rect_color", "/camera/rgb/image_color", "/camera/rgb/image_raw",
    "/camera/color/image_raw", "/rgb/image"};
const std::vector<std::string> kCommonDepthTopics = {"/camera/depth_registered/image_raw",
                                                     "/camera/depth_registered/image",
                                                     "/camera/aligned_depth_to_color/image_raw",
                                                     "/camera/depth/image",
                                                     "/camera/depth/image_raw",
                                                     "/depth/image"};
const std::vector<std::string> kCommonCameraInfoTopics = {
    "/camera/rgb/camera_info", "/camera/color/camera_info", "/rgb/camera_info"};

struct TopicRole {
  const char* what;    // "colour image"
  const char* option;  // the CLI option naming it
  const std::string& datatype;
  std::vector<std::string> encodings;  // empty: any
  const std::vector<std::string>& common_names;
};

std::string Namespace(const std::string& topic) {
  const std::size_t slash = topic.rfind('/');
  return slash == std::string::npos ? "" : topic.substr(0, slash);
}

std::string Names(const std::vector<const BagTopic*>& topics) {
  std::string text;
  for (const BagTopic* topic : topics) text += (text.empty() ? "" : ", ") + topic->name;
  return text;
}

// A topic given by name: in the bag (with or without the leading slash), of the right type.
bool CheckNamed(const std::string& bag_path, const std::vector<BagTopic>& topics,
                const TopicRole& role, const std::string& name, std::string* found_name,
                std::string* why) {
  const auto found = std::find_if(topics.begin(), topics.end(), [&](const BagTopic& topic) {
    return topic.name == name || topic.name == "/" + name;
  });
  if (found == topics.end()) {
    *why = std::string(role.what) + " topic '" + name + "' is not in " + bag_path +
           "; its topics: " + DescribeTopics(topics);
    return false;
  }
  if (found->datatype != role.datatype) {
    *why = std::string(role.what) + " topic '" + name + "' in " + bag_path + " holds " +
           found->datatype + ", not " + role.datatype;
    return false;
  }
  *found_name = found->name;
  return true;
}

// The only topic of the role's type (and encoding); the common names break ties, then the
// camera info beside the colour topic.
bool Detect(const std::string& bag_path, const std::vector<BagTopic>& topics, const TopicRole& role,
            const std::string& preferred, std::string* name, std::string* why) {
  std::vector<const BagTopic*> candidates;
  for (const BagTopic& topic : topics) {
    const bool encoding_fits =
        role.encodings.empty() || std::find(role.encodings.begin(), role.encodings.end(),
                                            topic.encoding) != role.encodings.end();
    if (topic.datatype == role.datatype && encoding_fits) candidates.push_back(&topic);
  }
  if (candidates.size() == 1) {
    *name = candidates.front()->name;
    return true;
  }
  std::vector<std::string> preference = role.common_names;
  if (!preferred.empty()) preference.insert(preference.begin(), preferred);
  for (const std::string& wanted : preference) {
    for (const BagTopic* candidate : candidates) {
      if (candidate->name != wanted) continue;
      *name = candidate->name;
      return true;
    }
  }
  std::string accepted = role.datatype;
  for (const std::string& encoding : role.encodings) {
    accepted += (&encoding == &role.encodings.front() ? " in " : "/") + encoding;
  }
  if (candidates.empty()) {
    *why = std::string("no ") + role.what + " topic (" + accepted + ") in " + bag_path +
           "; its topics: " + DescribeTopics(topics);
  } else {
    *why = std::string("several ") + role.what + " topics in " + bag_path + ": " +
           Names(candidates) + "; choose one with " + role.option;
  }
  return false;
}

}  // namespace

std::vector<BagTopic> ListTopics(const rosbag::Bag& bag) {
  std::map<std::string, BagTopic> by_name;
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
    BagTopic& topic = by_name[connection->topic];
    topic.name = connection->topic;
    topic.datatype = connection->datatype;
  }
  for (auto& [name, topic] : by_name) {
    rosbag::View messages(bag, rosbag::TopicQuery(name));
    topic.messages = messages.size();
    if (topic.datatype != kImageType || topic.messages == 0) continue;
    const sensor_msgs::Image::ConstPtr first = messages.begin()->instantiate<sensor_msgs::Image>();
    if (first) topic.encoding = first->encoding;
  }
  std::vector<BagTopic> topics;
  for (auto& entry : by_name) topics.push_back(std::move(entry.second));
  return topics;
}

std::string DescribeTopics(const std::vector<BagTopic>& topics) {
  if (topics.empty()) return "none";
  std::string text;
  for (const BagTopic& topic : topics) {
    text += (text.empty() ? "" : ", ") + topic.name + " (" + topic.datatype +
            (topic.encoding.empty() ? "" : " " + topic.encoding) + ", " +
            std::to_string(topic.messages) + " messages)";
  }
  return text;
}

bool ChooseTopics(const std::string& bag_path, const std::vector<BagTopic>& topics,
                  const RosbagInputConfig& config, ChosenTopics* chosen, std::string* why) {
  const TopicRole color{"colour image",
                        "--bag-color-topic",
                        kImageType,
                        {encodings::RGB8, encodings::BGR8, encodings::RGBA8, encodings::BGRA8},
                        kCommonColorTopics};
  const TopicRole depth{"depth image",
                        "--bag-depth-topic",
                        kImageType,
                        {encodings::TYPE_16UC1, encodings::MONO16, encodings::TYPE_32FC1},
                        kCommonDepthTopics};
  const TopicRole info{
      "camera info", "--bag-camera-info-topic", kCameraInfoType, {}, kCommonCameraInfoTopics};
  const TopicRole pose{"pose", "--bag-pose-topic", kPoseType, {}, {}};
  const auto choose = [&](const TopicRole& role, const std::string& configured,
                          const std::string& preferred, std::string* name) {
    if (configured.empty()) return Detect(bag_path, topics, role, preferred, name, why);
    return CheckNamed(bag_path, topics, role, configured, name, why);
  };
  if (!choose(color, config.color_topic, "", &chosen->color) ||
      !choose(depth, config.depth_topic, "", &chosen->depth) ||
      !choose(info, config.camera_info_topic, Namespace(chosen->color) + "/camera_info",
              &chosen->camera_info)) {
    return false;
  }
  if (!config.pose_topic.empty()) return choose(pose, config.pose_topic, "", &chosen->pose);
  chosen->pose.clear();
  const bool has_tf = std::any_of(topics.begin(), topics.end(), [](const BagTopic& topic) {
    return topic.name == "/tf" || topic.name == "/tf_static";
  });
  if (!has_tf && config.poses_optional) {
    chosen->without_poses = true;
    return true;
  }
  if (!has_tf) {
    *why = bag_path +
           " has no /tf or /tf_static messages for the camera poses (or pass a "
           "geometry_msgs/PoseStamped topic with --bag-pose-topic); its topics: " +
           DescribeTopics(topics);
    return false;
  }
  return true;
}

}  // namespace objmap::rosbag_input
