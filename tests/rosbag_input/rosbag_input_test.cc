// The rosbag SequenceReader on bags written by the test: frames read back, pairing, poses from
// TF (interpolated) or a pose topic, and the errors a user meets.
#include "rosbag_input.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "test_bags.h"
#include "test_scenes.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::TestBagOptions;
using testing::WriteTestBag;

class RosbagInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_rosbag_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::vector<testing::SceneBox> boxes = {
        {{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},
        {{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}},
        {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}}};
    CameraIntrinsics K;
    K.width = 160;
    K.height = 120;
    K.fx = K.fy = 146.25;
    K.cx = 80.0;
    K.cy = 60.0;
    for (int i = 0; i < 5; ++i) {
      const Eigen::Isometry3d T_W_C =
          testing::LookAt({-1.0, -0.2 + 0.15 * i, 1.3}, Eigen::Vector3d(0, 0, 0.7));
      frames_.push_back(testing::RenderFrame(boxes, K, T_W_C, ""));
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::unique_ptr<SequenceReader> Open(const std::string& path,
                                       const RosbagInputConfig& config = {}) {
    why_.clear();
    return OpenRosbagSequence(path, config, &why_);
  }

  fs::path dir_;
  std::vector<RgbdFrame> frames_;
  std::string why_;
};

