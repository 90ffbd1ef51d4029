// objmap_node reading an OpenNI2 camera itself (~input openni2) against a real rosmaster: the
// failure paths this machine can reach (no device, a missing recording) and an .oni recording
// written by the test (tests/openni2/oni_file_writer.h) played into the map. A live camera's own
// paths (enumeration, video modes, registration) need hardware; see docs/ros.md.
#include <gtest/gtest.h>
#include <objmap_msgs/QueryOccupancy.h>
#include <objmap_msgs/Status.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <ros/topic.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <filesystem>
#include <thread>

#include "dataset/sequence_reader.h"
#include "openni2/oni_file_writer.h"
#include "ros_conversions.h"
#include "ros_node/ros_fixture.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::ChildProcess;
using testing::RosMaster;

class RosNodeCamera : public testing::RosFixture {
 protected:
  static void SetUpTestSuite() { StartRos("objmap_ros_camera"); }
  static void TearDownTestSuite() { StopRos(); }

  // objmap_node with the camera input, structure only, under its own name and database.
  static std::unique_ptr<ChildProcess> StartNode(const std::string& name,
                                                 const std::vector<std::string>& parameters) {
    std::vector<std::string> argv = {OBJMAP_NODE_PATH, "__name:=" + name,
                                     "_database:=" + (dir() / (name + ".db")).string(),
                                     "_input:=openni2", "_run_detector:=false"};
    argv.insert(argv.end(), parameters.begin(), parameters.end());
    auto node = std::make_unique<ChildProcess>(argv, (dir() / (name + ".log")).string());
    std::string why;
    EXPECT_TRUE(node->Start(&why)) << why;
    return node;
  }

  // Writes frames `indices` of `reader` as an .oni recording `name` in the test's folder (15
  // frames a second); their poses into `reference`. Its path, or empty with the reason.
  static std::string Record(const SequenceReader& reader, const std::vector<std::size_t>& indices,
                            const std::string& name, std::vector<Eigen::Isometry3d>* reference,
                            std::string* why) {
    std::vector<RgbdFrame> frames;
    for (const std::size_t index : indices) {
      RgbdFrame frame;
      if (!reader.ReadFrame(index, &frame, why)) return "";
      reference->push_back(frame.T_W_C);
      frames.push_back(std::move(frame));
    }
    const std::string path = (dir() / name).string();
    if (!testing::WriteOniFile(path, testing::RecordingOf(frames, 66667))) {
      *why = path + ": not written";
      return "";
    }
    return path;
  }
};

TEST_F(RosNodeCamera, WithoutACameraTheNodeSaysSoAndExits) {
  auto node = StartNode("objmap_node_no_camera", {"_openni2/static_camera:=true"});
  const int code = node->WaitForExit(std::chrono::seconds(60));
  if (code != 2 && node->Log().find("reading OpenNI2 device") != std::string::npos) {
    node->Stop(SIGINT);
    GTEST_SKIP() << "SKIPPED: an OpenNI2 camera is attached to this machine";
  }
  EXPECT_EQ(code, 2) << node->Log();
  EXPECT_NE(node->Log().find("no OpenNI2 device found"), std::string::npos) << node->Log();
}

TEST_F(RosNodeCamera, AMissingRecordingIsNamed) {
  const std::string path = (dir() / "absent.oni").string();
  auto node = StartNode("objmap_node_no_file",
                        {"_openni2/static_camera:=true", "_openni2/oni_path:=" + path});
  EXPECT_EQ(node->WaitForExit(std::chrono::seconds(60)), 2) << node->Log();
  EXPECT_NE(node->Log().find(path + ": no such .oni file"), std::string::npos) << node->Log();
}

TEST_F(RosNodeCamera, AMovingCameraNeedsItsTfFrame) {
  auto node = StartNode("objmap_node_no_frame", {});
  EXPECT_EQ(node->WaitForExit(std::chrono::seconds(60)), 2) << node->Log();
  EXPECT_NE(node->Log().find("~input openni2 needs ~camera_frame"), std::string::npos)
      << node->Log();
}

