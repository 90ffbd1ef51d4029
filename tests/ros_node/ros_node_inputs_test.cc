// objmap_node's other inputs against a real rosmaster, on small synthetic frames (a camera in
// front of a wall): poses from a PoseStamped topic instead of TF, colour and depth whose stamps
// differ (approximate-time pairing), and detections from the robot's own detector on a topic,
// bad ones refused with the reason.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <objmap_msgs/DetectionArray.h>
#include <objmap_msgs/Status.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include <filesystem>
#include <thread>

#include "ros_conversions.h"
#include "ros_node/ros_fixture.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::ChildProcess;
using testing::RosMaster;

constexpr int kWidth = 160;
constexpr int kHeight = 120;

// A camera 1.5 m from a flat wall, `x` metres along the wall.
RgbdFrame WallFrame(double x) {
  RgbdFrame frame;
  frame.intrinsics = {kWidth, kHeight, 146.0, 146.0, 80.0, 60.0};
  frame.color.width = frame.depth.width = kWidth;
  frame.color.height = frame.depth.height = kHeight;
  frame.color.rgb.assign(kWidth * kHeight * 3, 120);
  frame.depth.depth_m.assign(kWidth * kHeight, 1.5f);
  frame.T_W_C.translation().x() = x;
  return frame;
}

class RosNodeInputs : public testing::RosFixture {
 protected:
  static void SetUpTestSuite() { StartRos("objmap_ros_inputs"); }
  static void TearDownTestSuite() { StopRos(); }

  // objmap_node under `name` (its topics in namespace `name`), structure only unless detections
  // come on a topic; waits until it serves.
  static std::unique_ptr<ChildProcess> StartNode(const std::string& name,
                                                 const std::vector<std::string>& parameters) {
    std::vector<std::string> argv = {
        OBJMAP_NODE_PATH,       "__name:=" + name,
        "__ns:=/" + name,       "_database:=" + (dir() / (name + ".db")).string(),
        "_run_detector:=false", "_keyframes/every_nth_frame:=1"};
    argv.insert(argv.end(), parameters.begin(), parameters.end());
    auto node = std::make_unique<ChildProcess>(argv, (dir() / (name + ".log")).string());
    std::string why;
    EXPECT_TRUE(node->Start(&why)) << why;
    EXPECT_TRUE(WaitForService("/" + name + "/" + name + "/status", node.get())) << node->Log();
    return node;
  }

  static objmap_msgs::Status::Response Status(const std::string& name) {
    objmap_msgs::Status status;
    EXPECT_TRUE(ros::service::call("/" + name + "/" + name + "/status", status));
    return status.response;
  }

  // Waits until the node has handled `frames` frames (60 s at most).
  // Until `frames` frames are received and each is also mapped or refused: a frame is counted
  // when read and mapped a little later (the map server's queue). Every frame of these tests is
  // a keyframe.
  static objmap_msgs::Status::Response WaitForFrames(const std::string& name, long long frames) {
    objmap_msgs::Status::Response status = Status(name);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while ((status.frames_received < frames || status.keyframes + status.frames_rejected < frames) &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      status = Status(name);
    }
    return status;
  }

