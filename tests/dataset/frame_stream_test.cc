// FrameStream over a sequence folder, and poses from a TUM trajectory matched by stamp.
#include "dataset/frame_stream.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "dataset/trajectory.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

class FrameStreamTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_frame_stream_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // Frames 0..count-1 of the 7-Scenes layout, frame i at depth (1000 + i) mm and x = i metres.
  void WriteSevenScenes(int count) const {
    for (int i = 0; i < count; ++i) {
      const std::string stem = Path("frame-00000" + std::to_string(i));
      cv::imwrite(stem + ".depth.png", cv::Mat(480, 640, CV_16UC1, cv::Scalar(1000 + i)));
      cv::imwrite(stem + ".color.png", cv::Mat(480, 640, CV_8UC3, cv::Scalar(10, 20, 30)));
      std::ofstream(stem + ".pose.txt") << "1 0 0 " << i << "\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
    }
  }

  fs::path dir_;
};

TEST_F(FrameStreamTest, SequenceStreamGivesTheReadersFramesInOrder) {
  WriteSevenScenes(4);
  std::string why;
  auto reader = OpenSequence(dir_.string(), &why);
  ASSERT_NE(reader, nullptr) << why;
  auto stream = MakeSequenceStream(*reader, 1, 2);
  EXPECT_EQ(stream->size(), 2u);
  EXPECT_EQ(stream->Describe(), reader->Describe());
  for (std::size_t index = 1; index <= 2; ++index) {
    RgbdFrame expected, frame;
    ASSERT_TRUE(reader->ReadFrame(index, &expected, &why)) << why;
    ASSERT_EQ(stream->Next(&frame, &why), FrameStatus::kFrame) << why;
    EXPECT_EQ(frame.frame_index, static_cast<std::int64_t>(index));
    EXPECT_EQ(frame.name, expected.name);
    EXPECT_EQ(frame.depth.depth_m, expected.depth.depth_m);
    EXPECT_EQ(frame.color.rgb, expected.color.rgb);
    EXPECT_TRUE(frame.T_W_C.isApprox(expected.T_W_C));
    EXPECT_DOUBLE_EQ(frame.T_W_C.translation().x(), static_cast<double>(index));
  }
  RgbdFrame frame;
  EXPECT_EQ(stream->Next(&frame, &why), FrameStatus::kEnded);
  EXPECT_EQ(MakeSequenceStream(*reader)->size(), 4u);
}

TEST_F(FrameStreamTest, UnreadableFrameIsABadFrameNamingIt) {
  WriteSevenScenes(3);
  std::string why;
  auto reader = OpenSequence(dir_.string(), &why);
  ASSERT_NE(reader, nullptr) << why;
  std::ofstream(Path("frame-000001.color.png")) << "not a png";
  auto stream = MakeSequenceStream(*reader);
  RgbdFrame frame;
  EXPECT_EQ(stream->Next(&frame, &why), FrameStatus::kFrame) << why;
  EXPECT_EQ(stream->Next(&frame, &why), FrameStatus::kBadFrame);
  EXPECT_EQ(frame.frame_index, 1);
  EXPECT_NE(why.find("frame-000001.color.png"), std::string::npos) << why;
  EXPECT_EQ(stream->Next(&frame, &why), FrameStatus::kFrame) << why;
  EXPECT_EQ(frame.frame_index, 2);
}

// Frames with stamps 0.0, 0.1, 0.2, ... and identity poses, as a camera gives them.
class StampedStream : public FrameStream {
 public:
  explicit StampedStream(int count) : count_(count) {}
  FrameStatus Next(RgbdFrame* frame, std::string*) override {
    if (next_ == count_) return FrameStatus::kEnded;
    frame->frame_index = next_;
    frame->stamp_s = 0.1 * next_;
    frame->name = "camera frame " + std::to_string(next_++);
    return FrameStatus::kFrame;
  }
  std::string Describe() const override { return "camera"; }

 private:
  int count_;
  int next_ = 0;
};

