#include "bag_index.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cstdio>

#include "ros_conversions.h"

namespace objmap::rosbag_input {
namespace {

// Child frame under which pose-topic poses enter the transform buffer, so that they are
// interpolated like TF.
constexpr char kPoseTopicFrame[] = "objmap_pose_topic_camera";

// The stamps of one image topic, sorted, with handles to the messages.
struct ImageStamps {
  std::vector<rosbag::MessageInstance> messages;  // in bag order
  struct Entry {
    ros::Time stamp;
    std::size_t message;
    std::string frame_id;
  };
  std::vector<Entry> sorted;
};

// Header stamps (the bag's receive time where a header has none).
ImageStamps ReadImageStamps(const rosbag::Bag& bag, const std::string& topic) {
  ImageStamps stamps;
  for (const rosbag::MessageInstance& message : rosbag::View(bag, rosbag::TopicQuery(topic))) {
    const sensor_msgs::Image::ConstPtr image = message.instantiate<sensor_msgs::Image>();
    if (!image) continue;
    const ros::Time stamp = image->header.stamp.isZero() ? message.getTime() : image->header.stamp;
    stamps.sorted.push_back({stamp, stamps.messages.size(), image->header.frame_id});
    stamps.messages.push_back(message);
  }
  std::stable_sort(stamps.sorted.begin(), stamps.sorted.end(),
                   [](const auto& a, const auto& b) { return a.stamp < b.stamp; });
  return stamps;
}

// Index of the entry of `sorted` (by .stamp, not empty) nearest to `stamp`.
template <typename Entry>
std::size_t Nearest(const std::vector<Entry>& sorted, const ros::Time& stamp) {
  const auto after = std::lower_bound(
      sorted.begin(), sorted.end(), stamp,
      [](const Entry& entry, const ros::Time& time) { return entry.stamp < time; });
  if (after == sorted.begin()) return 0;
  if (after == sorted.end()) return sorted.size() - 1;
  const auto before = after - 1;
  return static_cast<std::size_t>((stamp - before->stamp) <= (after->stamp - stamp)
                                      ? before - sorted.begin()
                                      : after - sorted.begin());
}

struct StampedInfo {
  ros::Time stamp;
  std::size_t info;
};

std::string StripSlash(const std::string& frame) {
  return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame;
}

// Every transform of the pose topics, and whether it came from /tf_static.
struct PoseMessages {
  std::vector<geometry_msgs::TransformStamped> transforms;
  std::vector<bool> is_static;
};

PoseMessages ReadPoseMessages(const rosbag::Bag& bag, const ChosenTopics& topics,
                              const std::string& world_frame) {
  PoseMessages poses;
  if (!topics.pose.empty()) {
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topics.pose))) {
      const geometry_msgs::PoseStamped::ConstPtr pose = m.instantiate<geometry_msgs::PoseStamped>();
      if (!pose) continue;
      geometry_msgs::TransformStamped transform;
      transform.header.stamp = pose->header.stamp;
      transform.header.frame_id = StripSlash(world_frame);
      transform.child_frame_id = kPoseTopicFrame;
      transform.transform.translation.x = pose->pose.position.x;
      transform.transform.translation.y = pose->pose.position.y;
      transform.transform.translation.z = pose->pose.position.z;
      transform.transform.rotation = pose->pose.orientation;
      poses.transforms.push_back(transform);
      poses.is_static.push_back(false);
    }
    return poses;
  }
  const std::vector<std::string> tf_topics = {"/tf", "/tf_static"};
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(tf_topics))) {
    const tf2_msgs::TFMessage::ConstPtr message = m.instantiate<tf2_msgs::TFMessage>();
    if (!message) continue;
    for (const geometry_msgs::TransformStamped& transform : message->transforms) {
      poses.transforms.push_back(transform);
      poses.is_static.push_back(m.getTopic() == "/tf_static");
    }
  }
  return poses;
}

// A buffer that holds every transform of the bag: its cache spans all their stamps, so that
// no transform is pruned as the later ones go in.
std::unique_ptr<tf2::BufferCore> MakeTransformBuffer(const PoseMessages& poses) {
  ros::Time first = ros::TIME_MAX, last = ros::TIME_MIN;
  for (std::size_t i = 0; i < poses.transforms.size(); ++i) {
    if (poses.is_static[i]) continue;
    first = std::min(first, poses.transforms[i].header.stamp);
    last = std::max(last, poses.transforms[i].header.stamp);
  }
  const ros::Duration span = first <= last ? last - first : ros::Duration(0);
  auto buffer = std::make_unique<tf2::BufferCore>(span + ros::Duration(10.0));
  for (std::size_t i = 0; i < poses.transforms.size(); ++i) {
    // setTransform refuses (and logs) malformed transforms; lookups through them then fail
    // with tf2's reason, which the frame reports.
    (void)buffer->setTransform(poses.transforms[i], "rosbag", poses.is_static[i]);
  }
  return buffer;
}