  template <typename Message>
  static ros::Publisher Advertise(ros::NodeHandle& handle, const std::string& topic) {
    ros::Publisher publisher = handle.advertise<Message>(topic, 10);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (publisher.getNumSubscribers() == 0 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_GT(publisher.getNumSubscribers(), 0u) << topic;
    return publisher;
  }
};

// Poses from a PoseStamped topic, depth stamped 5 ms after colour: approximate pairing takes
// every frame but the last (a set is handed over once the next messages show no better match).
TEST_F(RosNodeInputs, PoseTopicAndApproximatePairing) {
  const std::string name = "approximate";
  auto node = StartNode(name, {"_pose_topic:=camera_pose", "_sync_max_interval_s:=0.02"});
  ros::NodeHandle handle("/" + name);
  ros::Publisher pose_pub = Advertise<geometry_msgs::PoseStamped>(handle, "camera_pose");
  ros::Publisher color_pub = Advertise<sensor_msgs::Image>(handle, "rgb/image");
  ros::Publisher depth_pub = Advertise<sensor_msgs::Image>(handle, "depth/image");
  ros::Publisher info_pub = Advertise<sensor_msgs::CameraInfo>(handle, "rgb/camera_info");
  constexpr int kFrames = 5;
  for (int i = 0; i < kFrames; ++i) {
    const RgbdFrame frame = WallFrame(0.2 * i);
    const ros::Time stamp(50.0 + 0.1 * i);
    ros_bridge::FrameMessages m = ros_bridge::FrameToMsgs(frame, stamp, "map", "camera");
    m.depth.header.stamp += ros::Duration(0.005);
    geometry_msgs::PoseStamped pose;
    pose.header = m.T_W_C.header;
    pose.pose = ros_bridge::PoseToMsg(frame.T_W_C);
    pose_pub.publish(pose);
    info_pub.publish(m.camera_info);
    color_pub.publish(m.color);
    depth_pub.publish(m.depth);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  const objmap_msgs::Status::Response status = WaitForFrames(name, kFrames - 1);
  EXPECT_EQ(status.frames_received, kFrames - 1) << node->Log();
  EXPECT_EQ(status.frames_rejected, 0) << status.last_rejection;
  EXPECT_EQ(status.keyframes, kFrames - 1);
  EXPECT_EQ(node->Stop(SIGINT), 0) << node->Log();
}

// Detections on a topic, paired with the images by stamp; a detection of no COCO class refuses
// its frame with the reason, and the next frame is taken.
TEST_F(RosNodeInputs, DetectionsTopic) {
  const std::string name = "detections";
  auto node = StartNode(name, {"_detections_topic:=detector/detections",
                               "_sync_max_interval_s:=0.0", "_camera_frame:=camera"});
  ros::NodeHandle handle("/" + name);
  ros::Publisher tf_pub = handle.advertise<tf2_msgs::TFMessage>("/tf", 10);
  ros::Publisher color_pub = Advertise<sensor_msgs::Image>(handle, "rgb/image");
  ros::Publisher depth_pub = Advertise<sensor_msgs::Image>(handle, "depth/image");
  ros::Publisher info_pub = Advertise<sensor_msgs::CameraInfo>(handle, "rgb/camera_info");
  ros::Publisher detections_pub =
      Advertise<objmap_msgs::DetectionArray>(handle, "detector/detections");
  while (tf_pub.getNumSubscribers() == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const std::vector<std::string> classes = {"tv", "unicorn", "tv"};
  for (std::size_t i = 0; i < classes.size(); ++i) {
    const RgbdFrame frame = WallFrame(0.2 * static_cast<double>(i));
    const ros::Time stamp(70.0 + 0.1 * static_cast<double>(i));
    const ros_bridge::FrameMessages m = ros_bridge::FrameToMsgs(frame, stamp, "map", "camera");
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(m.T_W_C);
    tf_pub.publish(tf);
    objmap_msgs::DetectionArray detections;
    detections.header.stamp = stamp;
    objmap_msgs::Detection detection;
    detection.x_min = 40;
    detection.y_min = 30;
    detection.x_max = 120;
    detection.y_max = 90;
    detection.class_name = classes[i];
    detection.score = 0.9f;
    detections.detections.push_back(detection);
    detections_pub.publish(detections);
    info_pub.publish(m.camera_info);
    depth_pub.publish(m.depth);
    color_pub.publish(m.color);
    WaitForFrames(name, static_cast<long long>(i) + 1);
  }
  const objmap_msgs::Status::Response status = Status(name);
  EXPECT_EQ(status.frames_received, 3) << node->Log();
  EXPECT_EQ(status.frames_rejected, 1);
  EXPECT_EQ(status.keyframes, 2);
  EXPECT_NE(status.last_rejection.find("detections[0].class_name 'unicorn' is not a COCO class"),
            std::string::npos)
      << status.last_rejection;
  EXPECT_EQ(node->Stop(SIGINT), 0) << node->Log();
}

}  // namespace
}  // namespace objmap