TEST_F(FrameStreamTest, TrajectoryPosesFramesByNearestStamp) {
  // Out of order on purpose, a comment, a blank line; no pose near frame 2 (stamp 0.2).
  std::ofstream(Path("poses.txt")) << "# stamp tx ty tz qx qy qz qw\n"
                                   << "0.105 2 0 0 0 0 0 1\n\n"
                                   << "0.0 1 0 0 0 0 0.7071068 0.7071068\n"
                                   << "0.31 3 0 0 0 0 0 1\n";
  std::vector<TrajectoryPose> poses;
  std::string why;
  ASSERT_TRUE(ReadTumTrajectory(Path("poses.txt"), &poses, &why)) << why;
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_DOUBLE_EQ(poses[0].stamp_s, 0.0);
  TrajectoryMatchConfig match;
  match.max_stamp_difference_s = 0.02;
  auto stream = WithTrajectory(std::make_unique<StampedStream>(4), poses, match, "poses.txt");
  RgbdFrame frame;
  ASSERT_EQ(stream->Next(&frame, &why), FrameStatus::kFrame) << why;
  EXPECT_DOUBLE_EQ(frame.T_W_C.translation().x(), 1.0);
  EXPECT_NEAR((frame.T_W_C.linear() * Eigen::Vector3d::UnitX()).y(), 1.0, 1e-6);  // 90 deg yaw
  ASSERT_EQ(stream->Next(&frame, &why), FrameStatus::kFrame) << why;
  EXPECT_DOUBLE_EQ(frame.T_W_C.translation().x(), 2.0);
  EXPECT_EQ(stream->Next(&frame, &why), FrameStatus::kBadFrame);
  EXPECT_NE(why.find("camera frame 2: no pose in poses.txt within 0.02"), std::string::npos) << why;
  ASSERT_EQ(stream->Next(&frame, &why), FrameStatus::kFrame) << why;
  EXPECT_DOUBLE_EQ(frame.T_W_C.translation().x(), 3.0);
  EXPECT_EQ(stream->Next(&frame, &why), FrameStatus::kEnded);
}

TEST_F(FrameStreamTest, MalformedTrajectoryLineIsNamed) {
  std::ofstream(Path("bad.txt")) << "0.0 1 0 0 0 0 0 1\n0.1 1 0 0 0 0 1\n";
  std::vector<TrajectoryPose> poses;
  std::string why;
  EXPECT_FALSE(ReadTumTrajectory(Path("bad.txt"), &poses, &why));
  EXPECT_EQ(why.rfind(Path("bad.txt") + ":2: ", 0), 0u) << why;
  std::ofstream(Path("scaled.txt")) << "0.0 1 0 0 0 0 0 2\n";
  EXPECT_FALSE(ReadTumTrajectory(Path("scaled.txt"), &poses, &why));
  EXPECT_NE(why.find("unit quaternion"), std::string::npos) << why;
  std::ofstream(Path("empty.txt")) << "# nothing\n";
  EXPECT_FALSE(ReadTumTrajectory(Path("empty.txt"), &poses, &why));
  EXPECT_FALSE(ReadTumTrajectory(Path("absent.txt"), &poses, &why));
  EXPECT_NE(why.find("absent.txt: missing"), std::string::npos) << why;
}

TEST_F(FrameStreamTest, WrittenTrajectoriesReadBackAsWritten) {
  std::vector<TrajectoryPose> poses(2);
  poses[0].stamp_s = 12.5;
  poses[0].T_W_C.translation() = Eigen::Vector3d(1.0, -2.0, 0.5);
  poses[1].stamp_s = 12.6;
  poses[1].T_W_C.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).matrix();
  std::string why;
  ASSERT_TRUE(WriteTumTrajectory(Path("written.txt"), poses, "two poses", &why)) << why;
  std::vector<TrajectoryPose> read;
  ASSERT_TRUE(ReadTumTrajectory(Path("written.txt"), &read, &why)) << why;
  ASSERT_EQ(read.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(read[i].stamp_s, poses[i].stamp_s, 1e-6);
    EXPECT_TRUE(read[i].T_W_C.isApprox(poses[i].T_W_C, 1e-6));
  }
  EXPECT_FALSE(WriteTumTrajectory(Path("absent/dir/x.txt"), poses, "", &why));
  EXPECT_NE(why.find("cannot write"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