// `missing` names what is looked for in the message: "transform from 'camera' to 'map' (/tf,
// /tf_static)" or "pose on /pose".
void LookUpPose(const tf2::BufferCore& buffer, const std::string& world_frame,
                const std::string& camera_frame, const std::string& missing, IndexedFrame* frame) {
  if (camera_frame.empty()) {
    frame->pose_problem =
        "the colour image has no header.frame_id and no camera frame is set (--camera-frame)";
    return;
  }
  const std::string world = StripSlash(world_frame), camera = StripSlash(camera_frame);
  try {
    const geometry_msgs::TransformStamped transform =
        buffer.lookupTransform(world, camera, frame->stamp);
    Eigen::Isometry3d T_W_C;
    if (!ros_bridge::TransformFromMsg(transform.transform, "TF " + world + " <- " + camera, &T_W_C,
                                      &frame->pose_problem)) {
      return;
    }
    frame->T_W_C = T_W_C;
  } catch (const tf2::TransformException& e) {
    frame->pose_problem = "no " + missing + " at t=" + StampText(frame->stamp) + ": " + e.what();
  }
}

std::string SpanText(const std::vector<ImageStamps::Entry>& sorted) {
  return std::to_string(sorted.size()) + " messages, t=" + StampText(sorted.front().stamp) + ".." +
         StampText(sorted.back().stamp);
}

}  // namespace

std::string StampText(const ros::Time& stamp) {
  char text[32];
  std::snprintf(text, sizeof(text), "%u.%09u", stamp.sec, stamp.nsec);
  return text;
}

bool IndexBag(const rosbag::Bag& bag, const ChosenTopics& topics, const RosbagInputConfig& config,
              BagIndex* index, std::string* why) {
  const ImageStamps colors = ReadImageStamps(bag, topics.color);
  const ImageStamps depths = ReadImageStamps(bag, topics.depth);
  std::vector<StampedInfo> infos;
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery(topics.camera_info))) {
    const sensor_msgs::CameraInfo::ConstPtr info = m.instantiate<sensor_msgs::CameraInfo>();
    if (!info) continue;
    infos.push_back({info->header.stamp.isZero() ? m.getTime() : info->header.stamp,
                     index->camera_infos.size()});
    index->camera_infos.push_back(*info);
  }
  std::sort(infos.begin(), infos.end(),
            [](const StampedInfo& a, const StampedInfo& b) { return a.stamp < b.stamp; });
  for (const auto& [what, count] : {std::pair{topics.color, colors.sorted.size()},
                                    std::pair{topics.depth, depths.sorted.size()},
                                    std::pair{topics.camera_info, infos.size()}}) {
    if (count == 0) {
      *why = "no readable messages on " + what;
      return false;
    }
  }
  const PoseMessages poses = ReadPoseMessages(bag, topics, config.world_frame);
  const std::unique_ptr<tf2::BufferCore> buffer = MakeTransformBuffer(poses);
  const std::string pose_source = topics.pose.empty() ? "/tf, /tf_static" : topics.pose;
  std::size_t unpaired = 0, without_pose = 0;
  const ros::Duration max_gap(config.max_pair_interval_s);
  for (const ImageStamps::Entry& color : colors.sorted) {
    const ImageStamps::Entry& depth = depths.sorted[Nearest(depths.sorted, color.stamp)];
    const ros::Duration gap =
        depth.stamp > color.stamp ? depth.stamp - color.stamp : color.stamp - depth.stamp;
    if (gap > max_gap) {
      ++unpaired;
      continue;
    }
    IndexedFrame frame{colors.messages[color.message],
                       depths.messages[depth.message],
                       color.stamp,
                       infos[Nearest(infos, color.stamp)].info,
                       std::nullopt,
                       ""};
    const std::string camera_frame = !topics.pose.empty()           ? kPoseTopicFrame
                                     : !config.camera_frame.empty() ? config.camera_frame
                                                                    : color.frame_id;
    const std::string missing = !topics.pose.empty()
                                    ? "pose on " + topics.pose
                                    : "transform from '" + StripSlash(camera_frame) + "' to '" +
                                          StripSlash(config.world_frame) + "' (/tf, /tf_static)";
    if (topics.without_poses) {
      frame.pose_problem = "the bag has no /tf or /tf_static messages";
    } else {
      LookUpPose(*buffer, config.world_frame, camera_frame, missing, &frame);
    }
    without_pose += frame.T_W_C ? 0 : 1;
    index->frames.push_back(std::move(frame));
  }
  if (index->frames.empty()) {
    *why = "no colour image on " + topics.color + " (" + SpanText(colors.sorted) +
           ") has a depth image on " + topics.depth + " (" + SpanText(depths.sorted) + ") within " +
           std::to_string(config.max_pair_interval_s) + " s";
    return false;
  }
  index->without_poses = topics.without_poses;
  index->summary = std::to_string(index->frames.size()) + " frames (colour " + topics.color +
                   ", depth " + topics.depth + ", camera info " + topics.camera_info +
                   (topics.without_poses
                        ? "; no poses: no /tf or /tf_static messages)"
                        : "; poses from " + pose_source + " in frame '" + config.world_frame + "')");
  if (without_pose > 0 && !topics.without_poses) {
    index->summary += ", " + std::to_string(without_pose) + " without a pose";
  }
  if (unpaired > 0) {
    index->summary += ", " + std::to_string(unpaired) +
                      " colour images without a depth image within " +
                      std::to_string(config.max_pair_interval_s) + " s left out";
  }
  return true;
}

}  // namespace objmap::rosbag_input
