#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "dataset/keyframe_selector.h"
#include "dataset/sequence_reader.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

// A scratch folder removed at the end of each test.
class ScratchDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_dataset_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  void WriteText(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name)) << text;
  }

  // Writes frame `stem` of the 7-Scenes layout: constant depth (mm), grey colour, a pose.
  void WriteSevenScenesFrame(const std::string& stem, int width, int height,
                             const std::string& pose) const {
    cv::imwrite(Path(stem + ".depth.png"), cv::Mat(height, width, CV_16UC1, cv::Scalar(1500)));
    cv::imwrite(Path(stem + ".color.png"), cv::Mat(480, 640, CV_8UC3, cv::Scalar(10, 20, 30)));
    WriteText(stem + ".pose.txt", pose);
  }

  fs::path dir_;
};

const char kIdentityPose[] = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";

TEST(SevenScenes, ReadsRedkitchenFrame) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  EXPECT_EQ(reader->size(), 1000u);
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(500, &frame, &why)) << why;
  EXPECT_EQ(frame.name, "frame-000500");
  EXPECT_EQ(frame.depth.width, 640);
  EXPECT_EQ(frame.depth.height, 480);
  EXPECT_EQ(frame.color.width, 640);
  EXPECT_DOUBLE_EQ(frame.intrinsics.fx, 585.0);
  EXPECT_DOUBLE_EQ(frame.intrinsics.cx, 320.0);
  int valid = 0;
  for (float d : frame.depth.depth_m) {
    if (d > 0.f) {
      ++valid;
      EXPECT_LT(d, 10.f);  // metres, not millimetres
    }
  }
  EXPECT_GT(valid, 640 * 480 / 2);
  EXPECT_TRUE(IsValidRigidTransform(frame.T_W_C.matrix(), &why)) << why;
}

TEST_F(ScratchDir, EmptyFolderIsAnError) {
  std::string why;
  EXPECT_EQ(OpenSequence(dir_.string(), &why), nullptr);
  EXPECT_NE(why.find("empty sequence"), std::string::npos) << why;
}

TEST_F(ScratchDir, BadFramesNameTheFile) {
  WriteText("camera-intrinsics.txt", "585 0 320\n0 585 240\n0 0 1\n");
  WriteSevenScenesFrame("frame-000000", 640, 480, kIdentityPose);
  WriteSevenScenesFrame("frame-000001", 320, 240, kIdentityPose);  // wrong depth size
  WriteSevenScenesFrame("frame-000002", 640, 480, "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  WriteSevenScenesFrame("frame-000003", 640, 480, "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  WriteSevenScenesFrame("frame-000004", 640, 480, kIdentityPose);
  fs::remove(Path("frame-000004.color.png"));
  WriteSevenScenesFrame("frame-000005", 640, 480, kIdentityPose);
  WriteText("frame-000005.color.png", "this is not a png");
  std::string why;
  auto reader = OpenSequence(dir_.string(), &why);
  ASSERT_NE(reader, nullptr) << why;
  ASSERT_EQ(reader->size(), 6u);
  RgbdFrame frame;
  EXPECT_TRUE(reader->ReadFrame(0, &frame, &why)) << why;
  EXPECT_NEAR(frame.depth.depth_m[0], 1.5f, 1e-6);

  const std::vector<std::pair<int, std::string>> expected_errors = {
      {1, "frame-000001: depth image is 320x240 but the intrinsics say 640x480"},
      {2, "frame-000002.pose.txt: pose has NaN"},
      {3, "frame-000003.pose.txt: pose is not rigid"},
      {4, "frame-000004.color.png: missing"},
      {5, "frame-000005.color.png: missing or not a readable image"},
  };
  for (const auto& [index, message] : expected_errors) {
    why.clear();
    EXPECT_FALSE(reader->ReadFrame(index, &frame, &why)) << "frame " << index;
    EXPECT_NE(why.find(message), std::string::npos) << "got: " << why;
  }
  EXPECT_FALSE(reader->ReadFrame(99, &frame, &why));
}

TEST_F(ScratchDir, TumPairsByTimestampAndInterpolatesPose) {
  fs::create_directories(Path("rgb"));
  fs::create_directories(Path("depth"));
  cv::imwrite(Path("rgb/1.000.png"), cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 0, 255)));
  cv::imwrite(Path("rgb/2.000.png"), cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 255, 0)));
  cv::imwrite(Path("depth/1.010.png"), cv::Mat(480, 640, CV_16UC1, cv::Scalar(5000)));
  cv::imwrite(Path("depth/1.500.png"), cv::Mat(480, 640, CV_16UC1, cv::Scalar(5000)));
  cv::imwrite(Path("depth/2.005.png"), cv::Mat(480, 640, CV_16UC1, cv::Scalar(10000)));
  WriteText("rgb.txt", "# colour\n1.000 rgb/1.000.png\n2.000 rgb/2.000.png\n");
  WriteText("depth.txt",
            "# depth\n1.010 depth/1.010.png\n1.500 depth/1.500.png\n"
            "2.005 depth/2.005.png\n");
  WriteText("groundtruth.txt",
            "# gt\n1.00 0 0 0 0 0 0 1\n1.05 1 0 0 0 0 0 1\n"
            "2.00 2 0 0 0 0 0 1\n2.01 2 0 0 0 0 0 1\n");
  std::string why;
  auto reader = OpenSequence(dir_.string(), &why);
  ASSERT_NE(reader, nullptr) << why;
  // 1.500 has no colour within 20 ms; 2.005 pairs with 2.000.
  ASSERT_EQ(reader->size(), 2u);
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(0, &frame, &why)) << why;
  EXPECT_NEAR(frame.T_W_C.translation().x(), 0.2, 1e-9);  // 1.010 between 1.00 and 1.05
  EXPECT_NEAR(frame.depth.depth_m[0], 1.0f, 1e-6);        // 5000 units = 1 m
  EXPECT_EQ(frame.color.rgb[0], 255);                     // red channel first
  ASSERT_TRUE(reader->ReadFrame(1, &frame, &why)) << why;
  EXPECT_NEAR(frame.depth.depth_m[0], 2.0f, 1e-6);
  EXPECT_EQ(frame.color.rgb[1], 255);
}

TEST(KeyframeSelector, NeedsMotion) {
  KeyframeSelectorConfig config;
  config.min_translation_m = 0.1;
  config.min_rotation_deg = 10.0;
  KeyframeSelector selector(config);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(selector.IsKeyframe(T));
  T.translation().x() = 0.05;
  EXPECT_FALSE(selector.IsKeyframe(T));
  T.translation().x() = 0.11;
  EXPECT_TRUE(selector.IsKeyframe(T));
  T.linear() = Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_FALSE(selector.IsKeyframe(T));
  T.linear() = Eigen::AngleAxisd(12.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(selector.IsKeyframe(T));
}

TEST(KeyframeSelector, EveryNthFrameIgnoresMotion) {
  KeyframeSelectorConfig config;
  config.every_nth_frame = 3;
  KeyframeSelector selector(config);
  std::vector<int> keyframes;
  for (int frame = 0; frame < 10; ++frame) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = frame % 2 == 0 ? 0.0 : 5.0;  // large motion on every other frame
    if (selector.IsKeyframe(T)) keyframes.push_back(frame);
  }
  EXPECT_EQ(keyframes, (std::vector<int>{0, 3, 6, 9}));
  config.every_nth_frame = -1;
  std::string why;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("every_nth_frame"), std::string::npos);
}

}  // namespace
}  // namespace objmap
