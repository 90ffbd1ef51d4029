// `objmap map` on OpenNI2 inputs, run as a user would: no camera, .oni recordings, trajectories.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "dataset/sequence_reader.h"
#include "dataset/trajectory.h"
#include "evaluation/trajectory_evaluation.h"
#include "openni2/oni_file_writer.h"
#include "run_objmap.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::RunObjmap;

class MapOpenNI2 : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_cli_openni2_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(Path("detections.json")) << R"({"frames": {}})";
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // A recording of `count` frames 1/30 s apart (first at 1/30 s): a wall 1.5 m away.
  void WriteRecording(const std::string& name, int count) const {
    const testing::OniTestRecording size;  // the writer's default frame size
    ASSERT_TRUE(testing::WriteOniFile(
        Path(name), testing::WallRecording(count, size.width, size.height, 1500, 90)));
  }

  fs::path dir_;
};

TEST_F(MapOpenNI2, NoCameraExitsOneQuicklyWithTheReason) {
  const auto start = std::chrono::steady_clock::now();
  const CommandResult result = RunObjmap("map openni2 --out " + Path("out"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (result.exit_code == 0) GTEST_SKIP() << "a camera is attached";
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find("objmap map: no OpenNI2 device found: "), std::string::npos)
      << result.output;
  EXPECT_LT(seconds, 5.0);
  EXPECT_FALSE(fs::exists(Path("out/map.bt")));
}

TEST_F(MapOpenNI2, MissingAndCorruptRecordingsAreNamed) {
  CommandResult result = RunObjmap("map " + Path("absent.oni") + " --out " + Path("out"));
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.output.find(Path("absent.oni") + ": no such .oni file"), std::string::npos)
      << result.output;
  std::ofstream(Path("corrupt.oni")) << std::string(50000, '\x5a');
  result = RunObjmap("map " + Path("corrupt.oni") + " --out " + Path("out"));
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.output.find(Path("corrupt.oni") + ": not a readable .oni recording"),
            std::string::npos)
      << result.output;
}

TEST_F(MapOpenNI2, MapsARecordingAtTheIdentityPoseWhenAsked) {
  WriteRecording("wall.oni", 4);
  const CommandResult result =
      RunObjmap("map " + Path("wall.oni") + " --out " + Path("out") + " --detections " +
                Path("detections.json") + " --every-frame --poses input");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("mapping OpenNI2 recording " + Path("wall.oni")), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("no --trajectory: the camera is taken as static at the identity"),
            std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("keyframes: 4 of 4 frames read"), std::string::npos)
      << result.output;
  EXPECT_TRUE(fs::exists(Path("out/map.bt")));
}

TEST_F(MapOpenNI2, ARecordingWithoutTrajectoryIsMappedWithEstimatedPoses) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  const auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  // 20 redkitchen frames (every second of the first 40) recorded as a camera would.
  std::vector<RgbdFrame> frames;
  std::vector<TrajectoryPose> reference;
  for (int n = 0; n < 20; ++n) {
    RgbdFrame frame;
    ASSERT_TRUE(reader->ReadFrame(static_cast<std::size_t>(2 * n), &frame, &why)) << why;
    reference.push_back({0.0, frame.T_W_C});
    frames.push_back(std::move(frame));
  }
  const testing::OniTestRecording recording = testing::RecordingOf(frames, 66667);
  ASSERT_TRUE(testing::WriteOniFile(Path("kitchen.oni"), recording));
  const CommandResult result = RunObjmap("map " + Path("kitchen.oni") + " --out " + Path("out") +
                                         " --detections " + Path("detections.json"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("no --trajectory; poses estimated by RGB-D odometry"),
            std::string::npos)
      << result.output;
  std::vector<TrajectoryPose> estimated;
  ASSERT_TRUE(ReadTumTrajectory(Path("out/trajectory.txt"), &estimated, &why)) << why;
  ASSERT_EQ(estimated.size(), reference.size()) << result.output;
  for (std::size_t i = 0; i < estimated.size(); ++i) reference[i].stamp_s = estimated[i].stamp_s;
  TrajectoryErrors errors;
  ASSERT_TRUE(EvaluateTrajectory(estimated, reference, {}, &errors, &why)) << why;
  EXPECT_LT(errors.ate_rmse_m, 0.02);
  EXPECT_TRUE(fs::exists(Path("out/map.bt")));
}

TEST_F(MapOpenNI2, TrajectoryPosesFramesAndSkipsThoseWithout) {
  WriteRecording("wall.oni", 4);
  // Poses for frames 0, 1 and 3 (stamps 1/30, 2/30, 4/30 s); none near frame 2.
  std::ofstream(Path("trajectory.txt")) << "0.033333 0 0 0 0 0 0 1\n"
                                        << "0.066667 0.2 0 0 0 0 0 1\n"
                                        << "0.133333 0.4 0 0 0 0 0 1\n";
  const CommandResult result =
      RunObjmap("map " + Path("wall.oni") + " --out " + Path("out") + " --detections " +
                Path("detections.json") + " --every-frame --trajectory " + Path("trajectory.txt") +
                " --max-frames 4");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("poses from " + Path("trajectory.txt") + " (3 poses)"),
            std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("skipped frame 2: wall.oni frame 2: no pose in"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("keyframes: 3 of 4 frames read"), std::string::npos)
      << result.output;
}

TEST_F(MapOpenNI2, MaxFramesLimitsARecording) {
  WriteRecording("wall.oni", 5);
  const CommandResult result =
      RunObjmap("map " + Path("wall.oni") + " --out " + Path("out") + " --detections " +
                Path("detections.json") + " --every-frame --max-frames 2 --poses input");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("keyframes: 2 of 2 frames read"), std::string::npos)
      << result.output;
}

}  // namespace
}  // namespace objmap