void ExpectSameFrame(const RgbdFrame& source, const RgbdFrame& read) {
  EXPECT_EQ(read.color.width, source.color.width);
  EXPECT_EQ(read.color.height, source.color.height);
  EXPECT_TRUE(read.color.rgb == source.color.rgb) << "colour differs";
  ASSERT_EQ(read.depth.depth_m.size(), source.depth.depth_m.size());
  float worst_depth_error_m = 0.f;
  for (std::size_t i = 0; i < source.depth.depth_m.size(); ++i) {
    worst_depth_error_m =
        std::max(worst_depth_error_m, std::abs(read.depth.depth_m[i] - source.depth.depth_m[i]));
  }
  EXPECT_LE(worst_depth_error_m, 0.0005f + 1e-6f) << "depth differs by more than half a mm";
  EXPECT_EQ(read.intrinsics.width, source.intrinsics.width);
  EXPECT_EQ(read.intrinsics.height, source.intrinsics.height);
  EXPECT_EQ(read.intrinsics.fx, source.intrinsics.fx);
  EXPECT_EQ(read.intrinsics.fy, source.intrinsics.fy);
  EXPECT_EQ(read.intrinsics.cx, source.intrinsics.cx);
  EXPECT_EQ(read.intrinsics.cy, source.intrinsics.cy);
  EXPECT_LE((read.T_W_C.matrix() - source.T_W_C.matrix()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(RosbagInput, FramesReadBackEqualTheSourceFrames) {
  WriteTestBag(Path("scene.bag"), frames_);
  const auto reader = Open(Path("scene.bag"));
  ASSERT_TRUE(reader) << why_;
  ASSERT_EQ(reader->size(), frames_.size()) << reader->Describe();
  EXPECT_NE(reader->Describe().find("5 frames (colour /rgb/image, depth /depth/image, camera "
                                    "info /rgb/camera_info; poses from /tf, /tf_static"),
            std::string::npos)
      << reader->Describe();
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    RgbdFrame frame;
    ASSERT_TRUE(reader->ReadFrame(i, &frame, &why_)) << why_;
    EXPECT_EQ(frame.frame_index, static_cast<std::int64_t>(i));
    EXPECT_NEAR(frame.stamp_s, 100.0 + 0.1 * static_cast<double>(i), 1e-6);
    ExpectSameFrame(frames_[i], frame);
  }
  RgbdFrame frame;
  EXPECT_FALSE(reader->ReadFrame(5, &frame, &why_));
  EXPECT_NE(why_.find("out of range"), std::string::npos) << why_;
}

TEST_F(RosbagInput, ReadFrameIsSafeFromSeveralThreads) {
  WriteTestBag(Path("scene.bag"), frames_);
  const auto reader = Open(Path("scene.bag"));
  ASSERT_TRUE(reader) << why_;
  std::vector<std::thread> threads;
  std::vector<int> failures(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < 3; ++round) {
        for (std::size_t i = 0; i < reader->size(); ++i) {
          RgbdFrame frame;
          std::string why;
          if (!reader->ReadFrame(i, &frame, &why) || frame.color.rgb != frames_[i].color.rgb) {
            ++failures[t];
          }
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < 4; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;
}

TEST_F(RosbagInput, PairsDepthWithinTheIntervalAndLeavesOthersOut) {
  TestBagOptions options;
  options.depth_delay_s = 0.015;
  WriteTestBag(Path("late_depth.bag"), frames_, options);
  ASSERT_TRUE(Open(Path("late_depth.bag"))) << why_;

  options.depth_delay_s = 0.05;  // nearer the colour image than the next one, but beyond 0.02 s
  WriteTestBag(Path("too_late.bag"), frames_, options);
  EXPECT_FALSE(Open(Path("too_late.bag")));
  EXPECT_NE(why_.find("no colour image on /rgb/image (5 messages, t=100.000000000..100.400000000) "
                      "has a depth image on /depth/image"),
            std::string::npos)
      << why_;
  RosbagInputConfig wide;
  wide.max_pair_interval_s = 0.06;
  const auto reader = Open(Path("too_late.bag"), wide);
  ASSERT_TRUE(reader) << why_;
  EXPECT_EQ(reader->size(), 5u);
}

TEST_F(RosbagInput, PoseTopicReplacesTf) {
  const std::vector<RgbdFrame> three = {frames_[0], frames_[1], frames_[2]};
  TestBagOptions options;
  options.write_tf = false;
  options.pose_topic = "/camera_pose";
  WriteTestBag(Path("pose_topic.bag"), three, options);
  RosbagInputConfig config;
  config.pose_topic = "camera_pose";
  const auto reader = Open(Path("pose_topic.bag"), config);
  ASSERT_TRUE(reader) << why_;
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(1, &frame, &why_)) << why_;
  ExpectSameFrame(frames_[1], frame);
  EXPECT_NE(reader->Describe().find("poses from /camera_pose"), std::string::npos)
      << reader->Describe();
}

TEST_F(RosbagInput, InterpolatesTfBetweenItsStamps) {
  // Frames 0 and 2 carry TF; frame 1's colour stamp (100.1) is halfway: its pose is the
  // interpolation of the two, which for these poses (a pure translation along y) is exact.
  std::vector<RgbdFrame> frames = {frames_[0], frames_[0], frames_[0]};
  for (int k = 0; k < 3; ++k) frames[k].T_W_C.translation().y() += 0.1 * k;
  TestBagOptions options;
  options.write_tf = false;
  WriteTestBag(Path("gap.bag"), frames, options);
  {
    rosbag::Bag bag(Path("gap.bag"), rosbag::bagmode::Append);
    for (int k : {0, 2}) {
      tf2_msgs::TFMessage tf;
      geometry_msgs::TransformStamped transform;
      transform.header.stamp = ros::Time(100.0 + 0.1 * k);
      transform.header.frame_id = "map";
      transform.child_frame_id = "camera";
      transform.transform = ros_bridge::TransformToMsg(frames[k].T_W_C);
      tf.transforms.push_back(transform);
      bag.write("/tf", transform.header.stamp, tf);
    }
  }
  const auto reader = Open(Path("gap.bag"));
  ASSERT_TRUE(reader) << why_;
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(1, &frame, &why_)) << why_;
  EXPECT_LE((frame.T_W_C.matrix() - frames[1].T_W_C.matrix()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(RosbagInput, FrameWithoutTfIsRefusedNamingTheFrameAndTheTransform) {
  TestBagOptions options;
  options.frames_with_tf = 4;
  WriteTestBag(Path("no_last_tf.bag"), frames_, options);
  const auto reader = Open(Path("no_last_tf.bag"));
  ASSERT_TRUE(reader) << why_;
  EXPECT_NE(reader->Describe().find("1 without a pose"), std::string::npos) << reader->Describe();
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(3, &frame, &why_)) << why_;
  EXPECT_FALSE(reader->ReadFrame(4, &frame, &why_));
  EXPECT_NE(why_.find("no_last_tf.bag frame 4 (t=100.400000000): no transform from 'camera' to "
                      "'map' (/tf, /tf_static) at t=100.400000000"),
            std::string::npos)
      << why_;
  EXPECT_NE(why_.find("extrapolation"), std::string::npos) << why_;
}

TEST_F(RosbagInput, MissingFileAndNonBagFileAreRefused) {
  EXPECT_FALSE(Open(Path("absent.bag")));
  EXPECT_EQ(why_, Path("absent.bag") + ": no such file");
  std::ofstream(Path("text.bag")) << "these are not the messages you are looking for\n";
  EXPECT_FALSE(Open(Path("text.bag")));
  EXPECT_NE(why_.find(Path("text.bag") + ": not a ROS bag"), std::string::npos) << why_;
}

TEST_F(RosbagInput, TopicNotInTheBagIsRefusedListingTheTopics) {
  WriteTestBag(Path("scene.bag"), frames_);
  RosbagInputConfig config;
  config.color_topic = "/camera/rgb/image_color";
  EXPECT_FALSE(Open(Path("scene.bag"), config));
  EXPECT_NE(
      why_.find("colour image topic '/camera/rgb/image_color' is not in " + Path("scene.bag") +
                "; its topics: /depth/image (sensor_msgs/Image 16UC1, "
                "5 messages), /rgb/camera_info (sensor_msgs/CameraInfo, "
                "5 messages), /rgb/image (sensor_msgs/Image rgb8, 5 "
                "messages), /tf (tf2_msgs/TFMessage, 5 messages)"),
      std::string::npos)
      << why_;
  config.color_topic = "/rgb/camera_info";
  EXPECT_FALSE(Open(Path("scene.bag"), config));
  EXPECT_NE(why_.find("holds sensor_msgs/CameraInfo, not sensor_msgs/Image"), std::string::npos)
      << why_;
  config.color_topic = "rgb/image";  // without the leading slash, as a user may type it
  EXPECT_TRUE(Open(Path("scene.bag"), config)) << why_;
}

TEST_F(RosbagInput, AmbiguousOrAbsentTopicsAreRefusedListingTheCandidates) {
  TestBagOptions options;
  options.color_topic = "/front/image";
  WriteTestBag(Path("front.bag"), frames_, options);
  {
    rosbag::Bag bag(Path("front.bag"), rosbag::bagmode::Append);
    sensor_msgs::Image color = ros_bridge::ColorToMsg(frames_[0].color);
    color.header.stamp = ros::Time(100.0);
    bag.write("/back/image", color.header.stamp, color);
  }
  EXPECT_FALSE(Open(Path("front.bag")));
  EXPECT_NE(why_.find("several colour image topics in " + Path("front.bag") +
                      ": /back/image, /front/image; choose one with --bag-color-topic"),
            std::string::npos)
      << why_;
  RosbagInputConfig config;
  config.color_topic = "/front/image";
  EXPECT_TRUE(Open(Path("front.bag"), config)) << why_;

  options = {};
  options.write_tf = false;
  WriteTestBag(Path("no_tf.bag"), frames_, options);
  EXPECT_FALSE(Open(Path("no_tf.bag")));
  EXPECT_NE(why_.find("has no /tf or /tf_static messages"), std::string::npos) << why_;
}

TEST(RosbagInputConfigTest, RefusesBadValues) {
  RosbagInputConfig config;
  std::string why;
  EXPECT_TRUE(config.IsValid(&why));
  config.depth_scale = 0.0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("depth_scale"), std::string::npos);
  config = {};
  config.world_frame.clear();
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("world_frame"), std::string::npos);
}

}  // namespace
}  // namespace objmap