TEST_F(RosNodeCamera, PlaysARecordingIntoTheMap) {
  // A static camera 1.5 m in front of a flat wall, six frames.
  constexpr int kFrames = 6;
  const std::string path = (dir() / "wall.oni").string();
  ASSERT_TRUE(testing::WriteOniFile(path, testing::WallRecording(kFrames, 160, 120, 1500, 128)));
  auto node =
      StartNode("objmap_node_oni", {"_openni2/static_camera:=true", "_openni2/oni_path:=" + path,
                                    "_keyframes/every_nth_frame:=1"});
  ASSERT_TRUE(WaitForService("/objmap_node_oni/status", node.get())) << node->Log();
  objmap_msgs::Status status;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  // A frame is counted when read and mapped a little later (the map server's queue): wait for
  // both.
  while (ros::service::call("/objmap_node_oni/status", status) &&
         (status.response.frames_received < kFrames ||
          status.response.keyframes + status.response.frames_rejected < kFrames) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(status.response.frames_received, kFrames) << node->Log();
  EXPECT_EQ(status.response.frames_rejected, 0) << status.response.last_rejection;
  EXPECT_EQ(status.response.keyframes, kFrames);

  // The wall is occupied where the camera looks; the air in front of it is free.
  objmap_msgs::QueryOccupancy wall;
  wall.request.region_min.x = wall.request.region_min.y = -0.1;
  wall.request.region_max.x = wall.request.region_max.y = 0.1;
  wall.request.region_min.z = 1.45;
  wall.request.region_max.z = 1.55;
  ASSERT_TRUE(ros::service::call("/objmap_node_oni/query_occupancy", wall));
  ASSERT_TRUE(wall.response.ok) << wall.response.error;
  EXPECT_GT(wall.response.occupied, 100u);
  objmap_msgs::QueryOccupancy air = wall;
  air.request.region_min.z = 0.7;
  air.request.region_max.z = 0.8;
  ASSERT_TRUE(ros::service::call("/objmap_node_oni/query_occupancy", air));
  EXPECT_EQ(air.response.occupied, 0u);
  EXPECT_GT(air.response.free, 0u);
  EXPECT_TRUE(node->running()) << "the node keeps serving after the recording ended";
  EXPECT_EQ(node->Stop(SIGINT), 0) << node->Log();
  EXPECT_NE(node->Log().find("ended; the map is still served"), std::string::npos);
}

// ~pose_source estimate: a recording of 20 redkitchen frames, no TF anywhere. The node tracks
// the camera, maps every frame at its tracked pose, publishes map -> kitchen_camera on TF and
// the keyframes on ~trajectory.
TEST_F(RosNodeCamera, EstimatesThePosesOfARecordingAndPublishesThemOnTfAndAsAPath) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  const auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  constexpr int kFrames = 20;
  std::vector<std::size_t> indices;
  for (int n = 0; n < kFrames; ++n) indices.push_back(static_cast<std::size_t>(2 * n));
  std::vector<Eigen::Isometry3d> reference;
  const std::string path = Record(*reader, indices, "kitchen.oni", &reference, &why);
  ASSERT_FALSE(path.empty()) << why;

  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);  // before the node publishes
  auto node = StartNode("objmap_node_estimate",
                        {"_openni2/oni_path:=" + path, "_pose_source:=estimate",
                         "_camera_frame:=kitchen_camera", "_keyframes/every_nth_frame:=1"});
  ASSERT_TRUE(WaitForService("/objmap_node_estimate/status", node.get())) << node->Log();
  objmap_msgs::Status status;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  // A frame is counted when read and mapped a little later (the map server's queue): wait for
  // both.
  while (ros::service::call("/objmap_node_estimate/status", status) &&
         (status.response.frames_received < kFrames ||
          status.response.keyframes + status.response.frames_rejected < kFrames) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(status.response.frames_received, kFrames) << node->Log();
  EXPECT_EQ(status.response.frames_rejected, 0) << status.response.last_rejection;
  EXPECT_EQ(status.response.keyframes, kFrames);

  // TF holds the last frame's tracked pose; the map's origin is the first frame's camera.
  geometry_msgs::TransformStamped last;
  ASSERT_NO_THROW(last = tf_buffer.lookupTransform("map", "kitchen_camera", ros::Time(0),
                                                   ros::Duration(5.0)));
  Eigen::Isometry3d T_W_C;
  ASSERT_TRUE(ros_bridge::TransformFromMsg(last.transform, "tf", &T_W_C, &why)) << why;
  const Eigen::Isometry3d expected = reference.front().inverse() * reference.back();
  EXPECT_LT((expected.inverse() * T_W_C).translation().norm(), 0.03) << T_W_C.matrix();

  const auto trajectory = ros::topic::waitForMessage<nav_msgs::Path>(
      "/objmap_node_estimate/trajectory", ros::Duration(10.0));
  ASSERT_TRUE(trajectory);
  ASSERT_EQ(trajectory->poses.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(trajectory->header.frame_id, "map");
  for (int n = 0; n < kFrames; ++n) {
    Eigen::Isometry3d keyframe;
    ASSERT_TRUE(ros_bridge::PoseFromMsg(trajectory->poses[n].pose, "path", &keyframe, &why));
    const Eigen::Isometry3d truth = reference.front().inverse() * reference[n];
    EXPECT_LT((truth.inverse() * keyframe).translation().norm(), 0.03) << "keyframe " << n;
  }
  EXPECT_EQ(node->Stop(SIGINT), 0) << node->Log();
}

// Two sessions of ~pose_source estimate on one database. The second starts where the first's
// views do not reach (redkitchen frames 640 back to 540 after a map of frames 250-350): its first
// keyframes are tracked in a provisional part of the session and held, not rejected; the frame
// that places the part maps them at their poses in the map, then itself.
TEST_F(RosNodeCamera, ASessionStartingOffTheMappedViewsIsHeldThenMappedOncePlaced) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  const auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  std::vector<std::size_t> first_indices, second_indices;
  for (std::size_t index = 250; index <= 350; index += 5) first_indices.push_back(index);
  for (std::size_t index = 640; index >= 540; index -= 10) second_indices.push_back(index);
  std::vector<Eigen::Isometry3d> first_reference, second_reference;
  const std::string first = Record(*reader, first_indices, "parts_1.oni", &first_reference, &why);
  ASSERT_FALSE(first.empty()) << why;
  const std::string second =
      Record(*reader, second_indices, "parts_2.oni", &second_reference, &why);
  ASSERT_FALSE(second.empty()) << why;
  const auto first_count = static_cast<long long>(first_indices.size());
  const auto second_count = static_cast<long long>(second_indices.size());

  // Runs the node on `path` until every frame is read and mapped or refused; its last status.
  auto run = [&](const std::string& path, long long frames, long long keyframes_before,
                 std::unique_ptr<ChildProcess>* node) {
    *node = StartNode("objmap_node_parts",
                      {"_openni2/oni_path:=" + path, "_pose_source:=estimate",
                       "_camera_frame:=kitchen_camera", "_keyframes/every_nth_frame:=1"});
    EXPECT_TRUE(WaitForService("/objmap_node_parts/status", node->get())) << (*node)->Log();
    objmap_msgs::Status status;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
    while (ros::service::call("/objmap_node_parts/status", status) &&
           (status.response.frames_received < frames ||
            status.response.keyframes - keyframes_before + status.response.frames_rejected +
                    status.response.keyframes_held <
                frames) &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return status.response;
  };
  std::unique_ptr<ChildProcess> node;
  const auto first_status = run(first, first_count, 0, &node);
  ASSERT_EQ(first_status.keyframes, first_count) << first_status.last_rejection << node->Log();
  EXPECT_EQ(first_status.keyframes_attached, 0);
  EXPECT_EQ(node->Stop(SIGINT), 0) << node->Log();

  const auto second_status = run(second, second_count, first_count, &node);
  EXPECT_EQ(second_status.frames_received, second_count) << node->Log();
  EXPECT_EQ(second_status.frames_rejected, 0) << second_status.last_rejection;
  EXPECT_EQ(second_status.keyframes_held, 0) << "a part never placed: " << node->Log();
  ASSERT_GT(second_status.keyframes_attached, 0)
      << "frame 640 was placed at once: the test needs a start off the map";
  EXPECT_EQ(second_status.keyframes, first_count + second_count) << node->Log();

  // Every keyframe of the second session, the held ones included, at its pose in the map (whose
  // origin is the first session's first camera).
  const auto trajectory = ros::topic::waitForMessage<nav_msgs::Path>(
      "/objmap_node_parts/trajectory", ros::Duration(10.0));
  ASSERT_TRUE(trajectory);
  ASSERT_EQ(trajectory->poses.size(), second_indices.size());
  for (std::size_t n = 0; n < second_indices.size(); ++n) {
    Eigen::Isometry3d keyframe;
    ASSERT_TRUE(ros_bridge::PoseFromMsg(trajectory->poses[n].pose, "path", &keyframe, &why));
    const Eigen::Isometry3d truth = first_reference.front().inverse() * second_reference[n];
    const Eigen::Isometry3d error = truth.inverse() * keyframe;
    EXPECT_LT(error.translation().norm(), 0.05) << "frame " << second_indices[n];
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle(), 3.0 * M_PI / 180.0)
        << "frame " << second_indices[n];
  }
  EXPECT_EQ(node->Stop(SIGINT), 0) << node->Log();
  // The node's output reaches its log once it stops.
  EXPECT_NE(node->Log().find("held keyframe(s) mapped"), std::string::npos) << node->Log();
}

