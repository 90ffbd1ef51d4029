// OpenNI2 through its own drivers: no device, the DummyDevice driver (a device by URI "Dummy",
// never listed, so it cannot stand in for a missing camera), and .oni files written here and
// played back by the OniFile driver.
#include "openni2/openni2_source.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "oni_file_writer.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

class OpenNI2SourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_openni2_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// Five frames, 64x48: depth (1000 + 100 i) mm with a hole at (0, 0), colour (10 i, 20, 30).
testing::OniTestRecording FiveFrames() {
  testing::OniTestRecording recording;
  for (int i = 0; i < 5; ++i) {
    testing::OniTestFrame frame;
    frame.timestamp_us = 33333u * (i + 1);
    frame.depth_mm.assign(recording.width * recording.height, 1000 + 100 * i);
    frame.depth_mm[0] = 0;
    for (int p = 0; p < recording.width * recording.height; ++p) {
      frame.rgb.insert(frame.rgb.end(), {static_cast<std::uint8_t>(10 * i), 20, 30});
    }
    recording.frames.push_back(frame);
  }
  return recording;
}

TEST(OpenNI2SourceConfig, RejectsTwoSourcesAndBadValues) {
  std::string why;
  OpenNI2SourceConfig config;
  EXPECT_TRUE(config.IsValid(&why)) << why;
  config.device_uri = "Dummy";
  config.oni_path = "a.oni";
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("exclusive"), std::string::npos) << why;
  config = OpenNI2SourceConfig();
  config.playback_speed = -2.0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("playback_speed"), std::string::npos) << why;
  config = OpenNI2SourceConfig();
  config.read_timeout_ms = 0;
  EXPECT_FALSE(config.IsValid(&why));
}

TEST_F(OpenNI2SourceTest, NoDeviceIsAClearErrorQuickly) {
  std::string why;
  const auto start = std::chrono::steady_clock::now();
  auto source = OpenNI2Source::Open(OpenNI2SourceConfig(), &why);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (source != nullptr) GTEST_SKIP() << "a camera is attached: " << source->Describe();
  EXPECT_EQ(why.rfind("no OpenNI2 device found: ", 0), 0u) << why;
  EXPECT_NE(why.find("no devices found"), std::string::npos) << why;  // OpenNI2's own words
  EXPECT_LT(seconds, 5.0);
}

TEST_F(OpenNI2SourceTest, UnknownUriIsNamed) {
  std::string why;
  OpenNI2SourceConfig config;
  config.device_uri = "no-such-device-uri";
  EXPECT_EQ(OpenNI2Source::Open(config, &why), nullptr);
  EXPECT_NE(why.find("'no-such-device-uri' cannot be opened"), std::string::npos) << why;
}

TEST_F(OpenNI2SourceTest, MissingOniNamesThePath) {
  std::string why;
  OpenNI2SourceConfig config;
  config.oni_path = Path("absent.oni");
  EXPECT_EQ(OpenNI2Source::Open(config, &why), nullptr);
  EXPECT_EQ(why, Path("absent.oni") + ": no such .oni file");
}

TEST_F(OpenNI2SourceTest, CorruptOniNamesTheFile) {
  {
    std::ofstream out(Path("garbage.oni"), std::ios::binary);
    for (int i = 0; i < 100000; ++i) out.put(static_cast<char>((i * 7919) % 251));
  }
  std::string why;
  OpenNI2SourceConfig config;
  config.oni_path = Path("garbage.oni");
  EXPECT_EQ(OpenNI2Source::Open(config, &why), nullptr);
  EXPECT_EQ(why.rfind(Path("garbage.oni") + ": not a readable .oni recording", 0), 0u) << why;
}

TEST_F(OpenNI2SourceTest, PlaysBackARecordingFrameByFrame) {
  const testing::OniTestRecording recording = FiveFrames();
  ASSERT_TRUE(testing::WriteOniFile(Path("five.oni"), recording));
  std::string why;
  OpenNI2SourceConfig config;
  config.oni_path = Path("five.oni");
  auto source = OpenNI2Source::Open(config, &why);
  ASSERT_NE(source, nullptr) << why;
  EXPECT_EQ(source->size(), 5u);
  // The recording's field of view: fx = 64 / (2 tan(0.5)), fy = 48 / (2 tan(0.4)).
  EXPECT_NEAR(source->intrinsics().fx, 64.0 / (2.0 * std::tan(0.5)), 1e-3);
  EXPECT_NEAR(source->intrinsics().fy, 48.0 / (2.0 * std::tan(0.4)), 1e-3);
  EXPECT_DOUBLE_EQ(source->intrinsics().cx, 32.0);
  for (int i = 0; i < 5; ++i) {
    RgbdFrame frame;
    ASSERT_EQ(source->Next(&frame, &why), FrameStatus::kFrame) << "frame " << i << ": " << why;
    EXPECT_EQ(frame.frame_index, i);
    EXPECT_EQ(frame.name, "five.oni frame " + std::to_string(i));
    EXPECT_NEAR(frame.stamp_s, 0.033333 * (i + 1), 1e-6);
    ASSERT_EQ(frame.depth.width, 64);
    ASSERT_EQ(frame.depth.height, 48);
    EXPECT_EQ(frame.depth.depth_m[0], 0.0f);  // invalid stays invalid
    EXPECT_NEAR(frame.depth.depth_m[100], 1.0 + 0.1 * i, 1e-6);
    ASSERT_EQ(frame.color.width, 64);
    EXPECT_EQ(frame.color.rgb[300], 10 * i);
    EXPECT_EQ(frame.color.rgb[301], 20);
    EXPECT_TRUE(frame.T_W_C.isApprox(Eigen::Isometry3d::Identity()));
    EXPECT_TRUE(ValidateFrame(frame, &why)) << why;
  }
  RgbdFrame frame;
  EXPECT_EQ(source->Next(&frame, &why), FrameStatus::kEnded) << why;
}

TEST_F(OpenNI2SourceTest, DummyDeviceGivesPairedFrames) {
  std::string why;
  OpenNI2SourceConfig config;
  config.device_uri = "Dummy";  // OpenNI2's DummyDevice driver: 320x240 depth and colour
  config.width = 320;
  config.height = 240;
  auto source = OpenNI2Source::Open(config, &why);
  ASSERT_NE(source, nullptr) << why;
  EXPECT_EQ(source->size(), 0u);  // live: length unknown
  // DummyDevice reports no field of view: the fallback (58 x 45 degrees) applies.
  EXPECT_NEAR(source->intrinsics().fx, 320.0 / (2.0 * std::tan(29.0 * M_PI / 180.0)), 1e-6);
  EXPECT_NEAR(source->intrinsics().fy, 240.0 / (2.0 * std::tan(22.5 * M_PI / 180.0)), 1e-6);
  for (int i = 0; i < 3; ++i) {
    RgbdFrame frame;
    ASSERT_EQ(source->Next(&frame, &why), FrameStatus::kFrame) << why;
    EXPECT_EQ(frame.name, "openni2 frame " + std::to_string(i));
    EXPECT_EQ(frame.depth.width, 320);
    EXPECT_EQ(frame.color.height, 240);
    EXPECT_FLOAT_EQ(frame.depth.depth_m[5], 2.0f);  // DummyDevice's top row is 2000 mm
    EXPECT_GT(frame.stamp_s, 0.0);
  }
}

}  // namespace
}  // namespace objmap