// launch/objmap_openni2.launch with a recording and a static camera serves the map it makes.
TEST_F(RosNodeCamera, OpenNI2LaunchPlaysARecording) {
  const std::string path = (dir() / "launched.oni").string();
  ASSERT_TRUE(testing::WriteOniFile(path, testing::WallRecording(3, 160, 120, 1200, 90)));
  setenv("ROS_PACKAGE_PATH", (std::string(OBJMAP_SOURCE_DIR) + ":/usr/share").c_str(), 1);
  setenv("CMAKE_PREFIX_PATH", OBJMAP_DEVEL_DIR, 1);
  ChildProcess launch(
      {"roslaunch", std::string(OBJMAP_SOURCE_DIR) + "/launch/objmap_openni2.launch",
       "node_name:=objmap_openni2_launched", "oni_path:=" + path, "static_camera:=true",
       "every_nth_frame:=1", "run_detector:=false",
       "database:=" + (dir() / "openni2_launched.db").string()},
      (dir() / "roslaunch_openni2.log").string());
  std::string why;
  ASSERT_TRUE(launch.Start(&why)) << why;
  objmap_msgs::Status status;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline && launch.running() &&
         !(ros::service::call("/objmap_openni2_launched/status", status) &&
           status.response.frames_received == 3)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(status.response.keyframes, 3) << launch.Log();
  EXPECT_EQ(launch.Stop(SIGINT), 0) << launch.Log();
}

}  // namespace
}  // namespace objmap
